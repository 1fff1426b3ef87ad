"""One closed-loop tracking run of any machine, from its verbs, two models and a motion."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, replace
from functools import cached_property, partial
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..control._laws import make_controller
from ..control._reference import JointReference, Reference, joint_reference, reference_window, sample_reference
from ..errors import MotionError
from ._loop import LoopResult, LoopSettings, check_timing, closed_loop, new_loop_state, run_span
from ._plant import make_plant

__all__ = ["Tracking", "track", "track_spans", "SPAN_CYCLES"]

#: control cycles of one span of :func:`track_spans` (its arrays: some megabytes)
SPAN_CYCLES = 20_000

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Tracking:
    """A run: the reference on the control grid, the joint reference of the controller's model
    (:attr:`joint`), the loop's records and the controller (see
    :class:`~pkmdyn.simulate.LoopResult`). ``joint_source`` is the joint reference, or a function
    that computes it on first use (a run whose loop did not read it, :func:`track`)."""

    reference: Any
    joint_source: Any
    result: LoopResult
    controller: Any
    fast_path: bool

    @cached_property
    def joint(self) -> Any:
        """The controller's :class:`~pkmdyn.control.JointReference` along :attr:`reference`."""
        src = self.joint_source
        return src() if callable(src) else src


def loop_reads_joint(kind: str, settings: LoopSettings) -> bool:
    """Whether a loop with controller ``kind`` reads the joint references along the run: the
    encoders' first-order model and its pose estimate do, and so do the joint-space PID and the
    task-space PD laws (the actuator map); with exact encoders, computed torque and feedforward
    read only the first instant's actuator rates and accelerations (the filters' start)."""
    return not settings.exact_encoders or kind not in ("computed-torque", "feedforward")


def _part(r: Any, o: int, n: int) -> Any:
    """Cycles ``o .. o + n`` of the reference ``r`` (its instants ``o .. o + n``)."""
    mid = slice(o, o + n)
    full = slice(o, o + n + 1)
    return Reference(r.T, r.t[full], r.q[full], r.qd[full], r.qdd[full], None if r.load is None else r.load[full],
                     r.mid_q[mid], r.mid_qd[mid], r.mid_qdd[mid], None if r.mid_load is None else r.mid_load[mid])


def _rate_map(Bt: Array) -> Array:
    """The controller's ``(B^T)^-1 (K + 1, nq, nu)`` along the reference: the task rates of the
    actuators' rates (a redundantly actuated machine's, more actuators than coordinates: the
    least-squares ``(B^T)^+``)."""
    return np.linalg.inv(Bt) if Bt.shape[-1] == Bt.shape[-2] else np.linalg.pinv(Bt)


def _first_instant(joint: Any, nq: int) -> tuple[Any, Array]:
    """A joint reference and a rate map of the first instant alone, for a loop that reads no more
    of them (:func:`loop_reads_joint`)."""
    one = JointReference(joint.Bt[:1], joint.s[:1], joint.sd[:1], joint.sdd[:1])
    return one, np.zeros((1, nq, joint.Bt.shape[1]))


def track(verbs: Any, model: Any, plant_model: Any, motion: Any, duration: float, kind: str,
          gains: Any, settings: LoopSettings, has_load: bool, progress: bool = False,
          joint_accelerations: bool = False) -> Tracking:
    """Track ``motion`` (``t -> q, qd, qdd, load``) for ``duration`` [s] with controller ``kind``.

    ``model`` is the controller's model, ``plant_model`` the simulated machine's (they may
    differ); ``verbs`` the machine's verbs (:class:`pkmdyn.machine_protocol.MachineDynamics`). Everything the controller needs from
    its model along the reference is computed first, in batched calls; the loop then calls the
    plant's single-sample forward dynamics (fast path) where the machine offers it. Where the
    loop reads no more than the first instant of the joint references
    (:func:`loop_reads_joint`: exact encoders, computed torque or feedforward), the result's
    joint reference is computed when first read (:attr:`Tracking.joint`: the same numbers, to
    the kinematics' tolerance, or the same error). A reference that leaves the controller
    model's workspace is then not refused before the run, naming its sample, but stops the run
    where the loop gets there (a :class:`DivergenceError` naming the time; feedforward's
    batched inverse dynamics still refuses it before).
    """

    check_timing(settings.cycle_s, settings.step_s)
    ref = sample_reference(motion, duration, settings.cycle_s)
    plant = make_plant(verbs, plant_model, has_load)
    if loop_reads_joint(kind, settings):
        joint = joint_reference(verbs, model, ref, motion, joint_accelerations)
        plant_joint = joint if plant_model is model else joint_reference(verbs, plant_model, ref, motion, False)
        rate_map = _rate_map(joint.Bt)
        joint_source: Any = joint
    else:
        # the loop reads the first instant alone: the whole joint reference when the result's
        # reader asks for it (Tracking.joint), not before the run
        joint, rate_map = _first_instant(joint_reference(verbs, model, _part(ref, 0, 1), motion, joint_accelerations),
                                         plant.nq)
        plant_joint = joint
        joint_source = partial(joint_reference, verbs, model, ref, motion, joint_accelerations)
    ctrl = make_controller(kind, gains, verbs, model, ref, joint)
    loads = None
    if ref.load is not None:
        # the plant feels the motion's own load at every step boundary and middle (with one
        # step per cycle: the reference's samples at the cycle instants and middles)
        steps = check_timing(settings.cycle_s, settings.step_s)
        if steps == 1 and ref.mid_load is not None:
            loads = np.empty(2 * ref.cycles + 1)
            loads[0::2] = ref.load
            loads[1::2] = ref.mid_load
        else:
            tt = np.arange(2 * ref.cycles * steps + 1) * (0.5 * settings.cycle_s / steps)
            loads = np.asarray(motion(tt)[3], dtype=float)
    res = closed_loop(plant, ctrl, ref, plant_joint, joint, rate_map, settings, loads=loads, progress=progress,
                      ctrl_model=model)
    return Tracking(ref, joint_source, res, ctrl, plant.fast)


def track_spans(verbs: Any, model: Any, plant_model: Any, motion: Any, duration: float, kind: str,
                gains: Any, settings: LoopSettings, has_load: bool, progress: bool = False,
                joint_accelerations: bool = False, span_cycles: int | None = None) -> Iterator[Tracking]:
    """:func:`track`, computed and handed out span by span: yields one :class:`Tracking` per
    ``span_cycles`` control cycles (default :data:`SPAN_CYCLES`; the last may be shorter), so that memory does not grow with
    the run. Each span's ``reference`` and ``joint`` cover its own cycles (``K + 1`` instants,
    as :func:`track`'s cover the whole run), its ``result`` holds its records.

    Every span is computed on a window one cycle wider at each side, so that the interval
    efforts and the actuator displacements (which use their neighbours) are those of the whole
    run; the loop's state (plant, filters, controller memory, noise, the delayed pose) carries
    over. The spans' records joined equal :func:`track`'s up to rounding.
    """

    steps = check_timing(settings.cycle_s, settings.step_s)
    T = settings.cycle_s
    K = int(round(duration / T))
    if K < 1:
        raise MotionError(f"motion: {duration:g} s is shorter than one control cycle ({T:g} s)")
    span_cycles = SPAN_CYCLES if span_cycles is None else int(span_cycles)
    if span_cycles < 1:
        raise ValueError(f"span_cycles: {span_cycles} must be >= 1")
    plant = make_plant(verbs, plant_model, has_load)
    reads = loop_reads_joint(kind, settings)

    def anchored(joint: JointReference, o: int, s0: Array | None) -> JointReference:
        return joint if s0 is None else replace(joint, s=joint.s - joint.s[o] + s0)

    state = None
    s_ctrl = s_plant = None
    bar = None
    if progress and K >= 2000:
        from tqdm import tqdm

        bar = tqdm(total=K, desc="closed loop", unit="cycle", leave=False, disable=None, mininterval=0.5)
    try:
        for k0 in range(0, K, span_cycles):
            k1 = min(K, k0 + span_cycles)
            w0, w1 = max(0, k0 - 1), min(K, k1 + 1)
            o, n = k0 - w0, k1 - k0
            ref = reference_window(motion, T, w0, w1)
            joint = anchored(joint_reference(verbs, model, ref, motion, joint_accelerations), o, s_ctrl)
            if reads:
                plant_joint = joint if plant_model is model else anchored(
                    joint_reference(verbs, plant_model, ref, motion, False), o, s_plant)
                rate_map = _rate_map(joint.Bt)
            else:  # the span's records carry the controller's joint reference; the loop reads neither
                plant_joint, rate_map = _first_instant(joint, plant.nq)
            ctrl = make_controller(kind, gains, verbs, model, ref, joint)
            loads = None
            if ref.load is not None:
                if steps == 1 and ref.mid_load is not None:
                    loads = np.empty(2 * ref.cycles + 1)
                    loads[0::2] = ref.load
                    loads[1::2] = ref.mid_load
                else:
                    tt = (2 * w0 * steps + np.arange(2 * ref.cycles * steps + 1)) * (0.5 * T / steps)
                    loads = np.asarray(motion(tt)[3], dtype=float)
            if state is None:
                state = new_loop_state(plant, ctrl, ref, joint, settings, model)
            res = run_span(plant, ctrl, ref, plant_joint, joint, rate_map, settings, state, o, n, loads=loads, bar=bar,
                           last=k1 == K)
            s_ctrl = joint.s[o + n].copy()
            s_plant = plant_joint.s[o + n].copy() if reads else None
            jp = slice(o, o + n + 1)
            yield Tracking(_part(ref, o, n), JointReference(joint.Bt[jp], joint.s[jp], joint.sd[jp], joint.sdd[jp]), res,
                           ctrl, plant.fast)
    finally:
        if bar is not None:
            bar.close()
