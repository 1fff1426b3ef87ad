"""The command groups, on which each concern registers its commands from its own module, and
the option types they share."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from .._lazy import lazy_module
from ..errors import PkmdynError
from ..profiles._columns import check_smoothing

if TYPE_CHECKING:
    from ..jobs import parameter_file as _params_job
else:  # the parameter files' writers load when a file is asked for, not for --help
    _params_job = lazy_module("pkmdyn.jobs.parameter_file")

__all__ = ["cli", "pdm", "PATH_IN", "MACHINE_HELP", "FiniteFloat", "list_files", "echo_lines", "echo", "show"]

#: an input file option (existence is checked by the readers, which name the file)
PATH_IN = click.Path(dir_okay=False, path_type=Path)
#: the help of every command's --machine that takes any machine
MACHINE_HELP = "A built-in machine (see pkmdyn machines) or a mechanism description FILE.toml."


@click.group()
@click.version_option(package_name="pkmdyn")
@click.option("--replace", is_flag=True,
              help="Let the command replace another pkmdyn command's results in its --out folder (by default "
                   "a command replaces only its own earlier run there).")
@click.pass_context
def cli(ctx: click.Context, replace: bool) -> None:
    """pkmdyn: kinematics, dynamics and control of parallel manipulators."""
    ctx.obj = {"replace": replace}


@cli.group()
def pdm() -> None:
    """The 4-DOF over-constrained parallel driving mechanism."""


class FiniteFloat(click.ParamType):
    """A finite float in ``[lo, hi]`` (``lo`` excluded when ``lo_open``): ``inf``/``nan`` refused."""

    name = "number"

    def __init__(self, lo: float, hi: float, lo_open: bool = False) -> None:
        self.lo, self.hi, self.lo_open = lo, hi, lo_open

    def convert(self, value, param, ctx):
        if isinstance(value, float):
            x = value
        else:
            try:
                x = float(str(value).strip())
            except ValueError:
                self.fail(f"{str(value)[:40]!r} is not a number", param, ctx)
        if not math.isfinite(x):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        if x < self.lo or (self.lo_open and x == self.lo) or x > self.hi:
            bracket = "(" if self.lo_open else "["
            self.fail(f"{x:g} is not in {bracket}{self.lo:g}, {self.hi:g}]", param, ctx)
        return x


def differentiator_options(when: str) -> Callable[[Any], Any]:
    """``--sg-window`` and ``--sg-order``: the Savitzky-Golay differentiator of positions logged
    without rates (``when`` says which input), checked by :func:`check_differentiator`."""
    window = click.option(
        "--sg-window", type=click.IntRange(0, 100_001), default=15, show_default=True,
        help=f"{when}: samples of the Savitzky-Golay smoothing differentiator (odd, >= 3; uniform sampling), or 0 "
             "for the interpolating quintic spline (exact positions).")
    order = click.option("--sg-order", type=click.IntRange(2, 20), default=5, show_default=True,
                         help="Degree of the Savitzky-Golay polynomial (less than --sg-window).")
    return lambda f: window(order(f))


def check_differentiator(sg_window: int, sg_order: int) -> None:
    """``--sg-window`` and ``--sg-order`` of the Savitzky-Golay differentiator, before any file
    is read (0: the spline, no differentiator)."""
    if sg_window != 0:
        check_smoothing(sg_window, sg_order)


def echo(line: str) -> None:
    """One line on standard output; a standard output that cannot be written (a full device) is a
    :class:`~pkmdyn.errors.PkmdynError` that says so."""
    try:
        click.echo(line)
    except OSError as exc:
        raise PkmdynError(f"standard output: cannot write ({exc.strerror or type(exc).__name__})") from None


def list_files(files: Mapping[str, Path]) -> None:
    """Print ``label: path`` for every file of a run; given to a run as its ``report``, so that the
    listing is written before the files move into place (:func:`pkmdyn.report.write_output`)."""
    for name, path in files.items():
        echo(f"{name}: {path}")


def show(result: Any) -> None:
    """Print a job's result (:class:`pkmdyn.jobs._files.JobResult`, its files announced as they were
    written): its lines on standard output, each warning as one ``pkmdyn: warning:`` line and each
    note as one ``note:`` line on stderr."""
    for line in result.lines:
        echo(line)
    for warning in result.warnings:
        click.echo(f"pkmdyn: warning: {warning}", err=True)
    for note in result.notes:
        click.echo(f"note: {note}", err=True)


def echo_lines(lines: list[str]) -> None:
    """Print each line (a run's ``report``, like :func:`list_files`)."""
    for line in lines:
        echo(line)


#: notes held back until the command has succeeded (stderr not a terminal: a failed run keeps to
#: its one error line)
HELD_NOTES: list[str] = []


def params_command(group: click.Group, machine: str, option: str) -> None:
    """Register ``pkmdyn MACHINE params`` on ``group``."""

    @group.command("params")
    @click.option("--control", is_flag=True,
                  help=f"Write the control settings ({option} control --gains) instead of the parameter file.")
    @click.option("--out", "out_path", type=click.Path(dir_okay=False, path_type=Path), required=True,
                  help="File to write (e.g. params.toml); an existing file is replaced only if pkmdyn wrote it and "
                       "nobody changed it since.")
    def params(control: bool, out_path: Path) -> None:
        """Write the built-in parameter file (TOML), every key with its unit and a comment, to edit and pass
        as --params (or, with --control, the control settings to pass as --gains)."""
        show(_params_job.job(machine, out_path, control=control, announce=list_files))
