"""``pkmdyn assemble``: every assembly mode of a mechanism at one actuator configuration."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

from .._lazy import lazy_module
from ._groups import MACHINE_HELP, cli, list_files, show

if TYPE_CHECKING:
    from ..jobs import assemble as job
else:  # the engine and its kernels load when the command runs, not for --help
    job = lazy_module("pkmdyn.jobs.assemble")



@cli.command("assemble")
@click.option("--machine", required=True, help=MACHINE_HELP)
@click.option("--actuators", required=True, metavar="NAME=VALUE,...",
              help="Every actuated joint's coordinate, SI (m for a prismatic joint, rad for a revolute one), e.g. "
                   "\"P_1=1.02,P_2=1.05,...\".")
@click.option("--starts", type=click.IntRange(1, 1_000_000), default=None,
              help="A fixed number of starts in all (the reference configuration and the continuation from it "
                   "among them). Default: start until --patience starts in a row find no new mode.")
@click.option("--patience", type=click.IntRange(1, 1_000_000), default=None,
              help="Without --starts: stop once this many consecutive starts found no new mode (default 5,000; "
                   "more, fewer modes missed).")
@click.option("--seed", type=click.IntRange(0, 2**32 - 1), default=0, show_default=True,
              help="Seed of the random starts.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Output folder for assemblies.json and report.html (an earlier run of this command there is replaced whole).")
def assemble(machine: str, actuators: str, starts: int | None, patience: int | None, seed: int,
             out_dir: Path | None) -> None:
    """Every assembly mode found at one actuator configuration (the direct kinematics' distinct
    solutions), each verified by the inverse kinematics, with its singularity measures; the
    search (damped Newton from random starts) guarantees that each mode is real, not that none
    is missing."""
    if starts is not None and patience is not None:
        raise click.UsageError("--starts and --patience exclude each other: a fixed count, or the stopping rule")
    show(job.job(machine, actuators, starts, seed, out_dir, announce=list_files,
                 patience=5000 if patience is None else patience))
