"""The closed loop: sensors -> controller -> held efforts -> plant, once per control cycle.

Per cycle ``k`` (instant ``t_k = k T``):

1. **Encoders.** The actuator displacement ``s`` (a motor's angle [rad] behind a
   screw, a limb's extension [m]) from the start, read as a whole number of counts: ``s_enc = res floor(s / res)``,
   ``res`` = travel per turn / counts per turn. With ``exact_encoders`` the true ``s`` is the
   plant's own: its actuated joints' coordinates at the present pose by its inverse kinematics,
   ``s = k (a(q) - a(q_0))`` (``k`` the drives' ratios, ``q_0`` the run's first pose); else it
   is taken to first order in the tracking error about the plant's own reference displacement,
   ``s = s_ref + B_p(q_ref)^T (q - q_ref)`` (``B_p`` the plant's actuator map; the neglected
   second-order term is ``O(|q - q_ref|^2)``, below one count for the errors these loops
   produce; the built-in machines' default). Rate: backward difference ``(s_enc,k - s_enc,k-1) / T`` through a first-order
   low-pass filter (cutoff ``velocity_cutoff_Hz``); acceleration: backward difference of the
   filtered rate through a second low-pass filter (``acceleration_cutoff_Hz``) - the chain of
   the PDM paper's section 7 (position differentiated twice, filtered). A cutoff of 0 means no
   filter. The filter is ``y += a (x - y)``, ``a = 1 - exp(-2 pi f_c T)``; both filters start
   on the reference's rate and acceleration (the loop starts in steady state on the reference).
2. **Pose.** The pose sensor (an attitude heading reference system, say) reads the pose
   ``delay`` cycles ago plus Gaussian noise of the given standard deviation per coordinate
   (seeded generator); it is recorded, and fed back only with ``pose_from_sensor``. By
   default the controller's pose comes from the encoders through the controller's model: with
   ``exact_encoders`` by its direct kinematics (:mod:`pkmdyn.multibody.kinematics.direct`, warm-started
   from the previous cycle), ``q_s = DK(a_0 + s_enc / k)`` with the rate ``qd_s = (dq/da)
   sd_enc / k``; else to first order about the reference,
   ``q_s = q_ref + (B(q_ref)^T)^-1 (s_enc - s_ref)``, ``qd_s = (B(q_ref)^T)^-1 sd_enc``.
3. **Controller** (:func:`pkmdyn.control.effort`) -> efforts, clipped to the effort limits.
4. **Plant**: the efforts held over the cycle, ``T / dt`` steps of the integrator
   (:mod:`pkmdyn.simulate._plant`), the load evaluated at every step boundary and middle.

A run diverges when the state stops being finite, a tracking error exceeds its
``divergence_limit`` or the machine's verbs fail (singular pose); :class:`DivergenceError`
names the time.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..control._laws import Sensed, _ct_acc, _pd, _pid, effort, new_memory
from ..control._settings import LoopSettings
from ..errors import ParameterError, PkmdynError
from . import _cycles
from ._plant import (
    Plant,
    _piecewise,
    _rk3_finish,
    _rk_stage,
    _stage1,
    _stage2,
    _stale,
    _stiffness,
    accelerations,
    hold_interval,
    make_work,
)
from ._sensors import _actuate, _sense

__all__ = ["LoopSettings", "LoopResult", "LoopState", "DivergenceError", "ExactEncoders", "closed_loop", "run_span",
           "new_loop_state", "check_timing"]

Array = NDArray[np.float64]


class DivergenceError(PkmdynError):
    """A closed-loop run that went unstable; the message names the time.

    Where a tracking error crossed its limit, ``coordinate`` is its index, ``error`` and
    ``limit`` the values in SI (rad or m) and ``t`` the time [s], so that a caller who knows the
    coordinates' names and units can say it in them."""

    def __init__(self, message: str, coordinate: int | None = None, error: float = float("nan"),
                 limit: float = float("nan"), t: float = float("nan")) -> None:
        super().__init__(message)
        self.coordinate, self.error, self.limit, self.t = coordinate, error, limit, t


@dataclass(frozen=True)
class LoopResult:
    """One row per cycle ``k = 0 .. K - 1`` at ``t_k``: true ``q, qd (K, nq)``, held efforts
    ``u (K, nu)`` (after the limits), the controller's pose and rate ``q_s, qd_s (K, nq)``, the
    pose sensor's reading ``q_att (K, nq)``, true actuator
    displacement ``s (K, nu)``, encoder ``s_enc, sd_enc, sdd_enc (K, nu)``; the state at the
    end ``q_end, qd_end (nq,)``; ``saturated (K, nu)`` where an effort hit its limit."""

    t: Array
    q: Array
    qd: Array
    u: Array
    q_s: Array
    qd_s: Array
    q_att: Array
    s: Array
    s_enc: Array
    sd_enc: Array
    sdd_enc: Array
    q_end: Array
    qd_end: Array
    saturated: Array


#: cycles per compiled call (the progress bar moves between calls)
CHUNK = 1000


def check_timing(cycle_s: float, step_s: float) -> int:
    """Integration steps per cycle; the cycle must be a positive whole multiple of the step."""
    for name, v in (("control_cycle_s", cycle_s), ("integration_step_s", step_s)):
        if not (np.isfinite(v) and v > 0):
            raise ParameterError(f"[timing] {name}: {v:g} must be finite and > 0")
    ratio = cycle_s / step_s
    n = int(round(ratio))
    if n < 1 or abs(ratio - n) > 1e-9 * max(1.0, ratio):
        raise ParameterError(
            f"[timing] control_cycle_s = {cycle_s:g} s is not a positive whole multiple of "
            f"integration_step_s = {step_s:g} s (ratio {ratio:.6g})")
    return n


def _alpha(fc: float, T: float) -> float:
    return 1.0 if fc <= 0 else float(1.0 - np.exp(-2.0 * np.pi * fc * T))


@dataclass
class LoopState:
    """What a closed loop carries from one cycle to the next (mutable; :func:`new_loop_state`):
    the plant's ``q, qd``, the sensed buffers ``y``, the controller's ``memory``, the integrator's
    ``work``, the encoder's previous reading and filtered rate, the noise generator, the pose
    records the delayed pose sensor still needs (``history``, at most ``delay`` rows), the
    cycles done and, with exact encoders, their :class:`ExactEncoders`. With it a run can be
    computed span by span in bounded memory (:func:`pkmdyn.simulate.track_spans`); the spans
    join exactly."""

    q: Array
    qd: Array
    y: Any
    memory: Array
    work: Any
    s_prev: Array
    sd_prev: Array
    rng: Any
    history: Array
    done: int = 0
    exact: Any = None


def compile_cycle_kernels() -> None:
    """Compile (or load) the cycle's own small kernels - the sensors', the limits', the laws' and
    the default integrator's - by calling each once on small arrays of the types the loop passes, so
    that they are compiled (or loaded from the cache) before the loop's first cycle."""

    v, m2, m3 = np.zeros(2), np.zeros((1, 2)), np.zeros((1, 2, 2))
    one = np.ones(2)
    _sense(0, 0, 0, True, True, v, v, v, one, m2, False, (m2, m2, m3, m2, m3), (one, 1.0, 1.0, 1.0),
           tuple(v.copy() for _ in range(7)), tuple(np.zeros((1, 2)) for _ in range(9)))
    _actuate(0, v, one, v.copy(), np.zeros((1, 2)), np.zeros((1, 2), dtype=bool))
    _ct_acc(0, m2, m2, m2, v, v, v, v, v.copy())
    _pd(0, m2, m2, v, v, v, v, m3, m2, False, v.copy())
    _pid(0, 1.0, m2, m2, v, v, v, v, v, v.copy(), v.copy())
    buf, A, W = np.zeros((8, 2)), np.zeros((2, 2)), np.zeros((2, 2, 2))
    _rk_stage(v, v, v, v, 1.0, buf[2], buf[3])
    _rk3_finish(v.copy(), v.copy(), v, v, v, 1.0, buf[6:8])
    _stage1(v, v, v, A, 1.0, W, buf)
    _stage2(v.copy(), v.copy(), v, 1.0, W, buf)
    _stiffness(A)
    _stale(v, v, 0.05)
    _piecewise(0.0, 0.5, 1.0, 0.25)


class ExactEncoders:
    """The encoders of a plant read through its kinematics (module docstring, items 1-2): the
    plant's actuated joint coordinates at its pose (``verbs.actuator_coordinates_one``) as the
    motors' displacement from the run's first pose, and the controller's pose from the reading
    by its model's direct kinematics (``verbs.direct_one``), primed at the run's first pose where
    the verbs can (``verbs.prime_direct``: the controller knows where its run starts). ``ratio
    (nu,)`` the drives' ratios (1 for a joint without one)."""

    def __init__(self, plant: Plant, ctrl_model: Any, q0: Array) -> None:
        verbs = plant.verbs
        if not (hasattr(verbs, "actuator_coordinates_one") and hasattr(verbs, "direct_one")):
            raise ParameterError("[sensors] exact_encoders: this machine's verbs have no single-sample inverse and "
                                 "direct kinematics; set exact_encoders = 0")
        self.verbs, self.plant_model, self.ctrl_model = verbs, plant.model, ctrl_model
        self.ratio = np.asarray(verbs.drive_ratios(plant.model), dtype=float)
        zero = np.zeros_like(q0)
        self.a0_plant = verbs.actuator_coordinates_one(plant.model, q0, zero, fresh=True)
        self.a0_ctrl = verbs.actuator_coordinates_one(ctrl_model, q0, zero, fresh=True)
        prime = getattr(verbs, "prime_direct", None)
        if prime is not None:  # the controller knows the pose its run starts from
            compile_cycle_kernels()
            prime(ctrl_model, q0)

    def read(self, q: Array, qd: Array, out: Array) -> None:
        """The plant's motor displacement at its pose ``q`` into ``out (nu,)``."""
        out[:] = self.ratio * (self.verbs.actuator_coordinates_one(self.plant_model, q, qd) - self.a0_plant)

    def pose(self, s: Array, sd: Array) -> tuple[Array, Array]:
        """The controller's pose and rate from the motors' reading ``s, sd``."""
        return self.verbs.direct_one(self.ctrl_model, self.a0_ctrl + s / self.ratio, sd / self.ratio)


def new_loop_state(plant: Plant, controller: Any, ref: Any, ctrl_joint: Any, settings: LoopSettings,
                   ctrl_model: Any = None) -> LoopState:
    """The state at the start of a run: the plant on the reference's initial state, the filters
    on the reference's rate and acceleration (the loop starts in steady state on it); with
    ``settings.exact_encoders`` the encoders through the kinematics of the plant and of the
    controller's model ``ctrl_model`` (:class:`ExactEncoders`)."""
    nq, nu = plant.nq, plant.nu
    y = Sensed(np.empty(nq), np.empty(nq), np.empty(nu), ctrl_joint.sd[0].astype(float).copy(),
               ctrl_joint.sdd[0].astype(float).copy())
    q0 = ref.q[0].astype(float).copy()
    if plant.kernel is not None:
        # the plant's single-sample kernel started at the run's first state, so that the first
        # cycle finds it solved (a cold kernel sends its first call to the checked route); a
        # state it cannot solve is left to the first cycle to report
        try:
            accelerations(plant, q0, ref.qd[0].astype(float), np.zeros(nu), 0.0)
        except PkmdynError:
            pass
    exact = ExactEncoders(plant, plant.model if ctrl_model is None else ctrl_model, q0) \
        if settings.exact_encoders else None
    return LoopState(q0, ref.qd[0].astype(float).copy(), y, new_memory(controller, nu),
                     make_work(plant, settings.method), np.zeros(nu), y.sd.copy(),
                     np.random.default_rng(settings.seed), np.empty((0, nq)), exact=exact)


def closed_loop(plant: Plant, controller: Any, ref: Any, plant_joint: Any, ctrl_joint: Any, rate_map: Array,
                settings: LoopSettings, loads: Array | None = None, progress: bool = False,
                ctrl_model: Any = None) -> LoopResult:
    """Run the loop over the reference's ``K`` cycles from the reference's initial state.

    ``controller`` from :func:`pkmdyn.control.make_controller`; ``ref`` its
    :class:`~pkmdyn.control.Reference`; ``plant_joint``, ``ctrl_joint`` the plant's and the
    controller's :class:`~pkmdyn.control.JointReference` (encoder model; pose from the
    encoders); ``rate_map (K + 1, nq, nu)`` the controller's ``(B^T)^-1`` along the reference
    (with exact encoders the loop reads the controller's joint reference at its first instant
    alone, the filters' start, and neither the plant's nor ``rate_map``: they may hold that
    instant alone, :func:`pkmdyn.simulate.track`);
    ``loads (2 K steps + 1,)`` the load [N] at every integration step boundary and middle,
    ``j dt / 2`` (None: the reference load, linear within a cycle; zeros for a machine without
    load; :func:`pkmdyn.simulate.track` passes the motion's own load); ``ctrl_model`` the
    controller's model (exact encoders; default the plant's).
    """
    state = new_loop_state(plant, controller, ref, ctrl_joint, settings, ctrl_model)
    bar = None
    if progress and ref.cycles >= 2000:
        from tqdm import tqdm

        bar = tqdm(total=ref.cycles, desc="closed loop", unit="cycle", leave=False, disable=None, mininterval=0.5)
    try:
        return run_span(plant, controller, ref, plant_joint, ctrl_joint, rate_map, settings, state, 0, ref.cycles,
                        loads=loads, bar=bar, last=True)
    finally:
        if bar is not None:
            bar.close()


def run_span(plant: Plant, controller: Any, ref: Any, plant_joint: Any, ctrl_joint: Any, rate_map: Array,
             settings: LoopSettings, state: LoopState, first: int, n: int, loads: Array | None = None,
             bar: Any = None, last: bool = False) -> LoopResult:
    """Run ``n`` cycles from ``state`` (updated in place), the first of them at row ``first`` of
    the reference arrays (``ref``, the joint references, ``rate_map``, ``loads`` and the
    controller's precomputed arrays all cover the same rows, e.g. a window of a longer run).
    Returns the records of these cycles; ``last``: the run ends here (its end state is checked)."""
    T = settings.cycle_s
    steps = check_timing(T, settings.step_s)
    dt = T / steps
    K = ref.cycles
    nq, nu = plant.nq, plant.nu
    if loads is None:
        if ref.load is None:
            loads = np.zeros(2 * K * steps + 1)
        else:
            tt = np.arange(2 * K * steps + 1) * (0.5 * dt)
            loads = np.interp(tt, ref.t - ref.t[0], ref.load)
    loads = np.asarray(loads, dtype=float)
    if loads.shape != (2 * K * steps + 1,):
        raise ValueError(f"loads: expected {2 * K * steps + 1} values (step boundaries and middles), got {loads.shape}")
    if not (0 <= first and first + n <= K):
        raise ValueError(f"cycles {first} to {first + n}: outside the reference's {K} cycles")
    delay = int(settings.pose_delay_cycles)
    pre = state.history.shape[0]
    rows = pre + n
    noise = np.zeros((rows, nq))
    noise[pre:] = state.rng.standard_normal((n, nq)) * settings.pose_noise
    a_v = _alpha(settings.velocity_cutoff_Hz, T)
    a_a = _alpha(settings.acceleration_cutoff_Hz, T)
    res = np.ascontiguousarray(np.broadcast_to(np.asarray(settings.encoder_resolution, dtype=float), (nu,)))
    lim = np.asarray(settings.effort_limit, dtype=float)
    div = np.asarray(settings.divergence_limit, dtype=float)
    from_sensor = bool(settings.pose_from_sensor)

    out_q = np.empty((rows, nq)); out_qd = np.empty((rows, nq)); out_u = np.empty((rows, nu))
    out_att = np.empty((rows, nq)); out_qds = np.empty((rows, nq)); out_s = np.empty((rows, nu))
    out_se = np.empty((rows, nu)); out_sde = np.empty((rows, nu)); out_sdde = np.empty((rows, nu))
    out_qs = np.empty((rows, nq))
    sat = np.zeros((rows, nu), dtype=bool)
    out_q[:pre] = state.history
    q, qd, y, memory, work = state.q, state.qd, state.y, state.memory, state.work
    exact = state.exact
    s_exact = np.zeros(nu)
    u = np.empty(nu)
    q_ref = np.ascontiguousarray(ref.q)
    args = (q, qd, div, noise, from_sensor,
            (q_ref, np.ascontiguousarray(plant_joint.s), np.ascontiguousarray(plant_joint.Bt),
             np.ascontiguousarray(ctrl_joint.s), np.ascontiguousarray(rate_map)), (res, T, a_v, a_a),
            (state.s_prev, state.sd_prev, y.q, y.qd, y.s, y.sd, y.sdd),
            (out_q, out_qd, out_att, out_s, out_qs, out_qds, out_se, out_sde, out_sdde))
    done = state.done

    def cycle(i: int) -> None:
        """Cycle ``i`` of the span in Python (the compiled cycles hand back any cycle they do not take)."""
        kr, k, g = first + i, pre + i, done + i
        if exact is not None:
            try:
                exact.read(q, qd, s_exact)
            except PkmdynError as exc:
                raise DivergenceError(f"run diverged at t = {ref.t[kr]:.4f} s: {exc}") from None
        bad = _sense(kr, k, k - delay if g >= delay else 0, g == 0, exact is not None, s_exact, *args)
        if bad >= 0:
            e = q[bad] - q_ref[kr, bad]
            raise DivergenceError(
                f"run diverged at t = {ref.t[kr]:.4f} s: tracking error of coordinate {bad + 1} is "
                f"{e:.3g}, beyond its divergence limit {div[bad]:g}", bad, float(e), float(div[bad]),
                float(ref.t[kr]))
        if exact is not None:  # the controller's pose by the direct kinematics of the reading
            try:
                xs, xds = exact.pose(y.s, y.sd)
            except PkmdynError as exc:
                raise DivergenceError(f"run diverged at t = {ref.t[kr]:.4f} s: {exc}") from None
            if not from_sensor:
                y.q[:] = xs
                out_qs[k] = xs
            y.qd[:] = xds
            out_qds[k] = xds
        _actuate(k, effort(controller, ref, kr, y, memory), lim, u, out_u, sat)
        try:
            hold_interval(plant, q, qd, u, loads[2 * kr * steps:2 * (kr + 1) * steps + 1], dt, work)
        except PkmdynError as exc:
            raise DivergenceError(f"run diverged at t = {ref.t[kr]:.4f} s: {exc}") from None

    fast = None
    next_try = 0
    i = 0
    while i < n:
        if fast is None and i >= next_try and settings.compiled_cycles:
            if _cycles.available(n - i):
                fast = _cycles.compiled_cycles(plant, controller, ref, exact, work, args, loads, lim, u, out_u, sat,
                                               memory, s_exact, steps, dt)
            next_try = i + (1 if i < 2 else CHUNK)
        j = i
        if fast is not None:
            j = fast.run(i, min(n, i + CHUNK), first, pre, done, delay)
        if j < n and (fast is None or j < min(n, i + CHUNK)):
            cycle(j)  # a cycle the compiled call did not take (or no compiled call)
            j += 1
        if bar is not None and (done + j) // 1000 > (done + i) // 1000:
            bar.update(1000 * ((done + j) // 1000 - (done + i) // 1000))
        i = j
    state.done = done + n
    state.history = out_q[max(0, rows - delay):rows].copy() if delay else np.empty((0, nq))
    if last and not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd))):
        raise DivergenceError(f"run diverged at t = {ref.t[first + n]:.4f} s: the state is not finite")
    return LoopResult(ref.t[first:first + n].copy(), out_q[pre:], out_qd[pre:], out_u[pre:], out_qs[pre:],
                      out_qds[pre:], out_att[pre:], out_s[pre:], out_se[pre:], out_sde[pre:], out_sdde[pre:],
                      q.copy(), qd.copy(), sat[pre:])
