"""Compiled per-sample kernel of the PDM's Newton-Euler and compliance solution (numba), of the
test oracle :mod:`.pdm_newton_euler`.

The batched numpy route of :mod:`.pdm_newton_euler` (``_solve_cuts``, ``_segments``) states the same
computation with arrays; this kernel does it sample by sample in compiled loops so that the
sample-independent structure (the spanning tree, the cut columns, which joint loads which
link) is read from small constant tables and nothing of size (n, 19, 23, 6) is ever formed.
Tests check it against the dense general solver of :mod:`pkmdyn.analysis.compliance`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from pkmdyn._dense import solve_in_place

__all__ = ["ne_kernel"]


@njit(cache=True)
def _solve_inplace(M, r):  # pragma: no cover - compiled
    """``M x = r`` in place (``r`` becomes ``x``); False when a pivot falls below 1e-13 of the
    largest entry of ``M`` (singular)."""
    m = M.shape[0]
    scale = 0.0
    for i in range(m):
        for j in range(m):
            if abs(M[i, j]) > scale:
                scale = abs(M[i, j])
    return solve_in_place(M, r)[1] > 1e-13 * scale


@njit(cache=True)
def ne_kernel(p, a, w, wd, R, mass, inertia, gravity, pts, axes, U3,
              sub, cut_sign, row_joint, row_dir, col_joint, col_kind, col_dir, col_owner, n_free,
              el_body, el_joint, el_sign, el_count, el_EI, el_GJ, compliance, W, X):  # pragma: no cover
    """Joint wrenches ``W`` (n, 19, 6) [N, N m about the origin] and redundants ``X`` (n, 9).

    Body arrays are body-major: ``p, a, w, wd`` (14, n, 3), ``R`` (14, n, 3, 3). One thread
    (the machine's cores are left to the caller). Returns the index of the first singular
    sample, or -1.
    """
    return _ne_range(0, p.shape[1], p, a, w, wd, R, mass, inertia, gravity, pts, axes, U3, sub, cut_sign,
                     row_joint, row_dir, col_joint, col_kind, col_dir, col_owner, n_free, el_body, el_joint,
                     el_sign, el_count, el_EI, el_GJ, compliance, W, X)


@njit(cache=True)
def _ne_range(s0, s1, p, a, w, wd, R, mass, inertia, gravity, pts, axes, U3,
              sub, cut_sign, row_joint, row_dir, col_joint, col_kind, col_dir, col_owner, n_free,
              el_body, el_joint, el_sign, el_count, el_EI, el_GJ, compliance, W, X):  # pragma: no cover
    """Samples ``s0 <= s < s1`` of :func:`ne_kernel`.

    Per sample: body loads ``D_b`` (dynamics module docstring), tree sums, the ``n_free``
    free-direction equations in the in-plane cut components, their solution, and with
    ``compliance`` the 9 x 9 compatibility system in the out-of-plane redundants (only the
    components ``F_z, M_x, M_y`` of a planar link's internal wrench carry them, and Eq. 64
    couples those only among themselves). Returns the index of the first singular sample or -1.
    """
    nb = p.shape[0]
    nj = pts.shape[1]
    ncut = cut_sign.shape[1]
    ncol = col_joint.shape[0]
    nred = ncol - n_free
    D = np.zeros((nb, 6))
    P = np.zeros((nj, 6))
    cols = np.zeros((ncol, 6))
    M = np.zeros((n_free, n_free))
    r = np.zeros(n_free)
    cw = np.zeros((ncut, 6))
    tmp = np.zeros(3)
    tmp2 = np.zeros(3)
    Iw = np.zeros(3)
    Iwd = np.zeros(3)
    ne = el_body.shape[0]
    K = np.zeros((nred, nred))
    fk = np.zeros(nred)
    s_node = np.zeros(8)
    L0 = np.zeros((8, 3))
    Lx = np.zeros((8, 3, nred))
    order = np.zeros(8, np.int64)
    Fq = np.zeros((3, nred))
    act = np.zeros(nred, np.int64)
    for s in range(s0, s1):
        # body loads D_b = (m (a - g), I wd + w x I w + c x m (a - g)), I = R I' R^T (Eq. 52)
        for b in range(nb):
            # I w and I wd through the body frame: R (I' (R^T w))
            for v in range(2):
                for i in range(3):
                    acc = 0.0
                    for k in range(3):
                        acc += R[b, s, k, i] * (w[b, s, k] if v == 0 else wd[b, s, k])
                    tmp[i] = acc
                for i in range(3):
                    acc = 0.0
                    for k in range(3):
                        acc += inertia[b, i, k] * tmp[k]
                    tmp2[i] = acc
                for i in range(3):
                    acc = 0.0
                    for k in range(3):
                        acc += R[b, s, i, k] * tmp2[k]
                    if v == 0:
                        Iw[i] = acc
                    else:
                        Iwd[i] = acc
            f0 = mass[b] * (a[b, s, 0] - gravity[0])
            f1 = mass[b] * (a[b, s, 1] - gravity[1])
            f2 = mass[b] * (a[b, s, 2] - gravity[2])
            c0, c1, c2 = p[b, s, 0], p[b, s, 1], p[b, s, 2]
            w0, w1, w2 = w[b, s, 0], w[b, s, 1], w[b, s, 2]
            D[b, 0], D[b, 1], D[b, 2] = f0, f1, f2
            D[b, 3] = Iwd[0] + w1 * Iw[2] - w2 * Iw[1] + c1 * f2 - c2 * f1
            D[b, 4] = Iwd[1] + w2 * Iw[0] - w0 * Iw[2] + c2 * f0 - c0 * f2
            D[b, 5] = Iwd[2] + w0 * Iw[1] - w1 * Iw[0] + c0 * f1 - c1 * f0
        # tree sums
        for j in range(nj):
            for k in range(6):
                P[j, k] = 0.0
            for b in range(nb):
                if sub[j, b] != 0.0:
                    for k in range(6):
                        P[j, k] += D[b, k]
        # unit wrenches of the cut components
        for c in range(ncol):
            j = col_joint[c]
            for k in range(6):
                cols[c, k] = 0.0
            d = col_dir[c]
            if col_kind[c] == 0:
                cols[c, d] = 1.0
                q0, q1, q2 = pts[s, j, 0], pts[s, j, 1], pts[s, j, 2]
                if d == 0:
                    cols[c, 4], cols[c, 5] = q2, -q1
                elif d == 1:
                    cols[c, 3], cols[c, 5] = -q2, q0
                else:
                    cols[c, 3], cols[c, 4] = q1, -q0
            elif col_kind[c] == 1:
                cols[c, 3 + d] = 1.0
            else:
                cols[c, 3], cols[c, 4], cols[c, 5] = U3[s, d, 0], U3[s, d, 1], U3[s, d, 2]
        # free-direction equations: twist (e, p x e) . tree wrench = 0
        for i in range(n_free):
            j = row_joint[i]
            if row_dir[i] < 0:
                e0, e1, e2 = axes[s, j, 0], axes[s, j, 1], axes[s, j, 2]
            else:
                e0 = 1.0 if row_dir[i] == 0 else 0.0
                e1 = 1.0 if row_dir[i] == 1 else 0.0
                e2 = 1.0 if row_dir[i] == 2 else 0.0
            q0, q1, q2 = pts[s, j, 0], pts[s, j, 1], pts[s, j, 2]
            v0, v1, v2 = q1 * e2 - q2 * e1, q2 * e0 - q0 * e2, q0 * e1 - q1 * e0
            r[i] = -(e0 * P[j, 3] + e1 * P[j, 4] + e2 * P[j, 5] + v0 * P[j, 0] + v1 * P[j, 1] + v2 * P[j, 2])
            for c in range(n_free):
                sg = cut_sign[j, col_owner[c]]
                M[i, c] = 0.0 if sg == 0.0 else sg * (
                    e0 * cols[c, 3] + e1 * cols[c, 4] + e2 * cols[c, 5]
                    + v0 * cols[c, 0] + v1 * cols[c, 1] + v2 * cols[c, 2])
        if not _solve_inplace(M, r):
            return s
        for c in range(ncut):
            for k in range(6):
                cw[c, k] = 0.0
        for c in range(n_free):
            for k in range(6):
                cw[col_owner[c], k] += r[c] * cols[c, k]
        for j in range(nj):
            for k in range(6):
                acc = P[j, k]
                for c in range(ncut):
                    acc += cut_sign[j, c] * cw[c, k]
                W[s, j, k] = acc
        if not compliance:
            continue
        # compatibility: minimise the complementary energy over the redundants (Eq. 63-83)
        for i in range(nred):
            fk[i] = 0.0
            for j in range(nred):
                K[i, j] = 0.0
        for e in range(ne):
            b = el_body[e]
            x0, x1 = R[b, s, 0, 0], R[b, s, 1, 0]  # planar link: x axis in the plane, z = base z
            y0, y1 = -x1, x0
            cnt = el_count[e]
            for i in range(cnt + 1):
                for k in range(3):
                    L0[i, k] = 0.0
                    for q in range(nred):
                        Lx[i, k, q] = 0.0
            for i in range(cnt):
                j = el_joint[e, i]
                sg = el_sign[e, i]
                sp = (pts[s, j, 0] - p[b, s, 0]) * x0 + (pts[s, j, 1] - p[b, s, 1]) * x1
                s_node[i] = sp
                n0 = p[b, s, 0] + sp * x0
                n1 = p[b, s, 1] + sp * x1
                n2 = p[b, s, 2]
                # zero-redundant load, out of plane: Fz, Mx, My in the link frame, about the node
                fx, fy, fz = sg * W[s, j, 0], sg * W[s, j, 1], sg * W[s, j, 2]
                mx = sg * W[s, j, 3] - (n1 * fz - n2 * fy)
                my = sg * W[s, j, 4] - (n2 * fx - n0 * fz)
                L0[i, 0] = fz
                L0[i, 1] = mx * x0 + my * x1
                L0[i, 2] = mx * y0 + my * y1
                for q in range(nred):
                    c = n_free + q
                    g = sg * cut_sign[j, col_owner[c]]
                    if g != 0.0:
                        fx, fy, fz = g * cols[c, 0], g * cols[c, 1], g * cols[c, 2]
                        mx = g * cols[c, 3] - (n1 * fz - n2 * fy)
                        my = g * cols[c, 4] - (n2 * fx - n0 * fz)
                        Lx[i, 0, q] = fz
                        Lx[i, 1, q] = mx * x0 + my * x1
                        Lx[i, 2, q] = mx * y0 + my * y1
            # centre of mass node: -D_b
            s_node[cnt] = 0.0
            fz = -D[b, 2]
            mx = -D[b, 3] + (p[b, s, 1] * D[b, 2] - p[b, s, 2] * D[b, 1])
            my = -D[b, 4] + (p[b, s, 2] * D[b, 0] - p[b, s, 0] * D[b, 2])
            L0[cnt, 0] = fz
            L0[cnt, 1] = mx * x0 + my * x1
            L0[cnt, 2] = mx * y0 + my * y1
            # sort the nodes along the link (insertion sort, stable)
            nn = cnt + 1
            for i in range(nn):
                order[i] = i
            for i in range(1, nn):
                t = order[i]
                k = i - 1
                while k >= 0 and s_node[order[k]] > s_node[t]:
                    order[k + 1] = order[k]
                    k -= 1
                order[k + 1] = t
            EI, GJ = el_EI[e], el_GJ[e]
            na = 0  # the redundants that load this link at all
            for q in range(nred):
                used = False
                for i in range(cnt):
                    if Lx[i, 0, q] != 0.0 or Lx[i, 1, q] != 0.0 or Lx[i, 2, q] != 0.0:
                        used = True
                if used:
                    act[na] = q
                    na += 1
            # segments from the tip: suffix sums of the loads, reduced to each segment's far end
            for seg in range(nn - 2, -1, -1):
                tip = s_node[order[seg + 1]]
                ln = tip - s_node[order[seg]]
                if ln <= 0.0:
                    continue
                c11 = ln**3 / (3.0 * EI)
                c13 = -(ln**2) / (2.0 * EI)
                c22 = ln / GJ
                c33 = ln / EI
                F0z = 0.0
                F0x = 0.0
                F0y = 0.0
                for i2 in range(seg + 1, nn):
                    nd = order[i2]
                    d = s_node[nd] - tip
                    F0z += L0[nd, 0]
                    F0x += L0[nd, 1]
                    F0y += L0[nd, 2] - d * L0[nd, 0]
                for qa in range(na):
                    q = act[qa]
                    Fq[0, q] = 0.0
                    Fq[1, q] = 0.0
                    Fq[2, q] = 0.0
                    for i2 in range(seg + 1, nn):
                        nd = order[i2]
                        d = s_node[nd] - tip
                        Fq[0, q] += Lx[nd, 0, q]
                        Fq[1, q] += Lx[nd, 1, q]
                        Fq[2, q] += Lx[nd, 2, q] - d * Lx[nd, 0, q]
                for qa in range(na):
                    q = act[qa]
                    Fz, Fx, Fy = Fq[0, q], Fq[1, q], Fq[2, q]
                    Cz = c11 * Fz + c13 * Fy
                    Cx = c22 * Fx
                    Cy = c13 * Fz + c33 * Fy
                    fk[q] += Cz * F0z + Cx * F0x + Cy * F0y
                    for qb in range(na):
                        q2 = act[qb]
                        K[q, q2] += Cz * Fq[0, q2] + Cx * Fq[1, q2] + Cy * Fq[2, q2]
        for q in range(nred):
            fk[q] = -fk[q]
        if not _solve_inplace(K, fk):
            return s
        for q in range(nred):
            X[s, q] = fk[q]
            c = n_free + q
            for j in range(nj):
                g = cut_sign[j, col_owner[c]]
                if g != 0.0:
                    for k in range(6):
                        W[s, j, k] += g * fk[q] * cols[c, k]
    return -1
