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

from ...errors import MotionError, SingularityError
from ...friction import coulomb_viscous, hip_bearing_friction
from ...spatial import cross, dot
from .kinematics import HipKinematics
from .params import HipModel

__all__ = ["HipTorques", "inverse_dynamics", "lever_generalised_force", "PARTS"]

Array = NDArray[np.float64]

#: names of the parts of Eq. (14) plus friction, in results-file order
PARTS = ("platform", "lever", "slider", "screw", "friction")


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


def lever_generalised_force(kin: HipKinematics, t_axis: Array, k: Array, F: Array, T: Array) -> Array:
    """``J_vl^T F + J_wl^T T`` for every lever: ``F, T (n, 3, 3)`` -> ``(n, 3, 3)`` [sample, leg, omega].

    ``F`` [N] acts at the lever centre, ``T`` [N m] on the lever; ``t_axis (3, 3)`` holds the U
    joints' first axes and ``k (n, 3)`` the spin gain c / (1 - c^2) (zero for perpendicular
    levers). See the module docstring for the derivation.
    """
    l2 = dot(kin.d, kin.d)
    Tp = T + (k * dot(kin.e_lever, T))[..., None] * t_axis
    X = 0.5 * F + cross(Tp, kin.d) / l2[..., None]
    return kin.J * (F[..., 2] - X[..., 2])[..., None] + cross(kin.r, X)


def _spin_gain(model: HipModel, kin: HipKinematics) -> Array:
    if model.geometry.lever_spin != "u_joint":
        return np.zeros(kin.e_lever.shape[:-1])
    c = dot(model.geometry.t, kin.e_lever)
    return c / (1.0 - c * c)


def _world_inertia_times(R: Array, I_diag: Array, w: Array) -> Array:
    """``(R diag(I) R^T) w`` for rotation ``R (..., 3, 3)`` and vectors ``w (..., 3)``."""
    body = np.matmul(w[..., None, :], R)[..., 0, :]  # R^T w
    return np.matmul(R, (I_diag * body)[..., None])[..., 0]


def _check_load(load: Array, t: Array) -> Array:
    load = np.asarray(load, dtype=float)
    if load.shape != t.shape:
        raise MotionError(f"load: expected {t.shape[0]} values, got shape {load.shape}")
    bad = np.flatnonzero(~(np.isfinite(load) & (load >= 0.0)))
    if bad.size:
        r = int(bad[0])
        what = "not finite" if not np.isfinite(load[r]) else "negative"
        raise MotionError(f"load row {r + 1} (t = {t[r]:g} s): {load[r]:g} N is {what}")
    return load


def inverse_dynamics(model: HipModel, kin: HipKinematics, load: Array) -> HipTorques:
    """Motor torques of the three linear modules, split into the parts of Eq. (14) plus friction.

    ``load (n,)`` [N] is the hydraulic force on each platform, along -Z through o_j.
    """
    load = _check_load(load, kin.t)
    g, m, f = model.geometry, model.inertia, model.friction
    n_platforms = g.h.shape[0]
    gear = g.p / (2.0 * np.pi)  # [m/rad]
    ez = np.array([0.0, 0.0, 1.0])

    # J^-T by cofactors: rows of J are j1, j2, j3; J^-T Q = (c . Q) / det with c_i the cofactor rows
    j1, j2, j3 = kin.J[:, 0], kin.J[:, 1], kin.J[:, 2]
    cof = np.stack((cross(j2, j3), cross(j3, j1), cross(j1, j2)), axis=1)
    det = dot(j1, cof[:, 0])
    singular = ~(np.abs(det) > 1e-12 * np.abs(kin.J).max(axis=(1, 2)) ** 3)
    if np.any(singular):
        row = int(np.flatnonzero(singular)[0])
        raise SingularityError(f"t = {kin.t[row]:.6g} s: J is singular (det(J_b) = 0), the motor torques are undefined")

    def to_motors(Q: Array) -> Array:
        return gear * np.matmul(cof, Q[..., None])[..., 0] / det[:, None]

    # platform inertia, Eq. (7): required torque I_w omega_dot + omega x I_w omega
    Iw_wd = _world_inertia_times(kin.R, m.I_m, kin.omega_dot)
    Iw_w = _world_inertia_times(kin.R, m.I_m, kin.omega)
    Q_platform = n_platforms * (Iw_wd + cross(kin.omega, Iw_w))

    # levers, Eq. (8): required force m_l (a_c + g e_z) and torque I_w w_l_dot + w_l x I_w w_l
    t_axis = g.t
    k = _spin_gain(model, kin)
    F_lever = m.m_l * (kin.a_lever + m.g * ez)
    T_lever = _world_inertia_times(kin.R_lever, m.I_l, kin.omega_lever_dot) + cross(
        kin.omega_lever, _world_inertia_times(kin.R_lever, m.I_l, kin.omega_lever)
    )
    Q_lever = n_platforms * lever_generalised_force(kin, t_axis, k, F_lever, T_lever).sum(axis=1)

    # sliders, Eq. (9), and lead screws, Eq. (10)
    Ld = kin.Ld[:, -1]
    Ldd = kin.Ldd[:, -1]
    tau_slider = gear * n_platforms * m.m_L * (Ldd + m.g)
    tau_screw = m.I_L * Ldd / gear

    # friction: hip joint + thrust bearing (Eq. 16), S and U joints, sliders, screws
    tau_mf = hip_bearing_friction(kin.omega, load, m.m_m * m.g, f.r_h, f.mu_h, f.r_t, f.mu_t, f.eps_w)
    hip = to_motors(n_platforms * tau_mf)
    Q_joints = np.zeros_like(Q_lever)
    zero = np.zeros_like(kin.omega_lever)
    if f.spherical_coulomb or f.spherical_viscous:
        w_rel = kin.omega_lever - kin.omega[:, None, :]
        tau_s = coulomb_viscous(w_rel, f.spherical_coulomb, f.spherical_viscous, f.eps_w, vector=True)
        Q_joints += (lever_generalised_force(kin, t_axis, k, zero, tau_s) - tau_s).sum(axis=1)
    if f.universal_coulomb or f.universal_viscous:
        tau_u = coulomb_viscous(kin.omega_lever, f.universal_coulomb, f.universal_viscous, f.eps_w, vector=True)
        Q_joints += lever_generalised_force(kin, t_axis, k, zero, tau_u).sum(axis=1)
    theta_dot = Ld / gear
    friction = hip + to_motors(n_platforms * Q_joints)
    friction = friction + gear * n_platforms * coulomb_viscous(Ld, f.slider_coulomb, f.slider_viscous, f.eps_v, vector=False)
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
        power=dot(tau, theta_dot),
    )
