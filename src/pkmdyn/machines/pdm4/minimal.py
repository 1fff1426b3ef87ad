"""The PDM's equations of motion in its minimal coordinates, by virtual power (issue 7 item 4).

Coordinates ``q = (x [m], y [m], alpha [rad], gamma [rad])`` (n, 4): the platform point P in
the base frame, the platform angle about the base z axis and about the R4 axis (section 2.2,
Eq. 2-4). Actuator efforts ``u = (f1, f2, f3, f4)`` (n, 4) [N]: the axial forces of the four
prismatic joints, in the order of the ``l{k}_m`` columns (l11, l12, l23, l24), each the force
that the cylinder exerts on its piston along the limb's unit vector ``u_k`` (fixed joint ->
moving joint), so that **a positive force pushes the limb longer** and its power is
``f_k l_dot_k``. The PDM has no external load and no friction model: ``load`` must be None.

Equations of motion (Lagrange's equations written by virtual power, Kane's form):

    M(q) qdd + h(q, qd) = B(q) u

Every body velocity of the closed chain is linear in ``qd`` (Eq. 10-48 at fixed q), so

    v_b = J_v,b(q) qd,   w_b = J_w,b(q) qd,   l_dot = J_l(q) qd,

and the columns of the Jacobians are the body velocities for unit rates ``qd = e_k``
(one batched call of :func:`~pkmdyn.machines.pdm4.kinematics.inverse_kinematics`). With
``m_b`` the body mass, ``I_b = R_b I_b' R_b^T`` its inertia about its centre of mass in the
base frame (``I_b'`` in the body's own frame, Eq. 52) and ``g`` the gravity vector,

    M = sum_b m_b J_v,b^T J_v,b + J_w,b^T I_b J_w,b
    h = sum_b J_v,b^T m_b (a0_b - g) + J_w,b^T (I_b wd0_b + w_b x I_b w_b)
    B = J_l^T

where ``a0_b, wd0_b`` are the body accelerations at ``qdd = 0`` (the velocity-product terms,
the same kinematics call with the actual ``qd``). This route shares nothing with the
Newton-Euler equations of section 4 (Eq. 49-62) beyond the kinematics; it never forms a joint
reaction, so the nine redundant constraints (Eq. 70) do not appear in it.

The rotation of every body (to carry the inertia to the base frame) is the ``R`` field of
:class:`~pkmdyn.machines.pdm4.kinematics.BodyState`. The stroke limits are not checked here:
the dynamics hold beyond them and a simulation decides what a stroke end does; an unclosable
six-bar loop or a singular configuration raises, naming the sample. The batched verbs work in
chunks of ``CHUNK`` samples to bound their memory.

:func:`inverse_dynamics_one` and :func:`forward_dynamics_one` are the single-sample real-time
path: a compiled (numba) second implementation of the same kinematics and sums for one sample,
tested against the batched verbs. :func:`kinetic_energy` and :func:`potential_energy` give
``T`` and ``V`` from the body velocities and centres of mass, for energy and power checks.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable

import numpy as np
from numba import njit
from numpy.typing import NDArray

from ..._dense import solve_in_place
from ...errors import MotionError, PkmdynError, SingularityError, UnreachablePoseError
from ...spatial import cross
from .kinematics import BODY_NAMES, inverse_kinematics

if TYPE_CHECKING:
    from .kinematics import PdmKinematics
    from .params import PdmModel

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
    "kinetic_energy",
    "potential_energy",
]

Array = NDArray[np.float64]

COORDINATES = ("x_m", "y_m", "alpha_rad", "gamma_rad")
ACTUATORS = ("f1_N", "f2_N", "f3_N", "f4_N")
NB = len(BODY_NAMES)
#: samples per kinematics call in the batched verbs (bounds the memory; the result is the same)
CHUNK = 2048
#: below this a 4 x 4 matrix is singular: for ``B``, ``|det B| / prod_i |row_i|`` (invariant to
#: the units of the coordinates, which scale B's rows); for the symmetric ``M``,
#: ``det M / prod_i M_ii`` (invariant to the units of the coordinates, ``D M D``); both are 1
#: for orthogonal rows / a diagonal matrix and 0 when singular
SINGULAR_RATIO = 1e-10


@dataclass(frozen=True)
class _Rates:
    """Platform rates handed to the kinematics without sample times (errors name the sample)."""

    t: None
    q: Array
    qd: Array
    qdd: Array


@dataclass(frozen=True)
class _Terms:
    """Per-sample Jacobians and inertias: ``Jv, Jw`` (n, NB, 3, 4) [m, rad per unit qd];
    ``Jl`` (n, 4, 4) limb rates per unit qd (row = limb); ``I`` (n, NB, 3, 3) [kg m^2] base
    frame; with ``qd``: ``w`` (n, NB, 3) [rad/s], ``a0, wd0`` (n, NB, 3) accelerations at
    ``qdd = 0`` [m/s^2, rad/s^2]."""

    Jv: Array
    Jw: Array
    Jl: Array
    I: Array
    w: Array | None
    a0: Array | None
    wd0: Array | None


# ----------------------------------------------------------------------------- checks
def _states(name: str, x: Array, n: int | None = None) -> Array:
    x = np.asarray(x, dtype=float)
    if x.ndim != 2 or x.shape[1] != 4 or (n is not None and x.shape[0] != n):
        want = f"({n if n is not None else 'n'}, 4)"
        raise MotionError(f"{name}: shape {x.shape}, expected {want}")
    if not np.all(np.isfinite(x)):
        s = int(np.argwhere(~np.isfinite(x))[0, 0])
        raise MotionError(f"{name}: sample {s} is not finite")
    return x


def _no_load(load: object) -> None:
    if load is not None:
        raise MotionError("load: the PDM has no external load; pass None")


def _regularity(A: Array, symmetric: bool) -> Array:
    """``|det A| / prod_i |row_i|`` or, ``symmetric``, ``det A / prod_i A_ii`` (n,)."""
    den = np.prod(np.diagonal(A, axis1=-2, axis2=-1) if symmetric else np.linalg.norm(A, axis=-1), axis=-1)
    det = np.linalg.det(A)
    return np.divide(det if symmetric else np.abs(det), den, out=np.zeros_like(den), where=den > 0)


def _check_regular(A: Array, what: str, symmetric: bool, offset: int) -> None:
    """Raise :class:`SingularityError` naming the first singular sample (``offset`` + index)."""
    ratio = _regularity(A, symmetric)
    bad = ~(ratio > SINGULAR_RATIO)
    if np.any(bad):
        s = int(np.argmax(bad))
        raise SingularityError(f"sample {offset + s}: {what} is singular "
                               f"(regularity {ratio[s]:.3g} < {SINGULAR_RATIO:g})")


# ----------------------------------------------------------------------------- body data
def _model_inertia(model: PdmModel) -> tuple[Array, Array, Array]:
    """``mass (NB,)`` [kg], ``inertia (NB, 3, 3)`` [kg m^2] about the centre of mass in each
    body's own frame, ``gravity (3,)`` [m/s^2], in ``BODY_NAMES`` order."""
    return (np.asarray(model.mass, dtype=float), np.asarray(model.inertia, dtype=float),
            np.asarray(model.gravity, dtype=float))


def _rotations(kin: PdmKinematics) -> Array:
    """Body-to-base rotations ``(n, NB, 3, 3)`` in ``BODY_NAMES`` order."""
    return np.stack([b.R for b in kin.bodies], axis=1)


def _kin(model: PdmModel, q: Array, qd: Array) -> PdmKinematics:
    """Body kinematics at ``qdd = 0``, strokes unchecked, errors naming the sample index."""
    return inverse_kinematics(model, _Rates(None, q, qd, np.zeros_like(q)), check_strokes=False)  # type: ignore[arg-type]


def _kinematics(model: PdmModel, q: Array, qd: Array | None) -> _Terms:
    """Body Jacobians (unit rates) and, with ``qd``, the velocity-product accelerations.

    One kinematics call on ``(4 or 5) n`` samples: blocks ``qd = e_1 .. e_4`` then the actual
    ``qd``, all with ``qdd = 0``.
    """
    n = q.shape[0]
    nblk = 4 if qd is None else 5
    Q = np.tile(q, (nblk, 1))
    QD = np.repeat(np.eye(4), n, axis=0)
    if qd is not None:
        QD = np.concatenate([QD, qd], axis=0)
    kin = _kin(model, Q, QD)

    def blocks(x: Array) -> Array:  # (nblk n, ...) -> (nblk, n, ...)
        return x.reshape((nblk, n) + x.shape[1:])

    v = blocks(np.stack([b.v for b in kin.bodies], axis=1))  # (nblk, n, NB, 3)
    w = blocks(np.stack([b.w for b in kin.bodies], axis=1))
    Jv = np.moveaxis(v[:4], 0, -1)  # (n, NB, 3, 4)
    Jw = np.moveaxis(w[:4], 0, -1)
    Jl = np.moveaxis(blocks(kin.ld)[:4], 0, -1)  # (n, 4 limbs, 4 coordinates)
    R = blocks(_rotations(kin))[0]  # (n, NB, 3, 3)
    _, inertia, _ = _model_inertia(model)
    I = R @ inertia[None] @ np.swapaxes(R, -1, -2)
    if qd is None:
        return _Terms(Jv, Jw, Jl, I, None, None, None)
    a = blocks(np.stack([b.a for b in kin.bodies], axis=1))[4]
    wd = blocks(np.stack([b.wd for b in kin.bodies], axis=1))[4]
    return _Terms(Jv, Jw, Jl, I, w[4], a, wd)


def _mass(model: PdmModel, k: _Terms) -> Array:
    mass, _, _ = _model_inertia(model)
    M = np.einsum("nbai,nbaj->nij", k.Jv * mass[None, :, None, None], k.Jv)
    M += np.einsum("nbai,nbaj->nij", k.Jw, k.I @ k.Jw)
    return 0.5 * (M + np.swapaxes(M, -1, -2))


def _bias(model: PdmModel, k: _Terms) -> Array:
    mass, _, g = _model_inertia(model)
    assert k.w is not None and k.a0 is not None and k.wd0 is not None
    f = mass[None, :, None] * (k.a0 - g)  # (n, NB, 3): inertia and weight, Newton
    Iw = np.einsum("nbac,nbc->nba", k.I, k.w)
    t = np.einsum("nbac,nbc->nba", k.I, k.wd0) + cross(k.w, Iw)  # Euler
    return np.einsum("nbai,nba->ni", k.Jv, f) + np.einsum("nbai,nba->ni", k.Jw, t)


def _by_chunks(model: PdmModel, q: Array, qd: Array | None, shape: tuple[int, ...],
               fn: Callable[[_Terms, int, int], Array]) -> Array:
    """``fn(terms, start, stop)`` over chunks of at most ``CHUNK`` samples, stacked (n, *shape).

    Chunks bound the memory (about 35 kB per sample in flight). A kinematic error is raised
    again from the kinematics of all n poses, so that it names the caller's sample.
    """
    n = q.shape[0]
    out = np.empty((n,) + shape)
    for start in range(0, n, CHUNK):
        stop = min(start + CHUNK, n)
        try:
            k = _kinematics(model, q[start:stop], None if qd is None else qd[start:stop])
        except PkmdynError:
            _kin(model, q, np.zeros_like(q))
            raise
        out[start:stop] = fn(k, start, stop)
    return out


# ----------------------------------------------------------------------------- the verbs
def mass_matrix(model: PdmModel, q: Array) -> Array:
    """``M(q)`` (n, 4, 4), symmetric positive definite [kg, kg m, kg m^2 blocks]:
    ``sum_b m_b J_v^T J_v + J_w^T I_b J_w`` over the 14 bodies."""
    q = _states("q", q)
    return _by_chunks(model, q, None, (4, 4), lambda k, a, b: _mass(model, k))


def bias_forces(model: PdmModel, q: Array, qd: Array, load: Array | None = None) -> Array:
    """``h(q, qd)`` (n, 4) [N, N, N m, N m]: velocity-product and gravity terms,
    ``sum_b J_v^T m_b (a0_b - g) + J_w^T (I_b wd0_b + w_b x I_b w_b)``; no friction model."""
    _no_load(load)
    q = _states("q", q)
    qd = _states("qd", qd, q.shape[0])
    return _by_chunks(model, q, qd, (4,), lambda k, a, b: _bias(model, k))


def actuator_map(model: PdmModel, q: Array) -> Array:
    """``B(q) = (dl/dq)^T`` (n, 4, 4): column k is the generalised force of a unit force in
    limb k (positive extending), from the limb rates at unit ``qd`` (Eq. 37, 44)."""
    q = _states("q", q)
    return _by_chunks(model, q, None, (4, 4), lambda k, a, b: np.swapaxes(k.Jl, -1, -2))


def inverse_dynamics(model: PdmModel, q: Array, qd: Array, qdd: Array, load: Array | None = None) -> Array:
    """Limb forces ``u`` (n, 4) [N] with ``B u = M qdd + h``; raises
    :class:`~pkmdyn.errors.SingularityError` naming the sample where ``B`` is singular."""
    _no_load(load)
    q = _states("q", q)
    qd = _states("qd", qd, q.shape[0])
    qdd = _states("qdd", qdd, q.shape[0])

    def solve(k: _Terms, start: int, stop: int) -> Array:
        B = np.swapaxes(k.Jl, -1, -2)
        _check_regular(B, "the actuator map B = (dl/dq)^T", False, start)
        rhs = np.einsum("nij,nj->ni", _mass(model, k), qdd[start:stop]) + _bias(model, k)
        return np.linalg.solve(B, rhs[..., None])[..., 0]

    return _by_chunks(model, q, qd, (4,), solve)


def forward_dynamics(model: PdmModel, q: Array, qd: Array, u: Array, load: Array | None = None) -> Array:
    """Accelerations ``qdd`` (n, 4) with ``M qdd = B u - h`` under limb forces ``u`` (n, 4) [N];
    raises :class:`~pkmdyn.errors.SingularityError` naming the sample where ``M`` is singular."""
    _no_load(load)
    q = _states("q", q)
    qd = _states("qd", qd, q.shape[0])
    u = _states("u", u, q.shape[0])

    def solve(k: _Terms, start: int, stop: int) -> Array:
        M = _mass(model, k)
        _check_regular(M, "the mass matrix M", True, start)
        rhs = np.einsum("nji,nj->ni", k.Jl, u[start:stop]) - _bias(model, k)
        return np.linalg.solve(M, rhs[..., None])[..., 0]

    return _by_chunks(model, q, qd, (4,), solve)


# ----------------------------------------------------------------------------- energies
def kinetic_energy(model: PdmModel, q: Array, qd: Array) -> Array:
    """``T = 1/2 sum_b (m_b |v_b|^2 + w_b . I_b w_b)`` (n,) [J], straight from the body
    velocities of the kinematics (not through ``M``)."""
    q = _states("q", q)
    qd = _states("qd", qd, q.shape[0])
    kin = _kin(model, q, qd)
    mass, inertia, _ = _model_inertia(model)
    R = _rotations(kin)
    T = np.zeros(q.shape[0])
    for b, body in enumerate(kin.bodies):
        Iw = R[:, b] @ (inertia[b] @ np.einsum("nba,nb->na", R[:, b], body.w)[..., None])
        T += 0.5 * (mass[b] * np.einsum("na,na->n", body.v, body.v) + np.einsum("na,na->n", body.w, Iw[..., 0]))
    return T


def potential_energy(model: PdmModel, q: Array) -> Array:
    """``V = -sum_b m_b g . p_b`` (n,) [J], centres of mass from the kinematics."""
    q = _states("q", q)
    kin = _kin(model, q, np.zeros_like(q))
    mass, _, g = _model_inertia(model)
    p = np.stack([b.p for b in kin.bodies], axis=1)
    return -np.einsum("b,nba,a->n", mass, p, g)


# ----------------------------------------------------------------------------- one sample
# A second, independent implementation of the same kinematics for one sample, compiled with
# numba: positions (Eq. 2-9), then velocities and velocity-product accelerations of every body
# written out per limb. The SPU limbs' spin is taken from the U-joint frame directly
# (``w = u x u_dot + s u`` with ``s = U2_dot . (u x U2)``) rather than through the z-x-z Euler
# rates of Eq. 30-32; the tests hold both paths to each other. Without Euler angles this path
# has no Euler singularity (an SPU limb parallel to base z), where the batched kinematics raise.

_OK, _NOT_CLOSED, _CRANK_ALIGNED, _SPU_U1, _B_SINGULAR, _M_SINGULAR, _NOT_FINITE = range(7)

# 3-vectors are tuples inside the compiled code: they live on the stack, so the kernel allocates
# nothing per vector operation.


@njit(cache=True)
def _add(a, b):  # type: ignore[no-untyped-def]
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


@njit(cache=True)
def _sub(a, b):  # type: ignore[no-untyped-def]
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@njit(cache=True)
def _sc(s, a):  # type: ignore[no-untyped-def]
    return (s * a[0], s * a[1], s * a[2])


@njit(cache=True)
def _cr(a, b):  # type: ignore[no-untyped-def]
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@njit(cache=True)
def _dt(a, b):  # type: ignore[no-untyped-def]
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True)
def _zc(s, r):  # type: ignore[no-untyped-def]
    """``(s z) x r`` for a rate ``s`` about the base z axis."""
    return (-s * r[1], s * r[0], 0.0)


@njit(cache=True)
def _mv(A, x):  # type: ignore[no-untyped-def]
    """``A x``, ``A`` three row tuples."""
    return (A[0][0] * x[0] + A[0][1] * x[1] + A[0][2] * x[2],
            A[1][0] * x[0] + A[1][1] * x[1] + A[1][2] * x[2],
            A[2][0] * x[0] + A[2][1] * x[1] + A[2][2] * x[2])


@njit(cache=True)
def _mva(A, x):  # type: ignore[no-untyped-def]
    """``A x`` for a 3 x 3 array ``A`` (element indexing: no row views)."""
    return (A[0, 0] * x[0] + A[0, 1] * x[1] + A[0, 2] * x[2],
            A[1, 0] * x[0] + A[1, 1] * x[1] + A[1, 2] * x[2],
            A[2, 0] * x[0] + A[2, 1] * x[1] + A[2, 2] * x[2])


@njit(cache=True)
def _row(A, i):  # type: ignore[no-untyped-def]
    return (A[i, 0], A[i, 1], A[i, 2])


@njit(cache=True)
def _put(out, r, b, x):  # type: ignore[no-untyped-def]
    out[r, b, 0] = x[0]
    out[r, b, 1] = x[1]
    out[r, b, 2] = x[2]


@njit(cache=True)
def _put_frame(R, b, c0, c1, c2):  # type: ignore[no-untyped-def]
    """``R[b]`` = the rotation with columns ``c0, c1, c2``."""
    for k in range(3):
        R[b, k, 0] = c0[k]
        R[b, k, 1] = c1[k]
        R[b, k, 2] = c2[k]


@njit(cache=True)
def _limb_one(r, bc, bp, u, ln, l1, l2, wl, wdl, c1, c3, v, w, a, wd):  # type: ignore[no-untyped-def]
    """Cylinder (index ``bc``) and piston (``bp``) centres of mass of one limb, Eq. 19-22."""
    r1 = _sc(c1, u)
    wr1 = _cr(wl, r1)
    _put(v, r, bc, wr1)
    _put(w, r, bc, wl)
    _put(a, r, bc, _add(_cr(wdl, r1), _cr(wl, wr1)))
    _put(wd, r, bc, wdl)
    r2 = _sc(ln - c3, u)
    wr2 = _cr(wl, r2)
    _put(v, r, bp, _add(wr2, _sc(l1, u)))
    _put(w, r, bp, wl)
    _put(a, r, bp, _add(_add(_cr(wdl, r2), _cr(wl, wr2)), _add(_sc(l2, u), _sc(2.0 * l1, _cr(wl, u)))))
    _put(wd, r, bp, wdl)


@njit(cache=True)
def _motion_one(geo, R1, R4, S, Ul, R3l, U1l, Pl, ccom, pcom, q, QD, v, w, a, wd, ld, R):  # type: ignore[no-untyped-def]
    """Every body of the PDM at pose ``q`` (4,) for ``nr`` sets of rates ``QD`` (nr, 4), all
    with ``qdd = 0``: velocities ``v, w`` (nr, NB, 3), accelerations ``a, wd`` (nr, NB, 3)
    (the velocity-product terms), limb rates ``ld`` (nr, 4), and the rotations ``R``
    (NB, 3, 3) (frames of :class:`~pkmdyn.machines.pdm4.kinematics.BodyState`).
    ``geo = (r0, r2, r3, branch1, branch2)``. Positions are solved once (Eq. 2-9), rates per
    row of ``QD``. Returns a status code."""
    nr = QD.shape[0]
    r0, r2, r3 = geo[0], geo[1], geo[2]
    ca, sa, cg, sg = np.cos(q[2]), np.sin(q[2]), np.cos(q[3]), np.sin(q[3])
    T = ((ca, -sa * cg, sa * sg), (sa, ca * cg, -ca * sg), (0.0, sg, cg))  # Eq. 3
    Rz = ((ca, -sa, 0.0), (sa, ca, 0.0), (0.0, 0.0, 1.0))
    z = (0.0, 0.0, 1.0)
    xr = (ca, sa, 0.0)
    zxr = (-sa, ca, 0.0)
    d = _mv(T, (Pl[0], Pl[1], Pl[2]))
    C = _sub((q[0], q[1], d[2]), d)
    md = _sc(-1.0, d)
    U1 = _mv(T, (U1l[0], U1l[1], U1l[2]))
    _put_frame(R, 0, (T[0][0], T[1][0], T[2][0]), (T[0][1], T[1][1], T[2][1]), (T[0][2], T[1][2], T[2][2]))
    _put_frame(R, 1, xr, zxr, z)
    for r in range(nr):
        # platform (Eq. 10-11, 35, 38) and output link (Eq. 14-16)
        xd, yd, ad, gd = QD[r, 0], QD[r, 1], QD[r, 2], QD[r, 3]
        wp = (gd * ca, gd * sa, ad)
        wdp = _sc(ad * gd, zxr)
        vP = (xd, yd, -r0 * sg * gd)
        aP = (0.0, 0.0, -r0 * cg * gd * gd)
        wmd = _cr(wp, md)
        _put(v, r, 0, vP)
        _put(w, r, 0, wp)
        _put(a, r, 0, aP)
        _put(wd, r, 0, wdp)
        _put(v, r, 1, _add(vP, wmd))
        _put(w, r, 1, (0.0, 0.0, ad))
        _put(a, r, 1, _add(aP, _add(_cr(wdp, md), _cr(wp, wmd))))
        _put(wd, r, 1, (0.0, 0.0, 0.0))
    for i in range(2):
        # six-bar, positions (Eq. 5-7, 12)
        rho3 = _mv(Rz, _row(R3l, i))
        R3 = _add(C, rho3)
        dx, dy = R3[0] - R1[i, 0], R3[1] - R1[i, 1]
        aa, bb = r2 * dx, r2 * dy
        dd = 0.5 * (dx * dx + dy * dy + r2 * r2 - r3 * r3)
        disc = aa * aa + bb * bb - dd * dd
        if not disc > 0.0:
            return _NOT_CLOSED
        th1 = np.arctan2(bb, aa) + geo[3 + i] * np.arctan2(np.sqrt(disc), dd)
        c1, s1 = np.cos(th1), np.sin(th1)
        rho2 = (r2 * c1, r2 * s1, 0.0)
        R2 = _add(_row(R1, i), rho2)
        e2 = _sub(R3, R2)
        th2 = np.arctan2(e2[1], e2[0])
        c2, s2 = np.cos(th2), np.sin(th2)
        det = r2 * r3 * (c1 * s2 - s1 * c2)
        if abs(det) < 1e-12 * r2 * r3:
            return _CRANK_ALIGNED
        h2 = _sc(0.5, rho2)
        hc = _sc(0.5, e2)
        L = _sub(R2, _row(R4, i))
        ln = np.sqrt(_dt(L, L))
        u = _sc(1.0 / ln, L)
        _put_frame(R, 2 + i, (c1, s1, 0.0), (-s1, c1, 0.0), z)
        _put_frame(R, 4 + i, (c2, s2, 0.0), (-s2, c2, 0.0), z)
        _put_frame(R, 6 + i, u, _cr(z, u), z)
        _put_frame(R, 10 + i, u, _cr(z, u), z)
        for r in range(nr):
            # six-bar rates: the loop R3 - R1 = r2 e(th1) + r3 e(th2) differentiated (Eq. 13, 36, 39)
            ad = QD[r, 2]
            vC = (v[r, 1, 0], v[r, 1, 1], v[r, 1, 2])
            aC = (a[r, 1, 0], a[r, 1, 1], a[r, 1, 2])
            vR3 = _add(vC, _zc(ad, rho3))
            aR3 = _sub(aC, _sc(ad * ad, rho3))
            th1d = r3 * (c2 * vR3[0] + s2 * vR3[1]) / det
            th2d = -r2 * (c1 * vR3[0] + s1 * vR3[1]) / det
            bx = aR3[0] + r2 * th1d * th1d * c1 + r3 * th2d * th2d * c2
            by = aR3[1] + r2 * th1d * th1d * s1 + r3 * th2d * th2d * s2
            th1dd = r3 * (c2 * bx + s2 * by) / det
            th2dd = -r2 * (c1 * bx + s1 * by) / det
            vR2 = _zc(th1d, rho2)
            aR2 = _sub(_zc(th1dd, rho2), _sc(th1d * th1d, rho2))
            _put(v, r, 2 + i, _zc(th1d, h2))
            _put(w, r, 2 + i, (0.0, 0.0, th1d))
            _put(a, r, 2 + i, _sub(_zc(th1dd, h2), _sc(th1d * th1d, h2)))
            _put(wd, r, 2 + i, (0.0, 0.0, th1dd))
            _put(v, r, 4 + i, _add(vR2, _zc(th2d, hc)))
            _put(w, r, 4 + i, (0.0, 0.0, th2d))
            _put(a, r, 4 + i, _add(aR2, _sub(_zc(th2dd, hc), _sc(th2d * th2d, hc))))
            _put(wd, r, 4 + i, (0.0, 0.0, th2dd))
            # RPR limb i (Eq. 17-22, 33-40, 43-47): planar, w = u x u_dot
            l1 = _dt(u, vR2)
            ud = _sc(1.0 / ln, _sub(vR2, _sc(l1, u)))
            l2 = _dt(u, aR2) + _dt(ud, vR2)
            udd = _sc(1.0 / ln, _sub(_sub(aR2, _sc(l2, u)), _sc(2.0 * l1, ud)))
            ld[r, i] = l1
            _limb_one(r, 6 + i, 10 + i, u, ln, l1, l2, _cr(u, ud), _cr(u, udd), ccom[i], pcom[i], v, w, a, wd)
    for j in range(2):
        # SPU limb j, positions (Eq. 9, 26)
        rhoU = _mv(T, _row(Ul, j))
        L = _sub(_add(C, rhoU), _row(S, j))
        ln = np.sqrt(_dt(L, L))
        u = _sc(1.0 / ln, L)
        W = _cr(u, U1)  # second U-joint axis U2 = W / |W| (Eq. 26), fixed in the limb
        wn = np.sqrt(_dt(W, W))
        if wn < 1e-9:
            return _SPU_U1
        U2 = _sc(1.0 / wn, W)
        Y = _cr(u, U2)
        _put_frame(R, 8 + j, u, U2, Y)
        _put_frame(R, 12 + j, u, U2, Y)
        for r in range(nr):
            wp = (w[r, 0, 0], w[r, 0, 1], w[r, 0, 2])
            wdp = (wd[r, 0, 0], wd[r, 0, 1], wd[r, 0, 2])
            wr = _cr(wp, rhoU)
            vU = _add((v[r, 1, 0], v[r, 1, 1], v[r, 1, 2]), wr)
            aU = _add((a[r, 1, 0], a[r, 1, 1], a[r, 1, 2]), _add(_cr(wdp, rhoU), _cr(wp, wr)))
            U1d = _cr(wp, U1)
            U1dd = _add(_cr(wdp, U1), _cr(wp, U1d))
            l1 = _dt(u, vU)
            ud = _sc(1.0 / ln, _sub(vU, _sc(l1, u)))
            l2 = _dt(u, aU) + _dt(ud, vU)
            udd = _sc(1.0 / ln, _sub(_sub(aU, _sc(l2, u)), _sc(2.0 * l1, ud)))
            # the limb's spin about u is that of the frame (u, U2): s = U2_dot . (u x U2)
            Wd = _add(_cr(ud, U1), _cr(u, U1d))
            Wdd = _add(_add(_cr(udd, U1), _sc(2.0, _cr(ud, U1d))), _cr(u, U1dd))
            wnd = _dt(U2, Wd)
            U2d = _sc(1.0 / wn, _sub(Wd, _sc(wnd, U2)))
            Yd = _add(_cr(ud, U2), _cr(u, U2d))
            sp = _dt(Wd, Y) / wn
            spd = (_dt(Wdd, Y) + _dt(Wd, Yd)) / wn - _dt(Wd, Y) * wnd / (wn * wn)
            wl = _add(_cr(u, ud), _sc(sp, u))
            wdl = _add(_add(_cr(u, udd), _sc(spd, u)), _sc(sp, ud))
            ld[r, 2 + j] = l1
            _limb_one(r, 8 + j, 12 + j, u, ln, l1, l2, wl, wdl, ccom[2 + j], pcom[2 + j], v, w, a, wd)
    return _OK


@njit(cache=True)
def _solve4(A, b):  # type: ignore[no-untyped-def]
    """``x`` with ``A x = b`` for a 4 x 4 ``A`` and ``det A``; ``x`` is not valid when the
    determinant is 0."""
    x = b.copy()
    det, _ = solve_in_place(A.copy(), x)
    return x, det


@njit(cache=True)
def _one(c, q, qd, x, forward, out):  # type: ignore[no-untyped-def]
    """One sample of ``M qdd + h = B u``: ``forward`` False solves for ``u`` (``x = qdd``),
    True for ``qdd`` (``x = u``); the result goes to ``out`` (4,). ``c``: the model's
    constants packed by :func:`_pack` (one array, so that a call unboxes few arguments).
    Returns a status code."""
    geo = c[0:5]
    R1 = c[5:11].reshape((2, 3))
    R4 = c[11:17].reshape((2, 3))
    S = c[17:23].reshape((2, 3))
    Ul = c[23:29].reshape((2, 3))
    R3l = c[29:35].reshape((2, 3))
    U1l = c[35:38]
    Pl = c[38:41]
    ccom = c[41:45]
    pcom = c[45:49]
    g = c[49:52]
    mass = c[52:66]
    inertia = c[66:192].reshape((14, 3, 3))
    for k in range(4):
        if not (np.isfinite(q[k]) and np.isfinite(qd[k]) and np.isfinite(x[k])):
            return _NOT_FINITE
    nb = 14
    # rows 0-3: unit rates (Jacobian columns; ld rows are B's rows); row 4: the actual qd
    QD = np.zeros((5, 4))
    for k in range(4):
        QD[k, k] = 1.0
        QD[4, k] = qd[k]
    v = np.empty((5, nb, 3))
    w = np.empty((5, nb, 3))
    a = np.empty((5, nb, 3))
    wd = np.empty((5, nb, 3))
    Jl = np.empty((5, 4))
    R = np.empty((nb, 3, 3))
    st = _motion_one(geo, R1, R4, S, Ul, R3l, U1l, Pl, ccom, pcom, q, QD, v, w, a, wd, Jl, R)
    if st != _OK:
        return st
    M = np.zeros((4, 4))
    h = np.zeros(4)
    Ib = np.empty((3, 3))
    RI = np.empty((3, 3))
    for b in range(nb):
        for i in range(3):  # I_b = R I' R^T (Eq. 52)
            for j in range(3):
                RI[i, j] = R[b, i, 0] * inertia[b, 0, j] + R[b, i, 1] * inertia[b, 1, j] + R[b, i, 2] * inertia[b, 2, j]
        for i in range(3):
            for j in range(3):
                Ib[i, j] = RI[i, 0] * R[b, j, 0] + RI[i, 1] * R[b, j, 1] + RI[i, 2] * R[b, j, 2]
        m = mass[b]
        wb = (w[4, b, 0], w[4, b, 1], w[4, b, 2])
        f = _sc(m, _sub((a[4, b, 0], a[4, b, 1], a[4, b, 2]), (g[0], g[1], g[2])))
        t = _add(_mva(Ib, (wd[4, b, 0], wd[4, b, 1], wd[4, b, 2])), _cr(wb, _mva(Ib, wb)))
        for i in range(4):
            jvi = (v[i, b, 0], v[i, b, 1], v[i, b, 2])
            jwi = (w[i, b, 0], w[i, b, 1], w[i, b, 2])
            h[i] += _dt(jvi, f) + _dt(jwi, t)
            Ijwi = _mva(Ib, jwi)
            for k in range(i, 4):
                M[i, k] += m * (jvi[0] * v[k, b, 0] + jvi[1] * v[k, b, 1] + jvi[2] * v[k, b, 2]) \
                    + Ijwi[0] * w[k, b, 0] + Ijwi[1] * w[k, b, 1] + Ijwi[2] * w[k, b, 2]
    for i in range(4):
        for k in range(i):
            M[i, k] = M[k, i]
    rhs = np.empty(4)
    if forward:  # M qdd = B u - h
        for k in range(4):
            rhs[k] = Jl[k, 0] * x[0] + Jl[k, 1] * x[1] + Jl[k, 2] * x[2] + Jl[k, 3] * x[3] - h[k]
        r, det = _solve4(M, rhs)
        den = M[0, 0] * M[1, 1] * M[2, 2] * M[3, 3]
        if not (den > 0.0 and det / den > SINGULAR_RATIO):
            return _M_SINGULAR
    else:  # B u = M qdd + h
        for k in range(4):
            rhs[k] = M[k, 0] * x[0] + M[k, 1] * x[1] + M[k, 2] * x[2] + M[k, 3] * x[3] + h[k]
        r, det = _solve4(Jl[:4], rhs)
        den = 1.0
        for k in range(4):
            den *= np.sqrt(Jl[k, 0] ** 2 + Jl[k, 1] ** 2 + Jl[k, 2] ** 2 + Jl[k, 3] ** 2)
        if not (den > 0.0 and abs(det) / den > SINGULAR_RATIO):
            return _B_SINGULAR
    out[:] = r
    return _OK


_PACKS: dict[int, tuple[object, Array]] = {}


def _pack(model: PdmModel) -> Array:
    """The model's constants as one array (192,) for :func:`_one`, cached per model object:
    ``r0, r2, r3, branch (2)``, ``R1, R4, S, U_local, R3_local`` (2 x 3 each), ``U1_local,
    P_local`` (3 each), ``cylinder_com, piston_com`` (4 each), ``gravity`` (3), ``mass`` (14),
    ``inertia`` (14 x 3 x 3)."""
    hit = _PACKS.get(id(model))
    if hit is not None and hit[0] is model:
        return hit[1]
    mass, inertia, g = _model_inertia(model)
    parts = [
        [model.r0, model.r2, model.r3, float(model.branch[0]), float(model.branch[1])],
        model.R1, model.R4, model.S, model.U_local, model.R3_local, model.U1_local, model.P_local,
        model.cylinder_com, model.piston_com, g, mass, inertia,
    ]
    pack = np.concatenate([np.asarray(x, dtype=np.float64).ravel() for x in parts])
    assert pack.shape == (192,)
    if len(_PACKS) >= 16:
        _PACKS.clear()
    _PACKS[id(model)] = (model, pack)
    return pack


_STATUS = {
    _NOT_CLOSED: (UnreachablePoseError, "a six-bar loop cannot close"),
    _CRANK_ALIGNED: (SingularityError, "a crank and its coupler are aligned (six-bar singular)"),
    _SPU_U1: (SingularityError, "an SPU limb is parallel to its first U-joint axis"),
    _B_SINGULAR: (SingularityError, "the actuator map B = (dl/dq)^T is singular"),
    _M_SINGULAR: (SingularityError, "the mass matrix M is singular"),
}


def _fail(st: int, q: Array, qd: Array, x: Array, name: str) -> None:
    """Raise the error for a status of :func:`_one` (or a wrong shape, ``st = -1``)."""
    if st == -1:
        for nm, v in (("q", q), ("qd", qd), (name, x)):
            if v.shape != (4,):
                raise MotionError(f"{nm}: shape {v.shape}, expected (4,)")
    if st == _NOT_FINITE:
        raise MotionError(f"q, qd, {name}: a value is not finite")
    cls, why = _STATUS[st]
    raise cls(f"q = {q.tolist()}: {why}")


def _checked_one(model: PdmModel, q: Array, qd: Array, x: Array, load: float | None, forward: bool,
                 name: str) -> Array:
    """The compiled sample (``x`` = ``qdd`` or ``u``, named ``name`` in errors) behind the two
    single-sample verbs, with their input checks and errors."""
    if load is not None:
        _no_load(load)
    q, qd, x = np.asarray(q, np.float64), np.asarray(qd, np.float64), np.asarray(x, np.float64)
    if q.shape != (4,) or qd.shape != (4,) or x.shape != (4,):
        _fail(-1, q, qd, x, name)
    out = np.empty(4)
    st = _one(_pack(model), q, qd, x, forward, out)
    if st != _OK:
        _fail(st, q, qd, x, name)
    return out


def inverse_dynamics_one(model: PdmModel, q: Array, qd: Array, qdd: Array, load: float | None = None) -> Array:
    """One sample of :func:`inverse_dynamics`: ``q, qd, qdd`` (4,) -> limb forces ``u`` (4,) [N].

    Compiled (numba) for a controller that calls once per cycle; its kinematics are a separate
    implementation of Eq. 2-48 for one sample (see the comment above :func:`_motion_one`).
    Errors as the batched verb, naming the pose instead of the sample.
    """
    return _checked_one(model, q, qd, qdd, load, False, "qdd")


def forward_dynamics_one(model: PdmModel, q: Array, qd: Array, u: Array, load: float | None = None) -> Array:
    """One sample of :func:`forward_dynamics`: ``q, qd`` (4,), limb forces ``u`` (4,) [N] ->
    ``qdd`` (4,). Compiled like :func:`inverse_dynamics_one`."""
    return _checked_one(model, q, qd, u, load, True, "u")


@njit(cache=True)
def _inverse_kernel(c, q, qd, qdd, load, out):  # type: ignore[no-untyped-def]
    return _one(c, q, qd, qdd, False, out) != _OK


@njit(cache=True)
def _forward_kernel(c, q, qd, u, load, out):  # type: ignore[no-untyped-def]
    return _one(c, q, qd, u, True, out) != _OK


def one_sample_kernels(model: PdmModel) -> tuple[Array, Callable, Callable]:
    """``(p, inverse, forward)``: the compiled kernels behind :func:`inverse_dynamics_one` and
    :func:`forward_dynamics_one` without their input checks (``pkmdyn.machine``): ``inverse(p,
    q, qd, qdd, load, out)``, ``forward(p, q, qd, u, load, out)`` write ``(4,)`` into ``out``,
    ignore ``load`` and return True for an invalid sample (then call the checked verb for the
    error)."""
    return _pack(model), _inverse_kernel, _forward_kernel
