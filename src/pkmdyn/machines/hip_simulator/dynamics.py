"""Inverse rigid-body dynamics with joint friction of the hip simulator, Eq. (7)-(14), (16).

Method (virtual work, Eq. 11-13). The machine has three degrees of freedom, the platforms'
common angular velocity ``omega``; every body velocity is linear in it:

    Ld_i = J_i omega,    v_l = J_vl omega,    omega_l = J_wl omega,    theta_dot = (2 pi / p) J omega.

For each body the *required* wrench (what the rest of the machine must supply so that the
body follows the motion against gravity and inertia, Eq. 7-9 with the sign reversed) and
for each friction term the resisting force or torque is projected onto ``omega``:

    Q = sum over bodies (J_v^T F_req + J_w^T T_req) + sum over joints J_rel^T tau_f,

and the motor torques follow from ``tau . theta_dot = Q . omega`` for every ``omega``:

    tau = (p / 2 pi) J^-T Q  +  the slider and screw terms, which act along the screw directly.

Projections are evaluated without forming 3x3 Jacobians. With ``J_d = -[r]x - e_z J_i`` (so
``d_dot = J_d omega``), ``J_vl = e_z J_i + J_d / 2`` and ``J_wl = (I + k e t^T) [d]x J_d / l^2``
(k = c / (1 - c^2), c = t . e; k = 0 for the paper's perpendicular levers):

    J_vl^T F + J_wl^T T = J_i (F_z - X_z) + r x X,   X = F/2 + (T + k (e . T) t) x d / l^2.

Both platforms carry identical bodies moving identically (same R, sliders rigidly h1 - h2
apart), so each platform-side term is evaluated once and multiplied by the number of
platforms.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ...errors import MotionError, ParameterError, SingularityError, check_type
from ...friction import coulomb_viscous, regularised_sign
from ...profiles.orientation import check_load
from ...spatial import cross0, dot0
from .kinematics import HipKinematics
from .params import HipModel

__all__ = ["HipTorques", "inverse_dynamics", "lever_generalised_force", "hip_bearing_friction", "PARTS"]

Array = NDArray[np.float64]

#: names of the parts of Eq. (14) plus friction, in results-file order
PARTS = ("platform", "lever", "slider", "screw", "friction")


def hip_bearing_friction(
    omega: Array,
    load: Array,
    platform_weight: float,
    hip_radius: float,
    hip_coefficient: float,
    thrust_radius: float,
    thrust_coefficient: float,
    eps: float,
) -> Array:
    """Hip-joint plus thrust-bearing friction torque on a platform, Eq. (16) of the hip paper.

        tau_mf = u(omega) (r_h mu_h F + r_t mu_t |F + m_m g|)

    ``omega (n, 3)`` [rad/s] platform angular velocity, ``load (n,)`` [N] hydraulic force,
    ``platform_weight`` = m_m g [N]. Returns ``(n, 3)`` [N m] in the base frame.
    """
    magnitude = hip_radius * hip_coefficient * np.abs(load) + thrust_radius * thrust_coefficient * np.abs(
        load + platform_weight
    )
    return regularised_sign(omega, eps, vector=True) * magnitude[..., None]


@dataclass(frozen=True)
class HipTorques:
    """Motor torques and their parts, ``(n, 3)`` [N m] per motor (module) i = 1..3.

    ``tau = platform + lever + slider + screw + friction`` exactly. ``hip_friction (n, 3)`` is
    the part of ``friction`` due to the hip joints and thrust bearings (Eq. 16) alone, and
    ``power (n,)`` [W] the total motor power ``sum_i tau_i theta_dot_i``.
    """

    tau: Array
    platform: Array
    lever: Array
    slider: Array
    screw: Array
    friction: Array
    hip_friction: Array
    power: Array


def _first(x: Array) -> Array:
    """Documented ``(n, leg, 3)`` or ``(n, 3)`` -> internal ``(3, leg, n)`` or ``(3, n)`` (a view)."""
    return x.T


def lever_generalised_force(kin: HipKinematics, t_axis: Array, k: Array, F: Array, T: Array) -> Array:
    """``J_vl^T F + J_wl^T T`` for every lever, internal layout: ``F, T (3, leg, n)`` -> ``(3, leg, n)``.

    ``F`` [N] acts at the lever centre, ``T`` [N m] on the lever; ``t_axis (3, leg, 1)`` holds
    the U joints' first axes and ``k (leg, n)`` the spin gain c / (1 - c^2) (zero for
    perpendicular levers). See the module docstring for the derivation.
    """
    d = _first(kin.d)
    l2 = dot0(d, d)
    Tp = T + k * dot0(_first(kin.e_lever), T) * t_axis
    X = 0.5 * F + cross0(Tp, d) / l2
    return _first(kin.J) * (F[2] - X[2]) + cross0(_first(kin.r), X)


def _spin_gain(model: HipModel, kin: HipKinematics, t_axis: Array) -> Array:
    """k = c / (1 - c^2), c = t . e, per lever ``(leg, n)``; zero for perpendicular levers."""
    c = dot0(t_axis, _first(kin.e_lever))
    if model.geometry.lever_spin != "u_joint":
        return np.zeros_like(c)
    return c / (1.0 - c * c)


def _inertia_times(cols: Array, I_diag: Array, w: Array) -> Array:
    """``(R diag(I) R^T) w``, component-first: frame columns ``cols (col, row, ...)``, ``w (3, ...)``."""
    out = np.zeros(np.broadcast_shapes(cols.shape[1:], w.shape))
    for k in range(3):
        out += cols[k] * (I_diag[k] * dot0(cols[k], w))
    return out


def inverse_dynamics(model: HipModel, kin: HipKinematics, load: Array) -> HipTorques:
    """Motor torques of the three linear modules, split into the parts of Eq. (14) plus friction.

    ``load (n,)`` [N] is the hydraulic force on each platform, along -Z through o_j.
    Vectors are handled component-first internally (see :func:`platform_kinematics`).
    """
    check_type(model, HipModel, "model", ParameterError)
    check_type(kin, HipKinematics, "kin", MotionError)
    load = check_load(kin.t, load)
    g, m, f = model.geometry, model.inertia, model.friction
    n_platforms = g.h.shape[0]
    gear = g.p / (2.0 * np.pi)  # [m/rad]
    t_axis = g.t.T[:, :, None]

    # J^-T by cofactors: rows of J are j1, j2, j3 (one per leg); J^-T Q = (c_i . Q) / det(J)
    J = _first(kin.J)  # (3 omega, leg, n)
    j1, j2, j3 = J[:, 0], J[:, 1], J[:, 2]
    cof = np.stack((cross0(j2, j3), cross0(j3, j1), cross0(j1, j2)), axis=1)  # (3, leg, n)
    det = dot0(j1, cof[:, 0])
    singular = ~(np.abs(det) > 1e-12 * np.abs(J).max(axis=(0, 1)) ** 3)
    if np.any(singular):
        row = int(np.flatnonzero(singular)[0])
        raise SingularityError(f"t = {kin.t[row]:.6g} s: J is singular (det(J_b) = 0), the motor torques are undefined")
    scale = gear / det

    def to_motors(Q: Array) -> Array:
        """(p / 2 pi) J^-T Q for generalised forces ``Q (3, n)`` -> motor torques ``(n, leg)``."""
        return (dot0(cof, Q[:, None, :]) * scale).T

    # platform inertia, Eq. (7): required torque I_w omega_dot + omega x I_w omega
    R_cols = kin.R.transpose(2, 1, 0)  # (col, row, n)
    w, wd = _first(kin.omega), _first(kin.omega_dot)
    Q_platform = n_platforms * (_inertia_times(R_cols, m.I_m, wd) + cross0(w, _inertia_times(R_cols, m.I_m, w)))

    # levers, Eq. (8): required force m_l (a_c + g e_z) and torque I_w w_l_dot + w_l x I_w w_l
    k = _spin_gain(model, kin, t_axis)
    lever_cols = kin.R_lever.transpose(3, 2, 1, 0)  # (col, row, leg, n)
    wl, wld = _first(kin.omega_lever), _first(kin.omega_lever_dot)
    F_lever = m.m_l * _first(kin.a_lever)
    F_lever[2] += m.m_l * m.g
    T_lever = _inertia_times(lever_cols, m.I_l, wld) + cross0(wl, _inertia_times(lever_cols, m.I_l, wl))
    Q_lever = n_platforms * lever_generalised_force(kin, t_axis, k, F_lever, T_lever).sum(axis=1)

    # sliders, Eq. (9), and lead screws, Eq. (10)
    Ld = kin.Ld[:, -1]
    Ldd = kin.Ldd[:, -1]
    tau_slider = gear * n_platforms * m.m_L * (Ldd + m.g)
    tau_screw = m.I_L * Ldd / gear

    # friction: hip joint + thrust bearing (Eq. 16), S and U joints, sliders, screws
    tau_mf = hip_bearing_friction(kin.omega, load, m.m_m * m.g, f.r_h, f.mu_h, f.r_t, f.mu_t, f.eps_w)
    hip = to_motors(n_platforms * _first(tau_mf))
    friction = hip
    Q_joints = None
    zero = np.zeros_like(wl)
    if f.spherical_coulomb or f.spherical_viscous:
        w_rel = kin.omega_lever - kin.omega[:, None, :]
        tau_s = _first(coulomb_viscous(w_rel, f.spherical_coulomb, f.spherical_viscous, f.eps_w, vector=True))
        Q_joints = (lever_generalised_force(kin, t_axis, k, zero, tau_s) - tau_s).sum(axis=1)
    if f.universal_coulomb or f.universal_viscous:
        tau_u = _first(coulomb_viscous(kin.omega_lever, f.universal_coulomb, f.universal_viscous, f.eps_w, vector=True))
        Q_u = lever_generalised_force(kin, t_axis, k, zero, tau_u).sum(axis=1)
        Q_joints = Q_u if Q_joints is None else Q_joints + Q_u
    if Q_joints is not None:
        friction = friction + to_motors(n_platforms * Q_joints)
    theta_dot = Ld / gear
    if f.slider_coulomb or f.slider_viscous:
        friction = friction + gear * n_platforms * coulomb_viscous(Ld, f.slider_coulomb, f.slider_viscous, f.eps_v, vector=False)
    if f.screw_coulomb or f.screw_viscous:
        friction = friction + coulomb_viscous(theta_dot, f.screw_coulomb, f.screw_viscous, f.eps_w, vector=False)

    platform = to_motors(Q_platform)
    lever = to_motors(Q_lever)
    tau = platform + lever + tau_slider + tau_screw + friction
    return HipTorques(
        tau=tau,
        platform=platform,
        lever=lever,
        slider=tau_slider,
        screw=tau_screw,
        friction=friction,
        hip_friction=hip,
        power=np.sum(tau * theta_dot, axis=1),
    )
