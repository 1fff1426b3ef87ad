"""The command groups; each concern registers its commands on them from its own module."""

from __future__ import annotations

from pathlib import Path

import click

__all__ = ["cli", "hip", "pdm", "PATH_IN"]

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
