"""Forward dynamics of the hip simulator: platform angular acceleration from motor torques.

The inverse dynamics of :mod:`.dynamics` (Eq. 7-14, 16 of the hip paper) is affine in the
platforms' angular acceleration ``omega_dot``: every body acceleration is linear in it, and
friction depends on velocities and the load only. So

    tau = A(R) omega_dot + b(R, omega, load),     A = (p / 2 pi) J^-T M_w(R),

where ``b`` is the inverse dynamics at ``omega_dot = 0`` (velocity terms, gravity, friction)
and ``M_w (3, 3)`` the machine's mass matrix in the generalised velocity ``omega`` (kinetic
energy ``T = omega . M_w omega / 2``). The motors' power is ``tau . theta_dot`` with
``theta_dot = (2 pi / p) J omega``, so ``Q = (2 pi / p) J^T tau`` is the generalised force dual
to ``omega``, and the forward dynamics solves the symmetric positive definite system

    M_w omega_dot = (2 pi / p) J^T (tau - b).

``M_w`` is assembled from the same body Jacobians the virtual-work projection of
:mod:`.dynamics` uses (its module docstring): with ``J_i`` the rows of ``J``,
``J_d = -[r]x - e_z J_i^T``, ``J_vl = e_z J_i^T + J_d / 2``,
``J_wl = (I + k e t^T) [d]x J_d / l^2``,

    M_w = n_p R diag(I_m) R^T                                   (platforms, Eq. 7)
        + n_p sum_i (m_l J_vl^T J_vl + J_wl^T I_lw J_wl)        (levers, Eq. 8)
        + (n_p m_L + I_L (2 pi / p)^2) sum_i J_i J_i^T            (sliders and screws, Eq. 9-10)

with ``n_p = 2`` platforms and ``I_lw = R_l diag(I_l) R_l^T`` each lever's inertia in the base
frame. One inverse-dynamics evaluation (for ``b``) plus this assembly replaces the four
inverse-dynamics calls a column-by-column construction of ``A`` would need.

With ``lever_spin = "perpendicular"`` (the paper's Eq. 4) the levers' angular velocity is not
the rate of their frames, so ``M_w`` is the mass matrix of that approximate kinematics: the
forward and inverse dynamics stay exact inverses of each other, but free motion conserves
energy only up to the neglected spin (tested with the default ``"u_joint"``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ...errors import MotionError, as_array
from ...spatial import skew
from .dynamics import inverse_dynamics
from .kinematics import HipKinematics, platform_kinematics
from .params import HipModel

__all__ = ["forward_dynamics", "mass_matrix_omega", "bias_torques", "accelerate"]

Array = NDArray[np.float64]


def mass_matrix_omega(model: HipModel, kin: HipKinematics) -> Array:
    """The mass matrix ``M_w (n, 3, 3)`` [kg m^2] in the platforms' angular velocity ``omega``.

    ``T = omega . M_w omega / 2`` is the kinetic energy of the whole machine (both platforms,
    six levers, six sliders, three screw rotors); see the module docstring. Depends on the
    pose only (``kin.R`` and the lever geometry), not on the velocities held in ``kin``.
    """
    g, m = model.geometry, model.inertia
    n_p = g.h.shape[0]
    gear = g.p / (2.0 * np.pi)
    R = kin.R
    M = n_p * np.einsum("nik,k,njk->nij", R, m.I_m, R)
    J = kin.J  # (n, leg, 3): row i of J
    M += (n_p * m.m_L + m.I_L / gear**2) * np.einsum("nli,nlj->nij", J, J)
    ez = np.array([0.0, 0.0, 1.0])
    Jd = -skew(kin.r) - ez[:, None] * J[:, :, None, :]  # (n, leg, 3, 3)
    Jvl = ez[:, None] * J[:, :, None, :] + 0.5 * Jd
    e = kin.e_lever
    if g.lever_spin == "u_joint":
        c = np.einsum("lk,nlk->nl", g.t, e)
        k = c / (1.0 - c * c)
    else:
        k = np.zeros(e.shape[:2])
    spin_map = np.eye(3) + k[..., None, None] * e[..., :, None] * g.t[None, :, None, :]
    Jwl = spin_map @ skew(kin.d) @ Jd / (g.l * g.l)
    I_lw = np.einsum("nlik,k,nljk->nlij", kin.R_lever, m.I_l, kin.R_lever)
    M_lever = m.m_l * np.swapaxes(Jvl, -1, -2) @ Jvl + np.swapaxes(Jwl, -1, -2) @ I_lw @ Jwl
    M += n_p * M_lever.sum(axis=1)
    return M


def bias_torques(model: HipModel, kin: HipKinematics, load: Array) -> Array:
    """``b (n, 3)`` [N m]: the motor torques that hold the motion in ``kin`` with its own
    ``omega_dot`` (velocity terms, gravity and every friction term with its load)."""
    return inverse_dynamics(model, kin, load).tau


def _check_inputs(R: object, omega: object, tau: object, load: object) -> tuple[Array, Array, Array, Array]:
    R = as_array(R, (None, 3, 3), "R", MotionError)
    n = R.shape[0]
    omega = as_array(omega, (n, 3), "omega", MotionError)
    tau = as_array(tau, (n, 3), "tau", MotionError)
    load = as_array(load, (n,), "load", MotionError)
    return R, omega, tau, load


def accelerate(model: HipModel, kin0: HipKinematics, tau: Array, load: Array) -> Array:
    """``omega_dot - kin0.omega_dot (n, 3)``: the angular acceleration that the torques ``tau``
    add to the acceleration held in ``kin0`` (used with ``kin0.omega_dot = 0`` by
    :func:`forward_dynamics`, and with the Euler-rate drift by the minimal-coordinate verbs)."""
    b = bias_torques(model, kin0, load)
    M = mass_matrix_omega(model, kin0)
    scale = 2.0 * np.pi / model.geometry.p
    rhs = scale * np.einsum("nli,nl->ni", kin0.J, tau - b)
    return np.linalg.solve(M, rhs[..., None])[..., 0]


def forward_dynamics(model: HipModel, R: Array, omega: Array, tau: Array, load: Array, t: Array | None = None) -> Array:
    """Platform angular acceleration ``omega_dot (n, 3)`` [rad/s^2], base frame, under motor torques.

    Solves ``M_w(R) omega_dot = (2 pi / p) J^T (tau - b(R, omega, load))`` (module docstring),
    the exact inverse of :func:`~pkmdyn.machines.hip_simulator.inverse_dynamics`.

    ``R (n, 3, 3)`` platform rotation; ``omega (n, 3)`` [rad/s] angular velocity, base frame;
    ``tau (n, 3)`` [N m] motor torques; ``load (n,)`` [N] hydraulic force on each platform;
    ``t (n,)`` [s] optional sample times, used only to name a sample in an error message.
    """
    R, omega, tau, load = _check_inputs(R, omega, tau, load)
    n = R.shape[0]
    t = np.zeros(n) if t is None else as_array(t, (n,), "t", MotionError)
    kin0 = platform_kinematics(model, t, R, omega, np.zeros((n, 3)), check_conditioning=False)
    return accelerate(model, kin0, tau, load)
