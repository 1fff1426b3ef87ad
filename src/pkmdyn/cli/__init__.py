"""Command line: argument parsing -> library calls -> files. Nothing else lives here.

Every user error (bad file, unreachable pose, bad option) ends as one line on stderr and
exit status 2, with no traceback. Each concern registers its commands on the groups of
:mod:`._groups` from its own module; importing them here builds the whole command tree.
"""

from __future__ import annotations

import sys

import click

from ..errors import PkmdynError
from . import hip as _hip_commands  # noqa: F401  (registers the commands)
from . import pdm as _pdm_commands  # noqa: F401
from ._groups import cli

__all__ = ["main", "cli", "run"]


def main(argv: list[str] | None = None) -> int:
    """Run the command line; return the exit status (0 ok, 2 user error)."""
    try:
        cli.main(args=argv, prog_name="pkmdyn", standalone_mode=False)
    except click.exceptions.Exit as exc:
        return int(exc.exit_code)
    except click.exceptions.Abort:
        click.echo("pkmdyn: aborted", err=True)
        return 2
    except click.ClickException as exc:
        message = " ".join(exc.format_message().split())
        click.echo(f"pkmdyn: error: {message}", err=True)
        return 2
    except PkmdynError as exc:
        message = " ".join(str(exc).split())
        click.echo(f"pkmdyn: error: {message}", err=True)
        return 2
    return 0


def run() -> None:
    """Console-script entry point."""
    sys.exit(main())

