"""Shared pieces of the planar drive oracles (``five_bar``, ``biglide``): planar vector
helpers, a smooth test motion, and the virtual-work route from a mechanism's body motion to
its joint efforts, their per-body shares, the motor torques and the energies.

A mechanism module supplies ``body_motion(par, P, Pd, Pdd)`` returning per body ``c, v, a``
(centre of mass, (n, nb, 2)), ``angle, w, alpha`` ((n, nb)), ``mass``, ``inertia`` ((nb,)) and
``ik`` (its inverse kinematics, with ``K (n, 2, 2)``: joint rates per end-point rate, and
``q, qd, qdd``); ``par`` carries ``gravity (2,)``, ``joint_sign (2,)``, the motor's
``rotor_inertia``, ``coulomb``, ``viscous`` and the transmission ratio ``k``.

Virtual work: ``H^T u = sum_b Jc_b^T m_b (a_b - g) + Jw_b^T I_b alpha_b`` with ``H = diag(joint_sign) K``
and ``Jc_b, Jw_b`` the bodies' rates per unit end-point rate; the motor torque of an ideal
transmission of ratio k is ``tau = u / k + I_r theta_dd + C sgn_eps(theta_d) + b theta_d``,
``theta = k q``.
"""

from __future__ import annotations

import numpy as np

from ._batch import as_batch as _as_batch

G0 = 9.80665          # standard gravity [m/s^2]
EPS_ROT = 1e-3        # regularisation of the Coulomb sign for rotations [rad/s]


def regularised_sign(x, eps=EPS_ROT):
    """``x / sqrt(x^2 + eps^2)``: a smooth sign for Coulomb friction."""
    x = np.asarray(x, float)
    return x / np.sqrt(x * x + eps * eps)


def e(a):
    """Unit vector at angle ``a`` from +x toward +z."""
    return np.stack([np.cos(a), np.sin(a)], -1)


def n(a):
    """Unit normal of :func:`e` (turned +90 degrees)."""
    return np.stack([-np.sin(a), np.cos(a)], -1)


def perp(v):
    """Rotate a planar vector by +90 degrees: (x, z) -> (-z, x)."""
    return np.stack([-v[..., 1], v[..., 0]], -1)


def cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def dot(a, b):
    return np.sum(a * b, axis=-1)


def sine_motion(t, p0, amp, omega, phase):
    """Smooth motion starting exactly at ``p0``: ``p = p0 + amp (sin(w t + ph) - sin ph)``.

    ``t (n,)``; ``p0, amp, omega, phase (k,)``. Returns ``p, pd, pdd (n, k)``.
    """
    t = np.asarray(t, float)[:, None]
    p0, amp, omega, phase = (np.asarray(v, float)[None] for v in (p0, amp, omega, phase))
    arg = omega * t + phase
    p = p0 + amp * (np.sin(arg) - np.sin(phase))
    pd = amp * omega * np.cos(arg)
    pdd = -amp * omega**2 * np.sin(arg)
    return p, pd, pdd


def velocity_jacobians(body_motion, par, P):
    """``Jc (n, nb, 2, 2)`` and ``Jw (n, nb, 2)``: body rates per unit end-point rate."""
    P = _as_batch(P, 2)
    cols_c, cols_w = [], []
    for k in range(2):
        unit = np.zeros((P.shape[0], 2))
        unit[:, k] = 1.0
        bm = body_motion(par, P, unit, None)
        cols_c.append(bm["v"])
        cols_w.append(bm["w"])
    return np.stack(cols_c, -1), np.stack(cols_w, -1)


def _body_forces(body_motion, par, P, Pd, Pdd):
    """Each body's required generalised force per end-point coordinate ``(n, nb, 2)`` and ``H``."""
    bm = body_motion(par, P, Pd, Pdd)
    Jc, Jw = velocity_jacobians(body_motion, par, P)
    f = bm["mass"][None, :, None] * (bm["a"] - par.gravity[None, None, :])
    m = bm["inertia"][None] * bm["alpha"]
    Qb = np.einsum("nbik,nbi->nbk", Jc, f) + np.einsum("nbk,nb->nbk", Jw, m)
    return Qb, par.joint_sign[None, :, None] * bm["ik"]["K"]


def effort_shares(body_motion, par, P, Pd, Pdd):
    """Each body's share of the joint efforts, ``(n, nb, 2)``: the efforts are linear in the
    bodies' required wrenches, so body b's share solves ``H^T u_b = Jc_b^T m_b (a_b - g) +
    Jw_b^T I_b alpha_b``; the shares sum to ``u``."""
    Qb, H = _body_forces(body_motion, par, P, Pd, Pdd)
    Ht = np.broadcast_to(np.swapaxes(H, 1, 2)[:, None], Qb.shape + (2,))
    return np.linalg.solve(Ht, Qb[..., None])[..., 0]


def joint_efforts(body_motion, par, P, Pd, Pdd):
    """Joint efforts ``u (n, 2)`` along ``q_i`` (mechanism side, no drive terms)."""
    Qb, H = _body_forces(body_motion, par, P, Pd, Pdd)
    return np.linalg.solve(np.swapaxes(H, 1, 2), Qb.sum(axis=1)[..., None])[..., 0]


def motor_torques(ik, u, par, k):
    """Motor torques (motor side) from the joint motion ``ik`` (``q, qd, qdd``) and efforts ``u``:
    ``torque (n, 2)`` [N m] and its parts ``load = u / k``, ``rotor = I_r theta_dd``,
    ``friction = C sgn_eps(theta_d) + b theta_d``; ``effort = u``; the motor motion
    ``theta, theta_d, theta_dd``; the joint coordinates ``q, qd, qdd``."""
    k = np.asarray(k, float)[None]
    th, thd, thdd = k * ik["q"], k * ik["qd"], k * ik["qdd"]
    load = u / k
    rotor = par.rotor_inertia[None] * thdd
    fric = par.coulomb[None] * regularised_sign(thd) + par.viscous[None] * thd
    return {
        "torque": load + rotor + fric, "load": load, "rotor": rotor, "friction": fric,
        "effort": u, "theta": th, "theta_d": thd, "theta_dd": thdd,
        "q": ik["q"], "qd": ik["qd"], "qdd": ik["qdd"],
    }


def energies(body_motion, par, P, Pd, k):
    """Kinetic energy of the bodies ``T``, potential energy ``V = -sum m g.c``, rotor kinetic
    energy ``T_rotor = sum I_r theta_d^2 / 2`` and the motors' friction power
    ``loss = sum (C sgn_eps(theta_d) + b theta_d) theta_d`` (each (n,))."""
    bm = body_motion(par, P, Pd, None)
    T = 0.5 * np.sum(bm["mass"][None] * dot(bm["v"], bm["v"]) + bm["inertia"][None] * bm["w"] ** 2, -1)
    V = -np.sum(bm["mass"][None] * dot(bm["c"], par.gravity[None, None, :]), -1)
    thd = np.asarray(k, float)[None] * bm["ik"]["qd"]
    Trot = 0.5 * np.sum(par.rotor_inertia[None] * thd**2, -1)
    loss = np.sum((par.coulomb[None] * regularised_sign(thd) + par.viscous[None] * thd) * thd, -1)
    return {"T": T, "V": V, "T_rotor": Trot, "loss": loss}
