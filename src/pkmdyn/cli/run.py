"""``pkmdyn run``: any machine along a motion (:mod:`pkmdyn.jobs.run`)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

from .._lazy import lazy_module
from ._groups import (
    MACHINE_HELP,
    PATH_IN,
    FiniteFloat,
    cli,
    differentiator_options,
    list_files,
    show,
)

if TYPE_CHECKING:
    from ..jobs import run as run_job
else:  # the engine and its kernels load when the command runs, not for --help
    run_job = lazy_module("pkmdyn.jobs.run")


@cli.command("run")
@click.option("--machine", required=True, help=MACHINE_HELP)
@click.option("--motion", "motion_path", type=PATH_IN, default=None,
              help="Motion CSV: t_s and one column per task coordinate (<name>_<unit>), optional rates "
                   "<name>d_<unit>_s and accelerations <name>dd_<unit>_s2 (default: the machine's default motion, "
                   "for a paper's machine the paper's motion).")
@click.option("--actuator-motion", "actuator_path", type=PATH_IN, default=None,
              help="Motion in actuator coordinates (CSV): t_s and one column per actuated joint, <joint>_pos_<m|rad>, "
                   "optional rates <joint>_vel_<u>_s and accelerations <joint>_acc_<u>_s2 and named loads; the pose "
                   "by the direct kinematics (docs/mechanism_format.md, \"Direct kinematics\").")
@differentiator_options("--actuator-motion without rate columns")
@click.option("--cycles", type=FiniteFloat(0.0, 1e9, lo_open=True), default=None,
              help="Cycles of the default motion (default 1; a periodic default motion repeats).")
@click.option("--samples-per-cycle", type=click.IntRange(1, 100_000_000), default=None,
              help="A described mechanism's default motion: samples per cycle (default: its [default_motion] "
                   "samples - 1).")
@click.option("--format", "fmt", type=click.Choice(["csv", "parquet"]), default="csv", show_default=True,
              help="Format of the results table (results.csv or results.parquet).")
@click.option("--limit", "limit_items", multiple=True, metavar="KEY=VALUE",
              help="Raise a plausibility limit of the description's [limits] (max_samples, max_body_samples, "
                   "max_task_speed_m_s, max_joint_acceleration_rad_s2, ...; docs/mechanism_format.md). Repeatable.")
@click.option("--minimum-norm-reactions", is_flag=True,
              help="For an over-constrained mechanism whose bodies lack the section and material data that make "
                   "its joint reactions unique (refused without this flag): write its kinematics and efforts "
                   "(unique all the same) with the minimum-norm reactions, which balance every body but are one "
                   "choice among its self-stress states; said on stderr and in summary.json.")
@click.option("--deflection", is_flag=True,
              help="Also the task body's elastic deflection under the run's loads with the actuators locked "
                   "(<coordinate>_deflection_<unit> columns; the description needs drive, link or joint "
                   "stiffness, docs/stiffness.md).")
@click.option("--unique-reactions", is_flag=True, hidden=True,
              help="The default: refuse reactions that are not unique.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), required=True,
              help="Output folder; an earlier run of this command there is replaced whole, any other non-empty folder is refused.")
def run(machine: str, motion_path: Path | None, actuator_path: Path | None, sg_window: int, sg_order: int,
        cycles: float | None, samples_per_cycle: int | None, fmt: str, limit_items: tuple[str, ...],
        minimum_norm_reactions: bool, deflection: bool, unique_reactions: bool, out_dir: Path) -> None:
    """Kinematics, actuator and motor efforts, the effort split and every joint reaction along a
    motion, streamed in chunks: results.csv (or .parquet), model.json, bodies.npz, summary.json,
    report.html.

    The same files for every machine; a paper's machine has its own job too, with the paper's
    columns and figures (pkmdyn <machine> run; see pkmdyn machines)."""
    if minimum_norm_reactions and unique_reactions:
        raise click.UsageError("--minimum-norm-reactions and --unique-reactions contradict each other")
    show(run_job.job(machine, out_dir, motion_path=motion_path, actuator_path=actuator_path, sg_window=sg_window,
                     sg_order=sg_order, cycles=cycles, samples_per_cycle=samples_per_cycle, fmt=fmt,
                     limit_items=limit_items, minimum_norm_reactions=minimum_norm_reactions, deflection=deflection,
                     announce=list_files))
