"""PDM commands: ``pkmdyn pdm run``."""

from __future__ import annotations

from pathlib import Path

import click

from ._groups import pdm


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
    from ..machines.pdm4.run import run_pdm

    summary = run_pdm(params_path, motion_path, out_dir, plots=not no_plots)
    for label, path in summary["files"].items():
        click.echo(f"{label}: {path}")


