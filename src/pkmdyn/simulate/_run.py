"""One closed-loop tracking run of any machine, from its verbs, two models and a motion."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ._loop import LoopResult, LoopSettings, closed_loop
from ._plant import make_plant

__all__ = ["Tracking", "track"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Tracking:
    """A run: the reference on the control grid, the joint reference of the controller's model,
    the loop's records and the controller (see :class:`~pkmdyn.simulate.LoopResult`)."""

    reference: Any
    joint: Any
    result: LoopResult
    controller: Any
    fast_path: bool


def track(verbs: Any, model: Any, plant_model: Any, motion: Any, duration: float, kind: str,
          gains: Any, settings: LoopSettings, has_load: bool, progress: bool = False,
          joint_accelerations: bool = False) -> Tracking:
    """Track ``motion`` (``t -> q, qd, qdd, load``) for ``duration`` [s] with controller ``kind``.

    ``model`` is the controller's model, ``plant_model`` the simulated machine's (they may
    differ); ``verbs`` the machine's ``minimal`` module. Everything the controller needs from
    its model along the reference is computed first, in batched calls; the loop then calls the
    plant's single-sample forward dynamics (fast path) where the machine offers it.
    """
    from ..control._laws import make_controller
    from ..control._reference import joint_reference, sample_reference
    from ._loop import check_timing

    check_timing(settings.cycle_s, settings.step_s)
    ref = sample_reference(motion, duration, settings.cycle_s)
    joint = joint_reference(verbs, model, ref, motion, joint_accelerations)
    plant_joint = joint if plant_model is model else joint_reference(verbs, plant_model, ref, motion, False)
    ctrl = make_controller(kind, gains, verbs, model, ref, joint)
    rate_map = np.linalg.inv(joint.Bt)
    plant = make_plant(verbs, plant_model, has_load)
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
    res = closed_loop(plant, ctrl, ref, plant_joint, joint, rate_map, settings, loads=loads, progress=progress)
    return Tracking(ref, joint, res, ctrl, plant.fast)
