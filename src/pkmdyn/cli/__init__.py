"""Command line: argument parsing -> library calls -> files. Nothing else lives here.

Every user error (bad file, unreachable pose, bad option) ends as one line on stderr and
exit status 2, with no traceback. Each concern registers its commands on the groups of
:mod:`._groups` from its own module; importing them here builds the whole command tree.
"""

from __future__ import annotations

import signal
import sys
import threading
import warnings

import click

from ..compile_notice import install, reset, summary
from ..errors import PkmdynError
from ..machines.registry import command_groups
from . import assemble as _assemble_commands  # noqa: F401
from . import compile as _compile_commands  # noqa: F401
from . import control as _control_commands  # noqa: F401
from . import describe as _describe_commands  # noqa: F401
from . import export as _export_commands  # noqa: F401
from . import identify as _identify_commands  # noqa: F401
from . import imports as _import_commands  # noqa: F401
from . import pdm as _pdm_commands  # noqa: F401  (registers the commands)
from . import retime as _retime_commands  # noqa: F401
from . import run as _run_commands  # noqa: F401
from . import stiffness as _stiffness_commands  # noqa: F401
from . import sweep as _sweep_commands  # noqa: F401
from . import view as _view_commands  # noqa: F401
from . import wear as _wear_commands  # noqa: F401
from . import workspace as _workspace_commands  # noqa: F401
from ._groups import HELD_NOTES, cli

for _group in command_groups():  # the generated machines' own commands, pkmdyn <machine> ...
    cli.add_command(_group)

__all__ = ["main", "cli", "run"]


#: a group called without a command (click >= 8.2 raises this; older versions print the help)
_NO_ARGS_IS_HELP: type[BaseException] = getattr(click.exceptions, "NoArgsIsHelpError", type("_Never", (Exception,), {}))


def _sigterm(signum: int, frame: object) -> None:
    raise KeyboardInterrupt


def main(argv: list[str] | None = None) -> int:
    """Run the command line; return the exit status (0 ok, 2 user error, 130 interrupted).

    Ctrl-C and SIGTERM end a run cleanly (its temporary output removed) with one line; a run
    that failed says nothing but its error line (notes held back are dropped).
    """
    reset()
    status = _main(argv)
    done = summary()
    if done is not None and status == 0:
        try:
            click.echo(done, err=True)
        except OSError:
            pass
    notes = list(HELD_NOTES) if status == 0 else []
    HELD_NOTES.clear()
    for note in notes:
        try:
            click.echo(f"pkmdyn: note: {note}", err=True)
        except OSError:
            pass
    return status


#: the messages of numpy's and scipy's floating-point warnings
_NUMERIC = r"(?i).*(overflow|invalid value|divide by zero|underflow)"


def _main(argv: list[str] | None) -> int:
    old = None
    if threading.current_thread() is threading.main_thread():
        old = signal.signal(signal.SIGTERM, _sigterm)
    args = sys.argv[1:] if argv is None else list(argv)
    try:
        with warnings.catch_warnings():
            # a floating-point warning of numpy or scipy (overflow, an invalid value, a division by
            # zero) means an input beyond what the computation can hold: one line, not a run
            # written with its consequences (and never the warnings' own lines on stderr)
            warnings.filterwarnings("error", message=_NUMERIC, category=RuntimeWarning)
            with cli.make_context("pkmdyn", args) as ctx:
                # once the arguments are read (a --help or a usage error compiles nothing and
                # imports no numba): say where a command compiles kernels the cache lacks
                install()
                cli.invoke(ctx)
    except RuntimeWarning as exc:
        click.echo(f"pkmdyn: error: the computation overflowed ({' '.join(str(exc).split())}); an input is beyond "
                   "what it can hold: check the magnitudes of the description, parameters and motion", err=True)
        return 2
    except click.exceptions.Exit as exc:
        return int(exc.exit_code)
    except _NO_ARGS_IS_HELP as exc:  # `pkmdyn`, `pkmdyn <machine>`: the group's help, as --help prints it
        click.echo(exc.ctx.get_help() if exc.ctx is not None else cli.get_help(click.Context(cli)))
        return 0
    except (KeyboardInterrupt, click.exceptions.Abort):
        click.echo("pkmdyn: interrupted; --out holds either the whole new run or what it held before", err=True)
        return 130
    except MemoryError:
        click.echo("pkmdyn: error: out of memory (lower the sample count or --limit max_samples)", err=True)
        return 2
    except OSError as exc:
        where = f" {exc.filename}" if exc.filename else ""
        click.echo(f"pkmdyn: error:{where} {exc.strerror or type(exc).__name__}", err=True)
        return 2
    except click.ClickException as exc:
        message = " ".join(exc.format_message().split())
        click.echo(f"pkmdyn: error: {message}", err=True)
        return 2
    except PkmdynError as exc:
        message = " ".join(str(exc).split())
        click.echo(f"pkmdyn: error: {message}", err=True)
        return 2
    finally:
        if old is not None:
            signal.signal(signal.SIGTERM, old)
    return 0


def run() -> None:
    """Console-script entry point."""
    sys.exit(main())

