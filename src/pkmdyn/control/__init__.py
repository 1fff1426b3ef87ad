"""Trajectory-tracking controllers for any machine, written against its verbs only.

``_reference``: the reference on the control grid and the actuator displacements along it;
``_settings``: the settings files (timing, sensors, limits, gains; each machine's built-in
file) and the loop's settings (:class:`LoopSettings`, which :mod:`pkmdyn.simulate` takes:
the simulation imports the controllers, never the other way); ``_laws``: the controllers (feedforward, the workspace PD and augmented PD of Chen,
Cheng & Pang 2022, a joint-space PID, computed torque) behind one function, :func:`effort`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

if TYPE_CHECKING:
    from ._laws import (CONTROLLERS, Controller, Gains, Sensed, check_gains, effort, held_efforts, make_controller,
                        new_memory)
    from ._settings import (LoopSettings, default_settings_text, gains, load_settings, loop_settings, overlay_settings,
                            scale_description)
    from ._reference import JointReference, Reference, hermite_motion, joint_reference, sample_reference

__all__ = [
    "CONTROLLERS",
    "Gains",
    "Sensed",
    "Controller",
    "make_controller",
    "check_gains",
    "effort",
    "new_memory",
    "held_efforts",
    "Reference",
    "JointReference",
    "sample_reference",
    "joint_reference",
    "hermite_motion",
    "default_settings_text",
    "load_settings",
    "overlay_settings",
    "loop_settings",
    "LoopSettings",
    "gains",
    "scale_description",
]

#: where each public name lives, imported on first use: ``import pkmdyn.control`` loads
#: neither Numba nor SciPy until a function is looked up
__getattr__, __dir__ = attach(__name__, {
    **dict.fromkeys(("CONTROLLERS", "Controller", "Gains", "Sensed", "check_gains", "effort", "held_efforts",
                     "make_controller", "new_memory"), "._laws"),
    **dict.fromkeys(("LoopSettings", "default_settings_text", "gains", "load_settings", "loop_settings",
                     "overlay_settings", "scale_description"), "._settings"),
    **dict.fromkeys(("JointReference", "Reference", "hermite_motion", "joint_reference", "sample_reference"),
                     "._reference"),
})
