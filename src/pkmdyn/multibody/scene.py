"""The 3D scene of a described mechanism (:class:`pkmdyn.report.Scene`): every body drawn through
its joint centres, each actuated joint as a chain coloured by its effort; for a run's samples
(:func:`mechanism_scene`) or along task poses with the verbs' efforts (:func:`motion_scene`)."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..report import scene_from_joints
from .description.joint_types import JOINT_TYPES
from .dynamics.actuators import motor_effort_unit
from .dynamics.newton_euler import effort_unit
from .kinematics.inverse import solve_kinematics
from .model.compiler import MechanismModel

__all__ = ["mechanism_scene", "motion_scene", "frame_indices_of"]

Array = NDArray[np.float64]


def mechanism_scene(model: MechanismModel, t: Array, joint_point: Array,
                    efforts: dict[str, tuple[Array, str, str]] | None = None) -> Any:
    """The report's 3D scene of ``model`` (:func:`pkmdyn.report.scene_from_joints`): every body
    through its joint centres ``joint_point (n, nj, 3)`` [m] at the times ``t (n,)`` [s];
    ``efforts``: ``{actuated joint: (effort (n,), label, unit)}``, those joints drawn as chains
    coloured by their effort."""
    joints = [(nm, JOINT_TYPES[model.joint_type[k]].name,
               "ground" if model.joint_parent[k] < 0 else model.body_names[model.joint_parent[k]],
               "ground" if model.joint_child[k] < 0 else model.body_names[model.joint_child[k]])
              for k, nm in enumerate(model.joint_names)]
    return scene_from_joints(t, joint_point, joints, efforts)


def frame_indices_of(t: Array, frame_t: Array) -> Array:
    """Indices into ``t`` (increasing) of the animation's sample times ``frame_t``."""
    return np.clip(np.searchsorted(t, frame_t), 0, t.shape[0] - 1)


def motion_scene(model: MechanismModel, t: Array, x: Array, u: Array,
                 labels: tuple[tuple[str, str], ...] | None = None) -> Any:
    """The 3D scene (:func:`mechanism_scene`) of the mechanism along task poses
    ``x (n, nt)`` at times ``t (n,)`` [s]: each body drawn through its joint centres, each
    actuated joint as a chain coloured by its effort ``u (n, na)`` (the verbs' efforts: a
    drive's motor effort). ``labels``: per actuator its ``(name, unit)`` in the legend (default:
    the actuator's name and the effort's unit). Raises where a pose is out of reach."""
    x = np.atleast_2d(np.asarray(x, dtype=float))
    kin = solve_kinematics(model, x, t=np.asarray(t, dtype=float))
    uu = np.asarray(u, dtype=float).reshape(x.shape[0], model.na)
    efforts = {}
    for i, name in enumerate(model.actuator_names):
        if labels is not None:
            label, unit = labels[i]
        elif model.drive_name[i] is not None:
            label, unit = f"{model.drive_name[i]} effort", motor_effort_unit(model, i)
        else:
            label, unit = f"{name} effort", effort_unit(model, i)
        efforts[name] = (uu[:, i], label, {"Nm": "N m"}.get(unit, unit))
    return mechanism_scene(model, np.asarray(t, dtype=float), kin.joint_point, efforts)

