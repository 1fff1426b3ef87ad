"""Closed-loop simulation of any machine through its verbs (:mod:`pkmdyn.machine_protocol`).

``_plant``: the integrator of the forward dynamics with efforts held over each control cycle
(a third-order explicit step where the motion is smooth, the linearly implicit ROS2 in the
friction band); ``_loop``: encoders, pose sensor, controller and effort limits, once
per control cycle. Nothing here imports a machine.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

if TYPE_CHECKING:
    from ._loop import DivergenceError, LoopResult, LoopSettings, check_timing, closed_loop
    from ._run import SPAN_CYCLES, Tracking, track, track_spans
    from ._plant import EXPLICIT_LIMIT, METHODS, ROS2_GAMMA, Plant, accelerations, hold_interval, make_plant, make_work

__all__ = [
    "Plant",
    "make_plant",
    "make_work",
    "accelerations",
    "hold_interval",
    "ROS2_GAMMA",
    "METHODS",
    "EXPLICIT_LIMIT",
    "LoopSettings",
    "LoopResult",
    "DivergenceError",
    "closed_loop",
    "check_timing",
    "Tracking",
    "track",
    "track_spans",
    "SPAN_CYCLES",
]

#: where each public name lives, imported on first use: ``import pkmdyn.simulate`` loads
#: neither Numba nor SciPy until a function is looked up
__getattr__, __dir__ = attach(__name__, {
    **dict.fromkeys(("DivergenceError", "LoopResult", "LoopSettings", "check_timing", "closed_loop"), "._loop"),
    **dict.fromkeys(("SPAN_CYCLES", "Tracking", "track", "track_spans"), "._run"),
    **dict.fromkeys(("EXPLICIT_LIMIT", "METHODS", "ROS2_GAMMA", "Plant", "accelerations", "hold_interval",
                     "make_plant", "make_work"), "._plant"),
})
