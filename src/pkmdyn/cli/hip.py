"""Hip simulator commands: ``pkmdyn hip run`` and ``pkmdyn hip profile``."""

from __future__ import annotations

from pathlib import Path

import click

from ._groups import PATH_IN as _PATH_IN
from ._groups import hip


@hip.command("run")
@click.option("--params", "params_path", type=_PATH_IN, help="Parameter file (TOML); default: the paper's Tables 1-2.")
@click.option("--motion", "motion_path", type=_PATH_IN, help="Motion file (CSV); default: the built-in ISO 14242-1 cycle.")
@click.option("--cycles", type=click.FloatRange(min=0, min_open=True), default=1.0, show_default=True,
              help="Cycles of the built-in motion.")
@click.option("--samples-per-cycle", type=click.IntRange(min=2), default=1000, show_default=True,
              help="Samples per cycle of the built-in motion.")
@click.option("--singularity-threshold", type=click.FloatRange(min=0), default=1e-3, show_default=True,
              help="Warn where 1/cond(J) falls below this.")
@click.option("--no-plots", is_flag=True, help="Write no PNG plots.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), required=True,
              help="Output directory.")
def hip_run(params_path, motion_path, cycles, samples_per_cycle, singularity_threshold, no_plots, out_dir) -> None:
    """Kinematics and driving torques along a motion; writes results.csv, summary.json, plots."""
    from ..machines.hip_simulator.run import run_hip

    if motion_path is not None and (cycles != 1.0 or samples_per_cycle != 1000):
        raise click.UsageError("--cycles and --samples-per-cycle apply to the built-in motion, not to --motion")
    files, messages = run_hip(out_dir, params_path, motion_path, cycles, samples_per_cycle,
                              make_plots=not no_plots, progress=True, singularity_threshold=singularity_threshold)
    for m in messages:
        click.echo(f"pkmdyn: warning: {m}", err=True)
    for name, path in files.items():
        click.echo(f"{name}: {path}")


@hip.command("profile")
@click.option("--cycles", type=click.FloatRange(min=0, min_open=True), default=1.0, show_default=True)
@click.option("--samples-per-cycle", type=click.IntRange(min=2), default=1000, show_default=True)
@click.option("--out", "out_path", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="Motion CSV to write.")
def hip_profile(cycles, samples_per_cycle, out_path) -> None:
    """Write the built-in ISO 14242-1 motion and load model as a motion CSV."""
    from ..profiles.iso14242 import iso14242_motion
    from ..profiles.orientation import write_motion_csv

    write_motion_csv(out_path, iso14242_motion(cycles, samples_per_cycle))
    click.echo(f"motion: {out_path}")


