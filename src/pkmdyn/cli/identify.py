"""Identification commands: ``pkmdyn hip identify`` and ``pkmdyn hip excite``."""

from __future__ import annotations

from pathlib import Path

import click

from ._groups import PATH_IN as _PATH_IN
from ._groups import hip


@hip.command("identify")
@click.option("--measured", "measured_path", type=_PATH_IN, required=True,
              help="Measured run (CSV): motion columns plus tau1_Nm, tau2_Nm, tau3_Nm.")
@click.option("--params", "params_path", type=_PATH_IN,
              help="Parameter file (TOML) holding everything not identified; default: the paper's Tables 1-2.")
@click.option("--identify", "which", type=click.Choice(["friction", "inertia", "all"]), default="friction",
              show_default=True, help="Which parameters to identify.")
@click.option("--sg-window", type=int, default=15, show_default=True,
              help="Savitzky-Golay window [samples, odd] for derivatives not given in the file.")
@click.option("--sg-order", type=int, default=5, show_default=True, help="Savitzky-Golay polynomial degree.")
@click.option("--rank-tol", type=click.FloatRange(min=0, min_open=True, max=1), default=1e-6, show_default=True,
              help="Singular values of the column-scaled regressor below this fraction of the largest count as zero.")
@click.option("--no-plots", is_flag=True, help="Write no PNG plots.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), required=True,
              help="Output directory.")
def hip_identify(measured_path, params_path, which, sg_window, sg_order, rank_tol, no_plots, out_dir) -> None:
    """Identify friction and/or inertia from measured motor torques; writes identified.toml,
    identification.json, torques.csv and plots."""
    from ..identify.hip_run import run_identify

    files, lines = run_identify(out_dir, measured_path, params_path, which, sg_window, sg_order, rank_tol,
                                make_plots=not no_plots)
    for line in lines:
        click.echo(line)
    for name, path in files.items():
        click.echo(f"{name}: {path}")


@hip.command("excite")
@click.option("--params", "params_path", type=_PATH_IN, help="Parameter file (TOML); default: the paper's Tables 1-2.")
@click.option("--identify", "which", type=click.Choice(["friction", "inertia", "all"]), default="all",
              show_default=True, help="Parameters the motion is designed to identify.")
@click.option("--period-s", type=click.FloatRange(min=0, min_open=True), default=2.0, show_default=True,
              help="Shortest period of the motion [s]; stretched where the slider limits need it.")
@click.option("--harmonics", type=click.IntRange(min=1, max=10), default=3, show_default=True)
@click.option("--cycles", type=click.IntRange(min=1, max=10000), default=2, show_default=True, help="Periods written.")
@click.option("--samples-per-cycle", type=click.IntRange(min=16, max=1000000), default=500, show_default=True)
@click.option("--iterations", type=click.IntRange(min=0, max=1000), default=15, show_default=True,
              help="L-BFGS-B iterations per start.")
@click.option("--starts", type=click.IntRange(min=1, max=20), default=1, show_default=True)
@click.option("--design-samples", type=click.IntRange(min=16, max=5000), default=120, show_default=True,
              help="Samples per period used while optimising.")
@click.option("--seed", type=int, default=0, show_default=True)
@click.option("--alpha-range-deg", type=(float, float), default=(-18.0, 25.0), show_default=True)
@click.option("--beta-range-deg", type=(float, float), default=(-4.0, 7.0), show_default=True)
@click.option("--gamma-range-deg", type=(float, float), default=(-10.0, 2.0), show_default=True)
@click.option("--load-range-N", "load_range", type=(float, float), default=(300.0, 3000.0), show_default=True)
@click.option("--max-slider-speed-m-s", type=float, default=0.3, show_default=True)
@click.option("--max-slider-accel-m-s2", type=float, default=3.0, show_default=True)
@click.option("--max-cond-j", type=float, default=10.0, show_default=True)
@click.option("--out", "out_path", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="Motion CSV to write (motion columns and load_N; no torques).")
def hip_excite(params_path, which, period_s, harmonics, cycles, samples_per_cycle, iterations, starts, design_samples, seed,
               alpha_range_deg, beta_range_deg, gamma_range_deg, load_range, max_slider_speed_m_s,
               max_slider_accel_m_s2, max_cond_j, out_path) -> None:
    """Design an excitation motion and load (optimised Fourier series) for identification."""
    from ..identify.hip_excite import ExcitationLimits
    from ..identify.hip_run import run_excite

    limits = ExcitationLimits(alpha_range_deg, beta_range_deg, gamma_range_deg, load_range, max_slider_speed_m_s,
                              max_slider_accel_m_s2, max_cond_j)
    lines = run_excite(out_path, params_path, which, limits, period_s, harmonics, cycles, samples_per_cycle,
                       iterations, starts, seed, design_samples)
    for line in lines:
        click.echo(line)
    click.echo(f"motion: {out_path}")
