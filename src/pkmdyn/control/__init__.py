"""Trajectory-tracking controllers for any machine, written against its verbs only.

``_reference``: the reference on the control grid and the actuator displacements along it;
``_settings``: the settings files (timing, sensors, limits, gains; built-in ``hip.toml``,
``pdm.toml``) and the loop's settings (:class:`LoopSettings`, which :mod:`pkmdyn.simulate` takes:
the simulation imports the controllers, never the other way); ``_laws``: the controllers (feedforward, the hip paper's workspace PD and augmented PD, the
PDM paper's joint-space PID, computed torque) behind one function, :func:`effort`.
"""

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
