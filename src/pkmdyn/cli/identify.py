"""Identification commands: ``pkmdyn hip identify`` and ``pkmdyn hip excite`` (the options; the
jobs are the machine's, :mod:`pkmdyn.machines.hip_simulator.identify_job`)."""

from __future__ import annotations

from pathlib import Path

import click

from ..machines.hip_simulator import identify_bounds as _ex
from ..machines.hip_simulator.identify_bounds import MAX_EXCITE_ROWS, MAX_SG_ORDER, MAX_SG_WINDOW
from ._groups import PATH_IN as _PATH_IN
from ._groups import echo_lines, hip
from ._groups import FiniteFloat
from ._hip_options import paper_option


@hip.command("identify")
@paper_option
@click.option("--measured", "measured_path", type=_PATH_IN, required=True,
              help="Measured run (CSV): motion columns plus tau1_Nm, tau2_Nm, tau3_Nm.")
@click.option("--params", "params_path", type=_PATH_IN,
              help="Parameter file (TOML) holding everything not identified; default: the paper's Tables 1-2.")
@click.option("--identify", "which", type=click.Choice(["friction", "inertia", "all"]), default="friction",
              show_default=True, help="Which parameters to identify.")
@click.option("--sg-window", type=click.IntRange(min=3, max=MAX_SG_WINDOW), default=15, show_default=True,
              help=f"Savitzky-Golay window [samples, odd, 3 to {MAX_SG_WINDOW}] for derivatives not given in the file.")
@click.option("--sg-order", type=click.IntRange(min=2, max=MAX_SG_ORDER), default=5, show_default=True,
              help=f"Savitzky-Golay polynomial degree (2 to {MAX_SG_ORDER}, below the window).")
@click.option("--rank-tol", type=FiniteFloat(0.0, 1.0, lo_open=True), default=1e-6, show_default=True,
              help="Singular values of the column-scaled regressor below this fraction of the largest count as zero "
                   "(0 < rank-tol < 1).")
@click.option("--no-plots", is_flag=True, help="Write no PNG plots.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), required=True,
              help="Output directory; an earlier run there is replaced whole, nothing else is.")
def hip_identify(measured_path, params_path, which, sg_window, sg_order, rank_tol, no_plots, out_dir) -> None:
    """Identify friction and/or inertia from measured motor torques; writes identified.toml,
    identification.json, torques.csv and plots."""
    from ..machines.hip_simulator.identify_job import run_identify

    run_identify(out_dir, measured_path, params_path, which, sg_window, sg_order, rank_tol, make_plots=not no_plots,
                 report=echo_lines)


_ANGLE = FiniteFloat(-180.0, 180.0)
_LOAD = FiniteFloat(0.0, _ex.MAX_LOAD_N)


@hip.command("excite")
@paper_option
@click.option("--params", "params_path", type=_PATH_IN, help="Parameter file (TOML); default: the paper's Tables 1-2.")
@click.option("--identify", "which", type=click.Choice(["friction", "inertia", "all"]), default="all",
              show_default=True, help="Parameters the motion is designed to identify.")
@click.option("--period-s", type=FiniteFloat(_ex.MIN_PERIOD_S, _ex.MAX_PERIOD_S), default=2.0, show_default=True,
              help=f"Shortest period of the motion [s], {_ex.MIN_PERIOD_S:g} to {_ex.MAX_PERIOD_S:g}; stretched "
                   "where the slider limits need it.")
@click.option("--harmonics", type=click.IntRange(min=1, max=_ex.MAX_HARMONICS), default=3, show_default=True,
              help=f"Harmonics of each Fourier series (1 to {_ex.MAX_HARMONICS}).")
@click.option("--cycles", type=click.IntRange(min=1, max=10000), default=2, show_default=True,
              help="Periods written (1 to 10000).")
@click.option("--samples-per-cycle", type=click.IntRange(min=16, max=1000000), default=500, show_default=True,
              help=f"Samples per period written (16 to 1000000; the file at most {MAX_EXCITE_ROWS:,} rows).")
@click.option("--iterations", type=click.IntRange(min=0, max=_ex.MAX_ITERATIONS), default=15, show_default=True,
              help=f"L-BFGS-B iterations per start (0 to {_ex.MAX_ITERATIONS}).")
@click.option("--starts", type=click.IntRange(min=1, max=_ex.MAX_STARTS), default=1, show_default=True,
              help=f"Random starts refined by the optimiser (1 to {_ex.MAX_STARTS}).")
@click.option("--design-samples", type=click.IntRange(min=16, max=_ex.MAX_DESIGN_SAMPLES), default=120,
              show_default=True,
              help=f"Samples per period used while optimising (16 to {_ex.MAX_DESIGN_SAMPLES}, >= 8 per harmonic). "
                   "The design's effort, (4 starts + 2 starts iterations (8 harmonics + 5) + 51) cost evaluations "
                   f"x design samples, is at most {_ex.MAX_WORK:,}; a progress bar shows it on a terminal.")
@click.option("--seed", type=click.IntRange(min=0, max=2**63 - 1), default=0, show_default=True,
              help="Seed of the random starts (>= 0).")
@click.option("--alpha-range-deg", type=(_ANGLE, _ANGLE), default=(-18.0, 25.0), show_default=True,
              help="FE angle range MIN MAX [deg], within -180..180.")
@click.option("--beta-range-deg", type=(_ANGLE, _ANGLE), default=(-4.0, 7.0), show_default=True,
              help="AA angle range MIN MAX [deg], within -180..180.")
@click.option("--gamma-range-deg", type=(_ANGLE, _ANGLE), default=(-10.0, 2.0), show_default=True,
              help="IER angle range MIN MAX [deg], within -180..180.")
@click.option("--load-range-N", "load_range", type=(_LOAD, _LOAD), default=(300.0, 3000.0), show_default=True,
              help=f"Load range MIN MAX [N], within 0..{_ex.MAX_LOAD_N:g}.")
@click.option("--max-slider-speed-m-s", type=FiniteFloat(0.0, _ex.MAX_SLIDER_SPEED_M_S, lo_open=True), default=0.3,
              show_default=True, help=f"Slider speed limit [m/s] (> 0, at most {_ex.MAX_SLIDER_SPEED_M_S:g}).")
@click.option("--max-slider-accel-m-s2", type=FiniteFloat(0.0, _ex.MAX_SLIDER_ACCEL_M_S2, lo_open=True), default=3.0,
              show_default=True, help=f"Slider acceleration limit [m/s^2] (> 0, at most {_ex.MAX_SLIDER_ACCEL_M_S2:g}).")
@click.option("--max-cond-j", type=FiniteFloat(1.0, _ex.MAX_COND_J), default=10.0, show_default=True,
              help=f"Limit of the Jacobian's condition number (1 to {_ex.MAX_COND_J:g}).")
@click.option("--out", "out_path", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="Motion CSV to write (motion columns and load_N; no torques).")
def hip_excite(params_path, which, period_s, harmonics, cycles, samples_per_cycle, iterations, starts, design_samples, seed,
               alpha_range_deg, beta_range_deg, gamma_range_deg, load_range, max_slider_speed_m_s,
               max_slider_accel_m_s2, max_cond_j, out_path) -> None:
    """Design an excitation motion and load (optimised Fourier series) for identification."""
    from ..machines.hip_simulator.identify_excite import ExcitationLimits
    from ..machines.hip_simulator.identify_job import run_excite

    limits = ExcitationLimits(alpha_range_deg, beta_range_deg, gamma_range_deg, load_range, max_slider_speed_m_s,
                              max_slider_accel_m_s2, max_cond_j)
    run_excite(out_path, params_path, which, limits, period_s, harmonics, cycles, samples_per_cycle,
               iterations, starts, seed, design_samples, progress=True, report=echo_lines)
