"""Small dense linear systems inside compiled (Numba) kernels; knows no machine.

One solver serves every compiled single-sample path (the plant integrator's stage systems, the
PDM's Newton-Euler free-direction equations and compatibility system, its minimal-coordinate
route), so that each does not carry its own elimination loop.
"""

from __future__ import annotations

from numba import njit

__all__ = ["solve_in_place"]


@njit(cache=True)
def solve_in_place(M, r):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """Solve ``M x = r`` by Gaussian elimination with partial pivoting, in place.

    ``M (m, m)`` is overwritten by its eliminated form and ``r (m,)`` by ``x``. Returns
    ``(det M, smallest |pivot|)``; both are 0.0 when a pivot is exactly zero, and ``r`` is then
    not a solution. A caller that needs a relative singularity test compares the smallest pivot
    with its own scale.
    """
    m = r.shape[0]
    det = 1.0
    small = abs(M[0, 0]) if m else 0.0
    for k in range(m):
        p = k
        for i in range(k + 1, m):
            if abs(M[i, k]) > abs(M[p, k]):
                p = i
        if p != k:
            for j in range(m):
                t = M[k, j]
                M[k, j] = M[p, j]
                M[p, j] = t
            t = r[k]
            r[k] = r[p]
            r[p] = t
            det = -det
        piv = M[k, k]
        if piv == 0.0:
            return 0.0, 0.0
        det *= piv
        if k == 0 or abs(piv) < small:
            small = abs(piv)
        for i in range(k + 1, m):
            f = M[i, k] / piv
            if f != 0.0:
                for j in range(k, m):
                    M[i, j] -= f * M[k, j]
                r[i] -= f * r[k]
    for k in range(m - 1, -1, -1):
        acc = r[k]
        for j in range(k + 1, m):
            acc -= M[k, j] * r[j]
        r[k] = acc / M[k, k]
    return det, small
