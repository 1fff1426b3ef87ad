"""Compiled bounds on the singularity measures (:func:`pkmdyn.multibody.kinematics.singularity.measures.singularity_measures`),
driven by the model's arrays only.

Each measure is the ratio ``sigma_min / sigma_max`` of a dimensionless matrix ``M (m, n)``. Its
singular values squared are the eigenvalues of the Gram matrix ``G`` (``M^T M`` for ``m >= n``,
``M M^T`` otherwise, ``d = min(m, n)`` of them), and

* ``sigma_max^2 <= trace G = |M|_F^2`` and ``sigma_max^2 >= max(max_i G_ii, trace G / d)``;
* ``sigma_min^2 > c`` exactly when ``G - c I`` is positive definite, which its Cholesky
  factorisation decides (every pivot positive); and each pivot ``p_k`` of ``G - c I`` (the
  last one computed included) is ``x^T (G - c I) x`` for a vector ``x`` whose ``k``-th entry is
  1 (``x = [-A^-1 a; 1]`` with ``[A a; a^T alpha]`` the leading block), so the least eigenvalue
  of ``G - c I`` is at most ``max(p_k, 0)`` and ``sigma_min^2 <= c + max(min_k p_k, 0)``.

So a Cholesky factorisation of ``G - (level^2 |M|_F^2 (1 + 1e-8) + g) I`` with positive pivots
proves the measure above ``level`` (:func:`measure_bounds`: ``passed``): the margin ``g`` covers
the rounding of ``G`` and of the factorisation (Higham, *Accuracy and Stability of Numerical
Algorithms*, 2002, Thm. 10.3: the computed factor is exact for ``G + E``, ``|E|_2 <= c_d u
|G|_2``), and the relative 1e-8 keeps a proven measure above ``level`` by more than the rounding
of its singular value decomposition. The pivots bound the measure from above (``upper``). Both cost a few thousand operations for a matrix of
21 rows, against some 15 us for its singular value decomposition; where a bound decides nothing,
the caller computes the measure itself.

Brackets (``brackets``: :func:`_bracket`, for :func:`pkmdyn.multibody.kinematics.singularity.measures.least_measures`). Along a
motion each measure is bracketed from both sides by bracketing the largest and the least
eigenvalue of ``G`` (:func:`_extreme`). For the largest, a shift ``s`` a little above the last
samples' value (extrapolated, moved out by twice its last change) is proven above it by the
Cholesky factorisation of ``s I - G`` (moved further out until that holds; its rounding covered
by the margin ``g``, as above): ``lambda_max < s + g``. One step of inverse iteration on that
factor from the last sample's vector gives ``x``, and the Rayleigh quotient
``x^T G x / x^T x <= lambda_max`` bounds it from below (to ``g``). The least eigenvalue is
bracketed the other way round: ``G - s I`` positive definite proves ``lambda_min > s - g``, and
the quotient after one step bounds it from above. The shift lies within about twice the
eigenvalue's change over a sample of it, so that the step converges by that ratio to the gap
and the bracket is about as wide as the change from one sample to the next. Then
``sqrt(lo_min / hi_max) <= sigma_min / sigma_max <= sqrt(hi_min / lo_max)``. The first sample's
state (the two eigenvalues and their vectors) comes from a symmetric eigendecomposition, so that
its bracket is as narrow as the later ones.

Screen (:func:`measure_brackets`). Only the samples that can hold a measure's least need a narrow
bracket. Every ``stride``-th sample (an anchor) is bracketed, which bounds the least from above;
any other sample whose matrix lies within ``delta`` (Frobenius norm of the difference) of its
nearest anchor's has singular values within ``delta`` of the anchor's (Weyl), so its measure is
at least ``(smin_lo - delta) / (smax_hi + delta)`` with the anchor's proven bounds. A sample whose
bound so found lies above the anchors' least (or a least given from elsewhere) is left with it;
the others are bracketed. The difference costs a few hundred operations where a bracket costs
two Cholesky factorisations; along a finely sampled motion most samples are left (the
Gough-Stewart platform's default motion at 20,000 samples: some 15 % to 40 % bracketed, per
measure, in chunks of 1,024).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["measure_bounds", "measure_brackets", "WIDEN_REL", "WIDEN_ABS"]

#: the unit roundoff of float64
_U = 2.0 ** -53
#: a bracket widened by the rounding of a singular value decomposition, relative and absolute
#: (:func:`pkmdyn.multibody.kinematics.singularity.measures.least_measures`; :func:`measure_brackets` screens with the same)
WIDEN_REL, WIDEN_ABS = 1e-8, 1e-12


@njit(cache=True, _nrt=False)
def _add_outer(G, M, m, n, nz):  # pragma: no cover - compiled
    """``G[:n, :n] += M[:m, :n]^T M[:m, :n]`` (upper triangle), over each row's nonzero entries
    (``nz`` a work vector of ``n`` integers)."""
    for r in range(m):
        k = 0
        for j in range(n):
            if M[r, j] != 0.0:
                nz[k] = j
                k += 1
        for a in range(k):
            i = nz[a]
            v = M[r, i]
            for b in range(a, k):
                j = nz[b]
                G[i, j] += v * M[r, j]


@njit(cache=True, _nrt=False)
def _outer_gram(M, m, n, G):  # pragma: no cover - compiled
    """``G[:m, :m] = M[:m, :n] M[:m, :n]^T``."""
    for i in range(m):
        for j in range(i, m):
            s = 0.0
            for k in range(n):
                s += M[i, k] * M[j, k]
            G[i, j] = s
            G[j, i] = s


@njit(cache=True, _nrt=False)
def _cholesky(G, d, shift):  # pragma: no cover - compiled
    """Cholesky factorisation of ``G[:d, :d] - shift I`` in place (by rows, its own loop: the
    reactions' normal equations, ``normal_solve``, are compiled with reassociation, and the
    margins here assume the operations in order). Returns whether every pivot is positive and
    the least pivot computed (the last one where it stopped)."""
    for i in range(d):
        G[i, i] -= shift
    least = math.inf
    for k in range(d):
        p = G[k, k]
        for j in range(k):
            p -= G[k, j] * G[k, j]
        least = min(least, p)
        if not p > 0.0:
            return False, least
        r = math.sqrt(p)
        G[k, k] = r
        for i in range(k + 1, d):
            s = G[i, k]
            for j in range(k):
                s -= G[i, j] * G[k, j]
            G[i, k] = s / r
    return True, least


@njit(cache=True, _nrt=False)
def _largest(G, d, guard, W, v, w):  # pragma: no cover - compiled
    """A proven upper bound of the largest eigenvalue of ``G[:d, :d]`` within 1 % to 25 % of it
    (else ``trace G``), and a lower bound: ten steps of the power iteration give a Rayleigh
    quotient ``rho <= lambda_max`` (within 1.5 % of it on the Delta robot's matrices, whose two
    largest eigenvalues are 0.8 to 0.85 apart), from a fixed vector of unequal entries (a
    column of ``G``, or equal entries, can be orthogonal to the top eigenvector of a symmetric
    mechanism's matrix: the Delta's stopped at 0.8 of it); ``c I - G`` positive definite
    (Cholesky of ``-(G - c I)`` in ``W``) proves ``lambda_max < c + guard`` for ``c = rho (1 +
    g)``, ``g`` = 0.01, 0.05, 0.25 in turn."""
    tr = 0.0
    k = 0
    for i in range(d):
        tr += G[i, i]
        if G[i, i] > G[k, k]:
            k = i
    for i in range(d):  # a fixed start without the symmetry of a mechanism's matrix
        v[i] = 0.5 + (0.6180339887498949 * (i + 1)) % 1.0
    rho = G[k, k]
    for _ in range(10):
        if not _normalise(v, d) > 0.0:
            return tr, rho
        rho = max(rho, _product(G, d, v, w))
        for i in range(d):
            v[i] = w[i]
    for grow in (0.01, 0.05, 0.25):
        c = rho * (1.0 + grow)
        if c + guard >= tr:
            break
        for i in range(d):
            for j in range(d):
                W[i, j] = -G[i, j]
        ok, _ = _cholesky(W, d, -c)
        if ok:
            return c + guard, rho
    return tr, rho


@njit(cache=True, _nrt=False)
def _bounds(G, d, level, tight, W, v, w):  # pragma: no cover - compiled
    """For the Gram matrix ``G[:d, :d]`` (overwritten): whether ``sigma_min / sigma_max > level``
    is proven, and an upper bound of ``sigma_min / sigma_max`` (module docstring); ``tight``:
    ``sigma_max^2`` bounded by :func:`_largest` rather than by ``trace G``."""
    if d == 0:
        return True, 1.0
    tr = 0.0
    big = 0.0
    for i in range(d):
        tr += G[i, i]
        big = max(big, G[i, i])
    if not tr > 0.0:  # a zero matrix: every measure 0
        return level < 0.0, 0.0
    guard = 4.0 * (d + 1) * (d + 1) * _U * tr
    top_hi, top_lo = tr, max(big, tr / d)
    if tight:
        top_hi, rho = _largest(G, d, guard, W, v, w)
        top_lo = max(top_lo, rho)
    shift = level * level * top_hi * (1.0 + 1e-8) + guard
    ok, least = _cholesky(G, d, shift)
    upper = math.sqrt((shift + max(least, 0.0)) / top_lo)
    return ok, min(upper, 1.0)


@njit(cache=True, _nrt=False)
def _solve_chol(L, d, x):  # pragma: no cover - compiled
    """``x = (L L^T)^-1 x`` in place, ``L`` the lower factor of :func:`_cholesky` in ``L[:d, :d]``."""
    for i in range(d):
        acc = x[i]
        for j in range(i):
            acc -= L[i, j] * x[j]
        x[i] = acc / L[i, i]
    for i in range(d - 1, -1, -1):
        acc = x[i]
        for j in range(i + 1, d):
            acc -= L[j, i] * x[j]
        x[i] = acc / L[i, i]


@njit(cache=True, _nrt=False)
def _normalise(x, d):  # pragma: no cover - compiled
    """``x[:d]`` scaled to unit length in place; its length before (a zero ``x`` left as it is)."""
    nx = 0.0
    for i in range(d):
        nx += x[i] * x[i]
    nx = math.sqrt(nx)
    if not nx > 0.0:
        return nx
    for i in range(d):
        x[i] /= nx
    return nx


@njit(cache=True, _nrt=False)
def _product(G, d, x, w):  # pragma: no cover - compiled
    """``w = G x`` (``G[:d, :d]``) and ``x^T G x``."""
    rq = 0.0
    for i in range(d):
        acc = 0.0
        for j in range(d):
            acc += G[i, j] * x[j]
        w[i] = acc
        rq += x[i] * acc
    return rq


@njit(cache=True, _nrt=False)
def _rayleigh(G, d, x, w):  # pragma: no cover - compiled
    """``x`` normalised in place, ``w = G x`` and the Rayleigh quotient ``x^T G x``."""
    _normalise(x, d)
    return _product(G, d, x, w)


@njit(cache=True, _nrt=False)
def _factor(G, d, W, shift, sign):  # pragma: no cover - compiled
    """Whether ``sign (G - shift I)`` is positive definite; its Cholesky factor then in ``W``."""
    for i in range(d):
        for j in range(i + 1):
            W[i, j] = sign * G[i, j]
    ok, _ = _cholesky(W, d, sign * shift)
    return ok


@njit(cache=True, _nrt=False)
def _extreme(G, d, W, x, w, guess, margin, sign, guard, tr, steps):  # pragma: no cover - compiled
    """A proven bracket ``(lo, hi)`` of the largest (``sign`` -1) or least (``sign`` +1)
    eigenvalue of ``G[:d, :d]``, and ``x`` refined towards its eigenvector (module docstring,
    "Brackets"): the shift ``sigma = guess -+ margin`` beyond the eigenvalue, proven by the
    Cholesky factorisation of ``sign (G - sigma I)`` (moved further out until it holds), then
    ``steps`` of inverse iteration on that factor from ``x``, whose Rayleigh quotient bounds the
    eigenvalue on the other side (to rounding, ``guard``). The shift lies within about twice
    the eigenvalue's change over a sample of it, so that one step from the last sample's vector
    leaves the quotient within rounding of the eigenvalue along a smooth motion."""
    sigma = guess - sign * margin
    found = False
    for _ in range(24):
        if sign < 0.0 and sigma + guard >= tr:
            sigma = tr
        if sign > 0.0 and sigma - guard <= 0.0:
            sigma = 0.0
        if _factor(G, d, W, sigma, sign):
            found = True
            break
        if sigma == tr or sigma == 0.0:
            break
        margin *= 4.0
        sigma = guess - sign * margin
    if not found:
        return 0.0, tr
    for _ in range(steps):
        _normalise(x, d)
        _solve_chol(W, d, x)
    rho = _rayleigh(G, d, x, w)
    if sign < 0.0:  # largest: rho - guard <= lambda_max < sigma + guard
        return rho - guard, sigma + guard
    return max(sigma - guard, 0.0), rho + guard  # least: sigma - guard < lambda_min <= rho + guard


@njit(cache=True, _nrt=False)
def _bracket(G, d, W, top, low, w, est, first):  # pragma: no cover - compiled
    """A proven bracket ``lo <= sigma_min / sigma_max <= hi`` of the matrix whose Gram matrix is
    ``G[:d, :d]``, from brackets of the largest and least eigenvalues of ``G``
    (:func:`_extreme`). ``top`` and ``low`` are the eigenvector estimates, ``est`` the two
    eigenvalues of the last sample and their change from the sample before (``first``: none
    yet, ten power steps instead), updated in place: each shift is the eigenvalue extrapolated
    from the last two samples, moved out by twice its last change (and 1e-9 of it). ``(0, 1)``
    where nothing is proven."""
    est[4] = 0.0  # no singular value bounds (until proven below): a screen from them proves nothing
    est[5] = math.inf
    if d == 0:
        return 1.0, 1.0
    tr = 0.0
    for i in range(d):
        tr += G[i, i]
    if not tr > 0.0:
        return 0.0, 0.0
    guard = 4.0 * (d + 1) * (d + 1) * _U * tr
    if first:
        for _ in range(10):
            _rayleigh(G, d, top, w)
            for i in range(d):
                top[i] = w[i]
        est[0] = _rayleigh(G, d, top, w)
        est[1] = 0.02 * est[0]
        est[2] = 0.0
        est[3] = 0.0
    top_guess = est[0] + est[1]
    steps = 3 if first else 1
    c, e = _extreme(G, d, W, top, w, top_guess, 2.0 * abs(est[1]) + 1e-9 * top_guess, -1.0, guard, tr, steps)
    low_guess = max(est[2] + est[3], 0.0)
    a, b = _extreme(G, d, W, low, w, low_guess, 2.0 * abs(est[3]) + 1e-9 * low_guess, 1.0, guard, tr, steps)
    if not first:
        est[1] = 0.5 * (c + e) - est[0]
        est[3] = 0.5 * (a + b) - est[2]
    est[0] = 0.5 * (c + e)
    est[2] = 0.5 * (a + b)
    est[4] = math.sqrt(max(a, 0.0))
    est[5] = math.sqrt(e)
    if not c > 0.0:
        return 0.0, 1.0
    return math.sqrt(max(a, 0.0) / e), min(math.sqrt(max(b, 0.0) / c), 1.0)


@njit(cache=True, _nrt=False)
def _rows(J, s, rs, cs, cut, task, idle, M, T):  # pragma: no cover - compiled
    """Sample ``s``'s dimensionless rows: ``Phi = [Js[cut]; idle]`` into ``M[:nc + ni]``, the
    task rows ``Js[task]`` into ``T`` (``Js`` the Jacobian ``J[s]`` scaled by ``rs`` and ``cs``)."""
    nq = J.shape[2]
    nc = cut.shape[0]
    for a in range(nc):
        r = cut[a]
        for j in range(nq):
            M[a, j] = J[s, r, j] * rs[r] * cs[j]
    for a in range(idle.shape[0]):
        for j in range(nq):
            M[nc + a, j] = idle[a, j]
    for a in range(task.shape[0]):
        r = task[a]
        for j in range(nq):
            T[a, j] = J[s, r, j] * rs[r] * cs[j]


@njit(cache=True, _nrt=False)
def _phi_gram(M, mp, nq, GP, nz):  # pragma: no cover - compiled
    """``GP = Phi^T Phi`` (upper triangle), ``Phi = M[:mp]``."""
    for i in range(nq):
        for j in range(nq):
            GP[i, j] = 0.0
    _add_outer(GP, M, mp, nq, nz)


@njit(cache=True, _nrt=False)
def _gram(which, M, T, mp, act, GP, G, nz):  # pragma: no cover - compiled
    """The Gram matrix of measure ``which`` (:func:`measure_bounds`) into ``G`` (whole) from
    ``Phi = M[:mp]``, its ``GP = Phi^T Phi`` (:func:`_phi_gram`) and the task rows ``T``: its
    size ``d``, 0 where the matrix has no rows. Writes the task rows or ``E_a`` into
    ``M[mp:]`` where the matrix has fewer rows than columns (``M M^T``)."""
    nq = M.shape[1]
    nt = T.shape[0]
    na = act.shape[0]
    m = mp + (0 if which == 0 else (nt if which == 1 else na))
    if m == 0:
        return 0
    if m >= nq:
        for i in range(nq):
            for j in range(i, nq):
                G[i, j] = GP[i, j]
        if which == 1:
            _add_outer(G, T, nt, nq, nz)
        elif which == 2:
            for a in range(na):
                G[act[a], act[a]] += 1.0
        for i in range(nq):
            for j in range(i):
                G[i, j] = G[j, i]
        return nq
    if which == 1:
        for a in range(nt):
            for j in range(nq):
                M[mp + a, j] = T[a, j]
    elif which == 2:
        for a in range(na):
            for j in range(nq):
                M[mp + a, j] = 0.0
            M[mp + a, act[a]] = 1.0
    _outer_gram(M, m, nq, G)
    return m


@njit(cache=True)
def _work(J, cut, task, idle, act):  # pragma: no cover - compiled
    """The work space of :func:`measure_bounds` and :func:`measure_brackets`: ``mp`` the rows of
    ``Phi``, ``big`` the largest matrix's size, the rows ``M (mp + max(nt, na), nq)`` and ``T
    (nt, nq)``, ``GP (nq, nq)``, the Gram matrix ``G`` and factor ``W`` (``big`` square), a
    vector ``w`` and the nonzero list ``nz``."""
    nq = J.shape[2]
    nt = task.shape[0]
    mp = cut.shape[0] + idle.shape[0]
    mt = mp + max(nt, act.shape[0])
    big = max(mt, nq)
    return (mp, big, np.empty((mt, nq)), np.empty((nt, nq)), np.empty((nq, nq)), np.empty((big, big)),
            np.empty((big, big)), np.empty(big), np.empty(nq, dtype=np.int64))


@njit(cache=True)
def measure_bounds(J, rs, cs, cut, task, idle, act, direct, levels, tight, passed, upper):  # pragma: no cover - compiled
    """Bounds on the three singularity measures of every sample (module docstring).

    ``J (n, nrow, nq)`` the constraint Jacobian (loop and task rows), ``rs (nrow,)`` and
    ``cs (nq,)`` the row and column factors that make it dimensionless, ``cut`` the solved loop
    rows, ``task`` the solved task rows, ``idle (ni, nq)`` the scaled idle rows, ``act`` the
    actuated coordinates, ``direct`` whether the direct measure applies (as many actuators as
    degrees of freedom). The matrices are those of :func:`pkmdyn.multibody.kinematics.singularity.measures.singularity_measures`:
    ``Phi = [Js[cut]; idle]`` (constraint, measure 0), ``[Phi; Js[task]]`` (inverse, 1),
    ``[Phi; E_a]`` (direct, 2); where one has at least ``nq`` rows its Gram matrix is
    ``Phi^T Phi`` (computed once a sample) plus its own rows' part. Writes ``passed[s, k]``
    (measure ``k`` proven above ``levels[k]``; True for the direct one where it does not
    apply) and ``upper[s, k]`` (an upper bound of measure ``k``; 1 where it does not apply).
    ``tight``: each ``sigma_max^2`` bounded within 1 % to 25 % (:func:`_largest`, some twice the
    cost) rather than by ``trace G``, which may exceed it by the number of rows."""
    n = J.shape[0]
    nq = J.shape[2]
    mp, big, M, T, GP, G, W, w, nz = _work(J, cut, task, idle, act)
    v = np.empty(big)
    for s in range(n):
        _rows(J, s, rs, cs, cut, task, idle, M, T)
        _phi_gram(M, mp, nq, GP, nz)
        for which in range(3):
            passed[s, which] = True
            upper[s, which] = 1.0
            if which == 2 and not direct:
                break
            d = _gram(which, M, T, mp, act, GP, G, nz)
            if d == 0:  # no rows: the measure is 1
                continue
            good, u = _bounds(G, d, levels[which], tight, W, v, w)
            passed[s, which] = good
            upper[s, which] = u


@njit(cache=True)
def _start(G, d, top, low, est):  # pragma: no cover - compiled
    """The brackets' state at the first sample: the largest and least eigenvalues of
    ``G[:d, :d]`` and their vectors by a symmetric eigendecomposition (LAPACK), so that the
    first bracket is as tight as the later ones (from a fixed vector, one step of inverse
    iteration a sample tightened it over some tens of samples); their changes zero."""
    lam, vec = np.linalg.eigh(np.ascontiguousarray(G[:d, :d]))
    for i in range(d):
        top[i] = vec[i, d - 1]
        low[i] = vec[i, 0]
    est[0] = lam[d - 1]
    est[1] = 0.0
    est[2] = max(lam[0], 0.0)
    est[3] = 0.0


@njit(cache=True)
def measure_brackets(J, rs, cs, cut, task, idle, act, direct, stride, below, out):  # pragma: no cover - compiled
    """A proven bracket ``out[s, k] = (lo, hi)`` of each measure ``k`` of every sample ``s``
    (:func:`measure_bounds`' arguments and matrices; ``(0, 1)`` where none was found, ``(1, 1)``
    where the measure does not apply), for :func:`pkmdyn.multibody.kinematics.singularity.measures.least_measures`.

    Two passes (module docstring, "Screen"). First every ``stride``-th sample and the last, the
    anchors: :func:`_bracket`, warm-started from the anchor before. The least ``hi`` of the
    anchors, ``top``, bounds each measure's least from above, as does ``below (3,)`` (a least
    found elsewhere: infinite where there is none). Then every other sample ``s``:
    its matrix differs from its nearest anchor's by ``delta <= |M_s - M_a|_F``, so by Weyl's
    inequality (``|sigma_i(A) - sigma_i(B)| <= |A - B|_2``; Horn and Johnson, *Matrix
    Analysis*, 2nd ed., Cor. 7.3.5) its measure is at least ``(smin_lo - delta) / (smax_hi +
    delta)`` with the anchor's proven singular value bounds. Where that exceeds ``top`` the
    sample cannot hold the least and keeps that bound, ``(lo, 1)``; elsewhere it is bracketed
    as the anchors are, warm-started from the sample before, or from the anchor before where
    that one was not bracketed."""
    n = J.shape[0]
    if n == 0:
        return
    nq = J.shape[2]
    nt = task.shape[0]
    mp, big, M, T, GP, G, W, w, nz = _work(J, cut, task, idle, act)
    mt = M.shape[0]
    # the anchors: every stride-th sample and the last
    na_ = (n - 1) // stride + 1
    if (n - 1) % stride != 0:
        na_ += 1
    anchor = np.empty(na_, dtype=np.int64)
    for k in range(na_):
        anchor[k] = min(k * stride, n - 1)
    # per anchor: its rows, and per measure the bracket's state (est, vectors)
    AM = np.empty((na_, mp, nq))
    AT = np.empty((na_, nt, nq))
    aest = np.empty((na_, 3, 6))
    atop = np.empty((na_, 3, big))
    alow = np.empty((na_, 3, big))
    tops = np.empty((3, big))
    lows = np.empty((3, big))
    est = np.zeros((3, 6))
    for k in range(3):
        for i in range(big):  # a fixed start without the symmetry of a mechanism's matrix (:func:`_largest`)
            tops[k, i] = 0.5 + (0.6180339887498949 * (i + 1)) % 1.0
            lows[k, i] = 0.5 + (0.7548776662466927 * (i + 1)) % 1.0
    top = np.empty(3)
    rows = np.ones(3, dtype=np.bool_)  # whether each measure's matrix has rows (else the measure is 1)
    for which in range(3):
        top[which] = below[which]
    rows[2] = direct
    # ---- pass 1: the anchors
    for k in range(na_):
        s = anchor[k]
        _rows(J, s, rs, cs, cut, task, idle, M, T)
        for i in range(mp):
            for j in range(nq):
                AM[k, i, j] = M[i, j]
        for i in range(nt):
            for j in range(nq):
                AT[k, i, j] = T[i, j]
        _phi_gram(M, mp, nq, GP, nz)
        for which in range(3):
            out[s, which, 0] = 1.0
            out[s, which, 1] = 1.0
            if which == 2 and not direct:
                break
            d = _gram(which, M, T, mp, act, GP, G, nz)
            if d == 0:
                rows[which] = False
                continue
            first = k == 0
            if first and np.all(np.isfinite(G[:d, :d])):
                _start(G, d, tops[which], lows[which], est[which])
                first = False
            lo, hi = _bracket(G, d, W, tops[which], lows[which], w, est[which], first)
            out[s, which, 0] = lo
            out[s, which, 1] = hi
            top[which] = min(top[which], hi)
        for which in range(3):
            for i in range(6):
                aest[k, which, i] = est[which, i]
            for i in range(big):
                atop[k, which, i] = tops[which, i]
                alow[k, which, i] = lows[which, i]
    # ---- pass 2: the samples between the anchors
    last = np.full(3, -2, dtype=np.int64)  # the last sample of pass 2 each measure bracketed
    for s in range(n):
        k = s // stride  # the anchor at or before s
        if anchor[k] == s or (k + 1 < na_ and anchor[k + 1] == s):
            continue
        near = k if s - anchor[k] <= anchor[k + 1] - s else k + 1
        _rows(J, s, rs, cs, cut, task, idle, M, T)
        dphi = 0.0
        for i in range(mp):
            for j in range(nq):
                e = M[i, j] - AM[near, i, j]
                dphi += e * e
        dtask = 0.0
        for i in range(nt):
            for j in range(nq):
                e = T[i, j] - AT[near, i, j]
                dtask += e * e
        gram = False
        for which in range(3):
            out[s, which, 0] = 1.0
            out[s, which, 1] = 1.0
            if which == 2 and not direct:
                break
            if not rows[which]:  # no rows: the measure is 1
                continue
            # Weyl from the nearest anchor, the norm's rounding covered (its sum of squares of
            # sums of at most mt nq terms); excluded where least_measures' widened bracket would
            # exclude it too
            delta = math.sqrt(dphi + dtask if which == 1 else dphi) * (1.0 + 4.0 * (mt * nq + 2) * _U)
            smin, smax = aest[near, which, 4], aest[near, which, 5]
            den = smax + delta
            lo = max(smin - delta, 0.0) / den * (1.0 - 4.0 * _U) if den > 0.0 else 0.0  # (rounded down)
            if lo * (1.0 - WIDEN_REL) - WIDEN_ABS > top[which] * (1.0 + WIDEN_REL) + WIDEN_ABS:
                out[s, which, 0] = lo
                continue
            if not gram:
                _phi_gram(M, mp, nq, GP, nz)
                gram = True
            d = _gram(which, M, T, mp, act, GP, G, nz)
            if last[which] != s - 1:  # warm start from the anchor before, its change scaled to the gap
                a = anchor[k]
                gap = anchor[k] - anchor[k - 1] if k > 0 else stride
                for i in range(6):
                    est[which, i] = aest[k, which, i]
                est[which, 1] *= (s - a) / gap
                est[which, 3] *= (s - a) / gap
                for i in range(big):
                    tops[which, i] = atop[k, which, i]
                    lows[which, i] = alow[k, which, i]
            lo, hi = _bracket(G, d, W, tops[which], lows[which], w, est[which], False)
            last[which] = s
            out[s, which, 0] = lo
            out[s, which, 1] = hi
