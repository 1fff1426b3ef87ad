"""Unique joint reactions of over-constrained mechanisms from link compliance (machine-independent).

A rigid over-constrained mechanism has more unknown reaction components ``lambda`` (k) than
independent equilibrium equations: ``A lambda = b`` (``A`` m x k, rank r < k) leaves ``k - r``
self-stress states undetermined. With elastic links the real reactions are the statically
admissible set that minimises the complementary energy (Menabrea / Castigliano):

    minimise   U(lambda) = 1/2 sum_s (G_s lambda + w0_s)^T C_s (G_s lambda + w0_s)
    subject to A lambda = b,

where ``s`` runs over beam segments, ``G_s lambda + w0_s`` (6) is the internal wrench
``[Fx Fy Fz Mx My Mz]`` of segment ``s`` at its far end in the segment's frame (x along the
beam) and ``C_s`` its flexibility (Eq. 63-64 of the PDM paper). With ``N`` (k x (k - r)) a
basis of the null space of ``A`` and ``lambda = lambda_p + N z``, the stationarity conditions

    N^T (H lambda + h) = 0,   H = sum_s G_s^T C_s G_s,   h = sum_s G_s^T C_s w0_s,

are the ``k - r`` deformation-compatibility equations (for the PDM: Eq. 83): the relative
deflection of every released redundant direction is zero. They are unique when ``N^T H N``
is positive definite (every self-stress state strains some elastic segment).

Everything is batched over a leading sample axis. :func:`unique_reactions` is the general
(dense, SVD-based) solver; machines with a known structure solve the same problem faster in
redundant coordinates with :func:`solve_redundants` and check against this one in tests.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..errors import SingularityError

__all__ = [
    "Section",
    "circular_section",
    "beam_flexibility",
    "segment_wrenches",
    "unique_reactions",
    "unique_reactions_energy",
    "compatibility_rows",
    "solve_redundants",
    "UniqueReactions",
]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Section:
    """Cross-section and material of a straight beam: ``E`` [Pa], ``G`` [Pa], area ``A`` [m^2],
    second moments ``Iy, Iz`` [m^4] about the section's y and z axes, polar ``Ip`` [m^4]."""

    E: float
    G: float
    A: float
    Iy: float
    Iz: float
    Ip: float


def circular_section(E: float, nu: float, outer: float, inner: float = 0.0) -> Section:
    """A solid rod (``inner = 0``) or tube of diameters ``outer, inner`` [m]; ``G = E / (2 (1 + nu))``."""
    I = np.pi * (outer**4 - inner**4) / 64.0
    return Section(E=E, G=E / (2.0 * (1.0 + nu)), A=np.pi * (outer**2 - inner**2) / 4.0, Iy=I, Iz=I, Ip=2.0 * I)


def beam_flexibility(length: Array, sec: Section) -> Array:
    """Flexibility ``C`` (..., 6, 6) of a cantilever of ``length`` (...) [m], Eq. 64.

    ``X = C F`` (Eq. 63) gives the end deflection ``X = [dx dy dz tx ty tz]`` [m, rad] of a
    uniform beam clamped at its root, x along the beam, under the end wrench
    ``F = [Fx Fy Fz Mx My Mz]`` [N, N m] (tension, torsion and bending; shear neglected).
    """
    l = np.asarray(length, dtype=float)
    C = np.zeros(l.shape + (6, 6))
    E, G = sec.E, sec.G
    C[..., 0, 0] = l / (E * sec.A)
    C[..., 1, 1] = l**3 / (3 * E * sec.Iz)
    C[..., 1, 5] = C[..., 5, 1] = l**2 / (2 * E * sec.Iz)
    C[..., 2, 2] = l**3 / (3 * E * sec.Iy)
    C[..., 2, 4] = C[..., 4, 2] = -(l**2) / (2 * E * sec.Iy)
    C[..., 3, 3] = l / (G * sec.Ip)
    C[..., 4, 4] = l / (E * sec.Iy)
    C[..., 5, 5] = l / (E * sec.Iz)
    return C


def segment_wrenches(s: Array, loads: Array) -> tuple[Array, Array]:
    """Internal wrenches of a straight beam loaded at nodes, in the beam's frame.

    ``s`` (n, N) [m]: node positions along the beam's x axis; ``loads`` (n, N, 6, *cols):
    the wrench ``[f, m]`` applied at each node, in the beam frame, moment about the node.
    Nodes are sorted along x; segment ``k`` joins the k-th and (k+1)-th sorted nodes and
    carries the resultant of the loads at the nodes beyond it, reduced to its far end:
    exactly the cantilever end load of Eq. 64 for that segment.
    Returns ``lengths`` (n, N-1) [m] and ``F`` (n, N-1, 6, *cols).
    """
    order = np.argsort(s, axis=1, kind="stable")
    extra = loads.ndim - 3
    if len(order) and np.all(order == order[:1]):  # the same order at every sample: plain indexing
        ss, L = s[:, order[0]], loads[:, order[0]]
    else:
        ss = np.take_along_axis(s, order, axis=1)
        L = np.take_along_axis(loads, order.reshape(order.shape + (1,) * (extra + 1)), axis=1)
    f, m = L[:, :, :3], L[:, :, 3:]
    sx = ss.reshape(ss.shape + (1,) * extra)
    # moment about the beam origin: m + s e_x x f, with e_x x f = (0, -fz, fy)
    mo = m.copy()
    mo[:, :, 1] -= sx * f[:, :, 2]
    mo[:, :, 2] += sx * f[:, :, 1]
    # the resultant beyond each segment: the sums of the nodes after it (a suffix sum)
    Sf = np.cumsum(f[:, :0:-1], axis=1)[:, ::-1]
    Sm = np.cumsum(mo[:, :0:-1], axis=1)[:, ::-1]
    tip = sx[:, 1:]
    Sm[:, :, 1] += tip * Sf[:, :, 2]
    Sm[:, :, 2] -= tip * Sf[:, :, 1]
    return ss[:, 1:] - ss[:, :-1], np.concatenate([Sf, Sm], axis=2)


@dataclass(frozen=True)
class UniqueReactions:
    """Result of :func:`unique_reactions`: ``lam`` (n, k) reactions; ``null`` (n, k, k - r)
    self-stress basis; ``rank`` (n,) of ``A``; ``residual`` (n,) of ``A lam - b``."""

    lam: Array
    null: Array
    rank: Array
    residual: Array


def unique_reactions(A: Array, b: Array, G: Array, w0: Array, C: Array, rtol: float = 1e-10) -> UniqueReactions:
    """The unique reactions of an over-constrained mechanism (module docstring), dense route.

    ``A`` (n, m, k) equilibrium matrix, ``b`` (n, m); ``G`` (n, S, 6, k) and ``w0`` (n, S, 6)
    the internal wrench of every elastic segment, ``C`` (n, S, 6, 6) its flexibility.
    The null space comes from the SVD of ``A`` (singular values below ``rtol`` times the
    largest count as zero; the rank must be the same for every sample). Raises
    :class:`~pkmdyn.errors.SingularityError` when some self-stress state strains no elastic
    segment (the compliance cannot decide it).
    """
    return unique_reactions_energy(A, b, *_energy_matrices(G, w0, C), rtol)


def unique_reactions_energy(A: Array, b: Array, H: Array, h: Array, rtol: float = 1e-10,
                            method: str = "auto") -> UniqueReactions:
    """:func:`unique_reactions` from the complementary energy ``lam^T H lam / 2 + h^T lam``
    (``H`` (n, k, k), ``h`` (n, k): ``sum_s G_s^T C_s G_s`` and ``sum_s G_s^T C_s w0_s``).

    The null space of ``A`` and a particular solution: ``method="svd"`` from every sample's
    singular value decomposition; ``"auto"`` from pivots chosen once (:func:`_pivot_basis`, a
    square solve per sample), and from the SVD where those pivots do not hold along the motion.
    The reactions do not depend on the basis or the particular solution taken: the energy is
    minimised over the same set ``lam_p + N z``."""
    n, m, k = A.shape
    basis = _pivot_basis(A, b, rtol) if method == "auto" else None
    if basis is not None:
        lam_p, N, ranks = basis
    else:
        U, sv, Vt = np.linalg.svd(A)
        ranks = (sv > rtol * sv[:, :1]).sum(axis=1)
        r = int(ranks[0])
        if np.any(ranks != r):
            raise SingularityError("the rank of the equilibrium equations changes along the motion")
        V = np.swapaxes(Vt, 1, 2)
        N = V[:, :, r:]
        # particular solution: minimum norm, lambda_p = V_r S_r^-1 U_r^T b
        coef = np.einsum("nmr,nm->nr", U[:, :, :r], b) / sv[:, :r]
        lam_p = np.einsum("nkr,nr->nk", V[:, :, :r], coef)
    K = np.swapaxes(N, 1, 2) @ H @ N
    rhs = -np.einsum("nkz,nk->nz", N, np.einsum("nkl,nl->nk", H, lam_p) + h)
    _check_definite(K)
    z = np.linalg.solve(K, rhs[..., None])[..., 0]
    lam = lam_p + np.einsum("nkz,nz->nk", N, z)
    res = np.abs(np.einsum("nmk,nk->nm", A, lam) - b).max(axis=1)
    return UniqueReactions(lam=lam, null=N, rank=ranks, residual=res)


def _pivot_basis(A: Array, b: Array, rtol: float) -> tuple[Array, Array, Array] | None:
    """Null space and particular solution of ``A lam = b`` from pivots chosen at the first sample.

    The rank ``r`` and ``r`` independent columns ``c`` and rows ``p`` come from the first
    sample (its SVD, then QR with column pivoting of ``A`` and of the pivot columns'
    transpose); at every sample the square block ``M = A[p, c]`` gives
    ``lam_c = M^-1 (b_p - A[p, f] lam_f)`` in the other unknowns ``f``: the basis
    ``N = [-M^-1 A[p, f]; I]`` and ``lam_p = [M^-1 b_p; 0]`` (reduced row echelon form).
    None where the pivots do not hold at some sample: ``A N`` not zero on every row (the rank
    changed) or the block near singular (entries of ``M^-1 A[p, f]`` above 1e6, or ``A lam_p``
    away from ``b``); the caller then takes the SVD."""
    import scipy.linalg as sl

    n, m, k = A.shape
    if n == 0:
        return None
    sv = np.linalg.svd(A[0], compute_uv=False)
    r = int((sv > rtol * sv[0]).sum())
    if r == 0 or r == k:
        return None
    _, _, pc = sl.qr(A[0], pivoting=True, mode="economic")
    cols, free = np.sort(pc[:r]), np.sort(pc[r:])
    _, _, pr = sl.qr(A[0][:, cols].T, pivoting=True, mode="economic")
    rows = np.sort(pr[:r])
    Ap = A[:, rows]
    rhs = np.concatenate([Ap[:, :, free], b[:, rows, None]], axis=2)
    try:
        X = np.linalg.solve(Ap[:, :, cols], rhs)
    except np.linalg.LinAlgError:
        return None
    if not np.all(np.isfinite(X)) or np.abs(X[:, :, :-1]).max(initial=0.0) > 1e6:
        return None
    N = np.zeros((n, k, k - r))
    N[:, cols] = -X[:, :, :-1]
    N[:, free, np.arange(k - r)] = 1.0
    lam_p = np.zeros((n, k))
    lam_p[:, cols] = X[:, :, -1]
    scale = np.abs(A).max(axis=(1, 2))
    AN = np.abs(A @ N).max(axis=(1, 2))
    res = np.abs(np.einsum("nmk,nk->nm", A, lam_p) - b).max(axis=1)
    bs = np.maximum(np.abs(b).max(axis=1), scale * np.abs(lam_p).max(axis=1))
    if np.any(AN > 1e3 * rtol * scale * np.abs(N).max(axis=(1, 2))) or np.any(res > 1e3 * rtol * np.maximum(bs, 1e-300)):
        return None
    return lam_p, N, np.full(n, r)


def compatibility_rows(G: Array, C: Array, w0: Array, N: Array) -> tuple[Array, Array]:
    """The compatibility equations ``N^T H lambda = -N^T h`` as rows ``(n, k - r, k)`` and right side."""
    H, h = _energy_matrices(G, w0, C)
    return np.swapaxes(N, 1, 2) @ H, -np.einsum("nkz,nk->nz", N, h)


def _energy_matrices(G: Array, w0: Array, C: Array) -> tuple[Array, Array]:
    """``H = sum_s G_s^T C_s G_s`` (n, k, k) and ``h = sum_s G_s^T C_s w0_s`` (n, k)."""
    n, S, _, k = G.shape
    CG = (C @ G).reshape(n, 6 * S, k)
    Gf = G.reshape(n, 6 * S, k)
    H = np.swapaxes(Gf, 1, 2) @ CG
    h = np.einsum("nak,na->nk", CG, w0.reshape(n, 6 * S))
    return H, h


def _check_definite(K: Array) -> None:
    d = np.linalg.eigvalsh(0.5 * (K + np.swapaxes(K, 1, 2)))
    if np.any(d[:, 0] <= 1e-13 * np.abs(d[:, -1])):
        raise SingularityError("a self-stress state strains no elastic link: the compliance cannot make "
                               "the reactions unique")


def solve_redundants(Wx: Array, C: Array, W0: Array) -> Array:
    """Redundant reactions ``x`` (n, r) that make the complementary energy stationary.

    The internal wrench of every segment is ``W0 + Wx x``: ``W0`` (n, S, 6), ``Wx`` (n, S, 6, r),
    ``C`` (n, S, 6, 6). Solves ``(sum Wx^T C Wx) x = -sum Wx^T C W0`` (r x r per sample),
    i.e. the compatibility equations written in the redundants (Castigliano).
    """
    CW = C @ Wx
    K = np.einsum("nsar,nsaq->nrq", Wx, CW, optimize=True)
    f = np.einsum("nsar,nsa->nr", CW, W0, optimize=True)
    try:
        return -np.linalg.solve(K, f[..., None])[..., 0]
    except np.linalg.LinAlgError:
        raise SingularityError("a redundant reaction strains no elastic link: the compliance cannot make "
                               "the reactions unique") from None
