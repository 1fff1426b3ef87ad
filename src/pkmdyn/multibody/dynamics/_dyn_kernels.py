"""Compiled kernels of the dynamics (once for every mechanism, driven by the model's arrays)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .. import _cache
from ..kinematics import _solve_kernels as _kernels
from ..model import _tree_kernels
from ..model._tree_kernels import _advance, _frame, _matmul3, _nn, _unit_twist, forward_positions


@njit(cache=True)
def twists_batch(q, body_parent, body_joint, joint_q0, joint_nq, coord_motion, coord_offset, coord_sign,
                 RP, pP, RC, pC, S_out):  # pragma: no cover - compiled
    """World unit twists ``S_out (n, nq, 6)`` of every tree coordinate at ``q (n, nq)``."""
    nb = body_parent.shape[0]
    R = np.empty((nb, 3, 3))
    p = np.empty((nb, 3))
    w33 = np.empty((5, 3, 3))
    w3 = np.empty((20, 3))
    trig = np.empty((q.shape[1], 3))
    late = np.full(nb, -1, dtype=np.int64)
    off = nb < 0  # False as a run-time value: forward_positions compiles once (_tree_kernels.jacobians_batch)
    for s in range(q.shape[0]):
        forward_positions(q[s], body_parent, body_joint, joint_q0, joint_nq, coord_motion, coord_offset, coord_sign,
                          RP, pP, RC, pC, R, p, S_out[s], w33, w3, trig, off, late, off)


@njit(cache=True, _nrt=False, inline="always")
def _inertia_in_base(R, inertia, tmp, Iw):  # pragma: no cover - compiled
    """``Iw = R I' R^T``: the inertia ``I' (3, 3)`` of a body frame expressed in the base frame
    (``tmp (3, 3)`` work space)."""
    for i in range(3):
        for j in range(3):
            acc = 0.0
            for k in range(3):
                acc += R[i, k] * inertia[k, j]
            tmp[i, j] = acc
    for i in range(3):
        for j in range(3):
            acc = 0.0
            for k in range(3):
                acc += tmp[i, k] * R[j, k]
            Iw[i, j] = acc


@njit(cache=True, _nrt=False, inline="always")
def body_wrench(R, w, wd, p, a, m, inertia, gravity, W, tmp, Iw):  # pragma: no cover - compiled
    """One body's required wrench ``W (6,)`` ``[n_O; f]`` of Eq. (1) (no loads):
    ``f = m (a - g)``, ``n_O = I_w wd + w x I_w w + p x f`` with ``I_w = R I' R^T`` (``R (3, 3)``,
    ``w, wd, p, a (3,)``; ``tmp, Iw (3, 3)`` work space)."""
    _inertia_in_base(R, inertia, tmp, Iw)
    L0 = Iw[0, 0] * w[0] + Iw[0, 1] * w[1] + Iw[0, 2] * w[2]
    L1 = Iw[1, 0] * w[0] + Iw[1, 1] * w[1] + Iw[1, 2] * w[2]
    L2 = Iw[2, 0] * w[0] + Iw[2, 1] * w[1] + Iw[2, 2] * w[2]
    f0 = m * (a[0] - gravity[0])
    f1 = m * (a[1] - gravity[1])
    f2 = m * (a[2] - gravity[2])
    x0, x1, x2 = p[0], p[1], p[2]
    w0, w1, w2 = w[0], w[1], w[2]
    for i in range(3):
        W[i] = Iw[i, 0] * wd[0] + Iw[i, 1] * wd[1] + Iw[i, 2] * wd[2]
    W[0] += w1 * L2 - w2 * L1 + x1 * f2 - x2 * f1
    W[1] += w2 * L0 - w0 * L2 + x2 * f0 - x0 * f2
    W[2] += w0 * L1 - w1 * L0 + x0 * f1 - x1 * f0
    W[3] = f0
    W[4] = f1
    W[5] = f2


@njit(cache=True, _nrt=False)
def _body_wrench_loop(R, w, wd, p, a, mass, inertia, gravity, W_out, tmp, Iw):  # pragma: no cover - compiled
    for s in range(R.shape[0]):
        for b in range(R.shape[1]):
            body_wrench(R[s, b], w[s, b], wd[s, b], p[s, b], a[s, b], mass[b], inertia[b], gravity, W_out[s, b],
                        tmp, Iw)


@njit(cache=True)
def body_wrench_batch(R, w, wd, p, a, mass, inertia, gravity, W_out):  # pragma: no cover - compiled
    """Required body wrenches ``W_out (n, nb, 6)`` ``[n_O; f]`` of Eq. (1) (no loads), every
    sample and body (:func:`body_wrench`)."""
    _body_wrench_loop(R, w, wd, p, a, mass, inertia, gravity, W_out, np.empty((3, 3)), np.empty((3, 3)))


@njit(cache=True, _nrt=False)
def generalised(S, W, anc_list, Q):  # pragma: no cover - compiled
    """One sample of Eq. (2): ``Q (nq,)``, ``Q_c = S_c . sum of W_b over the bodies c moves``
    (``S (nq, 6)``, ``W (nb, 6)``; ``anc_list`` the model's ``ancestor_list``: per body a count,
    then its coordinates)."""
    for c in range(Q.shape[0]):
        Q[c] = 0.0
    for b in range(W.shape[0]):
        for k in range(_nn(anc_list[b, 0])):
            c = _nn(anc_list[b, 1 + k])
            acc = 0.0
            for i in range(6):
                acc += S[c, i] * W[b, i]
            Q[c] += acc


@njit(cache=True, _nrt=False)
def generalised_batch(S, W, anc_list, Q_out):  # pragma: no cover - compiled
    """``Q_out (n, nq)``, Eq. (2), every sample (:func:`generalised`)."""
    for s in range(W.shape[0]):
        generalised(S[s], W[s], anc_list, Q_out[s])


@njit(cache=True)
def square_efforts_batch(G, Q, JT, scale, had_out, u_out):  # pragma: no cover - compiled
    """Eq. (3) with as many actuators as task coordinates: ``u_out (n, na)`` solving
    ``J_ax^T u = G^T Q`` by LU with partial pivoting, and ``had_out (n,)`` the Hadamard ratio
    ``|det A| / prod |a_k|`` of ``A = J_ax^T / scale`` (rows a_k; 1 orthogonal, 0 singular)."""
    n, nq, nt = G.shape
    na = JT.shape[2]
    A = np.empty((nt, na))
    r = np.empty(nt)
    for s in range(n):
        for t in range(nt):
            acc = 0.0
            for c in range(nq):
                acc += G[s, c, t] * Q[s, c]
            r[t] = acc
        prod = 1.0
        for i in range(nt):
            nrm = 0.0
            for j in range(na):
                A[i, j] = JT[s, i, j] / scale[j]
                nrm += A[i, j] * A[i, j]
            prod *= math.sqrt(nrm)
        det = 1.0
        for k in range(nt):
            piv = k
            best = abs(A[k, k])
            for i in range(k + 1, nt):
                if abs(A[i, k]) > best:
                    best = abs(A[i, k])
                    piv = i
            if piv != k:
                for j in range(na):
                    A[k, j], A[piv, j] = A[piv, j], A[k, j]
                r[k], r[piv] = r[piv], r[k]
                det = -det
            d = A[k, k]
            det *= d
            if d == 0.0:
                break
            for i in range(k + 1, nt):
                f = A[i, k] / d
                for j in range(k, na):
                    A[i, j] -= f * A[k, j]
                r[i] -= f * r[k]
        had_out[s] = abs(det) / prod if prod > 0.0 else 0.0
        if det == 0.0 or not (had_out[s] > 0.0):
            for j in range(na):
                u_out[s, j] = np.nan
            continue
        for k in range(nt - 1, -1, -1):
            acc = r[k]
            for j in range(k + 1, na):
                acc -= A[k, j] * u_out[s, j]
            u_out[s, k] = acc / A[k, k]
        for j in range(na):
            u_out[s, j] /= scale[j]


@njit(cache=True)
def twists_from_poses(q, Rb, ob, body_parent, body_joint, joint_q0, joint_nq, coord_motion, coord_offset,
                      coord_sign, RP, pP, RC, pC, S_out):  # pragma: no cover - compiled
    """World unit twists ``S_out (n, nq, 6)`` from the solved body poses ``Rb (n, nb, 3, 3)``,
    ``ob (n, nb, 3)`` (what :func:`twists_batch` computes from ``q`` alone): a joint's last
    coordinate turns or slides along its child frame's axis, the earlier ones along the parent
    frame's axes turned by the coordinates before them, so only those turns need the angle."""
    _twists_from_poses_loop(q, Rb, ob, body_parent, body_joint, joint_q0, joint_nq, coord_motion, coord_offset,
                            coord_sign, RP, pP, RC, pC, S_out, np.empty((3, 3)), np.empty(3))


@njit(cache=True, _nrt=False)
def _twists_from_poses_loop(q, Rb, ob, body_parent, body_joint, joint_q0, joint_nq, coord_motion, coord_offset,
                            coord_sign, RP, pP, RC, pC, S_out, Rf, o):  # pragma: no cover - compiled
    nb = body_parent.shape[0]
    for s in range(q.shape[0]):
        for b in range(nb):
            k = body_joint[b]
            _frame(body_parent[b], Rb[s], ob[s], RP[k], pP[k], Rf, o)  # the joint frame on the parent, world
            last = joint_q0[k] + joint_nq[k] - 1
            for c in range(joint_q0[k], last + 1):
                m = coord_motion[c]
                sg = coord_sign[c]
                if c == last:
                    # the child frame: Rc = Rb RC, origin oc = ob + Rb pC
                    mm = m % 3
                    a0 = Rb[s, b, 0, 0] * RC[k, 0, mm] + Rb[s, b, 0, 1] * RC[k, 1, mm] + Rb[s, b, 0, 2] * RC[k, 2, mm]
                    a1 = Rb[s, b, 1, 0] * RC[k, 0, mm] + Rb[s, b, 1, 1] * RC[k, 1, mm] + Rb[s, b, 1, 2] * RC[k, 2, mm]
                    a2 = Rb[s, b, 2, 0] * RC[k, 0, mm] + Rb[s, b, 2, 1] * RC[k, 1, mm] + Rb[s, b, 2, 2] * RC[k, 2, mm]
                    c0 = c1 = c2 = 0.0
                    if m < 3:
                        c0 = ob[s, b, 0] + Rb[s, b, 0, 0] * pC[k, 0] + Rb[s, b, 0, 1] * pC[k, 1] + Rb[s, b, 0, 2] * pC[k, 2]
                        c1 = ob[s, b, 1] + Rb[s, b, 1, 0] * pC[k, 0] + Rb[s, b, 1, 1] * pC[k, 1] + Rb[s, b, 1, 2] * pC[k, 2]
                        c2 = ob[s, b, 2] + Rb[s, b, 2, 0] * pC[k, 0] + Rb[s, b, 2, 1] * pC[k, 1] + Rb[s, b, 2, 2] * pC[k, 2]
                    _unit_twist(S_out[s], c, sg, m < 3, a0, a1, a2, c0, c1, c2)
                    continue
                mm = m % 3
                _unit_twist(S_out[s], c, sg, m < 3, Rf[0, mm], Rf[1, mm], Rf[2, mm], o[0], o[1], o[2])
                _advance(Rf, o, m, sg * (q[s, c] - coord_offset[c]))


@njit(cache=True, _nrt=False, fastmath={"reassoc", "contract"})
def _gram(Z, M):  # pragma: no cover - compiled
    """``M = Z Z^T`` (``Z (nt, k)``): sums over the long rows in any order, so that they run
    several lanes at once."""
    nt = Z.shape[0]
    for i in range(nt):
        for j in range(i, nt):
            acc = 0.0
            for k in range(Z.shape[1]):
                acc += Z[i, k] * Z[j, k]
            M[i, j] = acc
            M[j, i] = acc


@njit(cache=True, _nrt=False)
def task_mass(S, G, body_parent, body_joint, joint_q0, joint_nq, R, p, mass, factor, M, T, Z,
              RL):  # pragma: no cover - compiled
    """One sample's ``M (nt, nt) = sum_b T_b^T I_b T_b``: the bodies' kinetic energy in the task
    rates, with ``T_b`` the twist of body b per task rate, built down the tree as ``T_b =
    T_parent + sum_{c of b's joint} S_c G_c`` (Eq. 3.40 of Featherstone 2008 per task rate).
    With ``I' = L L^T`` the body-frame inertia's constant factor, ``m |v_c|^2 + w^T R I' R^T w
    = |Z_b^T xd|^2`` where row t of ``Z_b (nt, 6)`` is the body's ``[sqrt(m) v_c; (R L)^T w]``
    per unit task rate t (``v_c = v_O + w x p`` the centre-of-mass velocity); the bodies' blocks
    side by side make ``Z (nt, 6 nb)`` and ``M = Z Z^T``. ``S (nq, 6)``, ``G (nq, nt)``, ``R
    (nb, 3, 3)``, ``p (nb, 3)`` the centres of mass, ``factor (nb, 3, 3)``
    (:func:`pkmdyn.multibody.dynamics.newton_euler.inertia_factors`); ``T (nb, nt, 6)`` (row t of body b: its twist per unit
    task rate t), ``Z (nt, 6 nb)``, ``RL (3, 3)`` work space."""
    nt = G.shape[1]
    for b in range(R.shape[0]):
        a = body_parent[b]
        k = _nn(body_joint[b])
        sm = math.sqrt(mass[b])
        p0, p1, p2 = p[b, 0], p[b, 1], p[b, 2]
        _matmul3(R[b], factor[b], RL)
        o = 6 * b
        for t in range(nt):
            Tb = T[b, t]
            for r in range(6):
                Tb[r] = T[_nn(a), t, r] if a >= 0 else 0.0
            for c in range(_nn(joint_q0[k]), _nn(joint_q0[k] + joint_nq[k])):
                g = G[c, t]
                for r in range(6):
                    Tb[r] += S[c, r] * g
            w0, w1, w2 = Tb[0], Tb[1], Tb[2]
            Z[t, o] = sm * (Tb[3] + w1 * p2 - w2 * p1)
            Z[t, o + 1] = sm * (Tb[4] + w2 * p0 - w0 * p2)
            Z[t, o + 2] = sm * (Tb[5] + w0 * p1 - w1 * p0)
            for i in range(3):
                Z[t, o + 3 + i] = RL[0, i] * w0 + RL[1, i] * w1 + RL[2, i] * w2
    _gram(Z, M)


@njit(cache=True)
def task_mass_batch(S, G, body_parent, body_joint, joint_q0, joint_nq, R, p, mass, factor,
                    M_out):  # pragma: no cover - compiled
    """``M_out (n, nt, nt)``, every sample (:func:`task_mass`)."""
    nt = G.shape[2]
    _task_mass_loop(S, G, body_parent, body_joint, joint_q0, joint_nq, R, p, mass, factor, M_out,
                    np.empty((R.shape[1], nt, 6)), np.empty((nt, 6 * R.shape[1])), np.empty((3, 3)))


@njit(cache=True, _nrt=False)
def _task_mass_loop(S, G, body_parent, body_joint, joint_q0, joint_nq, R, p, mass, factor, M_out, T, Z,
                    RL):  # pragma: no cover - compiled
    for s in range(G.shape[0]):
        task_mass(S[s], G[s], body_parent, body_joint, joint_q0, joint_nq, R[s], p[s], mass, factor, M_out[s], T, Z,
                  RL)


@njit(cache=True, _nrt=False, inline="always")
def joint_friction(w0, w1, w2, u0, u1, u2, p0, p1, p2, rot, slide, coef, ext, eps_r, eps_t, S, sc, idx, cnt,
                   Q):  # pragma: no cover - compiled
    """Add one joint's friction to ``Q (nq,)``: relative angular velocity ``w``, velocity ``u`` of
    the relative motion at the origin (the relative twist ``[w; u]``), joint point ``p``;
    ``coef = (C_t, b_t, C_f, b_f)``, ``ext`` the named loads' Coulomb part; ``v = u + w x p``,
    ``tau = (C_t + ext) u(w) + b_t w`` (``rot``), ``phi = (C_f [+ ext]) u(v) + b_f v`` (``slide``;
    ``ext`` only without rotation), ``W_f = [tau + p x phi; phi]``, ``Q_c += s_c S_c . W_f`` for
    the coordinates ``idx[:cnt]`` with signs ``sc`` (:func:`friction_batch`)."""
    v0 = u0 + w1 * p2 - w2 * p1
    v1 = u1 + w2 * p0 - w0 * p2
    v2 = u2 + w0 * p1 - w1 * p0
    t0 = t1 = t2 = 0.0
    f0 = f1 = f2 = 0.0
    if rot:
        mag = (coef[0] + ext) / math.sqrt(w0 * w0 + w1 * w1 + w2 * w2 + eps_r * eps_r) + coef[1]
        t0, t1, t2 = mag * w0, mag * w1, mag * w2
    if slide:
        mag = (coef[2] + (0.0 if rot else ext)) / math.sqrt(v0 * v0 + v1 * v1 + v2 * v2 + eps_t * eps_t) + coef[3]
        f0, f1, f2 = mag * v0, mag * v1, mag * v2
    W0 = t0 + p1 * f2 - p2 * f1
    W1 = t1 + p2 * f0 - p0 * f2
    W2 = t2 + p0 * f1 - p1 * f0
    for ic in range(cnt):
        c = idx[ic]
        Q[c] += sc[ic] * (S[c, 0] * W0 + S[c, 1] * W1 + S[c, 2] * W2 + S[c, 3] * f0 + S[c, 4] * f1 + S[c, 5] * f2)


@njit(cache=True, _nrt=False)
def friction_batch(w, ov, org, jpt, S, fsc, fidx, fcnt, fj, fch, fpa, frot, fslide, coef, ext, eps_r, eps_t,
                   Q_out):  # pragma: no cover - compiled
    """Generalised forces ``Q_out (n, nq)`` of the friction that does not depend on the
    reactions (laws F1-F2 of :mod:`pkmdyn.multibody.dynamics.friction` with ``mu = 0``): per joint ``fj[k]`` with
    ``coef[k] = (C_t, b_t, C_f, b_f)`` and the named loads' Coulomb part ``ext[:, k]``
    (:func:`joint_friction`).

    The joint's relative twist ``V_rel = V_child - V_parent`` (child ``fch[k]``, parent
    ``fpa[k]``, -1 the ground at rest) from the bodies' angular velocities ``w`` and the
    velocities ``ov`` of their frame origins ``org`` (``n, nb, 3``; ``v_O = ov - w x org``), at
    the joint point ``jpt``; ``Q_c += s_c S_c . W_f`` with ``s_c`` = 1 for a coordinate that moves
    the child and not the parent, -1 for the reverse (``fidx[k, :fcnt[k]]``, signs ``fsc``): the
    virtual power of the friction. For a tree joint these are its own coordinates and ``Q`` is
    the joint-by-joint route's exactly; for a cut joint the two differ by constraint forces only
    (the same efforts, ``G^T Q``)."""
    for s in range(w.shape[0]):
        for c in range(Q_out.shape[1]):
            Q_out[s, c] = 0.0
        for k in range(fj.shape[0]):
            j = fj[k]
            w0 = w1 = w2 = 0.0
            u0 = u1 = u2 = 0.0
            for b, sg in ((fch[k], 1.0), (fpa[k], -1.0)):
                if b >= 0:
                    a0, a1, a2 = w[s, b, 0], w[s, b, 1], w[s, b, 2]
                    o0, o1, o2 = org[s, b, 0], org[s, b, 1], org[s, b, 2]
                    w0 += sg * a0
                    w1 += sg * a1
                    w2 += sg * a2
                    u0 += sg * (ov[s, b, 0] - (a1 * o2 - a2 * o1))
                    u1 += sg * (ov[s, b, 1] - (a2 * o0 - a0 * o2))
                    u2 += sg * (ov[s, b, 2] - (a0 * o1 - a1 * o0))
            joint_friction(w0, w1, w2, u0, u1, u2, jpt[s, j, 0], jpt[s, j, 1], jpt[s, j, 2], frot[k], fslide[k],
                           coef[k], ext[s, k], eps_r, eps_t, S[s], fsc[k], fidx[k], fcnt[k], Q_out[s])


@njit(cache=True, _nrt=False, inline="always")
def load_wrench(Rb, ob, pt, F0, F1, F2, M, W):  # pragma: no cover - compiled
    """Subtract one external load from a body's required wrench ``W (6,)`` (Eq. 1): force ``F``
    at the body point ``pt`` (body frame; the body at ``Rb``, origin ``ob``) and moment ``M``
    (base frame): ``f -= F``, ``n_O -= M + r x F``."""
    r0 = ob[0] + Rb[0, 0] * pt[0] + Rb[0, 1] * pt[1] + Rb[0, 2] * pt[2]
    r1 = ob[1] + Rb[1, 0] * pt[0] + Rb[1, 1] * pt[1] + Rb[1, 2] * pt[2]
    r2 = ob[2] + Rb[2, 0] * pt[0] + Rb[2, 1] * pt[1] + Rb[2, 2] * pt[2]
    W[0] -= M[0] + r1 * F2 - r2 * F1
    W[1] -= M[1] + r2 * F0 - r0 * F2
    W[2] -= M[2] + r0 * F1 - r1 * F0
    W[3] -= F0
    W[4] -= F1
    W[5] -= F2


@njit(cache=True, _nrt=False)
def apply_loads(R, origin, load_body, load_point, LF, LM, W):  # pragma: no cover - compiled
    """Subtract the external loads from the required wrenches ``W (n, nb, 6)`` (Eq. 1): load k
    acts on body ``load_body[k]`` with force ``LF[s, k]`` at the body point ``load_point[k]``
    (body frame) and moment ``LM[s, k]`` (base frame) (:func:`load_wrench`)."""
    for s in range(W.shape[0]):
        for k in range(load_body.shape[0]):
            b = load_body[k]
            load_wrench(R[s, b], origin[s, b], load_point[k], LF[s, k, 0], LF[s, k, 1], LF[s, k, 2], LM[s, k],
                        W[s, b])


def _refresh_cache() -> None:
    """The twist kernels link or inline the kinematics kernels' ``forward_positions``,
    ``_frame``, ``_unit_twist`` and ``_advance``, the mass matrix kernels ``_matmul3``
    (:mod:`._cache`)."""

    _cache.refresh((twists_batch, twists_from_poses, _twists_from_poses_loop, task_mass_batch, _task_mass_loop),
                   (_kernels, _tree_kernels,))


_refresh_cache()
