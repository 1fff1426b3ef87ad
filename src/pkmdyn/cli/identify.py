"""``pkmdyn identify``: a mechanism's inertial parameters and joint friction from measured
efforts (:mod:`pkmdyn.jobs.identify`)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

from .._lazy import lazy_module
from ._groups import (
    MACHINE_HELP,
    PATH_IN,
    FiniteFloat,
    check_differentiator,
    cli,
    differentiator_options,
    list_files,
    show,
)

if TYPE_CHECKING:
    from ..jobs import identify as identify_job
else:  # the engine and the solvers load when the command runs, not for --help
    identify_job = lazy_module("pkmdyn.jobs.identify")


@cli.command("identify")
@click.option("--machine", required=True, help=MACHINE_HELP)
@click.option("--measured", "measured_path", type=PATH_IN, required=True,
              help="Measured run (CSV): t_s, the task columns (or the actuated joints' <joint>_pos_<m|rad>: the pose "
                   "by the direct kinematics) and one effort column per actuator, a drive's <actuator>_torque_Nm or a "
                   "joint's <joint>_effort_<N|Nm> (a pkmdyn run results.csv works as it is); optional: rates, "
                   "accelerations, named loads.")
@click.option("--rank-tol", type=FiniteFloat(0.0, 1.0, lo_open=True), default=1e-6, show_default=True,
              help="Singular values of the column-scaled regressor below this fraction of the largest count as zero.")
@differentiator_options("A log in actuator coordinates without rate columns")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), required=True,
              help="Output folder; an earlier run of this command there is replaced whole, any other non-empty folder is refused.")
def identify(machine: str, measured_path: Path, rank_tol: float, sg_window: int, sg_order: int,
             out_dir: Path) -> None:
    """Identify a mechanism's inertial parameters and joint friction coefficients from measured
    actuator efforts: identification.json, efforts.csv (docs/identification.md)."""
    check_differentiator(sg_window, sg_order)
    show(identify_job.job(machine, measured_path, out_dir, rank_tol=rank_tol, sg_window=sg_window, sg_order=sg_order,
                          announce=list_files))
