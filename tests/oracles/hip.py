"""The 2(3PUS+S) hip simulator's closed forms (Chen, Cheng & Pang 2022, Eq. 1-16) as an oracle.

Source: Z. Chen, X. Cheng & J. Pang, "Kinematics and dynamics of a 2(3PUS+S) dual-platform
hip-joint wear simulator", Appl. Sci. 12 (2022) 6682: the loop closure and its rates (Eq. 1-6),
the bodies' required wrenches (Eq. 7-10), their projection by virtual work (Eq. 11-14) and the
hip-joint and thrust-bearing friction (Eq. 16). Pure numpy, batched over a leading sample axis
``n``; the parameters come from :class:`pkmdyn.machines.hip_simulator.params.HipModel` (its
geometry, inertia and friction tables), the Euler angles through :func:`oracles.stewart.
euler_kinematics` (scipy's meaning of the sequence letters). Nothing of the generic engine.

Frames and layout (base frame O-XYZ, Z up, SI units). Both platforms turn by the same ``R``
about their fixed centres ``o_j`` (j = 0 upper, 1 lower); module i has its screw through
``A_i`` along Z, its U joint's first axis ``t_i`` fixed in the slider; the S joint of platform j
and module i is at ``a_ji = o_j + R r_ai``. The two sliders of one screw are rigidly
``h1 - h2`` apart, so the two levers of a module are parallel and move with the same velocity
field: lever vector ``d_i = a_ji - b_ji`` (from the U-joint centre ``b_ji = A_i + L_ji e_z`` to
the S joint), its rates, the lever's angular motion and its centre's velocity and acceleration
are per module; positions are per platform. The slider branch is the one below its S joint
(``d_z > 0``).

Kinematics (:func:`platform_kinematics`, :func:`kinematics`): with ``r_i = R r_ai``

    L_2i = h2 + r_iz - sqrt(l^2 - |(o_2 + r_i - A_i)_xy|^2),   L_1i = L_2i + h1 - h2    (Eq. 1-2)
    Ld_i = d_i . (omega x r_i) / d_iz = J_i . omega,  J = J_a^-1 J_b,                    (Eq. 3)
    J_a = diag(e_iz),  rows of J_b = (r_i x e_i),  e_i = d_i / l
    Ldd_i = (d_i . a_i + |d_dot_i|^2) / d_iz,  a_i = omega_dot x r_i + omega x (omega x r_i)   (Eq. 5)
    d_dot = omega x r - Ld e_z,   d_ddot = a - Ldd e_z
    lever: omega_l = d x d_dot / l^2 + s e (Eq. 4 plus the spin s about the lever, Eq. 6 its rate)

The spin keeps ``omega_l`` in the plane of the U joint's two axes ``t`` and ``x = t x e / |t x e|``
(normal ``e - c t``, ``c = t . e``): ``s = c (t . d x d_dot / l^2) / (1 - c^2)``; zero for the
paper's own ``lever_spin = "perpendicular"`` (Eq. 4 as printed). The lever frame has columns
``(x, e x x, e)``; its centre is the lever's midpoint.

Dynamics (:func:`inverse_dynamics`): every body velocity is linear in ``omega``
(``Ld = J omega``, ``v_l = J_vl omega``, ``omega_l = J_wl omega``, screw rate
``theta_dot = J omega / gear`` with ``gear = p / 2 pi``):

    J_d = -[r]x - e_z J_i,   J_vl = e_z J_i + J_d / 2,   J_wl = (I + k e t^T) [d]x J_d / l^2,

``k = c / (1 - c^2)`` (0 for perpendicular levers). The required wrenches (Eq. 7-10, what the rest
of the machine supplies for the body to follow the motion against inertia and gravity) and the
friction torques (what the joints resist with) are projected onto ``omega``,
``Q = sum J^T W``, and the motors supply ``tau = gear J^-T Q`` plus the slider and screw terms
that act along the screws directly (Eq. 11-14):

* platform (both): ``n_p (I_w omega_dot + omega x I_w omega)``, ``I_w = R diag(I_m) R^T``;
* levers (six): ``F = m_l (a_c + g e_z)``, ``T = I_lw omega_l_dot + omega_l x I_lw omega_l``;
* sliders: ``tau = gear n_p m_L (Ldd + g)``; screw rotors: ``tau = I_L Ldd / gear``;
* friction: Eq. 16 on each platform, ``u(omega) (r_h mu_h |F| + r_t mu_t |F + m_m g|)``; the S
  joints (lever relative to platform, ``Q = (J_wl - I)^T tau_s``), the U joints (lever relative
  to the slider, ``Q = J_wl^T tau_u``), Coulomb plus viscous ``C u(w) + b w`` with
  ``u(w) = w / sqrt(|w|^2 + eps^2)``; each carriage (``gear n_p f(Ld)``, ``eps_v``) and each
  screw (``f(theta_dot)``, ``eps_w``) on the motor side.

Forward dynamics: ``tau`` is affine in ``omega_dot``, ``tau = gear J^-T M_w omega_dot + b``
with the mass matrix in ``omega``

    M_w = n_p I_w + n_p sum_i (m_l J_vl^T J_vl + J_wl^T I_lw J_wl) + (n_p m_L + I_L / gear^2) sum_i J_i^T J_i,

so ``omega_dot = M_w^-1 J^T (tau - b) / gear``. In the platforms' Euler angles ``q`` (the
parameter file's sequence), ``omega = E(q) qd`` and ``omega_dot = E qdd + Edot qd``:
``M = E^T M_w E``, ``B = E^T J^T / gear`` (generalised forces per unit motor torque),
``h = B tau_h`` with ``tau_h`` the torques at ``qdd = 0``, and ``M qdd + h = B u``.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from .stewart import euler_kinematics

__all__ = ["platform_kinematics", "kinematics", "rate_map", "lever_jacobians", "mass_matrix_omega",
           "inverse_dynamics", "hip_bearing_friction", "regularised_sign", "coulomb_viscous",
           "forward_dynamics_omega", "mass_matrix", "actuator_map", "bias_forces", "inverse_dynamics_q",
           "forward_dynamics_q", "energies", "dissipation", "PARTS"]

#: the parts of Eq. (14) plus friction; ``tau`` is their sum
PARTS = ("platform", "lever", "slider", "screw", "friction")

_EZ = np.array([0.0, 0.0, 1.0])


def _skew(v):
    v = np.asarray(v, dtype=float)
    out = np.zeros(v.shape + (3,))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def _dot(a, b):
    return np.sum(a * b, axis=-1)


def regularised_sign(w, eps, vector):
    """``w / sqrt(|w|^2 + eps^2)`` (the norm over the last axis when ``vector``)."""
    w = np.asarray(w, dtype=float)
    n2 = np.sum(w * w, axis=-1, keepdims=True) if vector else w * w
    return w / np.sqrt(n2 + eps * eps)


def coulomb_viscous(w, coulomb, viscous, eps, vector):
    """Coulomb plus viscous friction ``C u(w) + b w`` (resisting; ``w . f >= 0``)."""
    return coulomb * regularised_sign(w, eps, vector) + viscous * np.asarray(w, dtype=float)


def hip_bearing_friction(omega, load, platform_weight, hip_radius, hip_coefficient, thrust_radius,
                         thrust_coefficient, eps):
    """Eq. (16): ``u(omega) (r_h mu_h |F| + r_t mu_t |F + m_m g|)`` (n, 3) [N m] on one platform,
    ``omega (n, 3)`` [rad/s], ``load (n,)`` [N], ``platform_weight`` = m_m g [N]."""
    load = np.asarray(load, dtype=float)
    mag = hip_radius * hip_coefficient * np.abs(load) + thrust_radius * thrust_coefficient * np.abs(
        load + platform_weight)
    return regularised_sign(omega, eps, True) * mag[..., None]


# --------------------------------------------------------------------------- kinematics


def platform_kinematics(model, R, omega, omega_dot):
    """Every body's motion from the platforms' ``R (n, 3, 3)``, ``omega, omega_dot (n, 3)``.

    Returns a namespace (``[sample, (platform,) leg, xyz]``):
    ``R, omega, omega_dot``; ``r (n, 3, 3)`` = R r_ai; ``L, Ld, Ldd (n, 2, 3)`` slider position,
    velocity, acceleration [m, m/s, m/s^2] per platform; ``Ja (n, 3)`` the diagonal of J_a;
    ``Jb, J (n, 3, 3)`` (row i of J: ``Ld_i = J_i . omega``); ``det_Ja, det_Jb, cond_J (n,)``;
    ``d, d_dot, d_ddot, e_lever (n, 3, 3)``; ``R_lever (n, 3, 3, 3)`` lever frame per module;
    ``omega_lever, omega_lever_dot, v_lever, a_lever (n, 3, 3)``; ``c_lever (n, 2, 3, 3)`` lever
    centres per platform; ``spin (n, 3)``; ``theta_dot (n, 3)`` the screws' rates [rad/s].
    A pose a leg cannot reach gives NaN in its entries.
    """
    g = model.geometry
    R = np.asarray(R, dtype=float)
    w = np.asarray(omega, dtype=float)
    wd = np.asarray(omega_dot, dtype=float)
    l2 = g.l * g.l
    r = np.einsum("nij,lj->nli", R, g.r_a)
    a2 = g.o[1] + r  # the lower platform's S joints
    dxy = a2[..., :2] - g.A[:, :2]
    reach2 = l2 - np.sum(dxy * dxy, axis=-1)
    with np.errstate(invalid="ignore"):
        dz = np.sqrt(np.where(reach2 > 0.0, reach2, np.nan))
    d = np.concatenate([dxy, dz[..., None]], axis=-1)
    L2 = a2[..., 2] - g.A[:, 2] - dz
    dh = g.h[0] - g.h[1]
    L = np.stack([L2 + dh, L2], axis=1)
    wn = w[:, None, :]
    v_a = np.cross(wn, r)
    Ld = _dot(d, v_a) / dz
    d_dot = v_a - Ld[..., None] * _EZ
    acc_a = np.cross(wd[:, None, :], r) + np.cross(wn, np.cross(wn, r))
    Ldd = (_dot(d, acc_a) + _dot(d_dot, d_dot)) / dz
    d_ddot = acc_a - Ldd[..., None] * _EZ
    e = d / g.l
    Ja = e[..., 2]
    Jb = np.cross(r, e)
    J = Jb / Ja[..., None]
    w_perp = np.cross(d, d_dot) / l2
    wd_perp = np.cross(d, d_ddot) / l2
    t = g.t[None]
    e_dot = d_dot / g.l
    if g.lever_spin == "u_joint":
        c = _dot(t, e)
        one = 1.0 - c * c
        wt = _dot(w_perp, t)
        spin = wt * c / one
        c_dot = _dot(t, e_dot)
        spin_dot = (_dot(wd_perp, t) * c + wt * c_dot) / one + 2.0 * wt * c * c * c_dot / (one * one)
    else:
        spin = np.zeros_like(Ld)
        spin_dot = np.zeros_like(Ld)
    omega_l = w_perp + spin[..., None] * e
    omega_l_dot = wd_perp + spin_dot[..., None] * e + spin[..., None] * e_dot
    x = np.cross(t, e)
    x /= np.linalg.norm(x, axis=-1, keepdims=True)
    R_lever = np.stack([x, np.cross(e, x), e], axis=-1)
    b = g.A[None, None] + L[..., None] * _EZ  # (n, platform, leg, 3)
    c_lever = b + 0.5 * d[:, None]
    ok = np.all(np.isfinite(J), axis=(1, 2))
    cond, det_Jb = np.full(len(R), np.nan), np.full(len(R), np.nan)
    if ok.any():
        cond[ok], det_Jb[ok] = np.linalg.cond(J[ok]), np.linalg.det(Jb[ok])
    return SimpleNamespace(
        R=R, omega=w, omega_dot=wd, r=r,
        L=L, Ld=np.stack([Ld, Ld], axis=1), Ldd=np.stack([Ldd, Ldd], axis=1),
        Ja=Ja, Jb=Jb, J=J, det_Ja=np.prod(Ja, axis=1), det_Jb=det_Jb, cond_J=cond,
        d=d, d_dot=d_dot, d_ddot=d_ddot, e_lever=e, R_lever=R_lever,
        omega_lever=omega_l, omega_lever_dot=omega_l_dot,
        v_lever=0.5 * d_dot + Ld[..., None] * _EZ, a_lever=0.5 * d_ddot + Ldd[..., None] * _EZ,
        c_lever=c_lever, spin=spin, theta_dot=Ld * 2.0 * np.pi / g.p,
    )


def kinematics(model, angles, rates=None, accels=None):
    """:func:`platform_kinematics` of the platforms' Euler angles ``(n, 3)`` [rad] in the model's
    sequence and their rates [rad/s, rad/s^2] (zero when omitted)."""
    ek = euler_kinematics(angles, model.geometry.euler_sequence, rates, accels)
    return platform_kinematics(model, ek["R"], ek["omega"], ek["omega_dot"])


def rate_map(model, q):
    """``E(q) (n, 3, 3)`` with ``omega = E qd`` (column k: ``omega`` of a unit rate of angle k)."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    n = len(q)
    cols = [euler_kinematics(q, model.geometry.euler_sequence, np.tile(np.eye(3)[k], (n, 1)))["omega"]
            for k in range(3)]
    return np.stack(cols, axis=-1)


# --------------------------------------------------------------------------- dynamics


def lever_jacobians(model, kin):
    """``(J_vl, J_wl) (n, 3, 3, 3)``: each lever's centre velocity and angular velocity per unit
    ``omega`` (``[sample, leg]``)."""
    g = model.geometry
    J = kin.J
    Jd = -_skew(kin.r) - _EZ[:, None] * J[..., None, :]
    Jvl = _EZ[:, None] * J[..., None, :] + 0.5 * Jd
    e = kin.e_lever
    if g.lever_spin == "u_joint":
        c = np.einsum("lk,nlk->nl", g.t, e)
        k = c / (1.0 - c * c)
    else:
        k = np.zeros(e.shape[:2])
    spin_map = np.eye(3) + k[..., None, None] * e[..., :, None] * g.t[None, :, None, :]
    Jwl = spin_map @ _skew(kin.d) @ Jd / (g.l * g.l)
    return Jvl, Jwl


def _platform_inertia(model, R):
    return np.einsum("nik,k,njk->nij", R, model.inertia.I_m, R)


def _lever_inertia(model, kin):
    return np.einsum("nlik,k,nljk->nlij", kin.R_lever, model.inertia.I_l, kin.R_lever)


def _to_motors(model, kin, Q):
    """``gear J^-T Q``: generalised forces ``Q (n, 3)`` dual to ``omega`` -> motor torques."""
    gear = model.geometry.p / (2.0 * np.pi)
    return gear * np.linalg.solve(np.swapaxes(kin.J, 1, 2), Q[..., None])[..., 0]


def inverse_dynamics(model, kin, load):
    """Motor torques and their parts (Eq. 7-14, 16), a namespace of ``(n, 3)`` [N m]: ``tau``,
    ``platform, lever, slider, screw, friction`` (their sum is ``tau``), ``hip_friction`` (the
    Eq. 16 part of ``friction``) and ``power (n,)`` [W] = sum tau theta_dot. ``load (n,)`` [N] is
    the hydraulic force on each platform, along -Z through its centre."""
    g, m, f = model.geometry, model.inertia, model.friction
    n_p = g.h.shape[0]
    gear = g.p / (2.0 * np.pi)
    load = np.broadcast_to(np.asarray(load, dtype=float), kin.R.shape[:1])
    Jvl, Jwl = lever_jacobians(model, kin)
    Iw = _platform_inertia(model, kin.R)
    w, wd = kin.omega, kin.omega_dot
    T_pl = np.einsum("nij,nj->ni", Iw, wd) + np.cross(w, np.einsum("nij,nj->ni", Iw, w))
    Il = _lever_inertia(model, kin)
    wl, wld = kin.omega_lever, kin.omega_lever_dot
    F_l = m.m_l * (kin.a_lever + m.g * _EZ)
    T_l = np.einsum("nlij,nlj->nli", Il, wld) + np.cross(wl, np.einsum("nlij,nlj->nli", Il, wl))
    Q_lever = n_p * (np.einsum("nlji,nlj->ni", Jvl, F_l) + np.einsum("nlji,nlj->ni", Jwl, T_l))
    Ld, Ldd = kin.Ld[:, 1], kin.Ldd[:, 1]
    platform = _to_motors(model, kin, n_p * T_pl)
    lever = _to_motors(model, kin, Q_lever)
    slider = gear * n_p * m.m_L * (Ldd + m.g)
    screw = m.I_L * Ldd / gear
    # friction: what each joint resists with, projected on omega by its relative velocity
    tau_hip = hip_bearing_friction(w, load, m.m_m * m.g, f.r_h, f.mu_h, f.r_t, f.mu_t, f.eps_w)
    hip = _to_motors(model, kin, n_p * tau_hip)
    tau_s = coulomb_viscous(wl - w[:, None], f.spherical_coulomb, f.spherical_viscous, f.eps_w, True)
    tau_u = coulomb_viscous(wl, f.universal_coulomb, f.universal_viscous, f.eps_w, True)
    Q_joints = n_p * (np.einsum("nlji,nlj->ni", Jwl, tau_s + tau_u) - tau_s.sum(axis=1))
    theta_dot = Ld / gear
    friction = (hip + _to_motors(model, kin, Q_joints)
                + gear * n_p * coulomb_viscous(Ld, f.slider_coulomb, f.slider_viscous, f.eps_v, False)
                + coulomb_viscous(theta_dot, f.screw_coulomb, f.screw_viscous, f.eps_w, False))
    tau = platform + lever + slider + screw + friction
    return SimpleNamespace(tau=tau, platform=platform, lever=lever, slider=slider, screw=screw,
                           friction=friction, hip_friction=hip, power=np.sum(tau * theta_dot, axis=1))


def mass_matrix_omega(model, kin):
    """``M_w (n, 3, 3)`` [kg m^2]: kinetic energy ``omega . M_w omega / 2`` of the whole machine
    (both platforms, six levers, the sliders and the three screw rotors) at the pose of ``kin``."""
    g, m = model.geometry, model.inertia
    n_p = g.h.shape[0]
    gear = g.p / (2.0 * np.pi)
    Jvl, Jwl = lever_jacobians(model, kin)
    M = n_p * _platform_inertia(model, kin.R)
    M = M + (n_p * m.m_L + m.I_L / gear**2) * np.einsum("nli,nlj->nij", kin.J, kin.J)
    Il = _lever_inertia(model, kin)
    M_l = m.m_l * np.swapaxes(Jvl, -1, -2) @ Jvl + np.swapaxes(Jwl, -1, -2) @ Il @ Jwl
    return M + n_p * M_l.sum(axis=1)


def forward_dynamics_omega(model, R, omega, tau, load):
    """``omega_dot (n, 3)`` [rad/s^2] under motor torques ``tau (n, 3)``: the inverse of
    :func:`inverse_dynamics`."""
    z = np.zeros_like(np.asarray(omega, dtype=float))
    kin0 = platform_kinematics(model, R, omega, z)
    b = inverse_dynamics(model, kin0, load).tau
    gear = model.geometry.p / (2.0 * np.pi)
    rhs = np.einsum("nli,nl->ni", kin0.J, np.asarray(tau, dtype=float) - b) / gear
    return np.linalg.solve(mass_matrix_omega(model, kin0), rhs[..., None])[..., 0]


def mass_matrix(model, q):
    """``M(q) = E^T M_w E (n, 3, 3)`` in the Euler angles."""
    E = rate_map(model, q)
    return np.swapaxes(E, 1, 2) @ mass_matrix_omega(model, kinematics(model, q)) @ E


def actuator_map(model, q):
    """``B(q) = E^T J^T / gear (n, 3, 3)``: generalised forces per unit motor torque
    (``B^T qd`` = the motors' rates)."""
    gear = model.geometry.p / (2.0 * np.pi)
    return np.swapaxes(rate_map(model, q), 1, 2) @ np.swapaxes(kinematics(model, q).J, 1, 2) / gear


def bias_forces(model, q, qd, load):
    """``h(q, qd, load) = B tau_h (n, 3)``, ``tau_h`` the torques that hold ``qdd = 0``."""
    tau_h = inverse_dynamics(model, kinematics(model, q, qd), load).tau
    return np.einsum("nij,nj->ni", actuator_map(model, q), tau_h)


def inverse_dynamics_q(model, q, qd, qdd, load):
    """Motor torques ``(n, 3)`` [N m] along Euler angles, rates and accelerations."""
    return inverse_dynamics(model, kinematics(model, q, qd, qdd), load).tau


def forward_dynamics_q(model, q, qd, u, load):
    """Euler-angle accelerations ``qdd (n, 3)`` under motor torques ``u``:
    ``E qdd = M_w^-1 J^T (u - tau_h) / gear``."""
    kin0 = kinematics(model, q, qd)
    tau_h = inverse_dynamics(model, kin0, load).tau
    gear = model.geometry.p / (2.0 * np.pi)
    rhs = np.einsum("nli,nl->ni", kin0.J, np.asarray(u, dtype=float) - tau_h) / gear
    E_qdd = np.linalg.solve(mass_matrix_omega(model, kin0), rhs[..., None])[..., 0]
    return np.linalg.solve(rate_map(model, q), E_qdd[..., None])[..., 0]


# --------------------------------------------------------------------------- energy


def energies(model, kin):
    """``(T, V) (n,)`` [J]: kinetic energy of every body and rotor and the potential energy of
    gravity, body by body from positions and velocities alone (no mass matrix)."""
    g, m = model.geometry, model.inertia
    n_p = g.h.shape[0]
    Iw = _platform_inertia(model, kin.R)
    Il = _lever_inertia(model, kin)
    T = n_p * 0.5 * np.einsum("ni,nij,nj->n", kin.omega, Iw, kin.omega)
    T = T + n_p * 0.5 * (m.m_l * np.sum(kin.v_lever**2, axis=(1, 2))
                         + np.einsum("nli,nlij,nlj->n", kin.omega_lever, Il, kin.omega_lever))
    T = T + 0.5 * m.m_L * np.sum(kin.Ld**2, axis=(1, 2)) + 0.5 * m.I_L * np.sum(kin.theta_dot**2, axis=1)
    V = m.g * (m.m_l * kin.c_lever[..., 2].sum(axis=(1, 2)) + m.m_L * kin.L.sum(axis=(1, 2))
               + m.m_m * g.o[:, 2].sum())
    return T, V


def dissipation(model, kin, load):
    """The power [W] (n,) every friction term dissipates, from the friction laws and the
    joints' relative velocities (no projection)."""
    f, m, g = model.friction, model.inertia, model.geometry
    n_p = g.h.shape[0]
    hip = hip_bearing_friction(kin.omega, load, m.m_m * m.g, f.r_h, f.mu_h, f.r_t, f.mu_t, f.eps_w)
    P = n_p * _dot(kin.omega, hip)
    ws = kin.omega_lever - kin.omega[:, None]
    P = P + n_p * np.sum(_dot(ws, coulomb_viscous(ws, f.spherical_coulomb, f.spherical_viscous, f.eps_w, True)), 1)
    wu = kin.omega_lever
    P = P + n_p * np.sum(_dot(wu, coulomb_viscous(wu, f.universal_coulomb, f.universal_viscous, f.eps_w, True)), 1)
    v = kin.Ld
    P = P + np.sum(v * coulomb_viscous(v, f.slider_coulomb, f.slider_viscous, f.eps_v, False), axis=(1, 2))
    th = kin.theta_dot
    return P + np.sum(th * coulomb_viscous(th, f.screw_coulomb, f.screw_viscous, f.eps_w, False), axis=1)
