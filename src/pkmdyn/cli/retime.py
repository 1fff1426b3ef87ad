"""``pkmdyn retime``: the fastest timing of a path within the drives', speed, acceleration and
reaction limits, the joints' friction included (``docs/retime.md``)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

from .._lazy import lazy_module
from ._groups import MACHINE_HELP, PATH_IN, cli, list_files, show

if TYPE_CHECKING:
    from ..jobs import retime as job
else:  # the engine and its kernels load when the command runs, not for --help
    job = lazy_module("pkmdyn.jobs.retime")


@cli.command("retime")
@click.option("--machine", required=True, help=MACHINE_HELP)
@click.option("--path", "path_file", type=PATH_IN, default=None,
              help="The path: a CSV of task columns (x_m, euler1_rad, ... as in a motion file; t_s and rates, when "
                   "present, are not used), a spline through its rows. Default: the default motion's path.")
@click.option("--points", type=click.IntRange(3, 1_000_000), default=1000, show_default=True,
              help="Grid points along the path (the limits hold at each).")
@click.option("--max-effort", "efforts", multiple=True, metavar="JOINT=VALUE",
              help="Bound on an actuated joint's effort [N or N m, the joint's unit]; JOINT 'all' for every one. "
                   "Drives' [[actuators]] max_torque_Nm / max_force_N, speeds and accelerations hold too.")
@click.option("--max-reaction-force", "reaction_forces", multiple=True, metavar="JOINT=VALUE",
              help="Bound on a joint's reaction force magnitude [N]; JOINT 'all' for every joint.")
@click.option("--max-reaction-moment", "reaction_moments", multiple=True, metavar="JOINT=VALUE",
              help="Bound on a joint's reaction moment magnitude [N m]; JOINT 'all' for every joint.")
@click.option("--no-friction", is_flag=True, help="Time the path without the joints' and motors' friction.")
@click.option("--no-plots", is_flag=True, help="Leave out the PNG figures.")
@click.option("--limit", "limit_items", multiple=True, metavar="KEY=VALUE",
              help="A limit of the description's [limits]: the task's and actuated joints' speeds and accelerations "
                   "(max_task_speed_m_s, max_joint_acceleration_rad_s2, ...) bound the timing.")
@click.option("--cycle-time", "cycle_time", type=click.FloatRange(0.0, min_open=True), default=None, metavar="SECONDS",
              help="Find the least-energy timing within this cycle time [s] instead of the fastest: the motors' copper "
                   "losses and the friction's dissipation (docs/retime.md).")
@click.option("--pareto", type=click.IntRange(2, 200), default=None, metavar="COUNT",
              help="Also the Pareto curve of cycle time against energy: the least energy for COUNT cycle times from the "
                   "fastest to --pareto-span times it (pareto.csv, pareto.png).")
@click.option("--pareto-span", type=click.FloatRange(1.0, 100.0, min_open=True), default=3.0, show_default=True,
              help="The Pareto curve's longest cycle time over the fastest.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), required=True,
              help="Output folder (an earlier run of this command there is replaced whole).")
def retime_command(machine: str, path_file: Path | None, points: int, efforts: tuple[str, ...],
                   reaction_forces: tuple[str, ...], reaction_moments: tuple[str, ...], no_friction: bool,
                   no_plots: bool, limit_items: tuple[str, ...], cycle_time: float | None, pareto: int | None,
                   pareto_span: float, out_dir: Path) -> None:
    """The time-optimal timing of a geometric path of the task coordinates: rest at both ends, every
    effort, speed, acceleration and reaction bound met at every grid point, the friction computed as
    in pkmdyn run; or, with --cycle-time, the least-energy timing within a cycle time, and with --pareto
    the curve of cycle time against energy. Writes timed_motion.csv (a motion file for run, control, stiffness and wear),
    retime.json, retime.csv, plots and report.html."""
    show(job.job(machine, out_dir, path_file=path_file, points=points, efforts=efforts,
                 reaction_forces=reaction_forces, reaction_moments=reaction_moments, friction=not no_friction,
                 plots=not no_plots, limit_items=limit_items, cycle_time=cycle_time, pareto=pareto or 0,
                 pareto_span=pareto_span, announce=list_files))
