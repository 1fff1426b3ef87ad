"""The hip simulator's commands, ``pkmdyn hip ...`` (mounted by the command line through the
machine registry, :func:`pkmdyn.machines.registry.command_groups`): each parses its options
and calls one job of the machine (``run``: :mod:`.job`; ``control``: the control job of
:mod:`pkmdyn.jobs.control` with :mod:`.control_job`; ``identify``, ``excite``:
:mod:`.identify_job`; ``export``: the engine's MJCF writer of the hip's description;
``profile``: the ISO 14242-1 motion file; ``params``: the built-in parameter file).

Every option is checked here (finite, in range) before any file is read or written; sizes are
checked against the sample limit before anything is allocated.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from ..._lazy import lazy_module
from ...cli._groups import (
    PATH_IN,
    FiniteFloat,
    echo_lines,
    list_files,
    params_command,
    show,
)
from ...cli.control import control_command, control_options
from ...io import DEFAULT_MAX_SAMPLES
from . import identify_bounds as _ex
from .control_job import CONTROLLERS
from .identify_bounds import MAX_EXCITE_ROWS, MAX_SG_ORDER, MAX_SG_WINDOW

if TYPE_CHECKING:
    from ... import params_util as _params_util
    from . import identify_excite as _identify_excite
    from . import identify_job as _identify_job
    from . import job as _job
    from . import params as _params
else:  # loaded when a command runs, not on import (nor for --help)
    _identify_excite = lazy_module("pkmdyn.machines.hip_simulator.identify_excite")
    _identify_job = lazy_module("pkmdyn.machines.hip_simulator.identify_job")
    _job = lazy_module("pkmdyn.machines.hip_simulator.job")
    _params = lazy_module("pkmdyn.machines.hip_simulator.params")
    _params_util = lazy_module("pkmdyn.params_util")

__all__ = ["group"]


@click.group("hip")
def group() -> None:
    """The 2(3PUS+S) dual-platform hip-joint wear simulator."""


def paper_option(f: Callable[..., Any]) -> Callable[..., Any]:
    """Add ``--paper`` to a hip command that has ``--params`` (keyword ``params_path``)."""

    @click.option("--paper", is_flag=True,
                  help="Use the paper's own convention (FE about the base Z axis, the paper-fit-zxy ISO cycle): the "
                       "built-in paper.toml in place of --params; docs/hip_simulator.md.")
    @functools.wraps(f)
    def wrapped(*args: Any, paper: bool, **kwargs: Any) -> Any:
        if paper:
            if kwargs.get("params_path") is not None:
                raise click.UsageError("--paper and --params exclude each other: --paper is a built-in parameter file")
            kwargs["params_path"] = _params.paper_params_path()
        return f(*args, **kwargs)

    return wrapped

_LIMIT_HELP = ("Raise or lower a plausibility limit, KEY=VALUE (repeatable; overrides [limits] of the parameter "
               "file). Keys: max_samples, max_load_N, max_abs_angle_deg, max_slider_speed_m_s, "
               "max_slider_acceleration_m_s2, max_duration_s.")


@group.command("run")
@paper_option
@click.option("--params", "params_path", type=PATH_IN, help="Parameter file (TOML); default: the paper's Tables 1-2.")
@click.option("--motion", "motion_path", type=PATH_IN, help="Motion file (CSV); default: the built-in ISO 14242-1 cycle.")
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
              help="Output folder; an earlier run of this command there is replaced whole, nothing else is (docs/file_formats.md, "
                   "\"The output rule\").")
def hip_run(params_path, motion_path, cycles, samples_per_cycle, motion_model, singularity_threshold, fmt, limits,
            no_plots, out_dir) -> None:
    """Kinematics and driving torques along a motion; writes results.csv (or .parquet), summary.json, plots."""
    if motion_path is not None and (cycles != 1.0 or samples_per_cycle != 1000 or motion_model is not None):
        raise click.UsageError(
            "--cycles, --samples-per-cycle and --motion-model apply to the built-in motion, not to --motion")
    show(_job.run_hip(out_dir, params_path, motion_path, cycles, samples_per_cycle, make_plots=not no_plots,
                      progress=True, singularity_threshold=singularity_threshold, fmt=fmt, limits=tuple(limits),
                      motion_model=motion_model, report=list_files))


params_command(group, "hip", "pkmdyn hip")


@group.command("profile")
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
    max_samples = _params_util.parse_limit_options(limits, {"max_samples": int}).get("max_samples", DEFAULT_MAX_SAMPLES)
    show(_job.profile_job(out_path, cycles, samples_per_cycle, max_samples, announce=list_files))

@group.command("control")
@paper_option
@click.option("--controller", required=True, help="One of: " + ", ".join(CONTROLLERS) + ".")
@control_options
def hip_control(controller, params_path, plant_path, motion_path, cycles, gains_path, fmt, no_plots, out_dir) -> None:
    """Closed-loop tracking of a motion; writes control.csv (or .parquet), summary.json and plots."""
    control_command("hip", controller, params_path, plant_path, motion_path, cycles, gains_path, no_plots, out_dir,
             fmt)

@group.command("identify")
@paper_option
@click.option("--measured", "measured_path", type=PATH_IN, required=True,
              help="Measured run (CSV): motion columns plus tau1_Nm, tau2_Nm, tau3_Nm.")
@click.option("--params", "params_path", type=PATH_IN,
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
              help="Output directory; an earlier run of this command there is replaced whole, nothing else is.")
def hip_identify(measured_path, params_path, which, sg_window, sg_order, rank_tol, no_plots, out_dir) -> None:
    """Identify friction and/or inertia from measured motor torques; writes identified.toml,
    identification.json, torques.csv and plots."""
    show(_identify_job.run_identify(out_dir, measured_path, params_path, which, sg_window, sg_order, rank_tol,
                                    make_plots=not no_plots, report=list_files))


_ANGLE = FiniteFloat(-180.0, 180.0)
_LOAD = FiniteFloat(0.0, _ex.MAX_LOAD_N)


@group.command("excite")
@paper_option
@click.option("--params", "params_path", type=PATH_IN, help="Parameter file (TOML); default: the paper's Tables 1-2.")
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

    limits = _identify_excite.ExcitationLimits(alpha_range_deg, beta_range_deg, gamma_range_deg, load_range, max_slider_speed_m_s,
                              max_slider_accel_m_s2, max_cond_j)
    _identify_job.run_excite(out_path, params_path, which, limits, period_s, harmonics, cycles, samples_per_cycle,
               iterations, starts, seed, design_samples, progress=True, report=echo_lines)


@group.command("export")
@click.option("--format", "fmt", type=click.Choice(["mjcf"]), required=True,
              help="mjcf: a MuJoCo model of the machine's description (kinematic tree, the loops closed by "
                   "connect constraints, the motors with the screws' gear and rotor inertia; no load, no "
                   "load-dependent friction).")
@paper_option
@click.option("--params", "params_path", type=PATH_IN, help="Parameter file (TOML); default: the paper's Tables 1-2.")
@click.option("--timestep", "timestep_s", type=FiniteFloat(1e-6, 1.0), default=1e-3,
              show_default=True, help="MuJoCo integration step [s], 1e-6 to 1.")
@click.option("--out", "out_path", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="File to write (e.g. machine.xml).")
def hip_export(fmt, params_path, timestep_s, out_path) -> None:
    """Write the machine in another engine's format (MuJoCo's MJCF, the same writer as pkmdyn
    export --machine hip); the file is written only when the whole model is valid."""

    show(_job.export_job(fmt, params_path, timestep_s, out_path, announce=list_files))
