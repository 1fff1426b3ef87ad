"""Drives of the actuated joints: transmission, rotor inertia, motor friction, motor-side
efforts and rates, and the plausibility limits of a motion's rates.

A drive (``[[actuators]]`` of the description, :class:`~pkmdyn.multibody.description.schema.ActuatorSpec`) turns a
motor whose coordinate is ``theta = k q`` (``q`` the joint coordinate, reference value
included; ``k`` the transmission ratio: a gear ratio [rad/rad] for a revolute joint,
``gear_ratio 2 pi / lead`` [rad/m] for a prismatic joint driven by a screw, 1 for a linear
motor). The transmission is ideal (it stores and loses nothing; its losses are the motor's
friction), so by virtual power the joint receives ``u = k tau_t`` from the transmitted motor
effort ``tau_t``. The motor's own balance (rotor inertia ``I_r``, friction
``tau_f(theta_dot) = C u(theta_dot) + b theta_dot``, the regularised sign of
:func:`pkmdyn.multibody.dynamics.friction.regularised_sign`) gives the motor effort

    tau = u / k + I_r theta_ddot + tau_f(theta_dot),    theta_ddot = k q_ddot                 (A1)

(Chen, Cheng & Pang 2022, Eq. 10 and 14, for lead screws: ``tau = (p / 2 pi) F + I_L (2 pi / p) L_ddot +
screw friction``). Seen from the joint, the rotor adds the inertia ``k^2 I_r`` to the joint
coordinate (MuJoCo's ``armature``) and the friction ``k tau_f``. A joint without a drive has
``k = 1``, no rotor and no motor friction: its motor effort is its joint effort.

The power balance of a mechanism with drives (tested):

    sum_a tau_a theta_dot_a = d/dt (T + V + sum_a I_r,a theta_dot_a^2 / 2) + P_joints + sum_a tau_f,a theta_dot_a

with ``P_joints`` the joints' friction dissipation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ...errors import LimitError, at_sample
from .friction import regularised_sign
from .friction import EPS_ROTATION, EPS_TRANSLATION
from ..model.compiler import MechanismModel

__all__ = ["MotorEfforts", "motor_coordinates", "motor_friction", "motor_efforts", "rotor_energy", "motor_eps",
           "motor_effort_unit", "motor_effort_column", "check_task_rates", "check_actuator_rates", "effective_limits"]

Array = NDArray[np.float64]


def motor_eps(model: MechanismModel) -> Array:
    """The regularisation velocity of each motor's friction (rotary [rad/s], linear [m/s]): the
    joints' (:data:`pkmdyn.multibody.dynamics.friction.EPS_ROTATION`, :data:`pkmdyn.multibody.dynamics.friction.EPS_TRANSLATION`)."""
    return np.array([EPS_ROTATION if u == "rad" else EPS_TRANSLATION for u in model.motor_units])


def motor_coordinates(model: MechanismModel, act_q: Array, act_qd: Array, act_qdd: Array
                      ) -> tuple[Array, Array, Array]:
    """Motor coordinates ``theta = k q`` and their rates (n, na) [rad or m] from the actuated
    joints' coordinates ``act_q, act_qd, act_qdd`` (n, na)."""
    k = model.drive_ratio
    return act_q * k, act_qd * k, act_qdd * k


def motor_friction(model: MechanismModel, theta_dot: Array) -> Array:
    """Motor friction ``tau_f = C u(theta_dot) + b theta_dot`` (n, na) [N m or N], resisting."""
    return model.drive_coulomb * regularised_sign(theta_dot, motor_eps(model), False) + model.drive_viscous * theta_dot


@dataclass(frozen=True)
class MotorEfforts:
    """The motor efforts of Eq. (A1) and their parts (n, na) [N m for a rotary motor, N for a
    linear one]: ``effort = transmitted + rotor + friction`` with ``transmitted = u / k`` (what
    the mechanism needs), ``rotor = I_r theta_ddot``, ``friction = tau_f(theta_dot)``;
    ``theta, theta_dot, theta_ddot`` the motor coordinates."""

    effort: Array
    transmitted: Array
    rotor: Array
    friction: Array
    theta: Array
    theta_dot: Array
    theta_ddot: Array


def motor_efforts(model: MechanismModel, act_q: Array, act_qd: Array, act_qdd: Array, u: Array) -> MotorEfforts:
    """:class:`MotorEfforts` from the joint efforts ``u (n, na)`` along the actuated joints'
    motion, Eq. (A1)."""
    th, thd, thdd = motor_coordinates(model, act_q, act_qd, act_qdd)
    transmitted = u / model.drive_ratio
    rotor = model.drive_rotor * thdd
    fric = motor_friction(model, thd)
    return MotorEfforts(effort=transmitted + rotor + fric, transmitted=transmitted, rotor=rotor, friction=fric,
                        theta=th, theta_dot=thd, theta_ddot=thdd)


def rotor_energy(model: MechanismModel, act_qd: Array) -> Array:
    """Kinetic energy of the rotors ``sum I_r theta_dot^2 / 2`` (n,) [J]."""
    thd = act_qd * model.drive_ratio
    return 0.5 * (model.drive_rotor * thd * thd).sum(axis=-1)


def motor_effort_unit(model: MechanismModel, i: int) -> str:
    """Unit of actuator i's motor effort: ``Nm`` (a rotary motor), ``N`` (a linear one)."""
    return "Nm" if model.motor_units[i] == "rad" else "N"


def motor_effort_column(model: MechanismModel, i: int, part: str | None = None) -> str:
    """The results column of actuator i's motor effort (``<actuator>_torque_Nm`` or
    ``<actuator>_force_N``), or of one part of it (``<actuator>_torque_<part>_Nm``)."""
    name = model.drive_name[i]
    word = "torque" if model.motor_units[i] == "rad" else "force"
    unit = motor_effort_unit(model, i)
    return f"{name}_{word}_{unit}" if part is None else f"{name}_{word}_{part}_{unit}"


def effective_limits(model: MechanismModel, overrides: dict | None = None) -> dict[str, float]:
    """The plausibility limits of a run: the description's ``[limits]`` with ``overrides``
    (``--limit KEY=VALUE``) laid over them."""
    out = dict(model.limits)
    out.update(overrides or {})
    return out


def _how(key: str) -> str:
    return f"raise it with [limits] {key} in the description or --limit {key}=VALUE"


def check_task_rates(model: MechanismModel, t: Array | None, xd: Array, xdd: Array, limits: dict,
                     sample_offset: int = 0) -> None:
    """Refuse a task motion whose rates exceed the limits ``max_task_speed_m_s`` ...
    (:func:`effective_limits`): :class:`~pkmdyn.errors.LimitError` naming the coordinate, the
    sample and the value."""
    for k, (name, unit) in enumerate(zip(model.task_names, model.task_units)):
        for arr, what, key, u in ((xd, "rate", f"max_task_speed_{unit}_s", f"{unit}/s"),
                                  (xdd, "acceleration", f"max_task_acceleration_{unit}_s2", f"{unit}/s^2")):
            lim = float(limits[key])
            big = np.abs(arr[:, k])
            bad = np.flatnonzero(~(big <= lim))
            if bad.size:
                i = int(bad[0])
                raise LimitError(f"{at_sample(i, t, sample_offset)}: task coordinate {name}_{unit} {what} "
                                 f"{arr[i, k]:.4g} {u} exceeds the limit {key} = {lim:g} {u} ({_how(key)})")


def check_actuator_rates(model: MechanismModel, t: Array | None, act_qd: Array, act_qdd: Array, limits: dict,
                         sample_offset: int = 0) -> None:
    """Refuse a motion whose actuated joints move faster than the limits ``max_joint_speed_*``,
    ``max_joint_acceleration_*`` (:func:`effective_limits`) or whose motors exceed their drives'
    ``max_speed_*``, ``max_acceleration_*``: :class:`~pkmdyn.errors.LimitError` naming the
    joint (and actuator), the sample and the value."""
    for i, (joint, unit) in enumerate(zip(model.actuator_names, model.actuator_units)):
        for arr, what, key, u in ((act_qd, "speed", f"max_joint_speed_{unit}_s", f"{unit}/s"),
                                  (act_qdd, "acceleration", f"max_joint_acceleration_{unit}_s2", f"{unit}/s^2")):
            lim = float(limits[key])
            bad = np.flatnonzero(~(np.abs(arr[:, i]) <= lim))
            if bad.size:
                s = int(bad[0])
                raise LimitError(f"{at_sample(s, t, sample_offset)}: actuated joint {joint!r} {what} "
                                 f"{arr[s, i]:.4g} {u} exceeds the limit {key} = {lim:g} {u} ({_how(key)})")
        name = model.drive_name[i]
        if name is None:
            continue
        mu = model.motor_units[i]
        k = model.drive_ratio[i]
        for arr, what, lim, key, u in ((act_qd, "speed", model.drive_max_speed[i], f"max_speed_{mu}_s", f"{mu}/s"),
                                       (act_qdd, "acceleration", model.drive_max_acceleration[i],
                                        f"max_acceleration_{mu}_s2", f"{mu}/s^2")):
            if not np.isfinite(lim):
                continue
            m = arr[:, i] * k
            bad = np.flatnonzero(~(np.abs(m) <= lim))
            if bad.size:
                s = int(bad[0])
                raise LimitError(f"{at_sample(s, t, sample_offset)}: actuator {name!r} (joint {joint!r}) motor {what} "
                                 f"{m[s]:.4g} {u} exceeds its {key} = {lim:g} {u} ([[actuators]] {name}: raise it "
                                 "there or slow the motion)")
