"""The hip simulator's single-sample real-time path: inverse and forward dynamics in a few us.

A controller calls the model once per control cycle with one sample. The batched verbs spend
hundreds of microseconds of numpy call overhead on such a call, so this module evaluates the
same equations (Eq. 1-16 of the hip paper, the virtual-work projection of :mod:`.dynamics`
and the mass matrix of :mod:`.forward`, in the Euler coordinates of :mod:`.minimal`) as scalar
code compiled by Numba, over the model's numbers packed once into a flat array.

For one sample ``(q, qd)`` the kernel computes

- the rotation ``R``, the Euler-rate map ``E`` and the drift ``Edot qd`` (the sequence is
  handled as intrinsic axes; an extrinsic one by reversing its angles);
- per leg: the loop closure (Eq. 2), ``J_i`` (Eq. 3), the slider acceleration at zero
  platform acceleration (Eq. 5), the lever's angular velocity and acceleration (Eq. 4, 6,
  plus the U-joint spin), and the lever's Jacobians ``J_vl, J_wl``;
- ``M_w`` (mass matrix in ``omega``) and ``Q_b``, the generalised force dual to ``omega``
  that holds ``omega_dot = 0``: platform gyroscopic torque, lever inertia and gravity,
  slider and screw inertia and gravity, and every friction term with its load;

then ``tau = (p / 2 pi) J^-T (M_w omega_dot + Q_b)`` with ``omega_dot = E qdd + Edot qd``
(inverse dynamics) or ``qdd = E^-1 (M_w^-1 ((2 pi / p) J^T u - Q_b) - Edot qd)`` (forward
dynamics). The batched path remains the reference; the tests check that both agree.
"""

from __future__ import annotations

import math
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

from ...errors import MotionError, SingularityError, UnreachablePoseError
from .params import HipModel

__all__ = ["pack", "kernels", "inverse_dynamics_one", "forward_dynamics_one"]

Array = NDArray[np.float64]

# offsets into the packed parameter array
_L, _GEAR, _NP, _ML, _MLEV, _IL, _MM, _G = 0, 1, 2, 3, 4, 5, 6, 7
_ILEV, _IM = 8, 11  # 3 each
_SPIN, _RH, _MUH, _RT, _MUT, _EPSW, _EPSV = 14, 15, 16, 17, 18, 19, 20
_FRIC = 21  # 8: slider c, v, screw c, v, spherical c, v, universal c, v
_AXES, _EXTR = 29, 32  # 3 intrinsic axes, extrinsic flag
_A, _RA, _T = 33, 42, 51  # 9 each, [leg, xyz]
_SIZE = 60

_AXIS = {"x": 0, "y": 1, "z": 2}

_cache: dict[int, tuple[HipModel, Array]] = {}


def pack(model: HipModel) -> Array:
    """The model's numbers as one flat ``float64`` array (cached per model object)."""
    hit = _cache.get(id(model))
    if hit is not None and hit[0] is model:
        return hit[1]
    g, m, f = model.geometry, model.inertia, model.friction
    p = np.zeros(_SIZE)
    p[_L], p[_GEAR], p[_NP] = g.l, g.p / (2.0 * np.pi), g.h.shape[0]
    p[_ML], p[_MLEV], p[_IL], p[_MM], p[_G] = m.m_L, m.m_l, m.I_L, m.m_m, m.g
    p[_ILEV : _ILEV + 3] = m.I_l
    p[_IM : _IM + 3] = m.I_m
    p[_SPIN] = 1.0 if g.lever_spin == "u_joint" else 0.0
    p[_RH], p[_MUH], p[_RT], p[_MUT], p[_EPSW], p[_EPSV] = f.r_h, f.mu_h, f.r_t, f.mu_t, f.eps_w, f.eps_v
    p[_FRIC : _FRIC + 8] = (
        f.slider_coulomb,
        f.slider_viscous,
        f.screw_coulomb,
        f.screw_viscous,
        f.spherical_coulomb,
        f.spherical_viscous,
        f.universal_coulomb,
        f.universal_viscous,
    )
    seq = g.euler_sequence
    extrinsic = seq.islower()
    axes = [_AXIS[c.lower()] for c in (reversed(seq) if extrinsic else seq)]
    p[_AXES : _AXES + 3] = axes
    p[_EXTR] = 1.0 if extrinsic else 0.0
    p[_A : _A + 9] = g.A.ravel()
    p[_RA : _RA + 9] = g.r_a.ravel()
    p[_T : _T + 9] = g.t.ravel()
    p.setflags(write=False)
    if len(_cache) > 64:
        _cache.clear()
    _cache[id(model)] = (model, p)
    return p


# ---------------------------------------------------------------- scalar kernels
# 3-vectors are tuples (x, y, z) and 3x3 matrices tuples of rows, so that nothing is allocated
# on the heap inside a call.

_jit = numba.njit(cache=True, fastmath=False, error_model="numpy")


@_jit
def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@_jit
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@_jit
def _axpy(s, a, b):
    """``s a + b``."""
    return (s * a[0] + b[0], s * a[1] + b[1], s * a[2] + b[2])


@_jit
def _scale(s, a):
    return (s * a[0], s * a[1], s * a[2])


@_jit
def _col(A, j):
    return (A[0][j], A[1][j], A[2][j])


@_jit
def _mv(A, x):
    return (_dot(A[0], x), _dot(A[1], x), _dot(A[2], x))


@_jit
def _mtv(A, x):
    """``A^T x``."""
    return (
        A[0][0] * x[0] + A[1][0] * x[1] + A[2][0] * x[2],
        A[0][1] * x[0] + A[1][1] * x[1] + A[2][1] * x[2],
        A[0][2] * x[0] + A[1][2] * x[1] + A[2][2] * x[2],
    )


@_jit
def _mm(A, B):
    c0, c1, c2 = _col(B, 0), _col(B, 1), _col(B, 2)
    return (
        (_dot(A[0], c0), _dot(A[0], c1), _dot(A[0], c2)),
        (_dot(A[1], c0), _dot(A[1], c1), _dot(A[1], c2)),
        (_dot(A[2], c0), _dot(A[2], c1), _dot(A[2], c2)),
    )


@_jit
def _axis_rot(axis, angle):
    """Rotation by ``angle`` [rad] about base axis 0, 1 or 2 (rows)."""
    c, s = math.cos(angle), math.sin(angle)
    if axis == 0:
        return ((1.0, 0.0, 0.0), (0.0, c, -s), (0.0, s, c))
    if axis == 1:
        return ((c, 0.0, s), (0.0, 1.0, 0.0), (-s, 0.0, c))
    return ((c, -s, 0.0), (s, c, 0.0), (0.0, 0.0, 1.0))


@_jit
def _inv3(A):
    """Inverse of ``A`` by cofactors and its determinant (the inverse is garbage when det = 0)."""
    c0 = _cross(A[1], A[2])
    c1 = _cross(A[2], A[0])
    c2 = _cross(A[0], A[1])
    det = _dot(A[0], c0)
    inv = 1.0 / det if det != 0.0 else 0.0
    # columns of A^-1 are the cofactor rows / det
    return ((c0[0] * inv, c1[0] * inv, c2[0] * inv), (c0[1] * inv, c1[1] * inv, c2[1] * inv), (c0[2] * inv, c1[2] * inv, c2[2] * inv)), det


@_jit
def _inertia_times(f0, f1, f2, I0, I1, I2, w):
    """``(F diag(I) F^T) w`` for a frame with columns ``f0, f1, f2``."""
    return _axpy(I0 * _dot(f0, w), f0, _axpy(I1 * _dot(f1, w), f1, _scale(I2 * _dot(f2, w), f2)))


@_jit
def _reg(w, eps):
    """``w / sqrt(|w|^2 + eps^2)``: the regularised sign of a 3-vector."""
    return _scale(1.0 / math.sqrt(_dot(w, w) + eps * eps), w)


@_jit
def _lever_force(J_i, r, d, e, t, k, l2, F, T):
    """``J_vl^T F + J_wl^T T`` (the projection of :func:`.dynamics.lever_generalised_force`)."""
    Tp = _axpy(k * _dot(e, T), t, T)
    X = _axpy(1.0 / l2, _cross(Tp, d), _scale(0.5, F))
    return _axpy(F[2] - X[2], J_i, _cross(r, X))


@_jit
def _model(p, qi, qdi, load, M):
    """Mass matrix ``M_w`` (into ``M (3, 3)``), bias ``Q_b``, ``J`` (rows), ``E``, ``Edot qd``.

    ``qi, qdi`` are tuples in intrinsic order. Returns ``(status, Q_b, J, E, wd0)``; status 0 ok,
    1 + leg an unreachable leg, 10 a lever aligned with its U joint's first axis.
    """
    l = p[_L]
    l2 = l * l
    gear = p[_GEAR]
    n_p = p[_NP]
    m_L, m_l, I_L, m_m, g = p[_ML], p[_MLEV], p[_IL], p[_MM], p[_G]
    Il0, Il1, Il2 = p[_ILEV], p[_ILEV + 1], p[_ILEV + 2]
    spin_on = p[_SPIN] != 0.0
    eps_w, eps_v = p[_EPSW], p[_EPSV]
    sl_c, sl_v = p[_FRIC], p[_FRIC + 1]
    sc_c, sc_v = p[_FRIC + 2], p[_FRIC + 3]
    sp_c, sp_v = p[_FRIC + 4], p[_FRIC + 5]
    un_c, un_v = p[_FRIC + 6], p[_FRIC + 7]
    ez = (0.0, 0.0, 1.0)

    # Euler kinematics: R = R1 R2 R3, E = [k1, R1 k2, R1 R2 k3], drift Edot qd
    a1, a2, a3 = int(p[_AXES]), int(p[_AXES + 1]), int(p[_AXES + 2])
    R1 = _axis_rot(a1, qi[0])
    R12 = _mm(R1, _axis_rot(a2, qi[1]))
    R = _mm(R12, _axis_rot(a3, qi[2]))
    e1 = (1.0 if a1 == 0 else 0.0, 1.0 if a1 == 1 else 0.0, 1.0 if a1 == 2 else 0.0)
    e2 = _col(R1, a2)
    e3 = _col(R12, a3)
    E = ((e1[0], e2[0], e3[0]), (e1[1], e2[1], e3[1]), (e1[2], e2[2], e3[2]))
    w1 = _scale(qdi[0], e1)
    w12 = _axpy(qdi[1], e2, w1)
    w = _axpy(qdi[2], e3, w12)
    wd0 = _axpy(qdi[1], _cross(w1, e2), _scale(qdi[2], _cross(w12, e3)))

    # platforms, Eq. (7): M_w = n_p R diag(I_m) R^T; gyroscopic torque n_p w x I_w w
    R0c, R1c, R2c = _col(R, 0), _col(R, 1), _col(R, 2)
    Im0, Im1, Im2 = p[_IM], p[_IM + 1], p[_IM + 2]
    for i in range(3):
        for j in range(3):
            M[i, j] = n_p * (R[i][0] * Im0 * R[j][0] + R[i][1] * Im1 * R[j][1] + R[i][2] * Im2 * R[j][2])
    Qb = _scale(n_p, _cross(w, _inertia_times(R0c, R1c, R2c, Im0, Im1, Im2, w)))

    # hip joints and thrust bearings, Eq. (16)
    mag = p[_RH] * p[_MUH] * abs(load) + p[_RT] * p[_MUT] * abs(load + m_m * g)
    Qb = _axpy(n_p * mag, _reg(w, eps_w), Qb)

    m_ax = n_p * m_L + I_L / (gear * gear)
    zero = (0.0, 0.0, 0.0)
    J0 = zero
    J1 = zero
    J2 = zero
    for leg in range(3):
        ra = (p[_RA + 3 * leg], p[_RA + 3 * leg + 1], p[_RA + 3 * leg + 2])
        t = (p[_T + 3 * leg], p[_T + 3 * leg + 1], p[_T + 3 * leg + 2])
        r = _mv(R, ra)
        # loop closure, Eq. (2)
        dx = r[0] - p[_A + 3 * leg]
        dy = r[1] - p[_A + 3 * leg + 1]
        reach2 = l2 - dx * dx - dy * dy
        if not reach2 > 0.0:
            return 1 + leg, Qb, (J0, J1, J2), E, wd0
        dz = math.sqrt(reach2)
        d = (dx, dy, dz)
        e = _scale(1.0 / l, d)
        # Jacobian row, Eq. (3): J_i = (r x e) / e_z
        J_i = _scale(1.0 / e[2], _cross(r, e))
        if leg == 0:
            J0 = J_i
        elif leg == 1:
            J1 = J_i
        else:
            J2 = J_i
        # velocities and accelerations at omega_dot = 0, Eq. (3), (5)
        v_a = _cross(w, r)
        Ld = _dot(d, v_a) / dz
        d_dot = (v_a[0], v_a[1], v_a[2] - Ld)
        a_a = _cross(w, v_a)
        Ldd = (_dot(d, a_a) + _dot(d_dot, d_dot)) / dz
        d_dd = (a_a[0], a_a[1], a_a[2] - Ldd)
        # lever angular velocity and acceleration, Eq. (4), (6) plus the U-joint spin
        w_perp = _scale(1.0 / l2, _cross(d, d_dot))
        wd_perp = _scale(1.0 / l2, _cross(d, d_dd))
        k = 0.0
        w_l = w_perp
        wd_l = wd_perp
        if spin_on:
            c = _dot(t, e)
            one_c2 = 1.0 - c * c
            if one_c2 < 1e-12:
                return 10, Qb, (J0, J1, J2), E, wd0
            k = c / one_c2
            wt = _dot(w_perp, t)
            spin = wt * c / one_c2
            c_dot = _dot(t, d_dot) / l
            wt_dot = _dot(wd_perp, t)
            spin_dot = (wt_dot * c + wt * c_dot) / one_c2 + 2.0 * wt * c * c * c_dot / (one_c2 * one_c2)
            w_l = _axpy(spin, e, w_perp)
            wd_l = _axpy(spin / l, d_dot, _axpy(spin_dot, e, wd_perp))
        # lever frame: x = t x e / |t x e|, y = e x x, z = e
        tx = _cross(t, e)
        fx = _scale(1.0 / math.sqrt(_dot(tx, tx)), tx)
        fy = _cross(e, fx)
        # lever inertia and gravity, Eq. (8)
        F = (0.5 * m_l * d_dd[0], 0.5 * m_l * d_dd[1], 0.5 * m_l * d_dd[2] + m_l * (Ldd + g))
        T = _axpy(
            1.0,
            _inertia_times(fx, fy, e, Il0, Il1, Il2, wd_l),
            _cross(w_l, _inertia_times(fx, fy, e, Il0, Il1, Il2, w_l)),
        )
        Qb = _axpy(n_p, _lever_force(J_i, r, d, e, t, k, l2, F, T), Qb)
        # sliders and screws, Eq. (9), (10), with their friction
        theta_dot = Ld / gear
        f_axis = n_p * m_L * (Ldd + g) + I_L * Ldd / (gear * gear)
        f_axis += n_p * (sl_c * Ld / math.sqrt(Ld * Ld + eps_v * eps_v) + sl_v * Ld)
        f_axis += (sc_c * theta_dot / math.sqrt(theta_dot * theta_dot + eps_w * eps_w) + sc_v * theta_dot) / gear
        Qb = _axpy(f_axis, J_i, Qb)
        # S-joint friction (-tau_s on the lever, +tau_s on the platform) and U-joint friction
        if sp_c != 0.0 or sp_v != 0.0:
            w_rel = _axpy(-1.0, w, w_l)
            tau_s = _axpy(sp_c, _reg(w_rel, eps_w), _scale(sp_v, w_rel))
            Qb = _axpy(n_p, _axpy(-1.0, tau_s, _lever_force(J_i, r, d, e, t, k, l2, zero, tau_s)), Qb)
        if un_c != 0.0 or un_v != 0.0:
            tau_u = _axpy(un_c, _reg(w_l, eps_w), _scale(un_v, w_l))
            Qb = _axpy(n_p, _lever_force(J_i, r, d, e, t, k, l2, zero, tau_u), Qb)
        # mass matrix: columns b of J_d = -[r]x - e_z J_i^T, J_vl = e_z J_i^T + J_d / 2,
        # J_wl = (I + k e t^T) [d]x J_d / l^2
        Jd0 = (0.0, -r[2], r[1] - J_i[0])
        Jd1 = (r[2], 0.0, -r[0] - J_i[1])
        Jd2 = (-r[1], r[0], -J_i[2])
        Jv = (
            (0.5 * Jd0[0], 0.5 * Jd0[1], 0.5 * Jd0[2] + J_i[0]),
            (0.5 * Jd1[0], 0.5 * Jd1[1], 0.5 * Jd1[2] + J_i[1]),
            (0.5 * Jd2[0], 0.5 * Jd2[1], 0.5 * Jd2[2] + J_i[2]),
        )
        x0 = _cross(d, Jd0)
        x1 = _cross(d, Jd1)
        x2 = _cross(d, Jd2)
        Jw = (
            _scale(1.0 / l2, _axpy(k * _dot(t, x0), e, x0)),
            _scale(1.0 / l2, _axpy(k * _dot(t, x1), e, x1)),
            _scale(1.0 / l2, _axpy(k * _dot(t, x2), e, x2)),
        )
        IJw = (
            _inertia_times(fx, fy, e, Il0, Il1, Il2, Jw[0]),
            _inertia_times(fx, fy, e, Il0, Il1, Il2, Jw[1]),
            _inertia_times(fx, fy, e, Il0, Il1, Il2, Jw[2]),
        )
        for i in range(3):
            for j in range(i, 3):
                acc = m_l * _dot(Jv[i], Jv[j]) + _dot(Jw[i], IJw[j])
                M[i, j] += n_p * acc + m_ax * J_i[i] * J_i[j]
    for i in range(3):
        for j in range(i):
            M[i, j] = M[j, i]
    return 0, Qb, (J0, J1, J2), E, wd0


@_jit
def _order(p, x):
    """Model order <-> intrinsic order (reversed for an extrinsic sequence; an involution)."""
    if p[_EXTR] != 0.0:
        return (x[2], x[1], x[0])
    return (x[0], x[1], x[2])


@_jit
def _inverse_one(p, q, qd, qdd, load, tau):
    """Motor torques into ``tau (3,)`` for ``q, qd, qdd`` in model order; returns a status."""
    M = np.empty((3, 3))
    status, Qb, J, E, wd0 = _model(p, _order(p, q), _order(p, qd), load, M)
    if status != 0:
        return status
    wd = _axpy(1.0, _mv(E, _order(p, qdd)), wd0)
    Q = (
        M[0, 0] * wd[0] + M[0, 1] * wd[1] + M[0, 2] * wd[2] + Qb[0],
        M[1, 0] * wd[0] + M[1, 1] * wd[1] + M[1, 2] * wd[2] + Qb[1],
        M[2, 0] * wd[0] + M[2, 1] * wd[1] + M[2, 2] * wd[2] + Qb[2],
    )
    Jinv, det = _inv3(J)
    scale = 0.0  # the batched path's test: |det J| > 1e-12 max|J_ij|^3
    for i in range(3):
        for j in range(3):
            scale = max(scale, abs(J[i][j]))
    if not abs(det) > 1e-12 * scale**3:
        return 11
    # tau = gear J^-T Q
    out = _scale(p[_GEAR], _mtv(Jinv, Q))
    tau[0], tau[1], tau[2] = out[0], out[1], out[2]
    return 0


@_jit
def _forward_one(p, q, qd, u, load, qdd):
    """Euler accelerations into ``qdd (3,)`` (model order) under motor torques ``u``; returns a status."""
    M = np.empty((3, 3))
    status, Qb, J, E, wd0 = _model(p, _order(p, q), _order(p, qd), load, M)
    if status != 0:
        return status
    rhs = _axpy(1.0 / p[_GEAR], _mtv(J, (u[0], u[1], u[2])), _scale(-1.0, Qb))
    # M_w omega_dot = rhs by Cholesky (M_w is symmetric positive definite)
    L00 = math.sqrt(M[0, 0])
    L10 = M[1, 0] / L00
    L20 = M[2, 0] / L00
    L11 = math.sqrt(M[1, 1] - L10 * L10)
    L21 = (M[2, 1] - L20 * L10) / L11
    L22 = math.sqrt(M[2, 2] - L20 * L20 - L21 * L21)
    y0 = rhs[0] / L00
    y1 = (rhs[1] - L10 * y0) / L11
    y2 = (rhs[2] - L20 * y0 - L21 * y1) / L22
    wd2 = y2 / L22
    wd1 = (y1 - L21 * wd2) / L11
    wd_0 = (y0 - L10 * wd1 - L20 * wd2) / L00
    Einv, det = _inv3(E)
    if not abs(det) > 1e-12:
        return 12
    qddi = _mv(Einv, (wd_0 - wd0[0], wd1 - wd0[1], wd2 - wd0[2]))
    out = _order(p, qddi)
    qdd[0], qdd[1], qdd[2] = out[0], out[1], out[2]
    return 0


# ---------------------------------------------------------------- public single-sample verbs


def _fail(status: int, q: Array) -> None:
    deg = ", ".join(f"{x:.4g}" for x in np.rad2deg(q))
    if 1 <= status <= 3:
        raise UnreachablePoseError(f"q = ({deg}) deg: leg {status} cannot reach its platform")
    if status == 10:
        raise SingularityError(f"q = ({deg}) deg: a lever is aligned with its U joint's first axis")
    if status == 11:
        raise SingularityError(f"q = ({deg}) deg: J is singular (det(J_b) = 0), the motor torques are undefined")
    raise SingularityError(f"q = ({deg}) deg: the Euler-rate map is singular (gimbal lock)")


_F64 = np.dtype(np.float64)
_SHAPE3 = (3,)


def _vec3(x: object, name: str) -> Array:
    if x.__class__ is np.ndarray and x.dtype is _F64 and x.shape == _SHAPE3:  # type: ignore[attr-defined]
        return x  # type: ignore[return-value]
    a = np.asarray(x, dtype=np.float64)
    if a.shape != (3,):
        raise MotionError(f"{name}: expected shape (3,), got {a.shape}")
    return a


def _load(load: object) -> float:
    try:
        f = float(load)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise MotionError(f"load: expected the hydraulic force [N] as a number, got {type(load).__name__}") from None
    if not (f >= 0.0 and f < math.inf):
        raise MotionError(f"load: {f:g} N is not a finite non-negative force")
    return f


def kernels(model: HipModel) -> tuple[Array, Any, Any]:
    """``(p, inverse, forward)``: the packed model and the compiled kernels behind the two
    single-sample verbs, for callers that are compiled themselves (a Numba integrator or
    controller), where even the verbs' Python entry costs more than the model.

    ``inverse(p, q, qd, qdd, load, tau) -> status`` and ``forward(p, q, qd, u, load, qdd) ->
    status`` write their ``(3,)`` result into the last argument; ``q, qd, qdd, u`` are ``(3,)``
    float arrays in the model's Euler order, ``load`` [N] a float. Status 0 is success; 1-3 an
    unreachable leg, 10 a lever along its U joint's first axis, 11 a singular ``J``, 12 gimbal
    lock (the verbs turn these into the project's exceptions). No input is checked.
    """
    return pack(model), _inverse_one, _forward_one


def inverse_dynamics_one(model: HipModel, q: Array, qd: Array, qdd: Array, load: float) -> Array:
    """Motor torques ``(3,)`` [N m] of one sample: ``q, qd, qdd (3,)`` Euler angles [rad] and
    rates [rad/s, rad/s^2] in the model's sequence, ``load`` [N]. Equal to
    :func:`.minimal.inverse_dynamics` on one row, every friction term included."""
    q = _vec3(q, "q")
    out = np.empty(3)
    status = _inverse_one(pack(model), q, _vec3(qd, "qd"), _vec3(qdd, "qdd"), _load(load), out)
    if status:
        _fail(status, q)
    return out


def forward_dynamics_one(model: HipModel, q: Array, qd: Array, u: Array, load: float) -> Array:
    """Euler-angle accelerations ``(3,)`` [rad/s^2] of one sample under motor torques ``u (3,)``
    [N m]. Equal to :func:`.minimal.forward_dynamics` on one row."""
    q = _vec3(q, "q")
    out = np.empty(3)
    status = _forward_one(pack(model), q, _vec3(qd, "qd"), _vec3(u, "u"), _load(load), out)
    if status:
        _fail(status, q)
    return out
