"""PDM commands: ``pkmdyn pdm run``."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

from .._lazy import lazy_module
from ._groups import PATH_IN, list_files, params_command, pdm, show

if TYPE_CHECKING:
    from ..machines.pdm4 import run as _run
else:  # loaded when a command runs, not on import (nor for --help)
    _run = lazy_module("pkmdyn.machines.pdm4.run")


@pdm.command("run")
@click.option("--params", "params_path", type=PATH_IN, default=None,
              help="Parameter TOML file (default: the built-in PDM parameters).")
@click.option("--motion", "motion_path", type=PATH_IN, default=None,
              help="Motion CSV: t_s, x_m, y_m, alpha_rad, gamma_rad [+ derivative columns] "
                   "(default: the cycloidal motion of Eq. 84 from the parameter file).")
@click.option("--stroke-x-m", type=float, default=None, help="Eq. 84 amplitude S_x [m] (overrides [trajectory]).")
@click.option("--stroke-y-m", type=float, default=None, help="Eq. 84 amplitude S_y [m].")
@click.option("--stroke-alpha-deg", type=float, default=None, help="Eq. 84 amplitude S_alpha [deg].")
@click.option("--stroke-gamma-deg", type=float, default=None, help="Eq. 84 amplitude S_gamma [deg].")
@click.option("--period-s", type=float, default=None, help="Eq. 84 period T [s].")
@click.option("--peak-y-accel", "peak_y_accel", type=float, default=None,
              help="Set the period so that the y acceleration peaks at this value [m/s^2] "
                   "(T = sqrt(2 pi |S_y| / a); e.g. 0.05, 0.5, 1.0 for the paper's Fig. 23).")
@click.option("--limit", "limits", multiple=True, metavar="KEY=VALUE",
              help="Raise or lower a plausibility limit, KEY=VALUE (repeatable; overrides [limits] of the parameter "
                   "file). Keys: max_samples, max_limb_speed_m_s, max_limb_acceleration_m_s2, max_actuator_force_N, "
                   "max_duration_s.")
@click.option("--no-plots", is_flag=True, help="Skip the PNG plots and the schematic.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), required=True,
              help="Output folder (created if missing; an earlier run of this command there is replaced whole).")
def pdm_run(params_path: Path | None, motion_path: Path | None, stroke_x_m: float | None,
            stroke_y_m: float | None, stroke_alpha_deg: float | None, stroke_gamma_deg: float | None,
            period_s: float | None, peak_y_accel: float | None, limits: tuple[str, ...], no_plots: bool,
            out_dir: Path) -> None:
    """Kinematics, Newton-Euler dynamics and unique joint reactions, mobility, workspace and plots of the PDM."""
    trajectory = {"stroke_x_m": stroke_x_m, "stroke_y_m": stroke_y_m, "stroke_alpha_deg": stroke_alpha_deg,
                  "stroke_gamma_deg": stroke_gamma_deg, "period_s": period_s, "peak_y_accel_m_s2": peak_y_accel}
    show(_run.run_pdm(params_path, motion_path, out_dir, plots=not no_plots, trajectory=trajectory, report=list_files,
                      limits=tuple(limits)))


params_command(pdm, "pdm", "pkmdyn pdm")
