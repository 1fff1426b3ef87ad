"""The hip simulator in minimal coordinates: the verbs of :class:`pkmdyn.machine.MachineDynamics`.

Coordinates ``q (n, 3)`` [rad] are the platforms' Euler angles in the model's sequence
(``model.geometry.euler_sequence``, alpha FE, beta AA, gamma IER for the default ``"XYZ"``),
``qd, qdd`` their first and second rates [rad/s, rad/s^2], so the angles, rates and
accelerations of a motion file are ``q, qd, qdd`` directly. Actuator efforts ``u (n, 3)``
[N m] are the three motor torques, ``load (n,)`` [N] the hydraulic force on each platform.

With the Euler-rate map ``omega = E(q) qd`` and its drift ``omega_dot = E(q) qdd + Edot qd``
(:func:`pkmdyn.spatial.euler_kinematics`), the mass matrix ``M_w`` in ``omega`` and the motor
map of :mod:`.forward` (``theta_dot = (2 pi / p) J omega``) give the equations of motion in
generalised forces dual to ``qd``:

    M(q) qdd + h(q, qd, load) = B(q) u,
    M = E^T M_w E,    B = (2 pi / p) E^T J^T,    h = B tau_h,

where ``tau_h`` are the motor torques that hold ``qdd = 0`` (inverse dynamics at
``omega_dot = Edot qd``: velocity terms, gravity and every friction term with its load). ``M``
is symmetric positive definite wherever ``E`` is regular (away from the Euler sequence's
gimbal lock) and ``J`` finite. :func:`inverse_dynamics_one` and :func:`forward_dynamics_one`
are the single-sample real-time path (:mod:`.fast`), equal to the batched verbs.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ...errors import MotionError, SingularityError, as_array
from ...spatial import euler_kinematics
from .dynamics import inverse_dynamics as _torques
from .fast import forward_dynamics_one, inverse_dynamics_one, kernels
from .forward import accelerate, mass_matrix_omega
from .kinematics import HipKinematics, _platform_kinematics
from .params import HipModel

__all__ = [
    "COORDINATES",
    "ACTUATORS",
    "mass_matrix",
    "bias_forces",
    "actuator_map",
    "inverse_dynamics",
    "forward_dynamics",
    "inverse_dynamics_one",
    "forward_dynamics_one",
    "one_sample_kernels",
    "rate_map",
    "drive_ratios",
    "actuator_coordinates_one",
    "direct_one",
]

Array = NDArray[np.float64]

COORDINATES = ("alpha_rad", "beta_rad", "gamma_rad")
ACTUATORS = ("tau1_Nm", "tau2_Nm", "tau3_Nm")


def _q(q: object, name: str = "q") -> Array:
    return as_array(q, (None, 3), name, MotionError)


def _like(x: object, n: int, name: str) -> Array:
    return as_array(x, (n, 3), name, MotionError)


def rate_map(model: HipModel, q: Array) -> Array:
    """``E(q) (n, 3, 3)``: ``omega = E qd``, base frame (columns: ``omega`` of each unit rate)."""
    q = _q(q)
    n = q.shape[0]
    rates = np.tile(np.eye(3), (n, 1))
    _, cols, _ = euler_kinematics(model.geometry.euler_sequence, np.repeat(q, 3, axis=0), rates, np.zeros((3 * n, 3)))
    return cols.reshape(n, 3, 3).transpose(0, 2, 1)


def _kin(model: HipModel, q: Array, qd: Array, qdd: Array) -> HipKinematics:
    R, w, wd = euler_kinematics(model.geometry.euler_sequence, q, qd, qdd)
    return _platform_kinematics(model, np.zeros(q.shape[0]), R, w, wd, check_conditioning=False)


def _load(load: object, n: int) -> Array:
    return as_array(load, (n,), "load", MotionError)


def mass_matrix(model: HipModel, q: Array) -> Array:
    """``M(q) = E^T M_w E (n, 3, 3)`` [kg m^2], symmetric positive definite."""
    q = _q(q)
    z = np.zeros_like(q)
    E = rate_map(model, q)
    M_w = mass_matrix_omega(model, _kin(model, q, z, z))
    return np.swapaxes(E, 1, 2) @ M_w @ E


def actuator_map(model: HipModel, q: Array) -> Array:
    """``B(q) = (2 pi / p) E^T J^T (n, 3, 3)``: generalised forces [N m] of unit motor torques [N m]."""
    q = _q(q)
    z = np.zeros_like(q)
    E = rate_map(model, q)
    J = _kin(model, q, z, z).J
    return (2.0 * np.pi / model.geometry.p) * np.swapaxes(E, 1, 2) @ np.swapaxes(J, 1, 2)


def bias_forces(model: HipModel, q: Array, qd: Array, load: Array) -> Array:
    """``h(q, qd, load) (n, 3)`` [N m per rad]: velocity terms, gravity and every friction term."""
    q = _q(q)
    n = q.shape[0]
    qd = _like(qd, n, "qd")
    load = _load(load, n)
    E = rate_map(model, q)
    kin = _kin(model, q, qd, np.zeros_like(q))
    tau_h = _torques(model, kin, load).tau
    B = (2.0 * np.pi / model.geometry.p) * np.swapaxes(E, 1, 2) @ np.swapaxes(kin.J, 1, 2)
    return np.einsum("nij,nj->ni", B, tau_h)


def inverse_dynamics(model: HipModel, q: Array, qd: Array, qdd: Array, load: Array) -> Array:
    """Motor torques ``u (n, 3)`` [N m] that produce ``qdd`` (Eq. 7-14, 16 of the hip paper)."""
    q = _q(q)
    n = q.shape[0]
    kin = _kin(model, q, _like(qd, n, "qd"), _like(qdd, n, "qdd"))
    return _torques(model, kin, _load(load, n)).tau


def forward_dynamics(model: HipModel, q: Array, qd: Array, u: Array, load: Array) -> Array:
    """Euler-angle accelerations ``qdd (n, 3)`` [rad/s^2] under motor torques ``u (n, 3)`` [N m].

    ``E qdd = M_w^-1 (2 pi / p) J^T (u - tau_h)`` with ``tau_h`` the torques that hold
    ``qdd = 0`` (module docstring).
    """
    q = _q(q)
    n = q.shape[0]
    qd = _like(qd, n, "qd")
    u = _like(u, n, "u")
    load = _load(load, n)
    kin = _kin(model, q, qd, np.zeros_like(q))
    E_qdd = accelerate(model, kin, u, load)
    E = rate_map(model, q)
    lock = ~(np.abs(np.linalg.det(E)) > 1e-12)
    if np.any(lock):
        k = int(np.flatnonzero(lock)[0])
        raise SingularityError(
            f"q sample {k + 1} = {np.rad2deg(q[k]).round(4).tolist()} deg: the Euler-rate map of "
            f"sequence {model.geometry.euler_sequence!r} is singular (gimbal lock)"
        )
    return np.linalg.solve(E, E_qdd[..., None])[..., 0]


def one_sample_kernels(model: HipModel) -> tuple[Array, object, object]:
    """``(p, inverse, forward)``: the compiled kernels behind :func:`inverse_dynamics_one` and
    :func:`forward_dynamics_one` without their input checks (see :func:`.fast.kernels`), for the
    plant integrator and the controllers' per-cycle calls."""
    return kernels(model)


def drive_ratios(model: HipModel) -> Array:
    """``(3,)`` [rad/m]: each motor's angle per metre of its slider's travel, ``2 pi / p``
    (the ball screws' lead ``p``): the encoders' displacement is ``k (L - L_0)``."""
    return np.full(3, 2.0 * np.pi / float(model.geometry.p))


#: the engine's compiled verbs of each model's description (:func:`_engine`), by the model's id
#: (the model kept beside them, so that an id is not reused while its entry lives)
_ENGINES: dict[int, tuple[HipModel, object, object]] = {}


def _engine(model: HipModel) -> tuple[object, object]:
    """``(mechanism, verbs)``: the model's description compiled (:mod:`.description`) and the
    generic engine's verbs of it, made once per model."""
    hit = _ENGINES.pop(id(model), None)  # taken out and put back last: the latest used stay
    if hit is None or hit[0] is not model:
        from ...multibody import load_mechanism
        from ...multibody.machine import MechanismVerbs
        from .description import hip_description

        mech = load_mechanism(hip_description(model))
        hit = (model, mech, MechanismVerbs(mech))
        while len(_ENGINES) >= 8:  # a run holds two models (plant, controller); keep the latest few
            _ENGINES.pop(next(iter(_ENGINES)))
    _ENGINES[id(model)] = hit
    return hit[1], hit[2]


def actuator_coordinates_one(model: HipModel, q: Array, qd: Array, fresh: bool = False) -> Array:
    """The three sliders' positions ``L (3,)`` [m] at the platforms' angles ``q`` (one sample
    of the inverse kinematics, Eq. 2, warm-started from the last call; ``fresh``: from the
    reference configuration), by the engine's compiled kinematics of the model's description
    (:meth:`pkmdyn.multibody.machine.MechanismVerbs.actuator_coordinates_one`): the plant's
    exact encoders."""
    mech, verbs = _engine(model)
    return verbs.actuator_coordinates_one(mech, q, qd, fresh=fresh)


def direct_one(model: HipModel, a: Array, ad: Array) -> tuple[Array, Array]:
    """The platforms' angles and rates ``(3,), (3,)`` from the sliders' positions ``a`` [m] and
    rates ``ad`` [m/s] (the direct kinematics, warm-started from the previous call), by the
    engine's compiled direct kinematics of the model's description: the controller's pose from
    exact encoders."""
    mech, verbs = _engine(model)
    return verbs.direct_one(mech, a, ad)
