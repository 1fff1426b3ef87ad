"""Compiled kernels of the joint reactions' cut-wrench route (:class:`pkmdyn.multibody.dynamics.newton_euler._CutRoute`),
driven by the model's arrays and the cut-joint table of :func:`pkmdyn.multibody.dynamics.newton_euler.cut_table`.

Per sample and cut joint ``i`` (joint ``cut_j[i]`` with ``cut_f[i]`` freedoms): its free twists
``T_i (f, 6)`` (the joint type's elementary motions at its frames: rotation axes through the
child frame's origin, the last motion about the child frame's axis, the others about the
parent frame's; all the parent's for a spherical joint) and a basis ``C_i (6, 6 - f)`` of the
wrenches that do no work in them (``T_i C_i = 0``): three forces through the centre for a
spherical joint, ``I`` for a fixed one, else the orthogonal complement of the rows of ``T_i``
by Householder reflections (Golub & Van Loan 2013, Sec. 5.2.1). The tree's equations in the
cut joints' multipliers (one row per tree coordinate; the idle freedoms' holding forces as the
last columns) are solved by the normal equations (Cholesky), and every joint wrench follows,
the cut joints' from their multipliers and friction, the tree joints' leaves first.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .. import _cache
from ..kinematics import _solve_kernels as _kernels
from ..model import _tree_kernels
from ..model._tree_kernels import _cross, _frame


@njit(cache=True, _nrt=False)
def _complement(T, f, C, v, M):  # pragma: no cover - compiled
    """``C[:, :6 - f]``: an orthonormal basis of the wrenches orthogonal to the rows ``T[:f]``
    (6-vectors), by Householder QR of ``T[:f]^T`` (``v (3, 6)``, ``M (6, 3)`` work space: the
    reflectors, the matrix)."""
    for a in range(6):
        for k in range(f):
            M[a, k] = T[k, a]
    for k in range(f):
        nrm = 0.0
        for a in range(k, 6):
            nrm += M[a, k] * M[a, k]
        nrm = math.sqrt(nrm)
        for a in range(6):
            v[k, a] = 0.0
        if nrm == 0.0:
            continue
        alpha = -nrm if M[k, k] >= 0.0 else nrm
        for a in range(k, 6):
            v[k, a] = M[a, k]
        v[k, k] -= alpha
        vn = 0.0
        for a in range(k, 6):
            vn += v[k, a] * v[k, a]
        vn = math.sqrt(vn)
        for a in range(k, 6):
            v[k, a] /= vn
        for c in range(k + 1, f):
            d = 0.0
            for a in range(k, 6):
                d += v[k, a] * M[a, c]
            for a in range(k, 6):
                M[a, c] -= 2.0 * d * v[k, a]
    for c in range(f, 6):  # Q e_c = H_0 H_1 ... H_{f-1} e_c
        col = C[:, c - f]
        for a in range(6):
            col[a] = 0.0
        col[c] = 1.0
        for k in range(f - 1, -1, -1):
            d = 0.0
            for a in range(6):
                d += v[k, a] * col[a]
            for a in range(6):
                col[a] -= 2.0 * d * v[k, a]


@njit(cache=True, _nrt=False)
def cut_bases(Rs, os, cut_j, cut_f, joint_type, joint_child, joint_parent, jRc, jpc, jRp, jpp, type_motion,
              spherical, T, C, RP, oP, RC, oC, v, Mw):  # pragma: no cover - compiled
    """One sample: every cut joint's free twists ``T (nc, 3, 6)`` and constraint-wrench basis
    ``C (nc, 6, 6)`` (its first ``6 - f`` columns) from the bodies' poses ``Rs (nb, 3, 3)``,
    ``os (nb, 3)`` (module docstring; ``RP, RC (3, 3)``, ``oP, oC (3,)``, ``v (3, 6)``, ``Mw
    (6, 3)`` work space)."""
    for i in range(cut_j.shape[0]):
        j = cut_j[i]
        f = cut_f[i]
        ty = joint_type[j]
        _frame(joint_parent[j], Rs, os, jRp[j], jpp[j], RP, oP)
        _frame(joint_child[j], Rs, os, jRc[j], jpc[j], RC, oC)
        for k in range(f):
            mc = type_motion[ty, k]
            ax = mc % 3
            child = k == f - 1 and ty != spherical
            for a in range(3):
                e = RC[a, ax] if child else RP[a, ax]
                if mc < 3:
                    T[i, k, a] = e
                    T[i, k, 3 + a] = 0.0
                else:
                    T[i, k, a] = 0.0
                    T[i, k, 3 + a] = e
            if mc < 3:  # v_O of a rotation about the axis through oC: oC x axis
                _cross(oC, T[i, k, :3], T[i, k, 3:])
        Ci = C[i]
        if ty == spherical:  # three forces through the centre: C = [[o]x; 1]
            for a in range(6):
                for b in range(3):
                    Ci[a, b] = 0.0
            Ci[0, 1], Ci[0, 2] = -oC[2], oC[1]
            Ci[1, 0], Ci[1, 2] = oC[2], -oC[0]
            Ci[2, 0], Ci[2, 1] = -oC[1], oC[0]
            Ci[3, 0] = Ci[4, 1] = Ci[5, 2] = 1.0
        elif f == 0:
            for a in range(6):
                for b in range(6):
                    Ci[a, b] = 1.0 if a == b else 0.0
        else:
            _complement(T[i], f, Ci, v, Mw)


@njit(cache=True, _nrt=False, inline="always")
def _columns_t(S, C, cut_f, cut_pos, cut_sign, H, At):  # pragma: no cover - compiled
    """``At (K, nq)``: the transposed tree equations' matrix of one sample, each cut joint's
    block ``sign (S C_i)^T`` on the coordinates that move its child and not its parent (+1) or
    the reverse (-1), then the idle freedoms' holding directions ``H^T``."""
    nq = S.shape[0]
    for i in range(cut_f.shape[0]):
        m = 6 - cut_f[i]
        col = cut_pos[i]
        for c in range(m):
            for r in range(nq):
                sg = cut_sign[i, r]
                if sg == 0.0:
                    At[col + c, r] = 0.0
                    continue
                acc = 0.0
                for a in range(6):
                    acc += S[r, a] * C[i, a, c]
                At[col + c, r] = sg * acc
    n_cut = At.shape[0] - H.shape[1]
    for k in range(H.shape[1]):
        for r in range(nq):
            At[n_cut + k, r] = H[r, k]


@njit(cache=True, _nrt=False, fastmath={"reassoc", "contract"})
def normal_solve(a, r, M, x):  # pragma: no cover - compiled
    """Least squares ``x (K,)`` of ``A x = r`` by the normal equations: ``a (K, m)`` the
    transposed matrix, ``r (m,)``; ``A^T A`` factored by Cholesky in ``M (K, K)`` (work space).
    False where ``A^T A`` is not safely positive definite: a column whose part outside the span
    of the columns before it is below 3e-7 of its length (dependent; ``x`` is then left unsolved)."""
    K, m = a.shape[0], a.shape[1]
    for i in range(K):
        for j in range(i + 1):
            acc = 0.0
            for q in range(m):
                acc += a[i, q] * a[j, q]
            M[i, j] = acc
        acc = 0.0
        for q in range(m):
            acc += a[i, q] * r[q]
        x[i] = acc
    for j in range(K):
        d = M[j, j]
        for k in range(j):
            d -= M[j, k] * M[j, k]
        if not d > 1e-13 * M[j, j]:  # column j (nearly) in the span of the ones before it
            return False
        d = math.sqrt(d)
        M[j, j] = d
        for i in range(j + 1, K):
            v = M[i, j]
            for k in range(j):
                v -= M[i, k] * M[j, k]
            M[i, j] = v / d
    for i in range(K):
        v = x[i]
        for k in range(i):
            v -= M[i, k] * x[k]
        x[i] = v / M[i, i]
    for i in range(K - 1, -1, -1):
        v = x[i]
        for k in range(i + 1, K):
            v -= M[k, i] * x[k]
        x[i] = v / M[i, i]
    return True


@njit(cache=True, _nrt=False, inline="always")
def any_nonzero(F, f):  # pragma: no cover - compiled
    """Whether any of ``F[:f]`` is nonzero."""
    for k in range(f):
        if F[k] != 0.0:
            return True
    return False


@njit(cache=True, _nrt=False)
def _friction_wrench(T, f, F, G, out):  # pragma: no cover - compiled
    """``out (6,) = D F``, ``D = T^T (T T^T)^-1``: the wrench along the free twists ``T[:f]``
    whose power in each is the friction ``F[:f]`` (Gauss elimination with partial pivoting;
    ``G (3, 4)`` work space); zero without friction."""
    for k in range(6):
        out[k] = 0.0
    if not any_nonzero(F, f):
        return
    for a in range(f):
        for b in range(f):
            acc = 0.0
            for k in range(6):
                acc += T[a, k] * T[b, k]
            G[a, b] = acc
        G[a, 3] = F[a]
    for k in range(f):
        p = k
        for a in range(k + 1, f):
            if abs(G[a, k]) > abs(G[p, k]):
                p = a
        for b in range(4):
            G[k, b], G[p, b] = G[p, b], G[k, b]
        for a in range(k + 1, f):
            g = G[a, k] / G[k, k]
            for b in range(k, 4):
                G[a, b] -= g * G[k, b]
    for a in range(f - 1, -1, -1):
        acc = G[a, 3]
        for b in range(a + 1, f):
            acc -= G[a, b] * G[b, 3]
        G[a, 3] = acc / G[a, a]
    for k in range(6):
        acc = 0.0
        for a in range(f):
            acc += T[a, k] * G[a, 3]
        out[k] = acc


@njit(cache=True)
def cut_reactions_batch(motion, loads, cuts, joints, out, setup, bases):  # pragma: no cover - compiled
    """Every joint wrench ``z_out (n, nj, 6)`` ``[n_O; f]`` by the cut-wrench route and the
    largest equilibrium residual ``res_out (n,)`` (bodies' balances and joints' power rows).

    The arguments come in groups: ``motion`` ``(R, origin, S)``, ``loads`` ``(W, rhs, eff, F,
    given, lam)``, ``cuts`` ``(cut_j, cut_f, cut_pos, cut_sign, joint_cut_index, type_motion,
    spherical, H)``, ``joints`` ``(joint_type, joint_child, joint_parent, joint_q0, joint_nq,
    joint_flipped, jRc, jpc, jRp, jpp, body_parent, body_joint)``, ``out`` ``(z_out, res_out,
    ok_out)`` and, with ``setup``, ``bases`` ``(T_out, C_out, A_out)``; the names below.

    ``W (n, nb, 6)`` the required body wrenches; ``rhs (n, nq)`` the tree equations' right side
    ``Q + Q_f - E_a u``; ``eff (n, nq)`` the effort along each tree coordinate; ``F (n, nj, 3)``
    each joint's friction along its free twists (zero where none). ``lam (n, K)``: the cut
    joints' multipliers then the idle freedoms' holding forces, solved here (normal equations)
    or, where ``given[s]``, taken as they are. ``ok_out[s]`` false where the columns are
    dependent at sample s (nothing else written for it).

    ``setup``: instead, only every sample's cut-joint free twists ``T_out (n, nc, 3, 6)``,
    wrench bases ``C_out (n, nc, 6, 6)`` (:func:`cut_bases`) and the tree equations' matrix
    ``A_out (n, nq, K)`` (the other arguments unread: one kernel to compile for both uses)."""
    R, origin, S = motion
    W, rhs, eff, F, given, lam = loads
    cut_j, cut_f, cut_pos, cut_sign, joint_cut_index, type_motion, spherical, H = cuts
    (joint_type, joint_child, joint_parent, joint_q0, joint_nq, joint_flipped, jRc, jpc, jRp, jpp, body_parent,
     body_joint) = joints
    z_out, res_out, ok_out = out
    T_out, C_out, A_out = bases
    n, nq = S.shape[0], S.shape[1]
    nc, nj, nb = cut_j.shape[0], joint_type.shape[0], W.shape[1]
    K = A_out.shape[2] if setup else lam.shape[1]
    n_cut = K - H.shape[1]
    T = np.empty((nc, 3, 6))
    C = np.empty((nc, 6, 6))
    RP, RC = np.empty((3, 3)), np.empty((3, 3))
    oP, oC = np.empty(3), np.empty(3)
    v, Mw, G = np.empty((3, 6)), np.empty((6, 3)), np.empty((3, 4))
    At = np.empty((K, nq))
    M = np.empty((K, K))
    onbody = np.empty((nb, 6))
    DF = np.empty(6)
    for s in range(n):
        if setup:
            cut_bases(R[s], origin[s], cut_j, cut_f, joint_type, joint_child, joint_parent, jRc, jpc, jRp, jpp,
                      type_motion, spherical, T_out[s], C_out[s], RP, oP, RC, oC, v, Mw)
            _columns_t(S[s], C_out[s], cut_f, cut_pos, cut_sign, H, At)
            for r in range(nq):
                for c in range(K):
                    A_out[s, r, c] = At[c, r]
            continue
        cut_bases(R[s], origin[s], cut_j, cut_f, joint_type, joint_child, joint_parent, jRc, jpc, jRp, jpp,
                  type_motion, spherical, T, C, RP, oP, RC, oC, v, Mw)
        if not given[s] and K:
            _columns_t(S[s], C, cut_f, cut_pos, cut_sign, H, At)
            if not normal_solve(At, rhs[s], M, lam[s]):
                ok_out[s] = False
                continue
        ok_out[s] = True
        z = z_out[s]
        for b in range(nb):
            for a in range(6):
                onbody[b, a] = W[s, b, a]
        for i in range(nc):  # cut wrenches C lam - D F, taken off their bodies' required wrenches
            j = cut_j[i]
            m = 6 - cut_f[i]
            _friction_wrench(T[i], cut_f[i], F[s, j], G, DF)
            for a in range(6):
                acc = -DF[a]
                for c in range(m):
                    acc += C[i, a, c] * lam[s, cut_pos[i] + c]
                z[j, a] = acc
                if joint_child[j] >= 0:
                    onbody[joint_child[j], a] -= acc
                if joint_parent[j] >= 0:
                    onbody[joint_parent[j], a] += acc
        for b in range(nb - 1, -1, -1):  # tree joints, leaves first
            par = body_parent[b]
            k = body_joint[b]
            sg = -1.0 if joint_flipped[k] else 1.0
            for a in range(6):
                if par >= 0:
                    onbody[par, a] += onbody[b, a]
                z[k, a] = sg * onbody[b, a]
        # residual: every body's balance, then every free twist's power row
        for b in range(nb):
            for a in range(6):
                onbody[b, a] = -W[s, b, a]
        for j in range(nj):
            for a in range(6):
                if joint_child[j] >= 0:
                    onbody[joint_child[j], a] += z[j, a]
                if joint_parent[j] >= 0:
                    onbody[joint_parent[j], a] -= z[j, a]
        worst = 0.0
        for b in range(nb):
            for a in range(6):
                worst = max(worst, abs(onbody[b, a]))
        for j in range(nj):
            ci = joint_cut_index[j]
            f = cut_f[ci] if ci >= 0 else joint_nq[j]
            sg = -1.0 if joint_flipped[j] else 1.0
            for k in range(f):
                acc = F[s, j, k]  # T . W - (e - F)
                if ci >= 0:
                    for a in range(6):
                        acc += T[ci, k, a] * z[j, a]
                else:
                    c = joint_q0[j] + k
                    for a in range(6):
                        acc += sg * S[s, c, a] * z[j, a]
                    acc -= eff[s, c]
                    for h in range(H.shape[1]):
                        acc -= lam[s, n_cut + h] * H[c, h]
                worst = max(worst, abs(acc))
        res_out[s] = worst


def _refresh_cache() -> None:
    """The kernels inline the kinematics kernels' ``_frame`` and ``_cross`` (:mod:`._cache`)."""

    _cache.refresh((cut_bases, cut_reactions_batch), (_kernels, _tree_kernels,))


_refresh_cache()
