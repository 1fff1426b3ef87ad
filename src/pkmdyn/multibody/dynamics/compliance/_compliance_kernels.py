"""Compiled complementary energy of the elastic bodies, written in the cut joints' unknowns.

One pass per sample of the beam model of :mod:`pkmdyn.multibody.dynamics.compliance.reactions` (module docstring there; Eq. 63-64
of the PDM paper, generalised): for every elastic body its nodes (the joints' centres and the
centre of mass) projected on its beam axis, the loads at the nodes as affine functions of the
cut joints' unknowns ``lam`` (``z = z0 + Z lam``), the resultant beyond each segment and the
segment's cantilever flexibility, summed into ``H = sum_s G_s^T C_s G_s`` and
``h = sum_s G_s^T C_s w0_s`` (``K x K`` and ``K``), without forming any segment's wrench over
all the joints' columns. Driven by the model's arrays only (nothing here knows a mechanism);
:func:`pkmdyn.multibody.dynamics.compliance.reactions.beam_terms` is the same model in arrays over all samples (tested against
each other). The compatibility equations are homogeneous in the flexibilities, so each
sample's ``H, h`` are divided by that sample's largest flexibility entry (O(1) numbers; the
reactions do not change).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def beam_energy_batch(R, origin, com, W, z0, Z, bodies, mode, ends, start, joints, signs,
                      nodes, EA, EIy, EIz, GIp, H, h):  # pragma: no cover - compiled
    """``H (n, K, K)``, ``h (n, K)`` of every sample (module docstring).

    ``R (n, nb, 3, 3)``, ``origin (n, nb, 3)`` the bodies' frames, ``com (n, nb, 3)`` their
    centres of mass, ``W (n, nb, 6)`` their required wrenches ``[n_O; f]``; ``z0 (n, 6 nj)``,
    ``Z (n, 6 nj, K)``. Per elastic body e (index ``bodies[e]``): ``mode[e]`` 0 for the body's
    x axis through its centre of mass, 1 for the line from node ``ends[e, 0]`` to ``ends[e, 1]``;
    its joints ``joints[start[e]:start[e + 1]]`` with the sign ``signs`` (+1 as the child, -1 as
    the parent) and each one's node ``nodes (n, J, 3)`` (base frame, entry ``start[e] + m``);
    its section ``EA, EIy, EIz, GIp``."""
    n, K = Z.shape[0], Z.shape[2]
    nE = bodies.shape[0]
    maxN = 0
    for e in range(nE):
        maxN = max(maxN, start[e + 1] - start[e] + 1)
    pts = np.empty((maxN, 3))
    s = np.empty(maxN)
    order = np.empty(maxN, dtype=np.int64)
    LF = np.empty((maxN, 6, K))   # node loads' parts along lam, beam frame: [f; moment about the node]
    L0 = np.empty((maxN, 6))      # their constant parts
    Gk = np.empty((6, K))
    g0 = np.empty(6)
    CG = np.empty((6, K))
    Cw = np.empty(6)
    Rb = np.empty((3, 3))
    B = np.empty((6, 6))
    C = np.zeros((6, 6))
    for t in range(n):
        for a in range(K):
            h[t, a] = 0.0
            for c in range(K):
                H[t, a, c] = 0.0
        cmax = 0.0
        for e in range(nE):
            b = bodies[e]
            nj = start[e + 1] - start[e]
            N = nj + 1
            for m in range(nj):
                q = start[e] + m
                for i in range(3):
                    pts[m, i] = nodes[t, q, i]
            for i in range(3):
                pts[nj, i] = com[t, b, i]
            # the beam frame Rb (columns x, y, z) and its origin o
            if mode[e] == 0:
                for i in range(3):
                    for k in range(3):
                        Rb[i, k] = R[t, b, i, k]
                o0, o1, o2 = com[t, b, 0], com[t, b, 1], com[t, b, 2]
            else:
                i0, i1 = ends[e, 0], ends[e, 1]
                x0, x1, x2 = pts[i1, 0] - pts[i0, 0], pts[i1, 1] - pts[i0, 1], pts[i1, 2] - pts[i0, 2]
                nx = np.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
                x0, x1, x2 = x0 / nx, x1 / nx, x2 / nx
                a0, a1, a2 = abs(x0), abs(x1), abs(x2)
                pick = 0 if (a0 <= a1 and a0 <= a2) else (1 if a1 <= a2 else 2)  # the first smallest
                hx, hy, hz = (1.0 if pick == 0 else 0.0), (1.0 if pick == 1 else 0.0), (1.0 if pick == 2 else 0.0)
                y0, y1, y2 = x1 * hz - x2 * hy, x2 * hx - x0 * hz, x0 * hy - x1 * hx
                ny = np.sqrt(y0 * y0 + y1 * y1 + y2 * y2)
                y0, y1, y2 = y0 / ny, y1 / ny, y2 / ny
                Rb[0, 0], Rb[1, 0], Rb[2, 0] = x0, x1, x2
                Rb[0, 1], Rb[1, 1], Rb[2, 1] = y0, y1, y2
                Rb[0, 2], Rb[1, 2], Rb[2, 2] = x1 * y2 - x2 * y1, x2 * y0 - x0 * y2, x0 * y1 - x1 * y0
                o0, o1, o2 = pts[i0, 0], pts[i0, 1], pts[i0, 2]
            for m in range(N):
                s[m] = (pts[m, 0] - o0) * Rb[0, 0] + (pts[m, 1] - o1) * Rb[1, 0] + (pts[m, 2] - o2) * Rb[2, 0]
            # each node's load: the joint's wrench sg W_j about O -> [f; moment about the node on
            # the axis], beam frame: B (6 x 6) maps [n_O; f] to it
            for m in range(N):
                ax0, ax1, ax2 = o0 + s[m] * Rb[0, 0], o1 + s[m] * Rb[1, 0], o2 + s[m] * Rb[2, 0]
                if m < nj:
                    sg = signs[start[e] + m]
                    j = joints[start[e] + m]
                else:  # the centre of mass: -W_b
                    sg = -1.0
                    j = -1
                for r in range(3):
                    c0, c1, c2 = Rb[0, r], Rb[1, r], Rb[2, r]
                    # force rows: f' = Rb^T f
                    B[r, 0], B[r, 1], B[r, 2] = 0.0, 0.0, 0.0
                    B[r, 3], B[r, 4], B[r, 5] = sg * c0, sg * c1, sg * c2
                    # moment rows: m' = Rb^T (n_O - x f), with (x f) = skew(x) f
                    B[3 + r, 0], B[3 + r, 1], B[3 + r, 2] = sg * c0, sg * c1, sg * c2
                    B[3 + r, 3] = -sg * (c1 * ax2 - c2 * ax1)
                    B[3 + r, 4] = -sg * (c2 * ax0 - c0 * ax2)
                    B[3 + r, 5] = -sg * (c0 * ax1 - c1 * ax0)
                if j >= 0:
                    for r in range(6):
                        acc = 0.0
                        for c in range(6):
                            acc += B[r, c] * z0[t, 6 * j + c]
                        L0[m, r] = acc
                        for a in range(K):
                            acc = 0.0
                            for c in range(6):
                                acc += B[r, c] * Z[t, 6 * j + c, a]
                            LF[m, r, a] = acc
                else:
                    for r in range(6):
                        acc = 0.0
                        for c in range(6):
                            acc += B[r, c] * W[t, b, c]
                        L0[m, r] = acc
                        for a in range(K):
                            LF[m, r, a] = 0.0
            # nodes in order along the axis (insertion sort, stable)
            for m in range(N):
                order[m] = m
            for m in range(1, N):
                v = order[m]
                k = m - 1
                while k >= 0 and s[order[k]] > s[v]:
                    order[k + 1] = order[k]
                    k -= 1
                order[k + 1] = v
            # segments from the far end: the resultant of the loads beyond each, at its far end
            for r in range(6):
                g0[r] = 0.0
                for a in range(K):
                    Gk[r, a] = 0.0
            # Gk, g0 hold [sum f; sum (m + s e_x x f)] of the nodes beyond the segment
            for q in range(N - 1, 0, -1):
                m = order[q]
                sm = s[m]
                g0[0] += L0[m, 0]
                g0[1] += L0[m, 1]
                g0[2] += L0[m, 2]
                g0[3] += L0[m, 3]
                g0[4] += L0[m, 4] - sm * L0[m, 2]
                g0[5] += L0[m, 5] + sm * L0[m, 1]
                for a in range(K):
                    Gk[0, a] += LF[m, 0, a]
                    Gk[1, a] += LF[m, 1, a]
                    Gk[2, a] += LF[m, 2, a]
                    Gk[3, a] += LF[m, 3, a]
                    Gk[4, a] += LF[m, 4, a] - sm * LF[m, 2, a]
                    Gk[5, a] += LF[m, 5, a] + sm * LF[m, 1, a]
                tip = s[order[q]]
                l = tip - s[order[q - 1]]
                # the segment's wrench at its far end: moment about the tip
                w0, w1, w2, w3 = g0[0], g0[1], g0[2], g0[3]
                w4 = g0[4] + tip * g0[2]
                w5 = g0[5] - tip * g0[1]
                # flexibility, Eq. 64
                C[0, 0] = l / EA[e]
                C[1, 1] = l ** 3 / (3.0 * EIz[e])
                C[1, 5] = C[5, 1] = l ** 2 / (2.0 * EIz[e])
                C[2, 2] = l ** 3 / (3.0 * EIy[e])
                C[2, 4] = C[4, 2] = -(l ** 2) / (2.0 * EIy[e])
                C[3, 3] = l / GIp[e]
                C[4, 4] = l / EIy[e]
                C[5, 5] = l / EIz[e]
                for r in range(6):
                    for c in range(6):
                        cmax = max(cmax, abs(C[r, c]))
                for a in range(K):
                    v0, v1, v2, v3 = Gk[0, a], Gk[1, a], Gk[2, a], Gk[3, a]
                    v4 = Gk[4, a] + tip * Gk[2, a]
                    v5 = Gk[5, a] - tip * Gk[1, a]
                    CG[0, a] = C[0, 0] * v0
                    CG[1, a] = C[1, 1] * v1 + C[1, 5] * v5
                    CG[2, a] = C[2, 2] * v2 + C[2, 4] * v4
                    CG[3, a] = C[3, 3] * v3
                    CG[4, a] = C[4, 2] * v2 + C[4, 4] * v4
                    CG[5, a] = C[5, 1] * v1 + C[5, 5] * v5
                Cw[0] = C[0, 0] * w0
                Cw[1] = C[1, 1] * w1 + C[1, 5] * w5
                Cw[2] = C[2, 2] * w2 + C[2, 4] * w4
                Cw[3] = C[3, 3] * w3
                Cw[4] = C[4, 2] * w2 + C[4, 4] * w4
                Cw[5] = C[5, 1] * w1 + C[5, 5] * w5
                for a in range(K):
                    v0, v1, v2, v3 = Gk[0, a], Gk[1, a], Gk[2, a], Gk[3, a]
                    v4 = Gk[4, a] + tip * Gk[2, a]
                    v5 = Gk[5, a] - tip * Gk[1, a]
                    h[t, a] += v0 * Cw[0] + v1 * Cw[1] + v2 * Cw[2] + v3 * Cw[3] + v4 * Cw[4] + v5 * Cw[5]
                    for c in range(a, K):
                        H[t, a, c] += (v0 * CG[0, c] + v1 * CG[1, c] + v2 * CG[2, c] + v3 * CG[3, c]
                                       + v4 * CG[4, c] + v5 * CG[5, c])
        scale = 1.0 / cmax if cmax > 0.0 else 1.0
        for a in range(K):
            h[t, a] *= scale
            for c in range(a, K):
                H[t, a, c] *= scale
                H[t, c, a] = H[t, a, c]
