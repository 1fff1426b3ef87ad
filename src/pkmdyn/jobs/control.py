"""The control job of every machine (``pkmdyn control``, a machine's own ``control`` command such
as ``pkmdyn pdm control``): :func:`job` for a generated machine, :func:`described_job` for a
described mechanism.

This module wires a machine to the machine-independent layers :mod:`pkmdyn.control` and
:mod:`pkmdyn.simulate`, and writes the files: ``control.csv`` (one row per control cycle),
``summary.json``, the plots and ``report.html``. What is a generated machine's own (its
parameter loader, verbs, motions, column names, figures such as a paper's posture errors
or the PDM paper's Fig. 26 limb motion, its 3D scene) comes from its
control adapter in the registry (:mod:`pkmdyn.control_protocol`); a described mechanism has
none and gets the generic columns of its description. Everything is computed and checked
before the output folder is touched. :func:`builtin_closed_loop` is the public entry of the
real-time benchmark.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._lazy import lazy_module
from ..errors import MotionError, ParameterError, PkmdynError
from ..io import (
    check_output_dir,
    check_table_format,
    open_table_writer,
)
from ..machines.registry import control_adapter, generated_machines
from ..report import MAX_FRAMES, Curve, Curves, Extremes, FramePicker, Output, Report, TimePlot, write_output
from ._files import JobResult, prepare

if TYPE_CHECKING:
    from .. import control as _control
    from .. import multibody as _multibody
    from .. import simulate as _simulate
    from ..multibody import scene as _scene
    from ..multibody.dynamics import verbs as _verbs
    from ..multibody.kinematics import inverse as _inverse
else:  # loaded when a run starts: the command line imports this module for its constants and help
    _control = lazy_module("pkmdyn.control")
    _multibody = lazy_module("pkmdyn.multibody")
    _simulate = lazy_module("pkmdyn.simulate")
    _verbs = lazy_module("pkmdyn.multibody.dynamics.verbs")
    _inverse = lazy_module("pkmdyn.multibody.kinematics.inverse")
    _scene = lazy_module("pkmdyn.multibody.scene")

__all__ = ["job", "described_job", "described_control_settings", "DESCRIBED_CONTROLLERS", "builtin_closed_loop",
           "run_control", "machine_setup", "effort_label", "machine_controllers", "check_loop",
           "MAX_CYCLES", "MAX_CONTROL_CYCLES"]

#: most cycles of the built-in motion (``--cycles``)
MAX_CYCLES = 1000.0
#: most control cycles of one run (streamed in spans, so memory does not grow with it; the bound keeps the
#: run's time and files in reason)
MAX_CONTROL_CYCLES = 2_000_000
#: most plant integration steps per control cycle
MAX_STEPS_PER_CYCLE = 1000


@dataclass(frozen=True)
class _Setup:
    """A machine ready to run: verbs, controller and plant models, motion, duration, labels;
    ``job``: a generated machine's control adapter (:class:`pkmdyn.control_protocol.ControlJob`),
    None for a described mechanism."""

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
    span_s: float = 0.0  #: the motion as a whole [s]: a full cycle of a built-in motion even for a part of one
    fold_s: float = 0.0  #: the period a built-in motion repeats with [s] (plots fold the run by it); 0: none
    load_column: str = "load_N"  #: the column of the motion's load in control.csv (``has_load``)
    job: Any = None
    #: per actuator: ``(drive name, encoder key, unit)`` of the drive whose own encoder it reads
    #: ([[actuators]]), or None
    drive_encoders: tuple = ()


# ----------------------------------------------------------------------------- machines
def machine_setup(machine: str, params: Path | None, plant_params: Path | None, motion: Path | None, cycles: float,
                  settings: dict[str, Any]) -> _Setup:
    """The generated machine ``machine`` (a registry name) ready to run: the controller's model
    from ``params`` (None: built-in), the plant's from ``plant_params`` or else the controller's
    parameters with the ``[mismatch]`` factors of ``settings``, and ``cycles`` of the built-in
    motion or the motion file ``motion``."""
    job = control_adapter(machine)
    description, source = job.read_description(params)  # each file is read once (it may be a pipe)
    model = job.model_from_dict(description, source)
    if plant_params is not None:
        plant, plant_source = job.load_params(plant_params), str(plant_params)
    else:
        mm = settings["mismatch"]
        plant = job.model_from_dict(_control.scale_description(description, mm["mass_factor"], mm["friction_factor"]),
                                    "plant (parameters with the [mismatch] factors)")
        plant_source = (f"{params or 'built-in parameters'} with masses x {mm['mass_factor']:g}, "
                        f"friction x {mm['friction_factor']:g}")
    notes = getattr(job, "notes", None)  # what the machine says of a parameter file (ControlJob.notes)
    if notes is not None:
        for line in dict.fromkeys([*notes(model), *notes(plant)]):
            warnings.warn(line, ControlWarning, stacklevel=2)
    if motion is None:
        bm = job.builtin_motion(model, cycles)
        fn, duration, motion_source, span, fold = bm.fn, bm.duration_s, bm.source, bm.span_s, bm.fold_s
    else:
        mo = job.read_motion(model, motion)
        fn = _control.hermite_motion(mo.t, mo.q, mo.qd, mo.qdd, mo.load)
        duration = float(mo.t[-1] - mo.t[0])
        motion_source, span, fold = str(motion), duration, 0.0
    return _Setup(job.NAME, job.verbs(model), model, plant, fn, duration, job.HAS_LOAD, str(params or "built-in parameters"),
                  plant_source, motion_source, span, fold, job=job)


# ----------------------------------------------------------------------------- run
def run_control(machine: str, controller: str, params: Path | None = None, plant_params: Path | None = None,
                motion: Path | None = None, cycles: float = 1.0, gains_path: Path | None = None,
                progress: bool = False) -> tuple[_Setup, Any, dict[str, Any]]:
    """Set up and run one closed loop; returns the setup, the :class:`~pkmdyn.simulate.Tracking`
    and the settings. Raises a :class:`~pkmdyn.errors.PkmdynError` on any bad input. (The
    commands stream the same run span by span: :func:`pkmdyn.simulate.track_spans`.)"""
    with warnings.catch_warnings():
        # a model whose values overflow ends as a PkmdynError (unreachable pose, divergence), not as
        # numpy's warning lines on stderr
        warnings.simplefilter("ignore", RuntimeWarning)
        setup, settings, ls, g = _prepare(machine, controller, params, plant_params, motion, cycles, gains_path)
        try:
            tracking = _simulate.track(setup.verbs, setup.model, setup.plant_model, setup.motion, setup.duration, controller,
                             g, ls, setup.has_load, progress=progress, joint_accelerations=True)
        except _simulate.DivergenceError as exc:
            raise _simulate.DivergenceError(_divergence_message(setup, controller, exc), exc.coordinate, exc.error, exc.limit,
                                  exc.t) from None
    _warn_unstable(setup, controller)
    return setup, tracking, settings


def _prepare(machine: str, controller: str, params: Path | None, plant_params: Path | None, motion: Path | None,
             cycles: float, gains_path: Path | None) -> tuple[_Setup, dict[str, Any], Any, Any]:
    """Every check of a run, then its setup, settings, loop settings and gains."""
    allowed = control_adapter(machine).CONTROLLERS
    if controller not in allowed:
        raise ParameterError(f"--controller {controller!r}: unknown for the {machine} (choose from {', '.join(allowed)})")
    if not (np.isfinite(cycles) and 0 < cycles <= MAX_CYCLES):
        raise MotionError(f"--cycles: {cycles:g} must be > 0 and at most {MAX_CYCLES:g}")
    settings = _control.load_settings(machine, gains_path)
    ls = _control.loop_settings(settings)
    check_loop(ls, None, gains_path)
    setup = machine_setup(machine, params, plant_params, motion, cycles, settings)
    check_loop(ls, setup.duration, gains_path)
    _check_encoder(setup, ls, settings, gains_path)
    n = len(setup.verbs.ACTUATORS) if controller == "pid" else len(setup.verbs.COORDINATES)
    return setup, settings, ls, _control.gains(settings, controller, n)


def check_loop(ls: Any, duration: float | None, gains_path: Path | None) -> None:
    """The limits every closed loop keeps, whatever the machine: the cycle a whole multiple of
    the step, at most :data:`MAX_STEPS_PER_CYCLE` steps per cycle, the encoder filters below
    the cycle's Nyquist frequency and (with ``duration`` [s]) at most
    :data:`MAX_CONTROL_CYCLES` cycles and 50 times as many steps."""
    steps = _simulate.check_timing(ls.cycle_s, ls.step_s)
    _check_filters(ls, gains_path)
    if steps > MAX_STEPS_PER_CYCLE:
        raise ParameterError(f"[timing] integration_step_s = {ls.step_s:g} s: {steps:g} steps per control cycle, above "
                             f"the limit {MAX_STEPS_PER_CYCLE}")
    if duration is None:
        return
    n_cycles = duration / ls.cycle_s
    if not np.isfinite(n_cycles) or n_cycles > MAX_CONTROL_CYCLES or n_cycles * steps > 50 * MAX_CONTROL_CYCLES:
        raise MotionError(f"motion: {duration:g} s is {n_cycles:g} control cycles of {ls.cycle_s:g} s "
                          f"({n_cycles * steps:g} integration steps), above the limit {MAX_CONTROL_CYCLES:,} cycles "
                          f"({50 * MAX_CONTROL_CYCLES:,} steps)")


def _warn_unstable(setup: _Setup, controller: str) -> None:
    if controller == "feedforward":
        unstable = _open_loop_growth(setup)
        if unstable is not None:
            warnings.warn(f"feedforward alone: {unstable}; this run stayed within the divergence limits, a longer "
                          "one may not (use a feedback controller)", ControlWarning, stacklevel=2)


class ControlWarning(UserWarning):
    """A run that succeeded but whose result should be read with care (printed by the command)."""


def _divergence_message(setup: _Setup, controller: str, exc: Any) -> str:
    """The divergence said in the coordinate's name and in the unit of the settings file's
    ``[run] divergence_limit_*`` key (deg for angles, m for lengths); with feedforward on an
    open-loop unstable plant, why."""
    if exc.coordinate is None:
        text = str(exc)
    else:
        base, unit = setup.verbs.COORDINATES[exc.coordinate].rsplit("_", 1)
        name = base if setup.job is None else setup.job.COORDINATE_NAMES.get(base, base)
        scale, shown, key = (180 / np.pi, "deg", "divergence_limit_deg") if unit == "rad" else (1.0, "m",
                                                                                                  "divergence_limit_m")
        err = f"{exc.error * scale:.4g} {shown}" if np.isfinite(exc.error) else "not finite"
        text = (f"run diverged at t = {exc.t:.4f} s: the tracking error of {name} is {err}, beyond "
                f"[run] {key} = {exc.limit * scale:.4g} {shown}")
    if controller == "feedforward":
        unstable = _open_loop_growth(setup)
        if unstable is not None:
            text += f"; feedforward alone cannot hold it: {unstable} (use a feedback controller)"
    return text


def _open_loop_growth(setup: _Setup) -> str | None:
    """Whether the plant, held at the efforts that keep it at the start of the reference, is
    open-loop unstable there: the eigenvalues of the linearised forward dynamics (central
    differences of the ``forward_dynamics`` verb); a sentence naming the fastest growth, or None."""
    v, model = setup.verbs, setup.plant_model
    q, qd = (np.asarray(a, dtype=float)[:1] for a in setup.motion(np.zeros(1))[:2])
    load_t = setup.motion(np.zeros(1))[3]
    load = None if load_t is None else np.asarray(load_t, dtype=float)[:1]
    zero = np.zeros_like(q)
    try:
        u = v.inverse_dynamics(model, q, zero, zero, load)
        nq = q.shape[1]
        A = np.zeros((2 * nq, 2 * nq))
        A[:nq, nq:] = np.eye(nq)
        for j in range(2 * nq):
            h = 1e-6 * (1.0 + abs(float(q[0, j % nq])))
            d = np.zeros_like(q)
            d[0, j % nq] = h
            if j < nq:
                f = (v.forward_dynamics(model, q + d, zero, u, load) - v.forward_dynamics(model, q - d, zero, u, load))
            else:
                f = (v.forward_dynamics(model, q, zero + d, u, load) - v.forward_dynamics(model, q, zero - d, u, load))
            A[nq:, j] = f[0] / (2 * h)
        rate = float(np.max(np.linalg.eigvals(A).real))
    except (PkmdynError, np.linalg.LinAlgError, FloatingPointError, ValueError):
        return None
    if not (np.isfinite(rate) and rate > 1e-6):
        return None
    subject = f"mechanism {setup.machine}" if setup.job is None else setup.job.SUBJECT
    return f"{subject} is open-loop unstable at the start pose (an error grows by e every {1 / rate:.3g} s)"


#: fewest encoder counts over the largest actuator travel of a run
MIN_ENCODER_COUNTS = 10


def _check_filters(ls: Any, gains_path: Path | None) -> None:
    """The encoder filters must sit below the Nyquist frequency of the control cycle: a
    first-order filter at or above it does not filter a signal sampled once per cycle."""
    nyquist = 0.5 / ls.cycle_s
    where = f"{gains_path}: [sensors]" if gains_path is not None else "built-in settings: [sensors]"
    for key in ("velocity_cutoff_Hz", "acceleration_cutoff_Hz"):
        fc = float(getattr(ls, key))
        if fc >= nyquist:
            raise ParameterError(f"{where} {key}: {fc:g} Hz is at or above {nyquist:g} Hz, the Nyquist frequency of the "
                                 f"{ls.cycle_s:g} s control cycle, where a filter cannot act (lower it; 0: no filter)")


def _check_encoder(setup: _Setup, ls: Any, settings: dict[str, Any], gains_path: Path | None) -> None:
    """The encoders must resolve the motion: at least :data:`MIN_ENCODER_COUNTS` counts over the
    largest actuator travel of the motion (a whole cycle of a built-in motion, even when the run
    is a part of one; estimated on up to 2,001 samples)."""
    span = max(setup.span_s, setup.duration)
    n = int(min(2_001, max(3, span / ls.cycle_s + 1)))
    t = np.linspace(0.0, span, n)
    q, qd = setup.motion(t)[:2]
    sd = np.einsum("kji,kj->ki", setup.verbs.actuator_map(setup.model, q), qd)
    s = np.concatenate([np.zeros((1, sd.shape[1])), np.cumsum(0.5 * (sd[1:] + sd[:-1]) * np.diff(t)[:, None], axis=0)])
    travel_each = np.ptp(s, axis=0)
    res_each = np.broadcast_to(np.asarray(ls.encoder_resolution, dtype=float), travel_each.shape)
    coarse = np.flatnonzero((travel_each > 0) & (res_each * MIN_ENCODER_COUNTS > travel_each))
    if coarse.size:
        a = int(coarse[np.argmax(res_each[coarse] / travel_each[coarse])])
        travel, res = float(travel_each[a]), float(res_each[a])
        unit = _travel_unit(setup)
        drive = setup.drive_encoders[a] if setup.drive_encoders else None
        if drive is not None:
            name, key, u = drive
            raise ParameterError(
                f"[[actuators]] {name}: {key} makes one count {res:.3g} {u} of motor travel, while the motion moves "
                f"the motor at most {travel:.3g} {u}: fewer than {MIN_ENCODER_COUNTS} counts, too coarse to measure "
                f"it (raise its {key})")
        where = f"{gains_path}: [sensors]" if gains_path is not None else "built-in settings: [sensors]"
        counts = settings["sensors"]["encoder_counts_per_turn"]
        raise ParameterError(
            f"{where} encoder_counts_per_turn: {counts:g} counts per turn make one count {res:.3g} {unit} of actuator "
            f"travel, while the motion moves an actuator at most {travel:.3g} {unit}: fewer than "
            f"{MIN_ENCODER_COUNTS} counts, too coarse to measure it (raise encoder_counts_per_turn)")


def machine_controllers() -> dict[str, tuple[str, ...]]:
    """The controllers of every generated machine with a control job, by machine name."""
    out = {}
    for name in sorted(generated_machines()):
        try:
            out[name] = control_adapter(name).CONTROLLERS
        except ParameterError:  # a machine without a control job
            continue
    return out


def _travel_unit(setup: _Setup) -> str:
    """The unit of an actuator's travel: the machine's, or a described mechanism's by its
    actuators' effort columns (forces: m, torques: rad)."""
    if setup.job is not None:
        return setup.job.TRAVEL_UNIT
    units = {unit for _, _, unit, _, _ in _joint_columns(setup)}
    return units.pop() if len(units) == 1 else "m or rad"


def builtin_closed_loop(machine: str, duration_s: float = 10.0, controller: str = "augmented-pd",
                        integration_step_s: float | None = None, exact_plant: bool = False) -> Any:
    """The built-in machine ``machine`` (one with a control job) tracking its built-in motion for
    ``duration_s`` [s] at its built-in settings, default parameters, plant with the default
    mismatch (or the controller's own model with ``exact_plant``). ``integration_step_s``
    overrides the plant's step. Returns the :class:`~pkmdyn.simulate.Tracking`; for the
    real-time benchmark."""

    settings = _control.load_settings(machine)
    ls = _control.loop_settings(settings)
    if integration_step_s is not None:
        ls = replace(ls, step_s=float(integration_step_s))
    setup = machine_setup(machine, None, None, None, duration_s, settings)
    plant = setup.model if exact_plant else setup.plant_model
    return _simulate.track(setup.verbs, setup.model, plant, setup.motion, duration_s, controller,
                 _control.gains(settings, controller, 3), ls, True, joint_accelerations=False)


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


def _joint_columns(setup: _Setup) -> list[tuple[str, float, str, str, str]]:
    """Per actuator: its name in the columns, the scale to its file unit and the units of its
    displacement, rate and acceleration (a described mechanism: its actuated joints in SI, m or
    rad by the effort's unit)."""
    if setup.job is not None:
        return setup.job.joint_columns()
    out = []
    for act in setup.verbs.ACTUATORS:
        units = ("m", "m_s", "m_s2") if act.endswith("_N") else ("rad", "rad_s", "rad_s2")
        out.append((act.rsplit("_", 1)[0], 1.0, *units))
    return out


def _coordinate_scale(name: str) -> tuple[str, float, str]:
    base, unit = name.rsplit("_", 1)
    return (base, 180 / np.pi, "deg") if unit == "rad" else (base, 1e3, "mm")


def _columns(setup: _Setup, tr: Any) -> dict[str, np.ndarray]:
    """The rows of ``control.csv`` of one span of a run (or of a whole run)."""
    ref, r, j = tr.reference, tr.result, tr.joint
    K = r.t.shape[0]
    cols: dict[str, np.ndarray] = {"t_s": r.t}
    for c, name in enumerate(setup.verbs.COORDINATES):
        base, scale, out_unit = _coordinate_scale(name)
        cols[f"{base}_ref_{out_unit}"] = ref.q[:K, c] * scale
        cols[f"{base}_{out_unit}"] = r.q[:, c] * scale
        cols[f"{base}_err_{out_unit}"] = (ref.q[:K, c] - r.q[:, c]) * scale
        cols[f"{base}_sensed_{out_unit}"] = r.q_s[:, c] * scale
        if setup.job is not None and setup.job.ATTITUDE_COLUMNS:
            cols[f"{base}_attitude_{out_unit}"] = r.q_att[:, c] * scale
    for a, name in enumerate(setup.verbs.ACTUATORS):
        cols[name] = r.u[:, a]
    for a, (nm, sc, u0, u1, u2) in enumerate(_joint_columns(setup)):
        cols[f"{nm}_ref_{u0}"] = j.s[:K, a] * sc
        cols[f"{nm}_{u0}"] = r.s[:, a] * sc
        cols[f"{nm}_enc_{u0}"] = r.s_enc[:, a] * sc
        cols[f"{nm}_rate_ref_{u1}"] = j.sd[:K, a] * sc
        cols[f"{nm}_rate_enc_{u1}"] = r.sd_enc[:, a] * sc
        cols[f"{nm}_acc_ref_{u2}"] = j.sdd[:K, a] * sc
        cols[f"{nm}_acc_enc_{u2}"] = r.sdd_enc[:, a] * sc
    if ref.load is not None:
        cols[setup.load_column] = ref.load[:K]
    return cols


#: control cycles of the start of a run from which the encoders' lags and gain are estimated
ANALYSIS_CYCLES = 100_000


class _Summary:
    """The extremes and figures of ``summary.json``, gathered span by span (bounded memory):
    errors and efforts over the whole run; the encoders' lags and acceleration gain over its
    first :data:`ANALYSIS_CYCLES` cycles (least squares over shifts up to 0.2 s); the peak ratio
    over the whole run."""

    def __init__(self, setup: _Setup) -> None:
        self.setup = setup
        self.ext = Extremes()
        self.buf: dict[str, list[np.ndarray]] = {k: [] for k in ("s", "s_enc", "sd", "sd_enc", "sdd", "sdd_enc")}
        self.kept = 0
        self.T = 0.0

    def add(self, tr: Any) -> None:
        ref, r, j = tr.reference, tr.result, tr.joint
        K = r.t.shape[0]
        self.T = ref.T
        e = ref.q[:K] - r.q
        x = self.ext
        x.sum("sq", np.sum(e**2, axis=0))
        x.max("mx", np.max(np.abs(e), axis=0))
        x.sum("rows", K)
        x.max("peak", np.max(np.abs(r.u), axis=0))
        x.sum("sat", np.sum(r.saturated, axis=0))
        x.max("acc_ref_peak", np.max(np.abs(j.sdd[:K]), axis=0))
        x.max("acc_enc_peak", np.max(np.abs(r.sdd_enc), axis=0))
        take = min(K, ANALYSIS_CYCLES - self.kept)
        if take > 0:
            for key, v in (("s", j.s), ("s_enc", r.s_enc), ("sd", j.sd), ("sd_enc", r.sd_enc), ("sdd", j.sdd),
                           ("sdd_enc", r.sdd_enc)):
                self.buf[key].append(np.array(v[:take]))
            self.kept += take

    def result(self) -> dict[str, Any]:
        x = self.ext
        coords: dict[str, Any] = {}
        for c, name in enumerate(self.setup.verbs.COORDINATES):
            base, scale, unit = _coordinate_scale(name)
            coords[base] = {f"rms_err_{unit}": float(np.sqrt(x["sq"][c] / x["rows"])) * scale,
                            f"max_abs_err_{unit}": float(x["mx"][c]) * scale}
        efforts: dict[str, Any] = {}
        for a, name in enumerate(self.setup.verbs.ACTUATORS):
            base, unit = name.rsplit("_", 1)  # the actuator's name (it may hold "_"), then its unit
            efforts[base] = {f"peak_abs_{unit}": float(x["peak"][a]), "saturated_cycles": int(x["sat"][a])}
        b = {k: np.concatenate(v) for k, v in self.buf.items()}
        names = [c[0] for c in _joint_columns(self.setup)]
        T = self.T
        K = b["s"].shape[0]
        max_shift = int(round(0.2 / T))
        joints: dict[str, Any] = {}
        for a, nm in enumerate(names):
            acc_lag = _lag(b["sdd"][:, a], b["sdd_enc"][:, a], T, max_shift)
            d = int(round(acc_lag / T))
            den = float(np.sum(b["sdd"][:K - d, a] ** 2))
            peak = float(x["acc_ref_peak"][a])
            joints[nm] = {
                "position_lag_ms": 1e3 * _lag(b["s"][:, a], b["s_enc"][:, a], T, max_shift),
                "velocity_lag_ms": 1e3 * _lag(b["sd"][:, a], b["sd_enc"][:, a], T, max_shift),
                "acceleration_lag_ms": 1e3 * acc_lag,
                "acceleration_gain": float(np.sum(b["sdd_enc"][d:, a] * b["sdd"][:K - d, a]) / den) if den > 0 else 0.0,
                "acceleration_peak_ratio": float(x["acc_enc_peak"][a] / peak) if peak > 0 else 0.0,
            }
        return {"coordinates": coords, "actuators": efforts, "encoders": joints}


def _plot_curves(setup: _Setup, tr: Any) -> dict[str, np.ndarray]:
    out = {"u": tr.result.u}
    if setup.job is not None:
        out.update(setup.job.plot_curves(tr.reference.q, tr.result, tr.joint))
    else:  # a described mechanism: the task coordinates' tracking errors, in their own units
        out["err"] = tr.reference.q[:tr.result.t.shape[0]] - tr.result.q
    return out


def _coordinate_label(name: str) -> tuple[str, str]:
    """A task coordinate's column name ``x_m``, ``euler1_rad`` as ``(name, unit)``."""
    base, _, unit = name.rpartition("_")
    return (base, unit) if base else (name, "")


def _draw(ax: Any, mode: str, t: np.ndarray, first: np.ndarray, lo: np.ndarray, hi: np.ndarray, label: str | None,
          **kw: Any) -> None:
    """One curve: every sample, or the first cycle over the band of all cycles, or the envelope."""
    if mode == "raw":
        ax.plot(t, first, label=label, **kw)
        return
    line = None
    if mode == "fold":
        (line,) = ax.plot(t, first, label=label, **kw)
    ax.fill_between(t, lo, hi, alpha=0.25, lw=0, color=None if line is None else line.get_color(),
                    label=label if line is None else None)


def _plots(setup: _Setup, curves: Curves, kind: str, tmp: Path) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    d = curves.data()
    t, first, lo, hi, note, mode = d.t, d.first, d.lo, d.hi, d.note, d.mode
    suffix = f"\n{note}" if note else ""
    paths = []
    if setup.job is not None:
        def draw(ax: Any, *args: Any, **kw: Any) -> None:
            _draw(ax, mode, *args, **kw)

        paths += setup.job.figures(draw, t, first, lo, hi, f"{kind}{suffix}", tmp)
    else:  # a described mechanism: each task coordinate's tracking error
        names = setup.verbs.COORDINATES
        ncol = min(3, len(names))
        nrow = -(-len(names) // ncol)
        fig, axes = plt.subplots(nrow, ncol, figsize=(4.4 * ncol, 3.4 * nrow), squeeze=False)
        for ax in axes.ravel()[len(names):]:
            ax.set_visible(False)
        for c, (ax, name) in enumerate(zip(axes.ravel(), names)):
            label, unit = _coordinate_label(name)
            _draw(ax, mode, t, first["err"][:, c], lo["err"][:, c], hi["err"][:, c], None, lw=0.8)
            ax.set(xlabel="t [s]", ylabel=f"error [{unit}]", title=label)
            ax.grid(alpha=0.3)
        fig.suptitle(f"Tracking errors (reference - measured), {kind}{suffix}")
        fig.tight_layout()
        p = tmp / "tracking_errors.png"
        fig.savefig(p, dpi=110)
        plt.close(fig)
        paths.append(p)
    fig, ax = plt.subplots(figsize=(7, 4.2))
    for a in range(len(setup.verbs.ACTUATORS)):
        label, unit = _effort_label(setup, a)
        _draw(ax, mode, t, first["u"][:, a], lo["u"][:, a], hi["u"][:, a], f"{label} [{unit}]", lw=0.8)
    quantity, title = (("effort", "Actuator efforts") if setup.job is None else
                       (setup.job.EFFORT_QUANTITY, f"Actuator efforts ({setup.job.EFFORTS_TITLE})"))
    ax.set(xlabel="t [s]", ylabel=f"{quantity} [{_effort_label(setup, 0)[1]}]", title=f"{title}{suffix}")
    ax.legend()
    ax.grid(alpha=0.3)
    fig.tight_layout()
    p = tmp / "efforts.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    paths.append(p)
    return paths


def effort_label(machine: str, a: int) -> tuple[str, str]:
    """The name and unit of actuator ``a`` (0-based) of the generated machine ``machine`` for
    plots: ``("motor 1 torque", "N m")``, ``("limb l11 force", "N")``, not the column names
    ``tau1_Nm``, ``f1_N``."""
    return control_adapter(machine).effort_label(a)


def _effort_label(setup: _Setup, a: int) -> tuple[str, str]:
    """:func:`effort_label` of the run's machine; a described mechanism's from its effort column
    (``P_1_N`` -> ``("P_1 force", "N")``)."""
    if setup.job is not None:
        return setup.job.effort_label(a)
    base, unit = setup.verbs.ACTUATORS[a].rsplit("_", 1)
    return (f"{base} force", "N") if unit == "N" else (f"{base} torque", "N m")


def _report(setup: _Setup, kind: str, curves: Curves, frames: Any, summary: dict[str, Any],
            images: list[str], gains_path: Path | None, K: int) -> Report:
    """The content of a control run's ``report.html``: the plant's true motion animated (held efforts as colours),
    the machine's own curves (:meth:`~pkmdyn.control_protocol.ControlJob.report_plots`) and efforts
    against time, the PNG figures, summary,
    parameters and warnings."""

    warns = [f"{_effort_label(setup, a)[0]} hit its limit in {v['saturated_cycles']} control cycle(s)"
             for a, v in enumerate(summary["actuators"].values()) if v["saturated_cycles"]]
    f = frames.arrays()
    job = setup.job
    scene = None
    try:
        if job is not None:
            scene = job.scene(setup.plant_model, f["t"], f["q"], f["u"])
        else:  # a described mechanism: the engine's drawing of its description
            scene = _scene.motion_scene(setup.plant_model, f["t"], f["q"], f["u"])
    except PkmdynError as exc:  # the plant left the machine's reach: the page says so, the run stands
        warns.append(f"report: the 3D view could not be built ({exc})")
    d = curves.data()
    t, first, lo, hi, note = d.t, d.first, d.lo, d.hi, d.note

    def curve(key: str, c: int, name: str) -> Curve:
        if d.mode == "bins":
            return Curve(name, lo=lo[key][:, c], hi=hi[key][:, c])
        return Curve(name, first[key][:, c])

    if job is not None:
        plots = job.report_plots(curve, t, note)
        params = job.parameters_text(None if setup.params_source == "built-in parameters" else setup.params_source)
        title = f"{job.REPORT_NAME}: {setup.machine} control, {kind}"
    else:
        names = setup.verbs.COORDINATES
        units = sorted({_coordinate_label(n)[1] for n in names})
        plots = [TimePlot("Tracking errors (reference - measured)", f"error [{' or '.join(units)}]", t,
                          tuple(curve("err", c, n) for c, n in enumerate(names)), note)]
        try:
            params = f"# {setup.params_source}\n" + Path(setup.params_source).read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError):
            params = f"# {setup.params_source}"
        title = f"{setup.machine}: pkmdyn control, {kind}"
    plots.append(TimePlot("Actuator efforts", f"[{_effort_label(setup, 0)[1]}]", t, tuple(
        curve("u", a, _effort_label(setup, a)[0]) for a in range(len(setup.verbs.ACTUATORS))), note))
    if gains_path is not None:
        try:
            params += f"\n\n# control settings: {gains_path}\n" + Path(gains_path).read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError):
            pass
    return Report(title, scene=scene, plots=plots, parameters=params, warnings=warns, images=images,
                  notes=[f"parameters: {setup.params_source}", f"plant: {setup.plant_source}",
                         f"motion: {setup.motion_source}"],
                  scene_note="The plant's true pose; actuated chains coloured by the held effort.", samples=K)


def _loop_method(settings: dict[str, Any]) -> str:
    """The plant's integration method of a run with these settings."""
    return str(_control.loop_settings(settings).method)


def _stream(setup: _Setup, controller: str, g: Any, ls: Any, settings: dict[str, Any], out: Path, plots: bool,
            gains_path: Path | None, inputs: dict[str, Path | None], fmt: str, html_report: bool = True,
            announce: Callable[[Mapping[str, Path]], None] | None = None
            ) -> tuple[dict[str, Path], dict[str, Any], Report | None]:
    """Run the loop span by span (:func:`pkmdyn.simulate.track_spans`) straight into the output
    folder: the table is written span by span and the summary and plots gathered on the way, so
    memory does not grow with the run; the folder moves into place only when the whole run
    succeeded (:func:`pkmdyn.report.write_output`). ``html_report``: also ``report.html``, its
    animation's frames picked span by span (:class:`pkmdyn.report.FramePicker`); ``announce`` is
    given the files' final paths before they move into place. Returns the files, the summary and
    the report's content (None without one)."""
    check_table_format(fmt)
    K = int(round(setup.duration / ls.cycle_s))
    summ = _Summary(setup)
    fold = int(round(setup.fold_s / ls.cycle_s)) if setup.fold_s > 0 else 0
    curves = Curves(K, fold=fold, unit="control cycles") if plots or html_report else None
    frames = FramePicker(K, MAX_FRAMES) if html_report else None
    table = "control.csv" if fmt == "csv" else "control.parquet"
    kind, fast = controller, False

    def make(tmp: Path) -> Output:
        nonlocal kind, fast
        with open_table_writer(tmp / table, fmt) as writer:
            start = 0
            try:
                for tr in _simulate.track_spans(setup.verbs, setup.model, setup.plant_model, setup.motion, setup.duration,
                                      controller, g, ls, setup.has_load, progress=True, joint_accelerations=True):
                    kind, fast = tr.controller.kind, bool(tr.fast_path)
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore", RuntimeWarning)
                        cols = _columns(setup, tr)
                    for name, v in cols.items():
                        bad = np.flatnonzero(~np.isfinite(v))
                        if bad.size:
                            raise MotionError(f"run: column {name!r} is not finite at t = {cols['t_s'][bad[0]]:g} s "
                                              "(the model's values overflow)")
                    writer.write(cols)
                    summ.add(tr)
                    if curves is not None:
                        curves.add(start, tr.result.t, _plot_curves(setup, tr))
                    if frames is not None:
                        frames.add(start, t=tr.result.t, q=tr.result.q, u=tr.result.u)
                    start += tr.result.t.shape[0]
            except _simulate.DivergenceError as exc:
                raise _simulate.DivergenceError(_divergence_message(setup, controller, exc), exc.coordinate, exc.error,
                                      exc.limit, exc.t) from None
        summary = {
            "machine": setup.machine,
            "controller": kind,
            "duration_s": float(setup.duration),
            "cycles": int(K),
            "control_cycle_s": float(settings["timing"]["control_cycle_s"]),
            "integration_step_s": float(settings["timing"]["integration_step_s"]),
            "integration_method": _loop_method(settings),
            "fast_path": fast,
            **summ.result(),
            "results_format": fmt,
            "parameters": setup.params_source,
            "plant": setup.plant_source,
            "motion": setup.motion_source,
            "gains_file": str(gains_path) if gains_path else "built-in",
        }
        files = {table: tmp / table}
        if curves is not None and plots:
            files.update((p.name, p) for p in _plots(setup, curves, kind, tmp))
        report = None
        if frames is not None and curves is not None:
            report = _report(setup, kind, curves, frames, summary, [n for n in files if n.endswith(".png")],
                             gains_path, K)
        return Output(files, summary, report)

    files, output = write_output(out, inputs, make, announce)
    return files, dict(output.summary or {}), output.report


def _caught(caught: list) -> tuple[str, ...]:
    """The control warnings of a run as lines; any other warning but numpy's overflow shown as usual."""
    lines = []
    for w in caught:
        if issubclass(w.category, ControlWarning):
            lines.append(str(w.message))
        elif not issubclass(w.category, RuntimeWarning):
            warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    return tuple(lines)


def job(machine: str, controller: str, out_dir: Path, *, params_path: Path | None = None, plant_path: Path | None = None,
        motion_path: Path | None = None, cycles: float = 1.0, gains_path: Path | None = None, no_plots: bool = False,
        fmt: str = "csv", announce: Callable[[Mapping[str, Path]], None] | None = None) -> JobResult:
    """The generated machine ``machine`` (a registry name) tracking its built-in motion (``cycles``
    of it) or ``motion_path`` with ``controller``: the controller's model from ``params_path``, the
    plant's from ``plant_path`` (default: the controller's with the ``[mismatch]`` factors),
    ``gains_path`` over the built-in settings; ``control.csv`` (or ``.parquet``), ``summary.json``,
    the plots and ``report.html`` into ``out_dir``."""
    if motion_path is not None and cycles != 1.0:
        raise ParameterError("--cycles applies to the built-in motion, not to --motion")
    check_table_format(fmt)
    inputs = {"--params": params_path, "--plant-params": plant_path, "--motion": motion_path, "--gains": gains_path}
    check_output_dir(out_dir, inputs)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ControlWarning)
        warnings.simplefilter("ignore", RuntimeWarning)
        setup, settings, ls, g = _prepare(machine, controller, params_path, plant_path, motion_path, cycles, gains_path)
        files, summary, report = _stream(setup, controller, g, ls, settings, out_dir, not no_plots, gains_path,
                                         inputs, fmt, announce=announce)
        _warn_unstable(setup, controller)
    return JobResult(files, summary, (), _caught(caught), report=report)


# ----------------------------------------------------------------------------- a described mechanism
#: controllers a described mechanism takes (from its dynamics verbs; pkmdyn.control)
DESCRIBED_CONTROLLERS = ("computed-torque", "augmented-pd", "pd", "pid", "feedforward")


def described_control_settings(model) -> dict:
    """Control settings of a described mechanism, laid under ``--gains`` (no ``[mismatch]``: the
    plant is the controller's own model): 2 ms cycle, 1 ms plant step, exact pose feedback, effort
    limits the drives' rated efforts (``[[actuators]]`` ``max_torque_Nm`` or ``max_force_N``;
    far away without one), the efforts being the drives' motor efforts, divergence at 0.05 m or 0.2 rad of
    tracking error; every controller tuned for 5 Hz at damping 0.7 on the mechanism's inertia
    at its reference pose: computed torque ``kp = wn^2``, ``kd = 2 zeta wn`` [1/s^2, 1/s]; the
    task-space PD (and augmented PD) ``kp = wn^2 M_ii``, ``kd = 2 zeta wn M_ii`` with ``M`` the
    task mass matrix [N/m or N m/rad, ...]; the actuators' PID ``kp = wn^2 Ma_ii``,
    ``kd = 2 zeta wn Ma_ii``, ``ki = wn kp / 10`` with ``Ma = B^+ M B^+T`` (``B = J_ax^T K``) the inertia
    seen by each actuator. Keys ending ``_si`` are in SI units of their coordinate."""
    nt, na = model.nt, model.na
    wn, zeta = 2 * np.pi * 5.0, 0.7
    verbs = _verbs.machine_verbs(model)
    x0 = _multibody.reference_task(model)[None]
    M = verbs.mass_matrix(model, x0)[0]
    B = verbs.actuator_map(model, x0)[0]  # J_ax^T K (nt, na): the motors' map, K the drives' ratios
    Ma = np.linalg.pinv(B) @ M @ np.linalg.pinv(B.T) if na else np.zeros((0, 0))
    dm, da = np.abs(np.diag(M)), np.abs(np.diag(Ma))

    def lst(v) -> list[float]:
        return [float(f"{x:.6g}") for x in v]

    pd = {"kp_si": lst(wn * wn * dm), "kd_si": lst(2 * zeta * wn * dm)}
    limits = [float(v) if np.isfinite(v) else 1e9 for v in model.drive_max_effort]
    return {
        "timing": {"control_cycle_s": 0.002, "integration_step_s": 0.001},
        "actuators": {"effort_limit_si": limits},
        "sensors": {"encoder_counts_per_turn": 1000000, "encoder_travel_per_turn_m": 0.001,
                    "velocity_cutoff_Hz": 200.0, "acceleration_cutoff_Hz": 50.0, "pose_noise_si": [0.0] * nt,
                    "pose_delay_cycles": 0, "pose_feedback_from_sensor": 1, "seed": 1, "exact_encoders": 1},
        "run": {"divergence_limit_si": [0.05 if k else 0.2 for k in model.task_length]},
        "computed-torque": {"kp_1_s2": [wn * wn] * nt, "kd_1_s": [2 * zeta * wn] * nt},
        "pd": dict(pd),
        "augmented-pd": dict(pd),
        "pid": {"kp_si": lst(wn * wn * da), "ki_si": lst(wn * wn * wn * da / 10.0), "kd_si": lst(2 * zeta * wn * da)},
    }


def _control_load(model, motion, what: str, efforts: tuple[str, ...]):
    """The named load that a control run drives from its motion: ``(magnitudes [N] per sample,
    column)`` where the motion has the column of the mechanism's one named load, else ``(None,
    "")`` (the description's ``magnitude_N`` then holds, on the plant and in the controller
    alike). The loop carries one load: a motion with named-load columns for a mechanism with
    several is refused rather than run without them; so is a load whose name is that of an
    actuator's effort column of ``control.csv`` (``efforts``), which it would replace."""
    given = [nm for nm in model.named_loads if nm in motion.loads]
    if not given:
        return None, ""
    if len(model.named_loads) > 1:
        raise MotionError(f"{what}: column {given[0]!r}: control drives one named load from the motion, and "
                          f"{model.name!r} has {len(model.named_loads)} ({', '.join(model.named_loads)}); "
                          "remove the named-load columns to run on the description's magnitude_N")
    if given[0] in efforts:
        raise MotionError(f"{what}: column {given[0]!r}: the named load has the name of an actuator's effort column "
                          "of control.csv; rename the load (its [[loads]] name and the motion's column)")
    return motion.loads[given[0]], given[0]


def described_job(machine: str, controller: str, out_dir: Path, *, motion_path: Path | None = None,
                  gains_path: Path | None = None, duration_s: float | None = None, no_plots: bool = False,
                  fmt: str = "csv", announce: Callable[[Mapping[str, Path]], None] | None = None) -> JobResult:
    """The described mechanism ``machine`` (a built-in name or a description file) tracking its
    default motion or the task motion ``motion_path`` for ``duration_s`` [s] (default 1 s or the
    motion's length) with ``controller`` (:data:`DESCRIBED_CONTROLLERS`), in task space on its
    own dynamics (:func:`pkmdyn.multibody.dynamics.verbs.machine_verbs`), the controller the same
    model, at :func:`described_control_settings` with ``gains_path`` over them."""
    if controller not in DESCRIBED_CONTROLLERS:
        raise ParameterError(f"--controller {controller!r}: a described mechanism takes "
                             + ", ".join(DESCRIBED_CONTROLLERS))
    check_table_format(fmt)
    p = prepare(machine, out_dir, {"--motion": motion_path, "--gains": gains_path})
    model = p.model
    if model.na < model.nt:
        # the sensors' pose and rates come through the actuated joints (the encoders' direct
        # kinematics), and the laws' efforts map a task effort: neither is defined with fewer
        # actuators than freedoms (no under-actuated controller yet)
        raise ParameterError(f"{machine}: mechanism {model.name!r} is under-actuated ({model.na} actuator(s) for "
                             f"{model.nt} degrees of freedom): pkmdyn control's sensors and laws need as many "
                             "actuators as freedoms; pkmdyn run simulates its passive freedoms along its default "
                             "motion or an --actuator-motion")
    if motion_path is not None:
        motion = _multibody.read_task_motion(model, Path(motion_path).absolute())
        what = str(motion_path)
    else:
        motion = _multibody.default_motion(model)
        what = "the default motion"
    span = float(motion.t[-1] - motion.t[0])
    duration_s = min(1.0, span) if duration_s is None else duration_s
    if not duration_s <= span:
        raise MotionError(f"--duration: {duration_s:g} s must be at most the motion's {span:g} s")
    notes: list[str] = []
    limited = _inverse.limited_joints(model)
    if limited:  # the plant has no end stops: say where the reference leaves the joint limits
        span_mask = motion.t <= motion.t[0] + duration_s
        kin = _multibody.solve_kinematics(model, motion.x[span_mask], motion.xd[span_mask], motion.xdd[span_mask],
                                          motion.t[span_mask])
        beyond = _inverse.limit_message(model, kin)
        if beyond is not None:
            notes.append(f"the reference motion leaves the joint limits: {beyond}")
    settings = _control.overlay_settings(described_control_settings(model), gains_path)
    ls = _control.loop_settings(settings)
    if np.any(model.drive_encoder > 0):  # a drive's own encoder, counts per motor turn, in motor radians
        ls = replace(ls, encoder_resolution=np.where(model.drive_encoder > 0, model.drive_encoder,
                                                     float(ls.encoder_resolution)))
    check_loop(ls, duration_s, gains_path)
    verbs = _verbs.machine_verbs(model)
    load, column = _control_load(model, motion, what, verbs.ACTUATORS)
    fn = _control.hermite_motion(motion.t, motion.x, motion.xd, motion.xdd, load)
    encoders = tuple((d, "encoder_counts_per_turn" if u == "rad" else "encoder_counts_per_m", u) if r > 0 else None
                     for d, r, u in zip(model.drive_name, model.drive_encoder, model.motor_units))
    setup = _Setup(model.name, verbs, model, model, fn, duration_s, load is not None, str(p.path),
                   "the controller's model", what, span_s=span, load_column=column, drive_encoders=encoders)
    _check_encoder(setup, ls, settings, gains_path)
    n = model.na if controller == "pid" else model.nt
    files, summary, report = _stream(setup, controller, _control.gains(settings, controller, n), ls, settings,
                                     out_dir, not no_plots, gains_path, dict(p.inputs), fmt, announce=announce)
    return JobResult(files, summary, (), tuple(notes), report=report)
