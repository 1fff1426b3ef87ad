"""Hip simulator commands: ``pkmdyn hip run`` and ``pkmdyn hip profile``.

Every option is checked here (finite, in range) before any file is read or written; sizes are
checked against the sample limit before anything is allocated.
"""

from __future__ import annotations

from pathlib import Path

import click

from ._groups import PATH_IN as _PATH_IN
from ._groups import FiniteFloat, echo, hip, list_files, params_command
from ._hip_options import paper_option

_LIMIT_HELP = ("Raise or lower a plausibility limit, KEY=VALUE (repeatable; overrides [limits] of the parameter "
               "file). Keys: max_samples, max_load_N, max_abs_angle_deg, max_slider_speed_m_s, "
               "max_slider_acceleration_m_s2, max_duration_s.")


@hip.command("run")
@paper_option
@click.option("--params", "params_path", type=_PATH_IN, help="Parameter file (TOML); default: the paper's Tables 1-2.")
@click.option("--motion", "motion_path", type=_PATH_IN, help="Motion file (CSV); default: the built-in ISO 14242-1 cycle.")
@click.option("--cycles", type=FiniteFloat(0.0, 1e12, lo_open=True), default=1.0, show_default=True,
              help="Cycles of the built-in motion (finite, > 0; with --samples-per-cycle at least 2 samples).")
@click.option("--samples-per-cycle", type=click.IntRange(min=2), default=1000, show_default=True,
              help="Samples per cycle of the built-in motion.")
@click.option("--motion-model", type=click.Choice(["default", "paper-fit", "paper-fit-zxy"]), default=None,
              help="Cycle model of the built-in motion (default: the parameter file's [motion] iso_cycle, else "
                   "default): default (documented choices), paper-fit (phases fitted to the "
                   "hip paper's slider maxima), paper-fit-zxy (the same for euler_sequence = \"ZXY\"); see "
                   "docs/identification.md.")
@click.option("--singularity-threshold", type=FiniteFloat(0.0, 1.0), default=1e-3, show_default=True,
              help="Warn where 1/cond(J) falls below this (0 to 1).")
@click.option("--format", "fmt", type=click.Choice(["csv", "parquet"]), default="csv", show_default=True,
              help="Results table format: csv (text, any tool) or parquet (binary, compact, fast; needs pyarrow).")
@click.option("--limit", "limits", multiple=True, metavar="KEY=VALUE", help=_LIMIT_HELP)
@click.option("--no-plots", is_flag=True, help="Write no PNG plots.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), required=True,
              help="Output folder; an earlier run there is replaced whole, nothing else is (docs/file_formats.md, "
                   "\"The output rule\").")
def hip_run(params_path, motion_path, cycles, samples_per_cycle, motion_model, singularity_threshold, fmt, limits,
            no_plots, out_dir) -> None:
    """Kinematics and driving torques along a motion; writes results.csv (or .parquet), summary.json, plots."""
    from ..machines.hip_simulator.job import run_hip

    if motion_path is not None and (cycles != 1.0 or samples_per_cycle != 1000 or motion_model is not None):
        raise click.UsageError(
            "--cycles, --samples-per-cycle and --motion-model apply to the built-in motion, not to --motion")
    files, messages = run_hip(out_dir, params_path, motion_path, cycles, samples_per_cycle,
                              make_plots=not no_plots, progress=True, singularity_threshold=singularity_threshold,
                              fmt=fmt, limits=tuple(limits), motion_model=motion_model, report=list_files)
    for m in messages:
        click.echo(f"pkmdyn: warning: {m}", err=True)


params_command(hip, "hip", "pkmdyn hip")


@hip.command("profile")
@click.option("--cycles", type=FiniteFloat(0.0, 1e12, lo_open=True), default=1.0, show_default=True,
              help="Cycles of the ISO 14242-1 model to write (finite, > 0).")
@click.option("--samples-per-cycle", type=click.IntRange(min=2), default=1000, show_default=True,
              help="Samples per cycle (>= 2); the file has cycles x samples-per-cycle + 1 rows.")
@click.option("--limit", "limits", multiple=True, metavar="max_samples=N",
              help="Raise the sample limit (default 20,000,000 rows).")
@click.option("--out", "out_path", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="Motion CSV to write (atomically; a missing parent folder is created).")
def hip_profile(cycles, samples_per_cycle, limits, out_path) -> None:
    """Write the built-in ISO 14242-1 motion and load model as a motion CSV (all derivative columns)."""
    from ..io import DEFAULT_MAX_SAMPLES, atomic_file
    from ..params_util import parse_limit_options
    from ..profiles.iso14242 import iso14242_motion
    from ..profiles.orientation import write_motion_csv

    max_samples = parse_limit_options(limits, {"max_samples": int}).get("max_samples", DEFAULT_MAX_SAMPLES)
    motion = iso14242_motion(cycles, samples_per_cycle, max_samples=max_samples)
    with atomic_file(out_path) as tmp:
        write_motion_csv(tmp, motion)
        echo(f"motion: {out_path}")
