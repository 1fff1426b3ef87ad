"""The command groups, on which each concern registers its commands from its own module, and
the option types they share."""

from __future__ import annotations

import math
from pathlib import Path

import click

__all__ = ["cli", "hip", "pdm", "PATH_IN", "FiniteFloat"]

#: an input file option (existence is checked by the readers, which name the file)
PATH_IN = click.Path(dir_okay=False, path_type=Path)


@click.group()
@click.version_option(package_name="pkmdyn")
def cli() -> None:
    """pkmdyn: kinematics, dynamics and control of parallel manipulators."""


@cli.group()
def hip() -> None:
    """The 2(3PUS+S) dual-platform hip-joint wear simulator."""


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
