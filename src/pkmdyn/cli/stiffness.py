"""``pkmdyn stiffness``: stiffness, worst directions, deflection and natural frequencies of a
mechanism with its actuators locked (``docs/stiffness.md``)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

from .._lazy import lazy_module
from ._groups import MACHINE_HELP, PATH_IN, cli, list_files, show

if TYPE_CHECKING:
    from ..jobs import stiffness as job
else:  # the engine and its kernels load when the command runs, not for --help
    job = lazy_module("pkmdyn.jobs.stiffness")



@cli.command("stiffness")
@click.option("--machine", required=True, help=MACHINE_HELP)
@click.option("--pose", "poses", multiple=True, metavar="NAME=VALUE,...",
              help="A task pose (task coordinates by name, e.g. \"x=0.02,euler3_rad=0.1\"; the reference pose's "
                   "value for the others); repeat for several. Default: the reference pose.")
@click.option("--motion", "motion_path", type=PATH_IN, default=None,
              help="A task motion file (as for pkmdyn run): the stiffness at every sample and the deflection under "
                   "the motion's own loads, in results.csv.")
@click.option("--default-motion", is_flag=True,
              help="The description's default motion (one cycle) as the motion.")
@click.option("--grid", default=None, metavar="NAME=LOW:HIGH:COUNT[,NAME=...]",
              help="One or two task coordinates swept about the reference pose: grid.csv and stiffness_map.png.")
@click.option("--rotors", type=click.Choice(["held", "moving"]), default="held", show_default=True,
              help="The drives' rotors in the natural frequencies and modes: held (a brake, or a position loop "
                   "stiffer than the transmission the drive stiffness describes) or moving with their joints (the "
                   "drive stiffness is the servo's holding stiffness: their reflected inertia counts). "
                   "stiffness.json holds both frequency sets.")
@click.option("--limit", "limit_items", multiple=True, metavar="KEY=VALUE",
              help="Raise a plausibility limit of the description's numbers ([limits]).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), required=True,
              help="Output folder (an earlier run of this command there is replaced whole).")
def stiffness_command(machine: str, poses: tuple[str, ...], motion_path: Path | None, default_motion: bool,
                      grid: str | None, rotors: str,
                      limit_items: tuple[str, ...], out_dir: Path) -> None:
    """Cartesian stiffness of the task body with the actuators locked (from the drives', links' and
    joints' compliance), its eigen-stiffnesses and worst directions, natural frequencies and modes;
    along a motion the task body's elastic deflection under its loads; over a grid, maps."""
    show(job.job(machine, out_dir, poses=poses, motion_path=motion_path, default_motion=default_motion, grid=grid,
                 limit_items=limit_items, announce=list_files, rotors=rotors))
