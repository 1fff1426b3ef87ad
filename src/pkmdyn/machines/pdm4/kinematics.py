"""Inverse position, velocity and acceleration of every body of the PDM (Eq. 2-48).

All functions take a leading sample axis ``n``; nothing loops over samples. Pose
``q = (x, y, alpha, gamma)`` (n, 4) [m, m, rad, rad]: x, y of the platform point P in the
base frame A, alpha about the base z axis, gamma about the platform x axis (the R4 axis),
``T = Rz(alpha) Rx(gamma)`` (Eq. 3). The z coordinate of P is not free: ``p_z = r0 cos(gamma)``
(the parasitic motion of section 2.2).

Index ``i = 0, 1`` is the paper's crank / RPR limb i = 1, 2; ``j = 0, 1`` the SPU limb j = 3, 4;
limb arrays of width 4 are ordered l11, l12, l23, l24. Every vector is in the base frame A.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ...analysis.mobility import Joint
from ...errors import SingularityError, UnreachablePoseError
from ...spatial import axis_rotation, cross, dot
from .paper import BODY_NAMES, JOINTS, LIMB_LABELS
from .params import PdmModel, crank_angle

if TYPE_CHECKING:
    from ...profiles.pdm_motion import PdmMotion

__all__ = [
    "BodyState",
    "PdmPositions",
    "PdmKinematics",
    "BODY_NAMES",
    "unit_with_rates",
    "atan2_rates",
    "acos_rates",
    "inverse_position",
    "reachable",
    "inverse_kinematics",
    "mechanism_joints",
    "joint_points",
]

Array = NDArray[np.float64]
_Z = np.array([0.0, 0.0, 1.0])


# ----------------------------------------------------------------------------- helpers
def unit_with_rates(L: Array, Ld: Array, Ldd: Array) -> tuple[Array, Array, Array, Array, Array, Array]:
    """Unit vector ``u = L / l`` of a limb and the rates of ``u`` and ``l``, Eq. 33-34, 42-47.

    ``l_dot = u . L_dot`` (Eq. 43-44) and ``l_ddot = u . L_ddot + (|L_dot|^2 - l_dot^2) / l``
    (Eq. 47); ``u_dot = (L_dot - l_dot u) / l``, ``u_ddot = (L_ddot - l_ddot u - 2 l_dot u_dot) / l``.
    Shapes ``(..., 3)`` -> ``u, u_dot, u_ddot (..., 3)``, ``l, l_dot, l_ddot (...)``.
    """
    length = np.sqrt(dot(L, L))
    u = L / length[..., None]
    ld = dot(u, Ld)
    ud = (Ld - u * ld[..., None]) / length[..., None]
    ldd = dot(u, Ldd) + dot(ud, Ld)
    udd = (Ldd - u * ldd[..., None] - 2.0 * ud * ld[..., None]) / length[..., None]
    return u, ud, udd, length, ld, ldd


def atan2_rates(
    s: Array, sd: Array, sdd: Array, c: Array, cd: Array, cdd: Array
) -> tuple[Array, Array, Array]:
    """``phi = atan2(s, c)`` with ``phi_dot = (s_dot c - s c_dot) / D`` and its derivative, ``D = s^2 + c^2``."""
    den = s * s + c * c
    num = sd * c - s * cd
    numd = sdd * c - s * cdd
    dend = 2.0 * (s * sd + c * cd)
    return np.arctan2(s, c), num / den, (numd * den - num * dend) / (den * den)


def acos_rates(w: Array, wd: Array, wdd: Array) -> tuple[Array, Array, Array]:
    """``beta = acos(w)``, ``beta_dot = -w_dot / sin(beta)``, ``beta_ddot`` (Eq. 25 differentiated)."""
    s = np.sqrt(np.maximum(1.0 - w * w, 0.0))
    return np.arccos(np.clip(w, -1.0, 1.0)), -wd / s, -wdd / s - wd * wd * w / s**3


def _rigid(p0: Array, v0: Array, a0: Array, w: Array, e: Array, rho: Array) -> tuple[Array, Array, Array]:
    """Point ``p0 + rho`` of a rigid body: Eq. 35 and Eq. 38 (``a = a0 + e x rho + w x (w x rho)``)."""
    wr = cross(w, rho)
    return p0 + rho, v0 + wr, a0 + cross(e, rho) + cross(w, wr)


def _planar(v: Array) -> Array:
    """``(..., ) -> (..., 3)``: a scalar rate about the base z axis as a vector (Eq. 14, 18)."""
    out = np.zeros(v.shape + (3,))
    out[..., 2] = v
    return out


def _first(mask: Array) -> tuple[int, int]:
    """Sample and column of the first True of an (n, k) mask."""
    s, k = np.argwhere(mask)[0]
    return int(s), int(k)


def _when(t: Array | None, s: int) -> str:
    return f"t = {t[s]:.6g} s" if t is not None else f"sample {s}"


# ----------------------------------------------------------------------------- results
@dataclass(frozen=True)
class BodyState:
    """One rigid body: centre of mass ``p, v, a`` (n, 3) [m, m/s, m/s^2] and angular velocity
    ``w`` (n, 3) [rad/s] and acceleration ``wd`` (n, 3) [rad/s^2], all in the base frame;
    ``R`` (n, 3, 3) the rotation from the body's own frame to the base frame.

    Body frames (origin at the centre of mass; the x axis is the axis of the rod or tube that
    the inertia model of ``pdm4.inertia`` uses):

    - ``platform``: the platform frame, ``R = T = Rz(alpha) Rx(gamma)`` (Eq. 3), x = R4 axis;
    - ``link4``: ``Rz(alpha)``, x from R31 towards R32;
    - ``crank{i}``: ``Rz(theta_1i)``, x from R1i towards R2i; ``coupler{i}``: ``Rz(theta_2i)``,
      x from R2i towards R3i;
    - RPR ``cylinder{i}``, ``piston{i}``: x along the limb ``u`` (R4i -> R2i), z = base z,
      i.e. ``Rz(phi_i)`` (Eq. 17);
    - SPU ``cylinder{j}``, ``piston{j}``: x along the limb ``u`` (S2j -> U2j), y the second
      U-joint axis ``U_j2`` (Eq. 26, fixed in the limb), z = x cross y.

    The planar bodies (six-bar and RPR limbs) lie in stacked layers: their centres of mass sit
    at ``model.layer_z`` above the plane z = 0 of the output link; the offset is along their
    rotation axis, so it changes ``p`` only, never ``v`` or ``a``.
    """

    name: str
    p: Array
    v: Array
    a: Array
    w: Array
    wd: Array
    R: Array


@dataclass(frozen=True)
class PdmPositions:
    """Inverse position, Eq. 2-9. Base frame A; lengths [m], angles [rad].

    ``T`` (n, 3, 3) platform orientation (Eq. 3); ``P`` (n, 3) platform point; ``C`` (n, 3)
    output-link midpoint on the R4 axis; ``R2, R3`` (n, 2, 3) joint centres; ``theta1``
    (n, 2) crank angles (Eq. 7); ``theta2`` (n, 2) coupler angles (Eq. 12); ``U`` (n, 2, 3)
    U-joint centres; ``L`` (n, 4, 3) limb vectors from the fixed to the moving joint
    (Eq. 8-9, 33); ``l`` (n, 4) limb lengths.
    """

    T: Array
    P: Array
    C: Array
    R2: Array
    R3: Array
    theta1: Array
    theta2: Array
    U: Array
    L: Array
    l: Array


@dataclass(frozen=True)
class PdmKinematics:
    """Positions, velocities and accelerations of every body (Eq. 10-48), sample axis first.

    ``t`` (n,) [s]; ``q, qd, qdd`` (n, 4) pose and its rates; ``pos``: :class:`PdmPositions`;
    ``theta1d, theta1dd, theta2d, theta2dd`` (n, 2) [rad/s, rad/s^2] (Eq. 13, 36, 39);
    ``ld, ldd`` (n, 4) limb rates (Eq. 37, 40, 44, 47); ``u`` (n, 4, 3) limb unit vectors;
    ``rpr_angle, rpr_angle_d, rpr_angle_dd`` (n, 2) RPR limb angles about z (Eq. 17-18);
    ``euler, euler_d, euler_dd`` (n, 2, 3) z-x-z angles (alpha, beta, gamma) of the SPU limbs
    (Eq. 23-27) and their rates; ``U2, U3`` (n, 2, 3) second U-joint axis and the constraint
    torque direction (Eq. 26, 28); ``bodies``: one :class:`BodyState` per name in
    ``BODY_NAMES``; ``residual`` (n,) largest loop-closure error [m].
    """

    t: Array
    q: Array
    qd: Array
    qdd: Array
    pos: PdmPositions
    theta1d: Array
    theta1dd: Array
    theta2d: Array
    theta2dd: Array
    ld: Array
    ldd: Array
    u: Array
    rpr_angle: Array
    rpr_angle_d: Array
    rpr_angle_dd: Array
    euler: Array
    euler_d: Array
    euler_dd: Array
    U2: Array
    U3: Array
    bodies: tuple[BodyState, ...]
    residual: Array

    def body(self, name: str) -> BodyState:
        """The :class:`BodyState` called ``name`` (one of ``BODY_NAMES``)."""
        return self.bodies[BODY_NAMES.index(name)]


# ----------------------------------------------------------------------------- positions
def _platform_frame(model: PdmModel, q: Array) -> tuple[Array, Array, Array, Array]:
    """``T`` (Eq. 3), rotation of the output link ``Rz(alpha)``, ``P`` and ``C``, Eq. 2-4."""
    alpha, gamma = q[:, 2], q[:, 3]
    Rz = axis_rotation(2, alpha)
    T = Rz @ axis_rotation(0, gamma)
    d = T @ model.P_local
    P = np.stack([q[:, 0], q[:, 1], d[:, 2]], axis=-1)
    return T, Rz, P, P - d


def _positions(model: PdmModel, q: Array) -> tuple[PdmPositions, Array]:
    """Positions without checks; also returns the six-bar discriminants (n, 2)."""
    T, Rz, P, C = _platform_frame(model, q)
    R3 = C[:, None, :] + np.einsum("nab,ib->nia", Rz, model.R3_local)
    theta1, disc = crank_angle(model.R1[None], R3, model.r2, model.r3, np.asarray(model.branch, float))
    e1 = np.stack([np.cos(theta1), np.sin(theta1), np.zeros_like(theta1)], axis=-1)
    R2 = model.R1[None] + model.r2 * e1
    theta2 = np.arctan2(R3[..., 1] - R2[..., 1], R3[..., 0] - R2[..., 0])
    U = C[:, None, :] + np.einsum("nab,jb->nja", T, model.U_local)
    L = np.concatenate([R2 - model.R4[None], U - model.S[None]], axis=1)
    pos = PdmPositions(T=T, P=P, C=C, R2=R2, R3=R3, theta1=theta1, theta2=theta2, U=U, L=L,
                       l=np.sqrt(dot(L, L)))
    return pos, disc


def reachable(model: PdmModel, q: Array) -> Array:
    """Boolean mask (n,) of poses inside the workspace of section 2.2.

    A pose is reachable when both six-bar loops close (Eq. 7 has a real root), the angle
    between each crank and its coupler is at least ``min_transmission`` away from 0 and pi,
    and every limb extension ``l - l_home`` lies within ``+- stroke_limit``.
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    pos, disc = _positions(model, q)
    ok = np.all(disc > 0, axis=1)
    ok &= np.all(np.abs(np.sin(pos.theta2 - pos.theta1)) >= np.sin(model.min_transmission), axis=1)
    ok &= np.all(np.abs(pos.l - model.home_lengths) <= model.stroke_limit, axis=1)
    return ok


def inverse_position(
    model: PdmModel, q: Array, t: Array | None = None, check_strokes: bool = True
) -> PdmPositions:
    """Inverse position of module 1 and 2, Eq. 2-9, for poses ``q`` (n, 4).

    Raises :class:`~pkmdyn.errors.UnreachablePoseError` naming the sample time (``t`` (n,) [s],
    or the sample index) and the limb when a six-bar loop cannot close or, with
    ``check_strokes``, a limb would leave its ``+- stroke_limit`` range.
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    pos, disc = _positions(model, q)
    if np.any(disc < 0):
        s, i = _first(disc < 0)
        reach = np.linalg.norm(pos.R3[s, i, :2] - model.R1[i, :2])
        raise UnreachablePoseError(
            f"{_when(t, s)}: {LIMB_LABELS[i]}: the six-bar loop R1{i + 1}-R2{i + 1}-R3{i + 1} cannot close "
            f"(|R1{i + 1} R3{i + 1}| = {reach:.6g} m, crank and coupler span "
            f"{abs(model.r2 - model.r3):.6g} to {model.r2 + model.r3:.6g} m)"
        )
    if check_strokes:
        ext = pos.l - model.home_lengths
        bad = np.abs(ext) > model.stroke_limit * (1 + 1e-9)
        if np.any(bad):
            s, k = _first(bad)
            raise UnreachablePoseError(
                f"{_when(t, s)}: {LIMB_LABELS[k]} needs an extension of {ext[s, k] * 1e3:+.3f} mm, "
                f"beyond its stroke of +-{model.stroke_limit * 1e3:g} mm"
            )
    return pos


# ----------------------------------------------------------------------------- rates
def _sixbar_rates(
    model: PdmModel, pos: PdmPositions, vR3: Array, aR3: Array, t: Array | None
) -> tuple[Array, Array, Array, Array]:
    """Crank and coupler rates from the planar loop ``R3 - R1 = r2 e(theta1) + r3 e(theta2)``.

    Differentiating once gives ``[r2 e1_perp, r3 e2_perp] [theta1_dot, theta2_dot]^T = v_R3``
    (the closed form of Eq. 13 and 36); twice, the same matrix with right-hand side
    ``a_R3 + r2 theta1_dot^2 e1 + r3 theta2_dot^2 e2`` (Eq. 13 and 39). Solved by Cramer's
    rule; the determinant is ``r2 r3 sin(theta2 - theta1)``.
    """
    r2, r3 = model.r2, model.r3
    c1, s1 = np.cos(pos.theta1), np.sin(pos.theta1)
    c2, s2 = np.cos(pos.theta2), np.sin(pos.theta2)
    det = r2 * r3 * (c1 * s2 - s1 * c2)
    if np.any(np.abs(det) < 1e-12 * r2 * r3):
        s, i = _first(np.abs(det) < 1e-12 * r2 * r3)
        raise SingularityError(f"{_when(t, s)}: crank {i + 1} and coupler {i + 1} are aligned (six-bar singular)")

    def solve(bx: Array, by: Array) -> tuple[Array, Array]:
        return r3 * (c2 * bx + s2 * by) / det, -r2 * (c1 * bx + s1 * by) / det

    th1d, th2d = solve(vR3[..., 0], vR3[..., 1])
    bx = aR3[..., 0] + r2 * th1d**2 * c1 + r3 * th2d**2 * c2
    by = aR3[..., 1] + r2 * th1d**2 * s1 + r3 * th2d**2 * s2
    th1dd, th2dd = solve(bx, by)
    return th1d, th1dd, th2d, th2dd


def _limb_bodies(
    base: Array, u: Array, ud: Array, udd: Array, length: Array, ld: Array, ldd: Array,
    w: Array, wd: Array, c_cyl: Array, c_pis: Array,
) -> tuple[tuple[Array, Array, Array], tuple[Array, Array, Array]]:
    """Cylinder and piston centres of mass of a limb, Eq. 19-22.

    The cylinder turns about its fixed joint ``base``: ``r_1 = c1 u`` (Eq. 19-20). The piston's
    centre is ``r_2 = (l - c3) u`` from the same joint; besides the tangential and normal
    terms it carries the relative acceleration ``l_ddot u`` and the Coriolis term
    ``2 w x v_r`` with ``v_r = l_dot u`` (Eq. 21-22). ``c_cyl, c_pis`` broadcast over limbs.
    """
    zero = np.zeros_like(base)
    r1 = c_cyl[..., None] * u
    cyl = _rigid(base, zero, zero, w, wd, r1)
    r2 = (length - c_pis)[..., None] * u
    vr = ld[..., None] * u
    p, v, a = _rigid(base, zero, zero, w, wd, r2)
    pis = (p, v + vr, a + ldd[..., None] * u + 2.0 * cross(w, vr))
    return cyl, pis


def _spu_euler(
    Q: tuple[Array, Array, Array], U1: tuple[Array, Array, Array], t: Array | None
) -> tuple[Array, Array, Array, Array, Array, Array, Array]:
    """z-x-z Euler angles of the SPU limbs from the U-joint geometry, Eq. 23-32.

    The limb frame has its z axis along the limb ``Q`` (S2j -> U2j) and its x axis along the
    second U-joint axis ``U2 = Q x U1 / |Q x U1|`` (Eq. 26), U1 being the first axis, fixed
    in the platform. With ``R = Rz(a) Rx(b) Rz(g)`` (Eq. 23): ``a = atan2(Q_x, -Q_y)``,
    ``b = acos(Q_z)`` (Eq. 25) and ``g = atan2(U2_z, Y_z)`` with ``Y = Q x U2`` (Eq. 27 in
    four-quadrant form). Angular velocity ``w = J_t [a_dot, b_dot, g_dot]`` (Eq. 30-31) and
    acceleration ``J_t [a_ddot, b_ddot, g_ddot] + J_t_dot [a_dot, b_dot, g_dot]`` (Eq. 32).

    ``Q, U1``: (value, first, second derivative), each (n, 2, 3). Returns ``euler, euler_d,
    euler_dd`` (n, 2, 3), ``w, wd`` (n, 2, 3), ``U2`` and ``U3 = U1 x U2`` (Eq. 28).
    """
    q0, q1, q2 = Q
    u0, u1, u2 = U1
    W = (cross(q0, u0), cross(q1, u0) + cross(q0, u1), cross(q2, u0) + 2.0 * cross(q1, u1) + cross(q0, u2))
    wn = np.sqrt(dot(W[0], W[0]))
    if np.any(wn < 1e-9):
        s, j = _first(wn < 1e-9)
        raise SingularityError(f"{_when(t, s)}: {LIMB_LABELS[j + 2]} is parallel to its first U-joint axis")
    x0, x1, x2, *_ = unit_with_rates(*W)
    y0, y1, y2 = cross(q0, x0), cross(q1, x0) + cross(q0, x1), cross(q2, x0) + 2.0 * cross(q1, x1) + cross(q0, x2)
    sb = np.sqrt(q0[..., 0] ** 2 + q0[..., 1] ** 2)
    if np.any(sb < 1e-6):
        s, j = _first(sb < 1e-6)
        raise SingularityError(f"{_when(t, s)}: {LIMB_LABELS[j + 2]} is parallel to the base z axis (Euler singularity)")
    a = atan2_rates(q0[..., 0], q1[..., 0], q2[..., 0], -q0[..., 1], -q1[..., 1], -q2[..., 1])
    b = acos_rates(q0[..., 2], q1[..., 2], q2[..., 2])
    g = atan2_rates(x0[..., 2], x1[..., 2], x2[..., 2], y0[..., 2], y1[..., 2], y2[..., 2])
    euler = np.stack([a[0], b[0], g[0]], axis=-1)
    ed = np.stack([a[1], b[1], g[1]], axis=-1)
    edd = np.stack([a[2], b[2], g[2]], axis=-1)
    ca, sa, cb, sbb = np.cos(a[0]), np.sin(a[0]), np.cos(b[0]), np.sin(b[0])
    zero, one = np.zeros_like(ca), np.ones_like(ca)
    Jt = np.stack([
        np.stack([zero, ca, sa * sbb], axis=-1),
        np.stack([zero, sa, -ca * sbb], axis=-1),
        np.stack([one, zero, cb], axis=-1),
    ], axis=-2)
    ad, bd = a[1], b[1]
    Jtd = np.stack([
        np.stack([zero, -sa * ad, ca * sbb * ad + sa * cb * bd], axis=-1),
        np.stack([zero, ca * ad, sa * sbb * ad - ca * cb * bd], axis=-1),
        np.stack([zero, zero, -sbb * bd], axis=-1),
    ], axis=-2)
    w = np.einsum("njab,njb->nja", Jt, ed)
    wd = np.einsum("njab,njb->nja", Jt, edd) + np.einsum("njab,njb->nja", Jtd, ed)
    return euler, ed, edd, w, wd, x0, cross(u0, x0)


def inverse_kinematics(model: PdmModel, motion: PdmMotion, check_strokes: bool = True) -> PdmKinematics:
    """Positions, velocities and accelerations of all bodies for a platform motion, Eq. 2-48.

    ``motion`` carries ``t`` (n,) [s] and ``q, qd, qdd`` (n, 4). Order of the solution
    (section 3): platform (Eq. 2-4, 10-11, 35, 38), output link and R3i, cranks and couplers
    (Eq. 5-7, 12-16), RPR limbs (Eq. 8, 17-22, 33-40), SPU limbs (Eq. 9, 23-32, 41-48).
    Raises :class:`~pkmdyn.errors.UnreachablePoseError` or
    :class:`~pkmdyn.errors.SingularityError` naming the sample time and the limb.
    """
    t = motion.t
    q, qd, qdd = motion.q, motion.qd, motion.qdd
    pos = inverse_position(model, q, t, check_strokes)
    n = q.shape[0]
    alpha, gamma = q[:, 2], q[:, 3]
    ad, gd, add, gdd = qd[:, 2], qd[:, 3], qdd[:, 2], qdd[:, 3]

    # platform: w = alpha_dot z + gamma_dot x', x' = Rz(alpha) x (the R4 axis)
    xr = np.stack([np.cos(alpha), np.sin(alpha), np.zeros(n)], axis=-1)
    w_mp = _planar(ad) + gd[:, None] * xr
    wd_mp = _planar(add) + gdd[:, None] * xr + (ad * gd)[:, None] * cross(np.broadcast_to(_Z, xr.shape), xr)
    r0 = model.r0
    vP = np.stack([qd[:, 0], qd[:, 1], -r0 * np.sin(gamma) * gd], axis=-1)
    aP = np.stack([qdd[:, 0], qdd[:, 1], -r0 * (np.cos(gamma) * gd**2 + np.sin(gamma) * gdd)], axis=-1)
    d = pos.P - pos.C
    _, vC, aC = _rigid(pos.P, vP, aP, w_mp, wd_mp, -d)

    # output link r4 and R3i (Eq. 14-16 with the link's planar rotation alpha)
    w4, wd4 = _planar(ad), _planar(add)
    rho3 = pos.R3 - pos.C[:, None]
    _, vR3, aR3 = _rigid(pos.C[:, None], vC[:, None], aC[:, None], w4[:, None], wd4[:, None], rho3)

    # cranks and couplers (Eq. 12-16, 36, 39)
    th1d, th1dd, th2d, th2dd = _sixbar_rates(model, pos, vR3, aR3, t)
    R1 = np.broadcast_to(model.R1, pos.R2.shape)
    zero = np.zeros_like(pos.R2)
    rho2 = pos.R2 - R1
    _, vR2, aR2 = _rigid(R1, zero, zero, _planar(th1d), _planar(th1dd), rho2)
    crank = _rigid(R1, zero, zero, _planar(th1d), _planar(th1dd), 0.5 * rho2)
    coupler = _rigid(pos.R2, vR2, aR2, _planar(th2d), _planar(th2dd), 0.5 * (pos.R3 - pos.R2))

    # RPR limbs (Eq. 17-22, 33-40): planar, w = u x u_dot about z
    u12, ud12, udd12, l12, ld12, ldd12 = unit_with_rates(pos.L[:, :2], vR2, aR2)
    w_rpr = cross(u12, ud12)
    wd_rpr = cross(u12, udd12)
    rpr = atan2_rates(u12[..., 1], ud12[..., 1], udd12[..., 1], u12[..., 0], ud12[..., 0], udd12[..., 0])
    cyl12, pis12 = _limb_bodies(np.broadcast_to(model.R4, u12.shape), u12, ud12, udd12, l12, ld12, ldd12,
                                w_rpr, wd_rpr, model.cylinder_com[:2], model.piston_com[:2])

    # SPU limbs (Eq. 23-32, 41-48)
    rhoU = pos.U - pos.C[:, None]
    _, vU, aU = _rigid(pos.C[:, None], vC[:, None], aC[:, None], w_mp[:, None], wd_mp[:, None], rhoU)
    u34, ud34, udd34, l34, ld34, ldd34 = unit_with_rates(pos.L[:, 2:], vU, aU)
    U1 = np.broadcast_to((pos.T @ model.U1_local)[:, None], u34.shape)
    U1d = cross(w_mp[:, None], U1)
    U1dd = cross(wd_mp[:, None], U1) + cross(w_mp[:, None], U1d)
    euler, ed, edd, w_spu, wd_spu, U2, U3 = _spu_euler((u34, ud34, udd34), (U1, U1d, U1dd), t)
    cyl34, pis34 = _limb_bodies(np.broadcast_to(model.S, u34.shape), u34, ud34, udd34, l34, ld34, ldd34,
                                w_spu, wd_spu, model.cylinder_com[2:], model.piston_com[2:])

    def body(name: str, pva: tuple[Array, Array, Array], w: Array, wd: Array, R: Array) -> BodyState:
        p = pva[0]
        dz = float(model.layer_z[BODY_NAMES.index(name)])
        if dz != 0.0:
            p = p + np.array([0.0, 0.0, dz])
        return BodyState(name, p, pva[1], pva[2], np.ascontiguousarray(w), np.ascontiguousarray(wd), R)

    R_limb = np.empty((n, 4, 3, 3))
    R_limb[:, :2] = axis_rotation(2, rpr[0])
    R_limb[:, 2:, :, 0] = u34
    R_limb[:, 2:, :, 1] = U2
    R_limb[:, 2:, :, 2] = cross(u34, U2)

    w_l = np.concatenate([w_rpr, w_spu], axis=1)
    wd_l = np.concatenate([wd_rpr, wd_spu], axis=1)
    cyl = [np.concatenate([a, b], axis=1) for a, b in zip(cyl12, cyl34)]
    pis = [np.concatenate([a, b], axis=1) for a, b in zip(pis12, pis34)]
    bodies = [
        body("platform", (pos.P, vP, aP), w_mp, wd_mp, pos.T),
        body("link4", (pos.C, vC, aC), w4, wd4, axis_rotation(2, alpha)),
        *(body(f"crank{i + 1}", tuple(x[:, i] for x in crank), _planar(th1d[:, i]), _planar(th1dd[:, i]),  # type: ignore[arg-type]
               axis_rotation(2, pos.theta1[:, i])) for i in range(2)),
        *(body(f"coupler{i + 1}", tuple(x[:, i] for x in coupler), _planar(th2d[:, i]), _planar(th2dd[:, i]),  # type: ignore[arg-type]
               axis_rotation(2, pos.theta2[:, i])) for i in range(2)),
        *(body(f"cylinder{k + 1}", tuple(x[:, k] for x in cyl), w_l[:, k], wd_l[:, k], R_limb[:, k])  # type: ignore[arg-type]
          for k in range(4)),
        *(body(f"piston{k + 1}", tuple(x[:, k] for x in pis), w_l[:, k], wd_l[:, k], R_limb[:, k])  # type: ignore[arg-type]
          for k in range(4)),
    ]
    closure = np.abs(np.sqrt(dot(pos.R3 - pos.R2, pos.R3 - pos.R2)) - model.r3).max(axis=1)
    residual = np.maximum(closure, np.abs(pos.C[:, 2]))
    return PdmKinematics(
        t=t, q=q, qd=qd, qdd=qdd, pos=pos,
        theta1d=th1d, theta1dd=th1dd, theta2d=th2d, theta2dd=th2dd,
        ld=np.concatenate([ld12, ld34], axis=1), ldd=np.concatenate([ldd12, ldd34], axis=1),
        u=np.concatenate([u12, u34], axis=1),
        rpr_angle=rpr[0], rpr_angle_d=rpr[1], rpr_angle_dd=rpr[2],
        euler=euler, euler_d=ed, euler_dd=edd, U2=U2, U3=U3,
        bodies=tuple(bodies), residual=residual,
    )


# ----------------------------------------------------------------------------- joint list
def mechanism_joints(model: PdmModel, q: Array | None = None) -> list[Joint]:
    """The PDM's joints (Table I) at pose ``q`` (4,) (home when None), for
    :func:`pkmdyn.analysis.mobility.analyse`.

    Bodies: ``ground, crank1, crank2, coupler1, coupler2, link4, platform, cylinder1..4,
    piston1..4`` (14 moving links). Revolute axes of the six-bar and the RPR limbs are the
    base z axis; R4 is the platform x axis; U2j has first axis U1 (platform) and second axis
    U2 (limb). R2i is a compound joint of three bodies and counts as two revolutes
    (crank-coupler and crank-piston), which gives R = 11.
    """
    pose = np.zeros((1, 4)) if q is None else np.asarray(q, dtype=float).reshape(1, 4)
    pos = inverse_position(model, pose, check_strokes=False)
    z = (0.0, 0.0, 1.0)

    def pt(a: Array) -> tuple[float, float, float]:
        return (float(a[0]), float(a[1]), float(a[2]))

    u = pos.L[0] / pos.l[0][:, None]
    U1 = pos.T[0] @ model.U1_local
    joints = []
    for i in range(2):
        k = i + 1
        joints += [
            Joint(f"R1{k}", "R", "ground", f"crank{k}", pt(model.R1[i]), (z,)),
            Joint(f"R2{k}", "R", f"crank{k}", f"coupler{k}", pt(pos.R2[0, i]), (z,)),
            Joint(f"R2{k}'", "R", f"crank{k}", f"piston{k}", pt(pos.R2[0, i]), (z,)),
            Joint(f"R3{k}", "R", f"coupler{k}", "link4", pt(pos.R3[0, i]), (z,)),
            Joint(f"R4{k}", "R", "ground", f"cylinder{k}", pt(model.R4[i]), (z,)),
            Joint(f"P1{k}", "P", f"cylinder{k}", f"piston{k}", pt(pos.R2[0, i]), (pt(u[i]),)),
        ]
    joints.append(Joint("R4", "R", "link4", "platform", pt(pos.C[0]), (pt(U1),)))
    for j in range(2):
        k = j + 3
        U2 = np.cross(u[k - 1], U1)
        joints += [
            Joint(f"S2{k}", "S", "ground", f"cylinder{k}", pt(model.S[j])),
            Joint(f"P2{k}", "P", f"cylinder{k}", f"piston{k}", pt(pos.U[0, j]), (pt(u[k - 1]),)),
            Joint(f"U2{k}", "U", "platform", f"piston{k}", pt(pos.U[0, j]), (pt(U1), pt(U2 / np.linalg.norm(U2)))),
        ]
    return joints


_JOINT_NAMES = [j[0] for j in JOINTS]


def joint_points(model: PdmModel, kin: PdmKinematics) -> Array:
    """Joint centres (n, 19, 3) [m], base frame, in ``JOINTS`` order.

    Revolute joints between two planar layers sit half-way between the layers on the joint's
    axis; R1i and R4i sit in the crank and RPR-limb layers; P1i and P2j at the cylinder's
    mouth, ``2 c1`` from its fixed joint (the cylinder is a tube of length 2 c1, centre of
    mass at c1, section 4.2); R4 at C, S2j and U2j at their centres.
    """
    n = kin.q.shape[0]
    zk, zc, zl = (model.layer_z[BODY_NAMES.index(b)] for b in ("crank1", "coupler1", "cylinder1"))
    pos = kin.pos
    P = np.zeros((n, len(JOINTS), 3))

    def at(xy: Array, z: float) -> Array:
        out = np.array(xy, dtype=float, copy=True)
        out[..., 2] = z
        return out

    for i in range(2):
        k = i + 1
        P[:, _JOINT_NAMES.index(f"R1{k}")] = at(np.broadcast_to(model.R1[i], (n, 3)), zk)
        P[:, _JOINT_NAMES.index(f"R2{k}")] = at(pos.R2[:, i], 0.5 * (zk + zc))
        P[:, _JOINT_NAMES.index(f"R2{k}'")] = at(pos.R2[:, i], 0.5 * (zk + zl))
        P[:, _JOINT_NAMES.index(f"R3{k}")] = at(pos.R3[:, i], 0.5 * zc)
        P[:, _JOINT_NAMES.index(f"R4{k}")] = at(np.broadcast_to(model.R4[i], (n, 3)), zl)
        P[:, _JOINT_NAMES.index(f"P1{k}")] = at(model.R4[i] + 2.0 * model.cylinder_com[i] * kin.u[:, i], zl)
    P[:, _JOINT_NAMES.index("R4")] = pos.C
    for j in range(2):
        k = j + 3
        P[:, _JOINT_NAMES.index(f"S2{k}")] = model.S[j]
        P[:, _JOINT_NAMES.index(f"P2{k}")] = model.S[j] + 2.0 * model.cylinder_com[k - 1] * kin.u[:, k - 1]
        P[:, _JOINT_NAMES.index(f"U2{k}")] = pos.U[:, j]
    return P
