"""Closed-loop control commands: ``pkmdyn hip control`` and ``pkmdyn pdm control``.

This module wires a machine (its parameter loader, its ``minimal`` verbs, its motions) to the
machine-independent layers :mod:`pkmdyn.control` and :mod:`pkmdyn.simulate`, and writes the
files: ``control.csv`` (one row per control cycle), ``summary.json`` and the plots (posture
errors as the hip paper's Fig. 7; measured and theoretical limb displacement, velocity and
acceleration as the PDM paper's Fig. 26). Everything is computed and checked before the
output folder is touched. :func:`hip_closed_loop` is the public entry of the real-time
benchmark.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import click
import numpy as np

from ..errors import MotionError, ParameterError
from ._groups import PATH_IN, hip, pdm
from ._groups import FiniteFloat

__all__ = ["hip_closed_loop", "run_control", "HIP_CONTROLLERS", "PDM_CONTROLLERS", "MAX_CYCLES", "MAX_CONTROL_CYCLES"]

HIP_CONTROLLERS = ("pd", "augmented-pd", "feedforward", "computed-torque")
PDM_CONTROLLERS = ("pid", "feedforward", "computed-torque")
#: PDM limb names, in the order of the actuators (``l{k}_m`` columns)
PDM_LIMBS = ("l11", "l12", "l23", "l24")
#: most cycles of the built-in motion (``--cycles``)
MAX_CYCLES = 1000.0
#: most control cycles of one run (the loop stores every one of them)
MAX_CONTROL_CYCLES = 2_000_000
#: most plant integration steps per control cycle
MAX_STEPS_PER_CYCLE = 1000


@dataclass(frozen=True)
class _Setup:
    """A machine ready to run: verbs, controller and plant models, motion, duration, labels."""

    machine: str
    verbs: Any
    model: Any
    plant_model: Any
    motion: Any
    duration: float
    has_load: bool
    params_source: str
    plant_source: str
    motion_source: str


# ----------------------------------------------------------------------------- machines
def _plant_model(load: Any, from_dict: Any, description: Any, params: Path | None, plant_params: Path | None,
                 settings: dict[str, Any]) -> tuple[Any, str]:
    """The plant's model and a line saying where it came from: ``--plant-params`` when given, else
    the controller's description (``description()``) with the ``[mismatch]`` factors applied."""
    from ..control import scale_description

    if plant_params is not None:
        return load(plant_params), str(plant_params)
    mm = settings["mismatch"]
    plant = from_dict(scale_description(description(), mm["mass_factor"], mm["friction_factor"]),
                      "plant (parameters with the [mismatch] factors)")
    return plant, (f"{params or 'built-in parameters'} with masses x {mm['mass_factor']:g}, "
                   f"friction x {mm['friction_factor']:g}")


def _hip_setup(params: Path | None, plant_params: Path | None, motion: Path | None, cycles: float,
               settings: dict[str, Any]) -> _Setup:
    from ..machines.hip_simulator import minimal
    from ..machines.hip_simulator.params import default_params_dict, load_params, model_from_dict
    from ..params_util import read_toml
    from ..profiles.iso14242 import IsoCycle, angle_wave, iso_load

    model = load_params(params)
    plant, plant_source = _plant_model(
        load_params, model_from_dict, lambda: read_toml(params) if params is not None else default_params_dict(),
        params, plant_params, settings)
    if motion is None:
        cyc = IsoCycle()

        def fn(t: np.ndarray) -> tuple:
            w = [angle_wave(t, cyc.period_s, x) for x in (cyc.fe, cyc.aa, cyc.ier)]
            return (np.stack([a[0] for a in w], -1), np.stack([a[1] for a in w], -1),
                    np.stack([a[2] for a in w], -1), iso_load(t, cyc))

        duration, source = cycles * cyc.period_s, f"built-in ISO 14242-1 cycle model, {cycles:g} cycle(s)"
    else:
        from ..control import hermite_motion
        from ..profiles.orientation import read_motion_csv

        mo = read_motion_csv(motion)
        if mo.load is not None:
            lim = float(model.limits.max_load_N)
            big = np.flatnonzero(np.abs(mo.load) > lim)
            if big.size:
                raise MotionError(f"{motion}: row {big[0] + 1}, column 'load_N': {mo.load[big[0]]:g} N is above "
                                  f"max_load_N = {lim:g} N ([limits] of the parameter file)")
        fn = hermite_motion(mo.t, mo.angles, mo.rates, mo.accels, mo.load)
        duration, source = float(mo.t[-1] - mo.t[0]), str(motion)
    return _Setup("hip", minimal, model, plant, fn, duration, True, str(params or "built-in parameters"),
                  plant_source, source)


def _pdm_setup(params: Path | None, plant_params: Path | None, motion: Path | None, cycles: float,
               settings: dict[str, Any]) -> _Setup:
    from ..machines.pdm4 import minimal
    from ..machines.pdm4.params import default_params_path, load_params, params_from_dict
    from ..params_util import read_toml
    from ..profiles.cycloidal import cycloidal

    model = load_params(params)
    plant, plant_source = _plant_model(
        load_params, params_from_dict, lambda: read_toml(params if params is not None else default_params_path()),
        params, plant_params, settings)
    if motion is None:
        tr = model.trajectory
        S, P = np.asarray(tr.strokes, dtype=float), float(tr.period_s)
        n_cyc = max(1, int(np.ceil(cycles - 1e-9)))

        def fn(t: np.ndarray) -> tuple:
            t = np.asarray(t, dtype=float)
            c = np.clip(np.floor(t / P), 0, n_cyc - 1)
            tau = np.clip(t - c * P, 0.0, P)
            s, sd, sdd = cycloidal(tau, S, P)
            back = (c % 2 == 1)[:, None]
            return (np.where(back, S - s, s), np.where(back, -sd, sd), np.where(back, -sdd, sdd), None)

        duration = cycles * P
        source = f"Eq. 84 cycloidal motion of the parameter file, {cycles:g} stroke(s), alternately out and back"
    else:
        from ..control import hermite_motion
        from ..profiles.pdm_motion import read_pdm_motion

        mo = read_pdm_motion(motion)
        fn = hermite_motion(mo.t, mo.q, mo.qd, mo.qdd, None)
        duration, source = float(mo.t[-1] - mo.t[0]), str(motion)
    return _Setup("pdm", minimal, model, plant, fn, duration, False, str(params or "built-in parameters"),
                  plant_source, source)


# ----------------------------------------------------------------------------- run
def run_control(machine: str, controller: str, params: Path | None = None, plant_params: Path | None = None,
                motion: Path | None = None, cycles: float = 1.0, gains_path: Path | None = None,
                progress: bool = False) -> tuple[_Setup, Any, dict[str, Any]]:
    """Set up and run one closed loop; returns the setup, the :class:`~pkmdyn.simulate.Tracking`
    and the settings. Raises a :class:`~pkmdyn.errors.PkmdynError` on any bad input."""
    from ..control import load_settings, loop_settings
    from ..simulate import check_timing

    allowed = HIP_CONTROLLERS if machine == "hip" else PDM_CONTROLLERS
    if controller not in allowed:
        raise ParameterError(f"--controller {controller!r}: unknown for the {machine} (choose from {', '.join(allowed)})")
    if not (np.isfinite(cycles) and 0 < cycles <= MAX_CYCLES):
        raise MotionError(f"--cycles: {cycles:g} must be > 0 and at most {MAX_CYCLES:g}")
    settings = load_settings(machine, gains_path)
    ls = loop_settings(settings)
    steps = check_timing(ls.cycle_s, ls.step_s)
    if steps > MAX_STEPS_PER_CYCLE:
        raise ParameterError(f"[timing] integration_step_s = {ls.step_s:g} s: {steps:g} steps per control cycle, above "
                             f"the limit {MAX_STEPS_PER_CYCLE}")
    with warnings.catch_warnings():
        # a model whose values overflow ends as a PkmdynError (unreachable pose, divergence), not as
        # numpy's warning lines on stderr
        warnings.simplefilter("ignore", RuntimeWarning)
        return _run_control(machine, controller, params, plant_params, motion, cycles, gains_path, progress, settings,
                            ls, steps)


def _run_control(machine: str, controller: str, params: Path | None, plant_params: Path | None, motion: Path | None,
                 cycles: float, gains_path: Path | None, progress: bool, settings: dict[str, Any], ls: Any,
                 steps: int) -> tuple[_Setup, Any, dict[str, Any]]:
    from ..control import gains
    from ..simulate import track

    setup = (_hip_setup if machine == "hip" else _pdm_setup)(params, plant_params, motion, cycles, settings)
    n_cycles = setup.duration / ls.cycle_s
    if not np.isfinite(n_cycles) or n_cycles > MAX_CONTROL_CYCLES or n_cycles * steps > 50 * MAX_CONTROL_CYCLES:
        raise MotionError(f"motion: {setup.duration:g} s is {n_cycles:g} control cycles of {ls.cycle_s:g} s "
                          f"({n_cycles * steps:g} integration steps), above the limit {MAX_CONTROL_CYCLES:,} cycles "
                          f"({50 * MAX_CONTROL_CYCLES:,} steps)")
    n = len(setup.verbs.ACTUATORS) if controller == "pid" else len(setup.verbs.COORDINATES)
    g = gains(settings, controller, n)
    tracking = track(setup.verbs, setup.model, setup.plant_model, setup.motion, setup.duration, controller, g, ls,
                     setup.has_load, progress=progress, joint_accelerations=True)
    return setup, tracking, settings


def hip_closed_loop(duration_s: float = 10.0, controller: str = "augmented-pd",
                    integration_step_s: float | None = None, exact_plant: bool = False) -> Any:
    """The hip simulator tracking the built-in ISO cycle for ``duration_s`` [s] at the built-in
    settings (1 kHz control cycle), default parameters, plant with the default mismatch (or the
    controller's own model with ``exact_plant``). ``integration_step_s`` overrides the plant's
    step. Returns the :class:`~pkmdyn.simulate.Tracking`; for the real-time benchmark."""
    from dataclasses import replace

    from ..control import gains, load_settings, loop_settings
    from ..simulate import track

    settings = load_settings("hip")
    ls = loop_settings(settings)
    if integration_step_s is not None:
        ls = replace(ls, step_s=float(integration_step_s))
    setup = _hip_setup(None, None, None, duration_s, settings)
    plant = setup.model if exact_plant else setup.plant_model
    return track(setup.verbs, setup.model, plant, setup.motion, duration_s, controller,
                 gains(settings, controller, 3), ls, True, joint_accelerations=False)


# ----------------------------------------------------------------------------- outputs
def _lag(ref: np.ndarray, meas: np.ndarray, T: float, max_shift: int) -> float:
    """The delay [s] that best aligns ``meas`` with ``ref`` (least squares over whole cycles,
    refined by a parabola through the three best shifts)."""
    K = ref.shape[0]
    m = min(max_shift, K // 2)
    cost = np.array([np.mean((meas[d:] - ref[:K - d]) ** 2) for d in range(m + 1)])
    d = int(np.argmin(cost))
    frac = 0.0
    if 0 < d < m:
        a, b, c = cost[d - 1], cost[d], cost[d + 1]
        den = a - 2 * b + c
        frac = 0.5 * (a - c) / den if den > 0 else 0.0
    return (d + frac) * T


def _columns(setup: _Setup, tr: Any) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    ref, r, j = tr.reference, tr.result, tr.joint
    K = r.t.shape[0]
    cols: dict[str, np.ndarray] = {"t_s": r.t}
    summary_coords: dict[str, Any] = {}
    for c, name in enumerate(setup.verbs.COORDINATES):
        base, unit = name.rsplit("_", 1)
        scale, out_unit = (180 / np.pi, "deg") if unit == "rad" else (1e3, "mm")
        e = (ref.q[:K, c] - r.q[:, c]) * scale
        cols[f"{base}_ref_{out_unit}"] = ref.q[:K, c] * scale
        cols[f"{base}_{out_unit}"] = r.q[:, c] * scale
        cols[f"{base}_err_{out_unit}"] = e
        cols[f"{base}_sensed_{out_unit}"] = r.q_s[:, c] * scale
        if setup.machine == "hip":
            cols[f"{base}_attitude_{out_unit}"] = r.q_att[:, c] * scale
        summary_coords[base] = {f"rms_err_{out_unit}": float(np.sqrt(np.mean(e**2))),
                                f"max_abs_err_{out_unit}": float(np.max(np.abs(e)))}
    efforts: dict[str, Any] = {}
    for a, name in enumerate(setup.verbs.ACTUATORS):
        cols[name] = r.u[:, a]
        base, unit = name.split("_", 1)
        efforts[base] = {f"peak_abs_{unit}": float(np.max(np.abs(r.u[:, a]))),
                         "saturated_cycles": int(np.sum(r.saturated[:, a]))}
    if setup.machine == "hip":
        names, sc, u0, u1, u2 = [f"motor{a + 1}" for a in range(3)], 1.0, "rad", "rad_s", "rad_s2"
    elif setup.machine == "pdm":
        names, sc, u0, u1, u2 = list(PDM_LIMBS), 1e3, "mm", "mm_s", "mm_s2"
    else:  # a described mechanism: its actuated joints, in SI (m or rad by the effort's unit)
        names = [a.rsplit("_", 1)[0] for a in setup.verbs.ACTUATORS]
        sc = 1.0
    joints: dict[str, Any] = {}
    for a, nm in enumerate(names):
        if setup.machine not in ("hip", "pdm"):
            lin = setup.verbs.ACTUATORS[a].endswith("_N")
            u0, u1, u2 = ("m", "m_s", "m_s2") if lin else ("rad", "rad_s", "rad_s2")
        cols[f"{nm}_ref_{u0}"] = j.s[:K, a] * sc
        cols[f"{nm}_{u0}"] = r.s[:, a] * sc
        cols[f"{nm}_enc_{u0}"] = r.s_enc[:, a] * sc
        cols[f"{nm}_rate_ref_{u1}"] = j.sd[:K, a] * sc
        cols[f"{nm}_rate_enc_{u1}"] = r.sd_enc[:, a] * sc
        cols[f"{nm}_acc_ref_{u2}"] = j.sdd[:K, a] * sc
        cols[f"{nm}_acc_enc_{u2}"] = r.sdd_enc[:, a] * sc
        max_shift = int(round(0.2 / ref.T))
        peak = float(np.max(np.abs(j.sdd[:K, a])))
        acc_lag = _lag(j.sdd[:K, a], r.sdd_enc[:, a], ref.T, max_shift)
        d = int(round(acc_lag / ref.T))
        den = float(np.sum(j.sdd[:K - d, a] ** 2))
        joints[nm] = {
            "position_lag_ms": 1e3 * _lag(j.s[:K, a], r.s_enc[:, a], ref.T, max_shift),
            "velocity_lag_ms": 1e3 * _lag(j.sd[:K, a], r.sd_enc[:, a], ref.T, max_shift),
            "acceleration_lag_ms": 1e3 * acc_lag,
            "acceleration_gain": float(np.sum(r.sdd_enc[d:, a] * j.sdd[:K - d, a]) / den) if den > 0 else 0.0,
            "acceleration_peak_ratio": float(np.max(np.abs(r.sdd_enc[:, a])) / peak) if peak > 0 else 0.0,
        }
    if ref.load is not None:
        cols["load_N"] = ref.load[:K]
    return cols, {"coordinates": summary_coords, "actuators": efforts, "encoders": joints}


def _plots(setup: _Setup, tr: Any, tmp: Path) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ref, r, j = tr.reference, tr.result, tr.joint
    K = r.t.shape[0]
    paths = []
    if setup.machine == "hip":
        fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
        for ax, c, label in zip(axes, (1, 2, 0), ("(a) AA error", "(b) IER error", "(c) FE error")):
            ax.plot(r.t, np.rad2deg(ref.q[:K, c] - r.q[:, c]), lw=0.8)
            ax.set(xlabel="t [s]", ylabel="error [deg]", title=label)
            ax.grid(alpha=0.3)
        fig.suptitle(f"Posture-angle errors, {tr.controller.kind}")
        fig.tight_layout()
        p = tmp / "posture_errors.png"
        fig.savefig(p, dpi=110)
        plt.close(fig)
        paths.append(p)
    else:
        fig, axes = plt.subplots(3, 4, figsize=(15, 9), sharex=True)
        rows = ((j.s, r.s_enc, 1e3, "displacement [mm]"), (j.sd, r.sd_enc, 1e3, "velocity [mm/s]"),
                (j.sdd, r.sdd_enc, 1e3, "acceleration [mm/s^2]"))
        for i, (th, me, sc, lab) in enumerate(rows):
            for a in range(4):
                ax = axes[i, a]
                ax.plot(r.t, th[:K, a] * sc, label="theoretical", lw=1.0)
                ax.plot(r.t, me[:, a] * sc, label="measured", lw=0.8, ls="--")
                ax.grid(alpha=0.3)
                if i == 0:
                    ax.set_title(f"limb {PDM_LIMBS[a]}")
                if a == 0:
                    ax.set_ylabel(lab)
                if i == 2:
                    ax.set_xlabel("t [s]")
        axes[0, 0].legend()
        fig.suptitle(f"Measured and theoretical limb motion, {tr.controller.kind}")
        fig.tight_layout()
        p = tmp / "limb_tracking.png"
        fig.savefig(p, dpi=100)
        plt.close(fig)
        paths.append(p)
    fig, ax = plt.subplots(figsize=(7, 3.8))
    for a, name in enumerate(setup.verbs.ACTUATORS):
        ax.plot(r.t, r.u[:, a], label=name, lw=0.8)
    ax.set(xlabel="t [s]", ylabel="effort [" + setup.verbs.ACTUATORS[0].split("_", 1)[1] + "]", title="Actuator efforts")
    ax.legend()
    ax.grid(alpha=0.3)
    fig.tight_layout()
    p = tmp / "efforts.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    paths.append(p)
    return paths


def _loop_method(settings: dict[str, Any]) -> str:
    """The plant's integration method of a run with these settings."""
    from ..control import loop_settings

    return str(loop_settings(settings).method)


def _write(setup: _Setup, tr: Any, settings: dict[str, Any], out: Path, plots: bool, gains_path: Path | None) -> dict[str, Path]:
    from ..io import output_dir, write_csv, write_json

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        cols, parts = _columns(setup, tr)
    for name, v in cols.items():  # checked before --out is touched
        bad = np.flatnonzero(~np.isfinite(v))
        if bad.size:
            raise MotionError(f"run: column {name!r} is not finite at t = {cols['t_s'][bad[0]]:g} s "
                              "(the model's values overflow)")
    ls = tr.reference
    summary = {
        "machine": setup.machine,
        "controller": tr.controller.kind,
        "duration_s": float(setup.duration),
        "cycles": int(ls.cycles),
        "control_cycle_s": float(settings["timing"]["control_cycle_s"]),
        "integration_step_s": float(settings["timing"]["integration_step_s"]),
        "integration_method": _loop_method(settings),
        "fast_path": bool(tr.fast_path),
        **parts,
        "parameters": setup.params_source,
        "plant": setup.plant_source,
        "motion": setup.motion_source,
        "gains_file": str(gains_path) if gains_path else "built-in",
    }
    with output_dir(out) as tmp:
        write_csv(tmp / "control.csv", cols)
        write_json(tmp / "summary.json", summary)
        names = ["control.csv", "summary.json"]
        if plots:
            names += [p.name for p in _plots(setup, tr, tmp)]
    return {n: out / n for n in names}


def _command(machine: str, controller: str, params_path, plant_path, motion_path, cycles, gains_path, no_plots, out_dir) -> None:
    if motion_path is not None and cycles != 1.0:
        raise click.UsageError("--cycles applies to the built-in motion, not to --motion")
    setup, tr, settings = run_control(machine, controller, params_path, plant_path, motion_path, cycles, gains_path,
                                      progress=True)
    for name, path in _write(setup, tr, settings, out_dir, not no_plots, gains_path).items():
        click.echo(f"{name}: {path}")


def _options(f: Any) -> Any:
    for opt in reversed((
        click.option("--params", "params_path", type=PATH_IN, help="Controller model's parameter file (TOML); default: built-in."),
        click.option("--plant-params", "plant_path", type=PATH_IN,
                     help="Plant's parameter file (TOML); default: the controller's with the [mismatch] factors."),
        click.option("--motion", "motion_path", type=PATH_IN, help="Motion file (CSV); default: the built-in motion."),
        click.option("--cycles", type=FiniteFloat(0.0, MAX_CYCLES, lo_open=True), default=1.0, show_default=True,
                     help=f"Cycles of the built-in motion (> 0, at most {MAX_CYCLES:g}; a run holds at most "
                          f"{MAX_CONTROL_CYCLES:,} control cycles)."),
        click.option("--gains", "gains_path", type=PATH_IN, help="Control settings (TOML), laid over the built-in ones."),
        click.option("--no-plots", is_flag=True, help="Write no PNG plots."),
        click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), required=True,
                     help="Output directory."),
    )):
        f = opt(f)
    return f


@hip.command("control")
@click.option("--controller", required=True, help="One of: " + ", ".join(HIP_CONTROLLERS) + ".")
@_options
def hip_control(controller, params_path, plant_path, motion_path, cycles, gains_path, no_plots, out_dir) -> None:
    """Closed-loop tracking of a motion; writes control.csv, summary.json and plots."""
    _command("hip", controller, params_path, plant_path, motion_path, cycles, gains_path, no_plots, out_dir)


@pdm.command("control")
@click.option("--controller", required=True, help="One of: " + ", ".join(PDM_CONTROLLERS) + ".")
@_options
def pdm_control(controller, params_path, plant_path, motion_path, cycles, gains_path, no_plots, out_dir) -> None:
    """Closed-loop tracking of a motion; writes control.csv, summary.json and plots."""
    _command("pdm", controller, params_path, plant_path, motion_path, cycles, gains_path, no_plots, out_dir)
