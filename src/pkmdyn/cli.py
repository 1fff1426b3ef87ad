"""Command line: argument parsing -> library calls -> files. Nothing else lives here.

Every user error (bad file, unreachable pose, bad option) ends as one line on stderr and
exit status 2, with no traceback.
"""

from __future__ import annotations

import sys
from pathlib import Path

import click

from .errors import PkmdynError

__all__ = ["main", "cli"]


@click.group()
@click.version_option(package_name="pkmdyn")
def cli() -> None:
    """pkmdyn: kinematics and dynamics of parallel manipulators."""


# --------------------------------------------------------------------------- hip simulator
@cli.group()
def hip() -> None:
    """The 2(3PUS+S) dual-platform hip-joint wear simulator."""


_PATH_IN = click.Path(dir_okay=False, path_type=Path)


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
    from .machines.hip_simulator.run import run_hip

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
    from .profiles.iso14242 import iso14242_motion
    from .profiles.orientation import write_motion_csv

    write_motion_csv(out_path, iso14242_motion(cycles, samples_per_cycle))
    click.echo(f"motion: {out_path}")


# --------------------------------------------------------------------------- PDM (4-DOF)
@cli.group()
def pdm() -> None:
    """The 4-DOF over-constrained parallel driving mechanism."""


@pdm.command("run")
@click.option("--params", "params_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Parameter TOML file (default: the built-in PDM parameters).")
@click.option("--motion", "motion_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Motion CSV: t_s, x_m, y_m, alpha_rad, gamma_rad [+ derivative columns] "
                   "(default: the cycloidal motion of Eq. 84 from the parameter file).")
@click.option("--no-plots", is_flag=True, help="Skip the PNG plots and the schematic.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), required=True,
              help="Output folder (created if missing).")
def pdm_run(params_path: Path | None, motion_path: Path | None, no_plots: bool, out_dir: Path) -> None:
    """Kinematics of every body, mobility, workspace and plots of the PDM."""
    from .machines.pdm4.run import run_pdm

    summary = run_pdm(params_path, motion_path, out_dir, plots=not no_plots)
    for label, path in summary["files"].items():
        click.echo(f"{label}: {path}")


# ----------------------------------------------------------------------------- entry point
def main(argv: list[str] | None = None) -> int:
    """Run the command line; return the exit status (0 ok, 2 user error)."""
    try:
        cli.main(args=argv, prog_name="pkmdyn", standalone_mode=False)
    except click.exceptions.Exit as exc:
        return int(exc.exit_code)
    except click.exceptions.Abort:
        click.echo("pkmdyn: aborted", err=True)
        return 2
    except click.ClickException as exc:
        message = " ".join(exc.format_message().split())
        click.echo(f"pkmdyn: error: {message}", err=True)
        return 2
    except PkmdynError as exc:
        message = " ".join(str(exc).split())
        click.echo(f"pkmdyn: error: {message}", err=True)
        return 2
    return 0



def run() -> None:
    """Console-script entry point."""
    sys.exit(main())


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
