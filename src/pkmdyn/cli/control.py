"""``pkmdyn control`` (every machine) and ``pkmdyn pdm control``, and the options a generated
machine's own ``control`` command shares; the work is :mod:`pkmdyn.jobs.control` (light to
import: the loop, the controllers and the engine load when a run starts)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from ..jobs import control as control_job
from ..jobs.control import (
    DESCRIBED_CONTROLLERS,
    MAX_CONTROL_CYCLES,
    MAX_CYCLES,
    machine_controllers,
)
from ..machines.pdm4 import control_job as _pdm_job
from ..machines.registry import resolve
from ._groups import MACHINE_HELP, PATH_IN, FiniteFloat, cli, list_files, pdm, show


def control_command(machine: str, controller: str, params_path: Path | None, plant_path: Path | None,
                    motion_path: Path | None, cycles: float, gains_path: Path | None, no_plots: bool, out_dir: Path,
                    fmt: str = "csv") -> None:
    """A generated machine's ``control`` command (``pkmdyn control``, ``pkmdyn pdm control``, a
    machine folder's own): one call of :func:`pkmdyn.jobs.control.job`, its result printed."""
    show(control_job.job(machine, controller, out_dir, params_path=params_path, plant_path=plant_path,
                         motion_path=motion_path, cycles=cycles, gains_path=gains_path, no_plots=no_plots, fmt=fmt,
                         announce=list_files))


def control_options(f: Any) -> Any:
    """The options of a machine's own ``control`` command (its ``--controller`` apart)."""
    for opt in reversed((
        click.option("--params", "params_path", type=PATH_IN, help="Controller model's parameter file (TOML); default: built-in."),
        click.option("--plant-params", "plant_path", type=PATH_IN,
                     help="Plant's parameter file (TOML); default: the controller's with the [mismatch] factors."),
        click.option("--motion", "motion_path", type=PATH_IN, help="Motion file (CSV); default: the built-in motion."),
        click.option("--cycles", type=FiniteFloat(0.0, MAX_CYCLES, lo_open=True), default=1.0, show_default=True,
                     help=f"Cycles of the built-in motion (> 0, at most {MAX_CYCLES:g}; a run holds at most "
                          f"{MAX_CONTROL_CYCLES:,} control cycles)."),
        click.option("--gains", "gains_path", type=PATH_IN, help="Control settings (TOML), laid over the built-in ones."),
        click.option("--format", "fmt", type=click.Choice(["csv", "parquet"]), default="csv", show_default=True,
                     help="Table format of the per-cycle results: csv (text, any tool) or parquet (binary, compact; "
                          "needs pyarrow)."),
        click.option("--no-plots", is_flag=True, help="Write no PNG plots."),
        click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), required=True,
                     help="Output directory; an earlier run of this command there is replaced whole, nothing else is."),
    )):
        f = opt(f)
    return f


@pdm.command("control")
@click.option("--controller", required=True, help="One of: " + ", ".join(_pdm_job.CONTROLLERS) + ".")
@control_options
def pdm_control(controller, params_path, plant_path, motion_path, cycles, gains_path, fmt, no_plots, out_dir) -> None:
    """Closed-loop tracking of a motion; writes control.csv (or .parquet), summary.json and plots."""
    control_command(_pdm_job.NAME, controller, params_path, plant_path, motion_path, cycles, gains_path, no_plots,
                    out_dir, fmt)


@cli.command("control")
@click.option("--machine", required=True, help=MACHINE_HELP)
@click.option("--controller", default=None,
              help="; ".join(f"{n}: {', '.join(c)}" for n, c in machine_controllers().items()) + "; a described "
                   "mechanism: " + ", ".join(DESCRIBED_CONTROLLERS) + " (default computed-torque).")
@click.option("--params", "params_path", type=PATH_IN, help="Generated machines: the controller model's parameter file.")
@click.option("--plant-params", "plant_path", type=PATH_IN, help="Generated machines: the plant's parameter file.")
@click.option("--motion", "motion_path", type=PATH_IN,
              help="A motion file (CSV): the machine's own format; a described mechanism's task motion "
                   "(docs/mechanism_format.md), its named load's column driving the load. Default: the built-in "
                   "motion.")
@click.option("--cycles", type=FiniteFloat(0.0, MAX_CYCLES, lo_open=True), default=None,
              help="Generated machines: cycles of the built-in motion (default 1).")
@click.option("--gains", "gains_path", type=PATH_IN,
              help="Control settings (TOML) laid over the machine's defaults (docs/control.md; a described "
                   "mechanism's defaults are tuned from its inertia, docs/multibody_dynamics.md).")
@click.option("--format", "fmt", type=click.Choice(["csv", "parquet"]), default="csv", show_default=True,
              help="Table format of the per-cycle results.")
@click.option("--no-plots", is_flag=True, help="Write no PNG plots.")
@click.option("--duration", "duration_s", type=FiniteFloat(0.0, 1e6, lo_open=True), default=None,
              help="Described mechanisms: seconds of the motion to track (default 1 s or the motion's length).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), required=True,
              help="Output folder; an earlier run of this command there is replaced whole, any other non-empty folder is refused.")
def control(machine: str, controller: str | None, params_path: Path | None, plant_path: Path | None,
            motion_path: Path | None, cycles: float | None, gains_path: Path | None, fmt: str, no_plots: bool,
            duration_s: float | None, out_dir: Path) -> None:
    """Closed-loop tracking for any machine: control.csv (or .parquet), summary.json.

    A generated machine runs its own control job (the same as its pkmdyn <machine> control,
    with every option of that); a described mechanism tracks its default motion in
    task space on its own dynamics (pkmdyn.multibody.dynamics.verbs), the controller the same model."""
    entry, _ = resolve(machine)
    if entry is not None:
        if controller is None:
            raise click.UsageError(f"--controller is required for --machine {machine}")
        if duration_s is not None:
            raise click.UsageError("--duration applies to a described mechanism; a generated machine takes --cycles")
        control_command(entry.NAME, controller, params_path, plant_path, motion_path, 1.0 if cycles is None else cycles,
                        gains_path, no_plots, out_dir, fmt)
        return
    given = [o for o, v in (("--params", params_path), ("--plant-params", plant_path), ("--cycles", cycles))
             if v is not None]
    if given:
        raise click.UsageError(f"{given[0]} applies to the generated machines (see pkmdyn machines), not to a described mechanism")
    controller = controller or "computed-torque"  # (the job checks it against DESCRIBED_CONTROLLERS)
    show(control_job.described_job(machine, controller, out_dir, motion_path=motion_path, gains_path=gains_path,
                                   duration_s=duration_s, no_plots=no_plots, fmt=fmt, announce=list_files))
