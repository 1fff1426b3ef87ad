"""Gough-Stewart platform (6-UPS / 6-SPS) inverse kinematics oracle.

Closed-form inverse position, velocity and acceleration analysis of the
six-leg platform, following the classical vector-loop derivation
(Gough & Whitehall 1962; Stewart 1965; Merlet, *Parallel Robots*, 2nd ed.,
Springer 2006, ch. 3-5; Tsai, *Robot Analysis*, Wiley 1999, sec. 4.6 / 6.x).

Frames and units
----------------
* Base frame {O}: fixed.  Platform frame {P}: attached to the platform,
  origin at the platform reference point, position ``p`` and rotation ``R``
  expressed in {O}.
* ``a`` (6,3): base joint centres in {O} [m].
* ``b`` (6,3): platform joint centres in {P} [m].
* Angles in rad, lengths in m, time in s.

Leg loop:  l_i = p + R b_i - a_i,   L_i = |l_i|,   u_i = l_i / L_i.
"""

from __future__ import annotations

import numpy as np

from ._batch import as_batch as _as_batch

_AXES = {"X": 0, "Y": 1, "Z": 2}


def axis_rotation(axis, angle):
    """Elementary rotation matrices about a coordinate axis.

    axis: one of "X", "Y", "Z"; angle: (n,) [rad]  ->  (n,3,3).
    """
    angle = np.asarray(angle, dtype=float)
    c, s = np.cos(angle), np.sin(angle)
    one, zero = np.ones_like(angle), np.zeros_like(angle)
    ax = axis.upper()
    if ax == "X":
        rows = [[one, zero, zero], [zero, c, -s], [zero, s, c]]
    elif ax == "Y":
        rows = [[c, zero, s], [zero, one, zero], [-s, zero, c]]
    elif ax == "Z":
        rows = [[c, -s, zero], [s, c, zero], [zero, zero, one]]
    else:
        raise ValueError(f"unknown axis {axis!r}")
    return np.moveaxis(np.array(rows), (0, 1), (-2, -1))


def _factors(seq):
    """Ordered list of (axis letter, angle index) for R = F1 F2 F3."""
    if len(seq) != 3 or seq.upper() not in {
        a + b + c for a in "XYZ" for b in "XYZ" for c in "XYZ" if a != b and b != c
    }:
        raise ValueError(f"unsupported Euler sequence {seq!r}")
    if seq.isupper():  # intrinsic (moving axes): R = R_s0(q0) R_s1(q1) R_s2(q2)
        return [(seq[0], 0), (seq[1], 1), (seq[2], 2)]
    if seq.islower():  # extrinsic (fixed axes): R = R_s2(q2) R_s1(q1) R_s0(q0)
        s = seq.upper()
        return [(s[2], 2), (s[1], 1), (s[0], 0)]
    raise ValueError("Euler sequence must be all upper (intrinsic) or all lower (extrinsic) case")


def euler_kinematics(angles, seq="XYZ", angles_d=None, angles_dd=None):
    """Rotation, angular velocity and angular acceleration from Euler angles.

    angles, angles_d, angles_dd: (n,3) [rad, rad/s, rad/s^2], given in the
    order of the letters of ``seq``.

    seq upper case = intrinsic: "XYZ" -> R = Rx(q0) Ry(q1) Rz(q2);
                                 "ZYX" -> R = Rz(q0) Ry(q1) Rx(q2).
    seq lower case = extrinsic: "xyz" -> R = Rz(q2) Ry(q1) Rx(q0).
    (Same meaning as scipy.spatial.transform.Rotation.from_euler.)

    Returns dict:
      R (n,3,3)        platform orientation, maps {P} components to {O};
      omega (n,3)      angular velocity in {O} (space frame) [rad/s];
      omega_dot (n,3)  its time derivative in {O} [rad/s^2].
    For R = F1(x1) F2(x2) F3(x3) with unit axes e_k:
      s1 = e1, s2 = F1 e2, s3 = F1 F2 e3,  omega = sum_k xd_k s_k,
      omega_dot = sum_k xdd_k s_k + xd2 (xd1 s1 x s2) + xd3 ((xd1 s1 + xd2 s2) x s3).
    """
    angles = _as_batch(angles, 3)
    n = angles.shape[0]
    qd = np.zeros_like(angles) if angles_d is None else _as_batch(angles_d, 3)
    qdd = np.zeros_like(angles) if angles_dd is None else _as_batch(angles_dd, 3)
    fac = _factors(seq)
    mats = [axis_rotation(ax, angles[:, k]) for ax, k in fac]
    x_d = [qd[:, k] for _, k in fac]
    x_dd = [qdd[:, k] for _, k in fac]
    e = [np.eye(3)[_AXES[ax.upper()]] for ax, _ in fac]
    R = mats[0] @ mats[1] @ mats[2]
    s1 = np.broadcast_to(e[0], (n, 3))
    s2 = mats[0] @ e[1]
    s3 = (mats[0] @ mats[1]) @ e[2]
    omega = x_d[0][:, None] * s1 + x_d[1][:, None] * s2 + x_d[2][:, None] * s3
    w1 = x_d[0][:, None] * s1
    w12 = w1 + x_d[1][:, None] * s2
    omega_dot = (
        x_dd[0][:, None] * s1
        + x_dd[1][:, None] * s2
        + x_dd[2][:, None] * s3
        + x_d[1][:, None] * np.cross(w1, s2)
        + x_d[2][:, None] * np.cross(w12, s3)
    )
    return {"R": R, "omega": omega, "omega_dot": omega_dot}


def inverse_jacobian(a, b, p, R):
    """Inverse Jacobian J (n,6,6): Ld = J @ [v; omega].

    v = platform reference point velocity in {O}, omega = angular velocity in
    {O}.  Row i = [u_i^T, (R b_i x u_i)^T].
    a (6,3), b (6,3), p (n,3) [m], R (n,3,3).  Returns (J, u) with u (n,6,3).
    """
    a = np.asarray(a, float)
    b = np.asarray(b, float)
    p = _as_batch(p, 3)
    r = np.einsum("nij,kj->nki", R, b)  # (n,6,3) R b_i in {O}
    l = p[:, None, :] + r - a[None]
    u = l / np.linalg.norm(l, axis=-1, keepdims=True)
    J = np.concatenate([u, np.cross(r, u)], axis=-1)
    return J, u


def inverse_kinematics(a, b, p, angles, seq="XYZ", pd=None, angles_d=None,
                       pdd=None, angles_dd=None):
    """Leg lengths, rates, accelerations, Jacobian and leg angular motion.

    Inputs
      a (6,3) base joint points in {O} [m]; b (6,3) platform joint points in {P} [m]
      p, pd, pdd (n,3): platform reference point position / velocity /
        acceleration in {O} [m, m/s, m/s^2] (pd, pdd default 0)
      angles, angles_d, angles_dd (n,3): Euler angles of sequence ``seq``
        and their time derivatives (see ``euler_kinematics``)
    Returns dict (n = number of samples, i = leg 0..5):
      R (n,3,3), omega (n,3), omega_dot (n,3)     platform orientation / twist
      r (n,6,3)   R b_i, platform joint offset in {O} [m]
      B (n,6,3)   platform joint centres p + R b_i in {O} [m]
      l (n,6,3)   leg vectors B_i - a_i [m]
      L (n,6)     leg lengths |l_i| [m]
      u (n,6,3)   leg unit vectors l_i / L_i
      Ld (n,6)    leg rates  u_i . (v + omega x r_i) [m/s]
      Ldd (n,6)   leg accelerations u_i . ldd_i + (|ld_i|^2 - Ld_i^2) / L_i [m/s^2]
                  with ldd_i = a_p + omega_dot x r_i + omega x (omega x r_i)
      J (n,6,6)   inverse Jacobian, Ld = J [v; omega]
      ud, udd (n,6,3)  first / second time derivatives of u_i
      leg_omega (n,6,3)      u_i x ud_i : angular velocity of leg i (cylinder
                             about its base joint), the component perpendicular
                             to u_i (spin about u_i is not defined by the
                             kinematics and is taken as zero) [rad/s]
      leg_omega_dot (n,6,3)  u_i x udd_i, time derivative of leg_omega [rad/s^2]
    """
    a = np.asarray(a, float)
    b = np.asarray(b, float)
    p = _as_batch(p, 3)
    n = p.shape[0]
    v = np.zeros((n, 3)) if pd is None else _as_batch(pd, 3)
    acc = np.zeros((n, 3)) if pdd is None else _as_batch(pdd, 3)
    ek = euler_kinematics(angles, seq, angles_d, angles_dd)
    R, w, wd = ek["R"], ek["omega"], ek["omega_dot"]
    r = np.einsum("nij,kj->nki", R, b)
    Bpts = p[:, None, :] + r
    l = Bpts - a[None]
    L = np.linalg.norm(l, axis=-1)
    u = l / L[..., None]
    W = np.broadcast_to(w[:, None, :], r.shape)
    Wd = np.broadcast_to(wd[:, None, :], r.shape)
    ld = v[:, None, :] + np.cross(W, r)
    ldd = acc[:, None, :] + np.cross(Wd, r) + np.cross(W, np.cross(W, r))
    Ld = np.einsum("nki,nki->nk", u, ld)
    Ldd = np.einsum("nki,nki->nk", u, ldd) + (np.einsum("nki,nki->nk", ld, ld) - Ld**2) / L
    J = np.concatenate([u, np.cross(r, u)], axis=-1)
    ud = (ld - Ld[..., None] * u) / L[..., None]
    udd = (ldd - Ldd[..., None] * u - 2.0 * Ld[..., None] * ud) / L[..., None]
    return {
        "R": R, "omega": w, "omega_dot": wd, "r": r, "B": Bpts, "l": l,
        "L": L, "u": u, "Ld": Ld, "Ldd": Ldd, "J": J, "ud": ud, "udd": udd,
        "leg_omega": np.cross(u, ud), "leg_omega_dot": np.cross(u, udd),
    }


def ups_leg_angular_velocity(u, ud, udd, n1):
    """Angular velocity / acceleration of a leg hung from a base universal joint.

    For a 6-UPS leg the cylinder cannot spin freely about its axis: its
    angular velocity lies in the span of the U-joint axes n1 (fixed in the
    base, unit) and n2 = n1 x u / |n1 x u| (fixed in the cylinder, normal to
    n1 and u).  Writing omega = u x ud + s u (the first term is the
    perpendicular part returned by ``inverse_kinematics``), the condition
    omega . (n1 x n2) = 0 gives, with c = n1 . u,
        s = ((u x ud) . n1) c / (1 - c^2),
    and by differentiation (cd = n1 . ud, N = ((u x ud) . n1) c, D = 1 - c^2)
        sd = (Nd D - N Dd) / D^2,  Nd = ((u x udd) . n1) c + ((u x ud) . n1) cd,
        Dd = -2 c cd,
        omega_dot = u x udd + sd u + s ud.
    u, ud, udd (..., 3) from ``inverse_kinematics``; n1 (3,) or (..., 3).
    Singular when u is parallel to n1 (c = +-1).
    Returns (omega, omega_dot, spin) with spin = s (..., ) [rad/s].
    """
    u, ud, udd = (np.asarray(x, float) for x in (u, ud, udd))
    n1 = np.broadcast_to(np.asarray(n1, float), u.shape)
    wp = np.cross(u, ud)
    wpd = np.cross(u, udd)
    c = np.sum(n1 * u, -1)
    cd = np.sum(n1 * ud, -1)
    N = np.sum(wp * n1, -1) * c
    D = 1.0 - c**2
    Nd = np.sum(wpd * n1, -1) * c + np.sum(wp * n1, -1) * cd
    Dd = -2.0 * c * cd
    sp = N / D
    spd = (Nd * D - N * Dd) / D**2
    omega = wp + sp[..., None] * u
    omega_dot = wpd + spd[..., None] * u + sp[..., None] * ud
    return omega, omega_dot, sp


def semi_regular_hexagon(base_radius, platform_radius, base_half_angle,
                         platform_half_angle, base_offset=0.0):
    """Joint points of the semi-regular (6-6, "hexagonal") Gough-Stewart platform.

    All joints lie in the z = 0 plane of their own frame.  Angles in rad.
    Leg i = 0..5, pair k = i // 2, side s = -1 for even i, +1 for odd i:
      base:     a_i = R_b (cos A_i, sin A_i, 0),  A_i = base_offset + 120deg*k + s*gamma_b
      platform: b_i = R_p (cos B_i, sin B_i, 0),  B_i = base_offset + 120deg*k + s*(60deg - gamma_p)
    gamma_b = ``base_half_angle``: half the angle subtended at the base centre by
    the two joints of one base pair (pairs centred at 0, 120, 240 deg);
    gamma_p = ``platform_half_angle``: the same for the platform pairs, which are
    centred at 60, 180, 300 deg.  Each leg joins a base joint to the nearer
    joint of the adjacent platform pair, so adjacent legs cross (the usual
    "triangle-to-triangle" arrangement).  With gamma_b = 0 and gamma_p = 60 deg
    the geometry degenerates to the singular 3-3 octahedral case; use
    0 < gamma < 60 deg.

    Returns a (6,3), b (6,3) [m].
    """
    i = np.arange(6)
    k = i // 2
    s = np.where(i % 2 == 0, -1.0, 1.0)
    third = 2.0 * np.pi / 3.0
    A = base_offset + third * k + s * base_half_angle
    Bang = base_offset + third * k + s * (np.pi / 3.0 - platform_half_angle)
    a = np.stack([base_radius * np.cos(A), base_radius * np.sin(A), np.zeros(6)], -1)
    b = np.stack([platform_radius * np.cos(Bang), platform_radius * np.sin(Bang), np.zeros(6)], -1)
    return a, b


def default_geometry():
    """Documented default semi-regular hexagon (not a published design).

    R_b = 1.0 m, R_p = 0.5 m, gamma_b = 10 deg, gamma_p = 10 deg; nominal home
    height 1.0 m (p = (0, 0, 1.0)).  A plausible, well-conditioned geometry
    of the proportions typical of flight-simulator motion bases (platform
    radius about half the base radius, legs about 1 - 1.5 R_b long).
    Returns (a, b, home_p).
    """
    a, b = semi_regular_hexagon(1.0, 0.5, np.radians(10.0), np.radians(10.0))
    return a, b, np.array([0.0, 0.0, 1.0])
