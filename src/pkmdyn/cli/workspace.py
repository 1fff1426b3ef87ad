"""``pkmdyn workspace``: the workspace of any described mechanism on a grid of task poses
(``docs/workspace.md``)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

from .._lazy import lazy_module
from ._groups import MACHINE_HELP, FiniteFloat, cli, list_files, show

if TYPE_CHECKING:
    from ..jobs import workspace as job
else:  # the engine and its kernels load when the command runs, not for --help
    job = lazy_module("pkmdyn.jobs.workspace")


@cli.command("workspace")
@click.option("--machine", required=True, help=MACHINE_HELP)
@click.option("--grid", required=True, metavar="NAME=LOW:HIGH:COUNT[,...]",
              help="One to three task coordinates on a grid, e.g. \"x=-0.3:0.3:17,y=-0.3:0.3:17,z=0.8:1.2:9\".")
@click.option("--pose", default="", metavar="NAME=VALUE,...",
              help="The task coordinates held while the grid varies the others (default: the reference pose's), "
                   "e.g. a constant orientation \"euler3_rad=0.2\".")
@click.option("--orientation-range", "orientation_range", default=None, metavar="NAME=LOW:HIGH:COUNT[,...]",
              help="Held coordinates over ranges, e.g. \"euler1=-0.1:0.1:3,euler2=-0.1:0.1:3\": a pose is inside only "
                   "where it is inside at every combination of their values (the total orientation workspace).")
@click.option("--threshold", type=FiniteFloat(0.0, 1.0), default=1e-3, show_default=True,
              help="A pose is inside only where every singularity measure is at least this.")
@click.option("--centre", default=None, metavar="V1,V2,...",
              help="Centre of the inscribed cube and cylinder, one value per grid coordinate (default: the pose's).")
@click.option("--refine", type=click.IntRange(0, 64), default=0, show_default=True,
              help="Steps along each grid edge the workspace's boundary crosses, for a size that varies smoothly with "
                   "the design (0: inside poses times the cell; docs/workspace.md).")
@click.option("--limit", "limit_items", multiple=True, metavar="KEY=VALUE",
              help="Raise a limit of the description's [limits], e.g. max_workspace_poses=400000 (the grid's poses, "
                   "default 100,000; docs/mechanism_format.md). Repeatable.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), required=True,
              help="Output folder (an earlier run of this command there is replaced whole).")
def workspace_command(machine: str, grid: str, pose: str, orientation_range: str | None, threshold: float,
                      centre: str | None, refine: int, limit_items: tuple[str, ...], out_dir: Path) -> None:
    """The reachable workspace within the joint limits and away from every singularity, on a grid
    of task poses: its size with an error estimate, the largest inscribed cube and cylinder about a
    centre, dexterity statistics, a map."""
    show(job.job(machine, grid, pose, orientation_range, threshold, centre, refine, out_dir, announce=list_files,
                 limit_items=limit_items))
