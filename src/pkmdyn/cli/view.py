"""``pkmdyn view``: a page for any machine without running a motion (:mod:`pkmdyn.jobs.view`)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

from .._lazy import lazy_module
from ._groups import PATH_IN, cli, echo, show

if TYPE_CHECKING:
    from ..jobs import view as view_job
else:  # the engine loads when the command runs, not for --help
    view_job = lazy_module("pkmdyn.jobs.view")


def _listing(path: Path) -> None:
    echo(f"view: {path}")


@cli.command("view")
@click.option("--machine", required=True, help="A built-in machine (see pkmdyn machines) or a description FILE.toml.")
@click.option("--params", "params_path", type=PATH_IN,
              help="Parameter file (TOML) of a generated machine (see pkmdyn machines); default: the built-in one.")
@click.option("--out", "out_path", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="HTML file to write (atomically; only a page pkmdyn wrote is replaced).")
def view(machine: str, params_path: Path | None, out_path: Path) -> None:
    """A self-contained HTML page of a machine: home pose in 3D, topology graph, mobility and
    over-constraint counts."""

    show(view_job.job(machine, out_path, params_path=params_path, announce=_listing))
