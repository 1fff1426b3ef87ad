"""Redundant actuation: the actuated joints' efforts of a mechanism with more actuated joints
than degrees of freedom (``na > nt``), shared by the rule of its ``[actuation]``
(``docs/mechanism_format.md``, "Redundant actuation").

Every distribution meets the task-space balance of Eq. (3) of
:mod:`pkmdyn.multibody.dynamics.newton_euler`, ``A u = w`` with ``A = J_ax^T`` (nt, na) and
``w = G^T Q`` the generalised force the motion needs; the efforts differ by an internal force
``N lambda`` (``A N = 0``, ``N`` (na, r) the internal-force directions, ``r = na - nt`` the
degree of redundancy), which moves nothing and changes the joints' reactions.

- ``minimum_norm``: ``u = A^+ w`` (R1), the least ``sum u_i^2``;
- ``weighted``: the least ``sum c_i u_i^2`` (``c`` the weights), ``u = C^-1 A^T (A C^-1
  A^T)^-1 w`` (R2);
- ``minimax``: the least peak ``max |u_i|`` within the bounds ``|u_i| <= b_i`` (a linear
  program, R3); among the efforts of that least peak, the least ``sum u_i^2`` (a quadratic
  program), so that the efforts are unique and continuous along a motion;
- bounds (``act_bound``): where (R1) or (R2) leaves a bound, the least (weighted) norm within
  the bounds (a quadratic program, R4);
- preload: every drive with a sign ``s_i`` keeps ``s_i u_i >= m`` (``m`` = ``act_preload``),
  with the least weighted change of the distribution's efforts (a quadratic program, R5). The
  signs are ``preload_sign``'s, or, with one internal-force direction and no signs given, those
  of that direction (oriented so that the first actuated joint's share is positive): the
  antagonistic pattern in which a preload pulls every drive away from zero. A drive with no share in the direction
  cannot be preloaded.

The programs are solved per sample by Clarabel (an interior-point solver); where none has a
solution within the bounds, :class:`~pkmdyn.errors.LimitError` names the sample and the drive."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...errors import LimitError, ParameterError, at_sample
from ..model.compiler import MechanismModel

__all__ = ["distribute", "internal_directions", "least_norm_map", "weights"]

Array = NDArray[np.float64]


def internal_directions(JT: Array) -> Array:
    """The internal-force directions ``N (n, na, r)`` of ``A = J_ax^T (n, nt, na)``: an
    orthonormal basis of its null space per sample (``r = na - nt`` where ``A`` has full rank),
    each column oriented so that its first component of at least 1e-6 of its largest is
    positive (the first actuated joint's, unless it has no share)."""
    n, nt, na = JT.shape
    _, _, Vt = np.linalg.svd(JT, full_matrices=True)
    N = np.swapaxes(Vt[:, nt:, :], 1, 2)  # (n, na, r)
    big = np.abs(N) >= 1e-6 * np.abs(N).max(axis=1, keepdims=True)
    first = np.take_along_axis(N, np.argmax(big, axis=1)[:, None, :], axis=1)
    return N * np.where(first < 0.0, -1.0, 1.0)


def weights(model: MechanismModel) -> Array:
    """The weights ``c (na,)`` of the model's least (weighted) norm: ``[actuation] weights`` for
    the ``weighted`` distribution, else ones."""
    return model.act_weight if model.act_distribution == "weighted" else np.ones(model.na)


def least_norm_map(model: MechanismModel, JT: Array) -> Array:
    """``L = C^-1 A^T (A C^-1 A^T)^-1 (n, na, nt)`` of ``A = J_ax^T (n, nt, na)`` of full row rank
    (the caller has checked its singular values): the (weighted) least-norm efforts ``u = L w``
    of (R1) and (R2), linear in ``w``; ``C`` the model's :func:`weights`."""
    AC = JT / weights(model)[None, None, :]
    return np.swapaxes(np.linalg.solve(AC @ np.swapaxes(JT, 1, 2), AC), 1, 2)


def _solve(P: Array | None, q: Array, A: Array, w: Array, G: Array, h: Array) -> tuple[str, Array]:
    """``min 1/2 x'Px + q'x`` with ``A x = w`` and ``G x <= h`` (Clarabel): status and ``x``."""
    import clarabel
    from scipy import sparse

    nx = q.size
    M = sparse.csc_matrix(np.vstack([A, G]))
    b = np.concatenate([w, h])
    cones = [clarabel.ZeroConeT(A.shape[0])] + ([clarabel.NonnegativeConeT(G.shape[0])] if G.shape[0] else [])
    st = clarabel.DefaultSettings()
    st.verbose = False
    st.tol_gap_abs = st.tol_gap_rel = st.tol_feas = 1e-11
    Pm = sparse.csc_matrix((nx, nx)) if P is None else sparse.triu(sparse.csc_matrix(P), format="csc")
    sol = clarabel.DefaultSolver(Pm, q, M, b, cones, st).solve()
    return str(sol.status).split(".")[-1], np.asarray(sol.x)


_OK = ("Solved", "AlmostSolved")


def _box(na: int, bound: Array, extra: int = 0) -> tuple[Array, Array]:
    """Rows ``G x <= h`` of ``|u_i| <= b_i`` (finite bounds) over ``x = [u; extra]``."""
    fin = np.flatnonzero(np.isfinite(bound))
    G = np.zeros((2 * fin.size, na + extra))
    G[np.arange(fin.size), fin] = 1.0
    G[fin.size + np.arange(fin.size), fin] = -1.0
    return G, np.concatenate([bound[fin], bound[fin]])


def _beyond(model: MechanismModel, u: Array, bound: Array) -> str:
    """The drive whose bound ``u`` exceeds the most, named with its effort and bound."""
    use = np.abs(u) / bound
    i = int(np.argmax(use))
    unit = "N" if model.actuator_units[i] == "m" else "N m"
    return f"{model.actuator_names[i]} {u[i]:.6g} {unit} against its bound {bound[i]:.6g} {unit}"


def _signs(model: MechanismModel, N: Array, where: str) -> Array:
    """The preload's sign per drive (module docstring) at one sample with directions ``N (na, r)``."""
    given = model.act_preload_sign
    if np.any(given != 0):
        return given
    if N.shape[1] != 1:
        raise ParameterError(f"[actuation] preload_min_effort_SI: the mechanism has {N.shape[1]} internal-force "
                             "directions; give each preloaded joint's sign in preload_sign")
    n = N[:, 0]
    small = np.abs(n) <= 1e-6 * np.abs(n).max()
    if np.any(small):
        j = int(np.flatnonzero(small)[0])
        raise LimitError(f"{where}: {model.actuator_names[j]} has no share in the internal force, so no preload "
                         "reaches it (give preload_sign for the joints to preload)")
    return np.sign(n)


def distribute(model: MechanismModel, JT: Array, rhs: Array, t: Any = None, sample_offset: int = 0) -> Array:
    """The efforts ``u (n, na)`` with ``JT u = rhs`` (``JT`` (n, nt, na), ``rhs`` (n, nt)) by the
    model's distribution, bounds and preload (module docstring). Raises
    :class:`~pkmdyn.errors.LimitError` naming the first sample and drive where no distribution
    meets the bounds or the preload."""
    n, nt, na = JT.shape
    c = weights(model)
    u = np.einsum("nat,nt->na", least_norm_map(model, JT), rhs)
    b = model.act_bound
    pre = model.act_preload
    minimax = model.act_distribution == "minimax"
    bounded = np.isfinite(b).any()
    if not (minimax or pre or bounded):
        return u
    N = internal_directions(JT) if pre else None
    for i in range(n):
        ui = u[i]
        A, w = JT[i], rhs[i]
        where = at_sample(i, t, sample_offset)
        scale = max(float(np.abs(ui).max()), pre, 1e-300)  # (a mechanism at rest with no load: the preload's)
        if minimax:
            G, h = _box(na, b / scale, 1)
            Gt = np.zeros((2 * na, na + 1))
            Gt[:na, :na], Gt[na:, :na] = np.eye(na), -np.eye(na)
            Gt[:, na] = -1.0
            q = np.zeros(na + 1)
            q[na] = 1.0
            st, x = _solve(None, q, np.hstack([A, np.zeros((nt, 1))]), w / scale, np.vstack([Gt, G]),
                           np.concatenate([np.zeros(2 * na), h]))
            if st not in _OK:
                raise LimitError(f"{where}: no distribution of the efforts within the actuated joints' bounds "
                                 f"exists (at the least-norm distribution: {_beyond(model, ui, b)})")
            peak = float(x[na]) * (1.0 + 1e-9) + 1e-12
            G, h = _box(na, np.minimum(np.full(na, peak), b / scale))
            st, x = _solve(np.eye(na), np.zeros(na), A, w / scale, G, h)
            if st not in _OK:
                raise LimitError(f"{where}: the least-peak distribution of the efforts was not found ({st})")
            ui = x * scale
        elif bounded and np.any(np.abs(ui) > b):
            G, h = _box(na, b / scale)
            st, x = _solve(np.diag(c), np.zeros(na), A, w / scale, G, h)
            if st not in _OK:
                raise LimitError(f"{where}: no distribution of the efforts within the actuated joints' bounds "
                                 f"exists ({_beyond(model, ui, b)} at the least-norm distribution)")
            ui = x * scale
        if pre:
            sig = _signs(model, N[i], where)
            on = np.flatnonzero(sig != 0)
            if np.any(sig[on] * ui[on] < pre):
                m = pre / scale
                Gp = np.zeros((on.size, na))
                Gp[np.arange(on.size), on] = -sig[on]
                G, h = _box(na, b / scale)
                st, x = _solve(np.diag(c), -c * ui / scale, A, w / scale, np.vstack([Gp, G]),
                               np.concatenate([np.full(on.size, -m), h]))
                if st not in _OK:
                    j = on[int(np.argmin(sig[on] * ui[on]))]
                    raise LimitError(f"{where}: no preload of {pre:.6g} with these signs keeps every preloaded drive "
                                     f"within its bound ({model.actuator_names[j]} is the hardest to preload: "
                                     f"{ui[j]:.6g} before the preload; the internal forces may not reach the sign "
                                     "pattern, or a bound stops them)")
                ui = x * scale
        u[i] = ui
    return u
