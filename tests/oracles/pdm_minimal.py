"""Test oracle: the PDM's equations of motion in its minimal coordinates, by virtual power, on
the hand-derived kinematics of :mod:`pkmdyn.machines.pdm4.kinematics` (nothing of the generic
engine, whose verbs ``pkmdyn pdm control`` runs on the PDM's description).

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
chunks of ``CHUNK`` samples to bound their memory. :func:`kinetic_energy` and
:func:`potential_energy` give ``T`` and ``V`` from the body velocities and centres of mass,
for energy and power checks.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable

import numpy as np
from numpy.typing import NDArray

from pkmdyn.errors import MotionError, PkmdynError, SingularityError, UnreachablePoseError
from pkmdyn.machines.pdm4.kinematics import BODY_NAMES, inverse_kinematics
from pkmdyn.spatial import cross

if TYPE_CHECKING:
    from pkmdyn.machines.pdm4.kinematics import PdmKinematics
    from pkmdyn.machines.pdm4.params import PdmModel

__all__ = [
    "COORDINATES",
    "ACTUATORS",
    "mass_matrix",
    "bias_forces",
    "actuator_map",
    "inverse_dynamics",
    "forward_dynamics",
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
