"""Compiled kernels of the direct kinematics (:mod:`pkmdyn.multibody.kinematics.direct`), driven by the model's arrays only.

For actuator coordinates ``s (na,)`` the tree coordinates ``q (nq,)`` solve the square system

    Phi_sel(q) = 0            (the independent loop rows the inverse kinematics solves),
    N (q - q_ref) = 0         (the idle freedoms held as the inverse kinematics holds them),
    q_a = s                   (the actuated coordinates),

for the ``nu = nq - na`` coordinates that are not actuated, by Newton on
``K = [Phi_sel,u; N_u]`` (``u``: those columns; ``K`` is square when the mechanism has as
many actuators as degrees of freedom). Then, at the solution, the rates follow from the
derivatives of the same rows:

    K G_u = -[Phi_sel,a; N_a]           (G = dq/ds; G_a = I),      qd = G sd,
    K qdd_u = -[Phi_sel,a; N_a] sdd - [gamma_sel; 0],              qdd_a = sdd,

with ``gamma`` the rows' drift at ``qdd = 0`` (:func:`pkmdyn.multibody.kinematics._solve_kernels.rows`), and the task
coordinates are the task rows' values, ``xd = J_x qd``, ``xdd = J_x qdd + gamma_x``. The
determinant of ``K`` changes sign where the direct kinematics is singular (a type II or
parallel singularity of Gosselin and Angeles 1990): its sign tells the assembly branch along a
motion. Nothing here knows a mechanism; the row and pose kernels are those of the inverse
kinematics (:mod:`pkmdyn.multibody.kinematics._solve_kernels`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .. import _cache
from ..dynamics import _sample_kernels as _one
from ..dynamics._sample_kernels import _f, _f33, _fn3, _fview, _i, _i2, _iview
from ..model import _tree_kernels
from ..model._tree_kernels import (
    LEG_A2,
    LEG_TASK,
    LOOP_OPEN,
    NOT_CONVERGED,
    OK,
    ROWS_DRIFT,
    ROWS_JACOBIAN,
    ROWS_VALUES,
    SINGULAR,
    _dot,
    _inv3,
    _nn,
    _quadratic_nearest,
    _rotate_about,
    euler_matrix,
    euler_rate_map,
    first_joint,
    forward_positions,
    place_fixed_legs,
    rows,
)
from . import _solve_kernels as _kernels
from ._solve_kernels import _wrap, along_h2, bias_motion, jerk_factor, largest_scaled, second_order_applies

__all__ = ["CROSSED", "EULER_SINGULAR_RATES", "COLD", "BAD_INPUT", "direct_batch", "direct_starts", "direct_one",
           "ONE_ARRAYS"]

#: status of a sample where the determinant of ``K`` changed sign since the previous one
CROSSED = 5
#: status of a solved sample whose task Euler angles are at their singularity (no task rates)
EULER_SINGULAR_RATES = 6
#: status of a call of :func:`direct_one` without a previous solution to start from
COLD = 10
#: status of a call of :func:`direct_one` with a non-finite input
BAD_INPUT = 12


@njit(cache=True, _nrt=False)
def _lu(M, piv):  # pragma: no cover - compiled
    """``M = P L U`` in place (partial pivoting, ``piv`` the row swaps); returns the determinant
    and the ratio of the smallest to the largest pivot magnitude (0 for a zero pivot)."""
    n = M.shape[0]
    det = 1.0
    big = 0.0
    small = math.inf
    for k in range(n):
        p = k
        for i in range(k + 1, n):
            if abs(M[i, k]) > abs(M[p, k]):
                p = i
        piv[k] = p
        if p != k:
            for j in range(n):
                tmp = M[k, j]
                M[k, j] = M[p, j]
                M[p, j] = tmp
            det = -det
        d = M[k, k]
        det *= d
        a = abs(d)
        big = max(big, a)
        small = min(small, a)
        if d == 0.0:
            return 0.0, 0.0
        for i in range(k + 1, n):
            f = M[i, k] / d
            M[i, k] = f
            for j in range(k + 1, n):
                M[i, j] -= f * M[k, j]
    if n == 0:
        return 1.0, 1.0
    return det, small / big


@njit(cache=True, _nrt=False)
def _lu_solve(M, piv, b):  # pragma: no cover - compiled
    """``b = M^-1 b`` with the factors of :func:`_lu`."""
    n = b.shape[0]
    for k in range(n):
        p = piv[k]
        if p != k:
            tmp = b[k]
            b[k] = b[p]
            b[p] = tmp
    for i in range(n):
        acc = b[i]
        for j in range(i):
            acc -= M[i, j] * b[j]
        b[i] = acc
    for i in range(n - 1, -1, -1):
        acc = b[i]
        for j in range(i + 1, n):
            acc -= M[i, j] * b[j]
        b[i] = acc / M[i, i]


def direct_sample(s, sd, sdd, q, chord, tree, loops, task, sol, work, info):  # pragma: no cover - compiled
    """One sample (module docstring) from ``q`` (updated in place; its actuated coordinates are
    set to ``s``). With ``chord``, a first simplified Newton step with the factors of ``K`` left
    in ``work`` by the previous sample (the rows' values only: no Jacobian, no factorisation);
    from a close predictor it lands within rounding of the solution, which the next (full)
    evaluation then confirms. ``sol``: ``(act, unk, cut, idle, q_ref, row_scale, tol, check_tol, max_iter,
    damped)``; with ``damped`` a step that does not lower the residual is halved (a search from
    far away, :func:`direct_starts`). Converged when the scaled residual of the solved rows is
    at most ``tol`` (or stalls within a factor 1000 of it) and that of every loop row at most
    ``check_tol``. ``info``: worst row, scaled residual, Newton steps, ``det K``, smallest over
    largest pivot. Returns the status; on OK (or :data:`EULER_SINGULAR_RATES`) ``work`` holds
    the rows' values ``val`` and Jacobian ``J`` at the solution, ``G``, ``qd``, ``qdd`` and the
    drift ``gamma``."""
    (body_parent, body_joint, joint_q0, joint_nq, coord_motion, coord_offset, coord_sign, tRP, tpP, tRC, tpC) = tree
    RP, pP, RC, pC, anc, row_loop, row_kind, row_i, row_j, loop_joint, joint_parent, joint_child = loops
    task_body, task_point, task_kind, task_index, euler_axes = task
    act, unk, cut, idle, q_ref, row_scale, tol, check_tol, max_iter, damped = sol
    R, p, S, val, J, gamma, V, Vpre, A, K, piv, r, G, qd, qdd, w33, w3, trig, late, rowpos, colpos, q0, step = work
    nq = q.shape[0]
    na = act.shape[0]
    nu = unk.shape[0]
    nc = cut.shape[0]
    ni = idle.shape[0]
    nr = row_loop.shape[0]
    for a in range(na):
        q[act[a]] = s[a]
    off = nq < 0  # False, typed as a run-time value (a literal would compile another copy of the callees)
    jac = ROWS_JACOBIAN + 0 * nq
    drift = ROWS_DRIFT + 0 * nq
    values = ROWS_VALUES + 0 * nq
    prev = math.inf
    lam = 1.0
    it = 0
    evals = 0
    info[2] = 0.0
    while True:
        forward_positions(q, body_parent, body_joint, joint_q0, joint_nq, coord_motion, coord_offset, coord_sign,
                          tRP, tpP, tRC, tpC, R, p, S, w33, w3, trig, off, late, off)
        mode = values if chord else jac  # (a conditional among the arguments would not compile)
        ok = rows(R, p, S, anc, row_loop, row_kind, row_i, row_j, loop_joint, joint_parent, joint_child,
                  RP, pP, RC, pC, task_body, task_point, task_kind, task_index, euler_axes, q,
                  val, J, rowpos, colpos, mode, V, A, gamma, w33, w3)
        evals += 1
        big = 0.0
        worst = cut[0] if nc > 0 else 0
        for i in range(nc):
            rr = cut[i]
            r[i] = -val[rr]
            sc = abs(val[rr]) * row_scale[rr]
            if sc > big:
                big = sc
                worst = rr
        for k in range(ni):
            acc = 0.0
            for c in range(nq):
                acc += idle[k, c] * (q[c] - q_ref[c])
            r[nc + k] = -acc
            big = max(big, abs(acc))
        if chord:  # the simplified step; the next evaluation (with the Jacobian) checks it
            chord = False
            _lu_solve(K, piv, r)
            for j in range(nu):
                q[unk[j]] += r[j]
            continue
        if damped and it > 0 and not big < prev and lam > 1e-3 and evals < 4 * max_iter:
            # a step that did not lower the residual: half of it
            lam *= 0.5
            for j in range(nu):
                q[unk[j]] = q0[unk[j]] + lam * step[j]
            continue
        info[0] = worst
        info[1] = big
        done = big <= tol or (big <= 1e3 * tol and big > 0.5 * prev)
        if done:
            big_all, wa = largest_scaled(val, row_scale, nr)
            if big_all > check_tol:
                info[0] = wa
                info[1] = big_all
                return LOOP_OPEN
        elif it >= max_iter or not big < math.inf:
            return NOT_CONVERGED
        for i in range(nc):
            rr = cut[i]
            for j in range(nu):
                K[i, j] = J[rr, unk[j]]
        for k in range(ni):
            for j in range(nu):
                K[nc + k, j] = idle[k, unk[j]]
        det, ratio = _lu(K, piv)
        info[3] = det
        info[4] = ratio
        if not ratio > 1e-13:
            return SINGULAR
        if done:
            break
        _lu_solve(K, piv, r)
        for j in range(nu):
            c = unk[j]
            q0[c] = q[c]
            step[j] = r[j]
            q[c] += r[j]
        lam = 1.0
        prev = big
        it += 1
        info[2] = it
    # ---- rates at the solution: G = dq/ds, qd, the drift, qdd
    for a in range(na):
        ca = act[a]
        for i in range(nc):
            r[i] = -J[cut[i], ca]
        for k in range(ni):
            r[nc + k] = -idle[k, ca]
        _lu_solve(K, piv, r)
        for c in range(nq):
            G[c, a] = 0.0
        for j in range(nu):
            G[unk[j], a] = r[j]
        G[ca, a] = 1.0
    bias_motion(G, sd, qd, body_parent, body_joint, joint_q0, joint_nq, S, V, Vpre, A)
    rows(R, p, S, anc, row_loop, row_kind, row_i, row_j, loop_joint, joint_parent, joint_child,
         RP, pP, RC, pC, task_body, task_point, task_kind, task_index, euler_axes, q,
         val, J, rowpos, colpos, drift, V, A, gamma, w33, w3)
    for i in range(nc):
        rr = cut[i]
        acc = -gamma[rr]
        for a in range(na):
            acc -= J[rr, act[a]] * sdd[a]
        r[i] = acc
    for k in range(ni):
        acc = 0.0
        for a in range(na):
            acc -= idle[k, act[a]] * sdd[a]
        r[nc + k] = acc
    _lu_solve(K, piv, r)
    for c in range(nq):
        qdd[c] = 0.0
    for j in range(nu):
        qdd[unk[j]] = r[j]
    for a in range(na):
        qdd[act[a]] = sdd[a]
    return OK if ok else EULER_SINGULAR_RATES


#: compiled once and called as a function by both drivers below (inlining it twice would type
#: the whole solver twice)
direct_sample = njit(cache=True, _nrt=False)(direct_sample)


@njit(cache=True)
def _work(nq, nb, nrow, nu, na):  # pragma: no cover - compiled
    rowpos = np.arange(nrow)
    colpos = np.arange(nq)
    return (np.empty((nb, 3, 3)), np.empty((nb, 3)), np.empty((nq, 6)), np.empty(nrow), np.zeros((nrow, nq)),
            np.zeros(nrow), np.zeros((nb, 6)), np.zeros((nq, 6)), np.zeros((nb, 6)), np.empty((nu, nu)),
            np.empty(nu, dtype=np.int64), np.empty(nu), np.zeros((nq, na)), np.zeros(nq), np.zeros(nq),
            np.empty((5, 3, 3)), np.empty((20, 3)), np.empty((nq, 3)), np.full(nb, -1, dtype=np.int64), rowpos,
            colpos, np.zeros(nq), np.zeros(nu))


@njit(cache=True)
def direct_batch(tm, s, sd, sdd, q_start, x_start, tree, loops, task, sol, q_out, qd_out, qdd_out, x_out, xd_out,
                 xdd_out, res_out, it_out, det_out, ratio_out, status, worst):  # pragma: no cover - compiled
    """Every sample of the actuator motion ``s, sd, sdd (n, na)`` in order, each from the
    previous one's solution: ``q_{k-1} + qd dt + qdd dt^2 / 2 + (qdd_{k-1} - qdd_{k-2}) dt^3 /
    (6 dt_{k-1})`` (times ``tm``: Taylor to the third order, the jerk by the last step where it is at
    least a quarter of this one; without times
    ``q_{k-1} + G (s_k - s_{k-1})``), ``q_start`` for the first. Task angles are taken
    continuous, the first sample's nearest ``x_start``. Stops at the first sample that fails
    (``status``: NOT_CONVERGED, SINGULAR, LOOP_OPEN, :data:`CROSSED` where ``det K`` changed sign
    since the previous sample, :data:`EULER_SINGULAR_RATES`), with ``worst`` its worst row."""
    n = s.shape[0]
    nq = q_start.shape[0]
    nb = tree[0].shape[0]
    nr = loops[5].shape[0]
    nt = task[2].shape[0]
    na = sol[0].shape[0]
    nu = sol[1].shape[0]
    work = _work(nq, nb, nr + nt, nu, na)
    val, J, gamma, G, qd, qdd = work[3], work[4], work[5], work[12], work[13], work[14]
    info = np.zeros(5)
    q = q_start.copy()
    task_kind = task[2]
    det_prev = 0.0
    qdd_prev = np.zeros(nq)
    for k in range(n):
        if k > 0:
            if tm.shape[0] == n:
                dt = tm[k] - tm[k - 1]
                j3 = jerk_factor(tm, k)
                for c in range(nq):
                    q[c] += qd[c] * dt + 0.5 * qdd[c] * dt * dt + j3 * (qdd[c] - qdd_prev[c])
            else:
                for c in range(nq):
                    acc = 0.0
                    for a in range(na):
                        acc += G[c, a] * (s[k, a] - s[k - 1, a])
                    q[c] += acc
        for c in range(nq):
            qdd_prev[c] = qdd[c]
        st = direct_sample(s[k], sd[k], sdd[k], q, k > 0, tree, loops, task, sol, work, info)
        worst[k] = int(info[0])
        res_out[k] = info[1]
        it_out[k] = int(info[2])
        det_out[k] = info[3]
        ratio_out[k] = info[4]
        for c in range(nq):
            q_out[k, c] = q[c]
        if st == OK and k > 0 and info[3] * det_prev < 0.0:
            st = CROSSED
        if st != OK:
            status[k] = st
            return
        det_prev = info[3]
        for c in range(nq):
            qd_out[k, c] = qd[c]
            qdd_out[k, c] = qdd[c]
        for t in range(nt):
            rr = nr + t
            v = val[rr]
            if task_kind[t] == 1:  # continuous along the motion
                ref = x_start[t] if k == 0 else x_out[k - 1, t]
                v = ref + _wrap(v - ref)
            x_out[k, t] = v
            a1 = 0.0
            a2 = gamma[rr]
            for c in range(nq):
                a1 += J[rr, c] * qd[c]
                a2 += J[rr, c] * qdd[c]
            xd_out[k, t] = a1
            xdd_out[k, t] = a2
        status[k] = OK


@njit(cache=True)
def direct_starts(s, starts, tree, loops, task, sol, q_out, res_out, det_out, ratio_out, status):  # pragma: no cover
    """The actuator coordinates ``s (na,)`` solved from each row of ``starts (m, nq)`` alone
    (a damped Newton search when ``sol`` says so): the solutions ``q_out``, their residual,
    ``det K``, pivot ratio and status."""
    m = starts.shape[0]
    nq = starts.shape[1]
    nb = tree[0].shape[0]
    nrow = loops[5].shape[0] + task[2].shape[0]
    na = sol[0].shape[0]
    nu = sol[1].shape[0]
    work = _work(nq, nb, nrow, nu, na)
    info = np.zeros(5)
    zero = np.zeros(na)
    q = np.empty(nq)
    for i in range(m):
        for c in range(nq):
            q[c] = starts[i, c]
        st = direct_sample(s, zero, zero, q, False, tree, loops, task, sol, work, info)
        status[i] = st
        res_out[i] = info[1]
        det_out[i] = info[3]
        ratio_out[i] = info[4]
        for c in range(nq):
            q_out[i, c] = q[c]


# ---- one sample in one call: the model's arrays, the state and the work space packed into one
# buffer (:func:`pkmdyn.multibody.kinematics.direct.pack_one`), so that a call passes four arguments whatever the mechanism

#: the arrays of the packed buffer in order, each (name, kind, ndim): kind "i" int64, "f" float64
ONE_ARRAYS = (
    ("body_parent", "i", 1), ("body_joint", "i", 1), ("joint_q0", "i", 1), ("joint_nq", "i", 1),
    ("coord_motion", "i", 1), ("coord_offset", "f", 1), ("coord_sign", "f", 1), ("tree_R_parent", "f", 3),
    ("tree_p_parent", "f", 2), ("tree_R_child", "f", 3), ("tree_p_child", "f", 2),
    ("joint_R_parent", "f", 3), ("joint_p_parent", "f", 2), ("joint_R_child", "f", 3), ("joint_p_child", "f", 2),
    ("ancestor_list", "i", 2), ("row_loop", "i", 1), ("row_kind", "i", 1), ("row_i", "i", 1), ("row_j", "i", 1),
    ("loop_joint", "i", 1), ("joint_parent", "i", 1), ("joint_child", "i", 1),
    ("task_point", "f", 1), ("task_kind", "i", 1), ("task_index", "i", 1), ("euler_axes", "i", 1),
    ("act", "i", 1), ("unk", "i", 1), ("cut", "i", 1), ("idle", "f", 2), ("q_ref", "f", 1), ("row_scale", "f", 1),
    ("scalars", "f", 1),  # tolerance, check tolerance, task body, Newton steps at most
    # the work space of :func:`direct_sample` (:func:`_work`, in its order)
    ("R", "f", 3), ("p", "f", 2), ("S", "f", 2), ("val", "f", 1), ("J", "f", 2), ("gamma", "f", 1), ("V", "f", 2),
    ("Vpre", "f", 2), ("A", "f", 2), ("K", "f", 2), ("piv", "i", 1), ("r", "f", 1), ("G", "f", 2), ("qd", "f", 1),
    ("qdd", "f", 1), ("w33", "f", 3), ("w3", "f", 2), ("trig", "f", 2), ("late", "i", 1), ("rowpos", "i", 1),
    ("colpos", "i", 1), ("q0", "f", 1), ("step", "f", 1),
    # flag, det K, q (nq), x (nt), s (na), sd (na), step known, pivot ratio, step of q (nq)
    ("state", "f", 1),
    ("info", "f", 1), ("sdd", "f", 1), ("q", "f", 1),
)
#: the state's flag: nothing solved, a solution (set by the caller), a solution with its
#: factors and ``G`` in the work space (after a call)
ONE_COLD, ONE_PRIMED, ONE_FACTORED = 0.0, 1.0, 2.0


@njit(cache=True, inline="always")
def _v1(b, k, kind):  # pragma: no cover - compiled
    return kind(b, b[4 * k], (b[4 * k + 1],))


@njit(cache=True, inline="always")
def _v2(b, k, kind):  # pragma: no cover - compiled
    return kind(b, b[4 * k], (b[4 * k + 1], b[4 * k + 2]))


@njit(cache=True, inline="always")
def _v33(b, k):  # pragma: no cover - compiled
    return _fview(b, b[4 * k], (b[4 * k + 1], 3, 3))


@njit(cache=True, inline="always")
def _vn3(b, k):  # pragma: no cover - compiled
    return _fview(b, b[4 * k], (b[4 * k + 1], 3))


@njit(cache=True, _nrt=False)
def direct_one(b, s, sd, out):  # pragma: no cover - compiled
    """One sample of the direct kinematics from the previous call's solution, as
    :func:`direct_batch` solves its next sample (the predictor ``q + G (s - s_prev) + b h^2 / 2``,
    ``b`` the previous call's bias accelerations and ``h`` the step along its rate ``sd_prev``,
    and a simplified Newton step with the previous factors; from a solution the caller set, Newton
    alone), with the model, state and work space in the packed buffer ``b`` (:data:`ONE_ARRAYS`).
    Writes the task pose and rate into ``out (2 nt,)`` and returns the status: OK, or
    :data:`COLD`, :data:`BAD_INPUT`, a failure of :func:`direct_sample` or :data:`CROSSED`
    (the caller then solves the sample by the checked route, which names what is wrong)."""
    F, I = _fview, _iview
    tree = (_v1(b, 0, I), _v1(b, 1, I), _v1(b, 2, I), _v1(b, 3, I), _v1(b, 4, I), _v1(b, 5, F), _v1(b, 6, F),
            _v33(b, 7), _vn3(b, 8), _v33(b, 9), _vn3(b, 10))
    loops = (_v33(b, 11), _vn3(b, 12), _v33(b, 13), _vn3(b, 14), _v2(b, 15, I), _v1(b, 16, I), _v1(b, 17, I),
             _v1(b, 18, I), _v1(b, 19, I), _v1(b, 20, I), _v1(b, 21, I), _v1(b, 22, I))
    sc = _v1(b, 33, F)
    task_kind = _v1(b, 24, I)
    task = (int(sc[2]), _v1(b, 23, F), task_kind, _v1(b, 25, I), _v1(b, 26, I))
    act = _v1(b, 27, I)
    nq = tree[4].shape[0]
    sol = (act, _v1(b, 28, I), _v1(b, 29, I), _v2(b, 30, F), _v1(b, 31, F), _v1(b, 32, F), sc[0], sc[1], int(sc[3]),
           nq < 0)
    work = (_v33(b, 34), _vn3(b, 35), _v2(b, 36, F), _v1(b, 37, F), _v2(b, 38, F), _v1(b, 39, F), _v2(b, 40, F),
            _v2(b, 41, F), _v2(b, 42, F), _v2(b, 43, F), _v1(b, 44, I), _v1(b, 45, F), _v2(b, 46, F), _v1(b, 47, F),
            _v1(b, 48, F), _v33(b, 49), _vn3(b, 50), _vn3(b, 51), _v1(b, 52, I), _v1(b, 53, I), _v1(b, 54, I),
            _v1(b, 55, F), _v1(b, 56, F))
    st, info, sdd, q = _v1(b, 57, F), _v1(b, 58, F), _v1(b, 59, F), _v1(b, 60, F)
    na = act.shape[0]
    nt = task_kind.shape[0]
    nr = loops[5].shape[0]
    if st[0] == ONE_COLD:
        return COLD
    for a in range(na):
        if not (np.isfinite(s[a]) and np.isfinite(sd[a])):
            return BAD_INPUT
    chord = st[0] == ONE_FACTORED
    G, qdd = work[12], work[14]
    # along the previous call's rate, ``s - s_prev = sd_prev h`` to first order: the tree
    # coordinates' second-order term ``b h^2 / 2`` (``b = qdd`` of the previous call, at
    # ``sdd = 0``: the bias accelerations)
    so = 2 + nq + nt
    h2 = 0.0
    if chord:
        ss = 0.0
        vv = 0.0
        dd = 0.0
        for a in range(na):
            da = s[a] - st[so + a]
            ss += da * st[so + na + a]
            vv += st[so + na + a] * st[so + na + a]
            dd += da * da
        h2 = along_h2(ss, vv, dd)
    first = 0.0
    second = 0.0
    qdp = st[so + 2 * na + 2:so + 2 * na + 2 + nq]  # the previous call's step of the tree coordinates
    back = 0.0
    for c in range(nq):
        acc = 0.0
        if chord:
            for a in range(na):
                acc += G[c, a] * (s[a] - st[so + a])
        q[c] = st[2 + c] + acc
        back += acc * qdp[c]
        first = max(first, abs(acc))
        second = max(second, h2 * abs(qdd[c]))
    hp, near = st[so + 2 * na], st[so + 2 * na + 1]
    along = chord and back < 0.0 and hp > 0.0 and near < TASK_NEAR
    if along:
        # near a singularity the actuators turn back while the tree coordinates go on: the
        # previous step again (not the rates, which the singularity spoils), so that a crossing
        # shows as det K changing sign instead of the pose turning back onto the other mode
        for c in range(nq):
            q[c] = st[2 + c] + qdp[c]
    elif second_order_applies(first, second):
        for c in range(nq):
            q[c] += h2 * qdd[c]
    # (no simplified step with the factors of a matrix so near a singularity)
    status = direct_sample(s, sd, sdd, q, chord and not along, tree, loops, task, sol, work, info)
    if status == OK and info[3] * st[1] < 0.0:
        status = CROSSED
    if status != OK:
        st[0] = ONE_PRIMED  # the work space holds no factors of the last solution now
        return status
    val, J, qd = work[3], work[4], work[13]
    for t in range(nt):
        rr = nr + t
        v = val[rr]
        if task_kind[t] == 1:  # continuous from the previous pose
            ref = st[2 + nq + t]
            v = ref + _wrap(v - ref)
        out[t] = v
        acc = 0.0
        for c in range(nq):
            acc += J[rr, c] * qd[c]
        out[nt + t] = acc
    # this call's step of the tree coordinates (known: 1) and pivot ratio, for the next
    st[so + 2 * na] = 1.0 if chord else 0.0
    st[so + 2 * na + 1] = info[4]
    for c in range(nq):
        qdp[c] = q[c] - st[2 + c]
    st[0] = ONE_FACTORED
    st[1] = info[3]
    for c in range(nq):
        st[2 + c] = q[c]
    for t in range(nt):
        st[2 + nq + t] = out[t]
    for a in range(na):
        st[so + a] = s[a]
        st[so + na + a] = sd[a]
    return OK


# ---- the task-space route of one sample: legs placed from the task alone carry every actuator

#: status of :func:`direct_task_one` where a leg's closed form does not reach its point
NOT_REACHED = 21
#: the header of the task-space route's buffer (:func:`pkmdyn.multibody.kinematics.direct.pack_task`): the offsets of its
#: parts (26), then ``npos`` (task positions given: 3, or 0 for a task body on a ball fixed to the
#: ground) and ``nb``
TASK_HEAD = 28


#: the pivot ratio of the previous call's Jacobian below which the single-sample calls
#: (:func:`direct_one`, :func:`direct_task_one`) repeat the previous step where the actuators
#: turn back (near a singularity, where they turn back while the pose goes on; elsewhere the
#: pose turns back with them)
TASK_NEAR = 1e-2
#: Newton steps of :func:`direct_task_one` at most (a warm-started call takes one or two)
TASK_STEPS = 4
#: the largest move of the pose in one call of :func:`direct_task_one` (radians, or lengths over
#: the length scale): a larger one is refused (NOT_CONVERGED), for the caller to follow in
#: smaller steps (the legs' closed forms keep the branch nearest the previous solution only for
#: small moves)
TASK_MOVE = 0.05


#: calls of :func:`direct_task_one` by the actuated coordinates' closed forms alone between two
#: placements of every leg (the legs' other coordinates, which those calls leave as they were,
#: brought up to the pose for a later checked route to start from)
TASK_REFRESH = 8


@njit(cache=True, _nrt=False)
def _actuated(kind, c, axis, point, m0, e0, q0, cur, y, w3):  # pragma: no cover - compiled
    """The actuated coordinate of a leg from the ground whose end reaches the point ``c`` (base
    frame), for pattern ``kind`` (:mod:`pkmdyn.multibody.model.legs`): A2's first joint (a slide or a turn), B2's slide,
    by the first step of :func:`..model._tree_kernels._reach` alone (the leg's other coordinates are not
    needed), on the branch nearest ``cur`` (the coordinate's present value less its reference);
    ``y (3,)`` its gradient ``d th / d c`` from the closure ``f(th, c) = 0`` (``y = -f_c / f_th``).
    Returns ``(th, D)``, ``D`` the closure's derivative along the coordinate, which changes sign
    where the leg passes its own singularity (an R-U-S crank in line with its rod), or ``(nan,
    0)`` out of reach.

    * B2, ``|e0 - m0 + t a|^2 = |c - m0|^2``: ``D = t + a . (e0 - m0)``, ``y = (c - m0) / D``;
    * A2 from a slide, ``|m0 + t a - c|^2 = |e0 - m0|^2``: ``m = m0 + t a``, ``D = (c - m) . a``,
      ``y = (c - m) / D``;
    * A2 from a turn about ``a`` through ``r``: ``m = r + Rot(a, th) (m0 - r)`` at the distance
      ``|e0 - m0|`` from ``c``: ``D = (m - c) . (a x (m - r))``, ``y = (m - c) / D``."""
    u, v, m = w3[2], w3[3], w3[4]
    a = axis[0]
    scale = _dot(e0, e0) + _dot(m0, m0) + _dot(c, c) + 1e-300
    if kind != LEG_A2:  # B2: the slide, the leg's third coordinate
        a = axis[2]
        for i in range(3):
            u[i] = e0[i] - m0[i]
            v[i] = c[i] - m0[i]
        au = _dot(a, u)
        t = _quadratic_nearest(au, _dot(u, u) - _dot(v, v), cur, 1e-12 * scale)
        den = t + au
        if den == 0.0:  # the leg's own singularity, at its reach's end
            return t, den
        for i in range(3):
            y[i] = v[i] / den
        return t, den
    d2 = 0.0
    for i in range(3):
        d2 += (e0[i] - m0[i]) ** 2
    th = first_joint(a, point[0], m0, c, d2, cur, scale, u, v)
    if th != th:
        return th, 0.0
    den = 0.0
    if point[0, 0] != point[0, 0]:  # a slide
        for i in range(3):
            y[i] = c[i] - m0[i] - th * a[i]
            den += y[i] * a[i]
        if den == 0.0:
            return th, den
        for i in range(3):
            y[i] /= den
        return th, den
    r = point[0]
    _rotate_about(a, r, th, m0, m)
    for i in range(3):
        y[i] = m[i] - c[i]
    # (m - c) . (a x (m - r))
    den = (y[0] * (a[1] * (m[2] - r[2]) - a[2] * (m[1] - r[1])) + y[1] * (a[2] * (m[0] - r[0]) - a[0] * (m[2] - r[2]))
           + y[2] * (a[0] * (m[1] - r[1]) - a[1] * (m[0] - r[0])))
    if den == 0.0:
        return th, den
    for i in range(3):
        y[i] /= den
    return th, den


@njit(cache=True, _nrt=False)
def _task_fail(st, x, x0, q, q0, status):  # pragma: no cover - compiled
    """The previous solution back (the caller's checked route starts from it), no
    extrapolation on the next call; returns ``status``."""
    for i in range(x.shape[0]):
        x[i] = x0[i]
    for i in range(q.shape[0]):
        q[i] = q0[i]
    st[0] = ONE_PRIMED
    return status


@njit(cache=True, _nrt=False)
def direct_task_one(pk, d, s, sd, out):  # pragma: no cover - compiled
    """One sample of the direct kinematics in task space, for a mechanism whose every actuated
    coordinate belongs to a leg placed from the task alone (:mod:`pkmdyn.multibody.model.legs`: the Gough-Stewart
    platform, a 3-PUS platform's legs) and whose task gives the task body's three Euler angles (and
    its position, or the body sits on a ball fixed to the ground). Unknowns: the task coordinates
    ``x (nt)``; equations: ``q_a(x) = s`` with ``q_a(x)`` the legs' closed forms
    (:func:`..model._tree_kernels.place_fixed_legs`), by Newton from the previous call's solution plus
    ``A^-1 (s - s_prev)``, or, near a singularity (the previous ``A``'s pivot ratio below
    :data:`TASK_NEAR`), plus the previous call's step where ``A^-1 (s - s_prev)`` turns the
    pose back against it: the pose keeps moving through a singularity, where the actuators
    turn back, so that the crossing shows as ``det A`` changing sign instead of the pose
    turning back onto the other assembly mode. A call that would move the pose by more than
    :data:`TASK_MOVE` or take more than :data:`TASK_STEPS` Newton steps leaves the previous
    solution as it was and answers NOT_CONVERGED (the caller follows the move in smaller
    steps). The Jacobian ``A = dq_a/dx`` row by row: an actuated coordinate in the chain of
    leg L (coordinates ``c_1..c_3``, end point at the point ``c`` of the task body)
    moves with ``J_L qd_L = v_c``, ``J_L = [S_v + S_w x c]`` the chain's point velocities at
    ``c``, so its row is ``(J_L^-1)_i v_c(xd)``, with ``v_c = v_o + w x (c - o)``, ``w = E(phi)
    phi_dot`` (``E`` the Euler rate map) and ``o`` the task point (its velocity the task's
    positions) or the fixed ball's centre. Where each actuated coordinate is the one its leg's
    closed form gives first (A2's first joint, B2's slide: the Gough-Stewart platform's and the
    a 3-PUS platform's legs), that coordinate and its row come from the task alone (:func:`_actuated`: the
    leg's end ``c = o + R_T c_rel``, ``q_a`` and ``y = dq_a / dc``, the row's ``(J_L^-1)_i``), and
    the legs' other coordinates are placed every :data:`TASK_REFRESH` calls only (they do not
    enter the pose; a later checked route starts from them); the branch is then ``det A`` times
    the legs' ``D`` (:func:`_actuated`), the factor of ``det J_L`` that the actuated coordinate
    brings (the other, the universal joint's, vanishes only where the leg's passive angles are
    singular, which the pose does not see). Then
    ``xd = A^-1 sd``. ``pk``: the single-sample
    kinematics' packed model (:func:`pkmdyn.multibody.dynamics._sample_kernels.pack`, read only); ``d``: this route's state and
    work (:func:`pkmdyn.multibody.kinematics.direct.pack_task`). Writes ``x, xd`` into ``out (2 nt)``; returns OK,
    :data:`COLD`, :data:`BAD_INPUT`, :data:`NOT_REACHED`, NOT_CONVERGED, SINGULAR or
    :data:`CROSSED` (``det A`` changed sign since the previous call), each for the caller's
    checked route. The branch is the sign of ``det A`` times the legs' ``det J_L`` (``det A``
    alone also changes sign where a leg passes its own singularity, as an R-U-S crank lines up
    with its rod, while the direct kinematics stays regular)."""
    nq, nt, task_body = pk[4], pk[5], pk[2]
    na = nt
    nb = d[TASK_HEAD - 1]
    npos = d[TASK_HEAD - 2]
    st = _fview(d, d[0], (2,))
    if st[0] == ONE_COLD:
        return COLD
    for a in range(na):
        if not (np.isfinite(s[a]) and np.isfinite(sd[a])):
            return BAD_INPUT
    x = _fview(d, d[1], (nt,))
    sp = _fview(d, d[2], (na,))
    Ap = _fview(d, d[3], (nt, nt))
    scale = _fview(d, d[4], (na,))
    o = _fview(d, d[5], (3,))
    lmap = _iview(d, d[6], (na, 2))
    q = _fview(d, d[7], (nq,))
    R = _fview(d, d[8], (nb, 3, 3))
    p = _fview(d, d[9], (nb, 3))
    S = _fview(d, d[10], (nq, 6))
    w33 = _fview(d, d[11], (5, 3, 3))
    w3 = _fview(d, d[12], (20, 3))
    trig = _fview(d, d[13], (nq, 3))
    A = _fview(d, d[14], (nt, nt))
    LU = _fview(d, d[15], (nt, nt))
    r = _fview(d, d[16], (nt,))
    E = _fview(d, d[17], (3, 3))
    J = _fview(d, d[18], (6, 3))  # the chain's point velocities (3 x 3), then its inverse
    piv = _iview(d, d[19], (nt,))
    # the previous call's step of the task coordinates, whether known, 1 / the length scale, its
    # A's pivot ratio, Newton steps and scaled residual
    xdp = _fview(d, d[20], (nt + 5,))
    x0 = _fview(d, d[21], (nt,))
    q0 = _fview(d, d[22], (nq,))
    # each actuator's point on the task body less the task point (or the fixed ball's centre),
    # in the task body's frame; whether the actuated coordinates' closed forms alone answer, and
    # the calls since every leg was last placed
    crel = _fview(d, d[23], (na, 3))
    alone = _fview(d, d[24], (2,))
    # by the actuated coordinates alone: each one's gradient y = dq_a/dc and closure derivative D
    # at the last evaluation (at the solution, once converged: for the accelerations)
    yd = _fview(d, d[25], (na, 4))
    tol = _fview(pk, pk[6], (2,))[0]
    body_parent, body_joint, joint_q0, joint_nq, coord_motion = _i(pk, 0), _i(pk, 1), _i(pk, 2), _i(pk, 3), _i(pk, 4)
    task_kind, task_index, euler_axes = _i(pk, 13), _i(pk, 14), _i(pk, 15)
    act = _i(pk, 20)
    legs = (_i(pk, 34), _i(pk, 35), _i2(pk, 36), _i(pk, 37), _i(pk, 38), _fn3(pk, 32), _f33(pk, 33), _f33(pk, 34),
            _fn3(pk, 35), _fn3(pk, 36), _fn3(pk, 37), _i2(pk, 39), _i2(pk, 40), _i2(pk, 41), _fn3(pk, 38),
            _fn3(pk, 39), _f33(pk, 40), _i(pk, 42), _i(pk, 43))
    coord_offset, coord_sign = _f(pk, 0), _f(pk, 1)
    tRP, tpP, tRC, tpC = _f33(pk, 2), _fn3(pk, 3), _f33(pk, 4), _fn3(pk, 5)
    task_point = _f(pk, 10)
    task = (task_body, task_point, task_kind, task_index, euler_axes)
    tb = _nn(task_body)
    c, y, ang, cmo, wy = w3[13], w3[15], w3[16], w3[17], w3[19]
    Ji = J[3:]
    known = st[0] == ONE_FACTORED
    for i in range(nt):
        x0[i] = x[i]
    for i in range(nq):
        q0[i] = q[i]
    if known:
        # the first-order predictor with the previous Jacobian, ``A^-1 (s - s_prev)``; near a
        # singularity, where it turns the pose back against the previous step (the actuators
        # turning back, as they do there), that step again: the pose keeps moving, and a
        # crossing shows as det A changing sign rather than the pose turning back onto the
        # other assembly mode
        for i in range(nt):
            r[i] = s[i] - sp[i]
            for j in range(nt):
                LU[i, j] = Ap[i, j]
        _lu(LU, piv)
        _lu_solve(LU, piv, r)
        back = 0.0
        for i in range(nt):
            back += r[i] * xdp[i]
        along = back < 0.0 and xdp[nt] > 0.0 and xdp[nt + 2] < TASK_NEAR
        for i in range(nt):
            x[i] += xdp[i] if along else r[i]
    prev = math.inf
    it = 0
    det = 0.0
    ratio = 0.0
    legs_det = 1.0
    closed = alone[0] != 0.0
    RT, Rt, Rb = w33[1], w33[2], w33[3]
    while True:
        for t in range(nt):
            if task_kind[t] == 1:
                ang[_nn(task_index[t])] = x[t]
            elif closed:
                o[_nn(task_index[t])] = x[t]
        if closed:  # the task body's rotation R_T = Rot_a1(phi_1) Rot_a2(phi_2) Rot_a3(phi_3)
            euler_matrix(euler_axes, ang, RT, Rt, Rb)
        elif not place_fixed_legs(q, body_parent, body_joint, joint_q0, joint_nq, coord_motion, coord_offset,
                                  coord_sign, tRP, tpP, tRC, tpC, R, p, S, w33, w3, trig, legs, x, task):
            return _task_fail(st, x, x0, q, q0, NOT_REACHED)
        # the Jacobian at x
        euler_rate_map(ang, euler_axes, E)
        if npos == 3 and not closed:
            for i in range(3):
                o[i] = (p[tb, i] + R[tb, i, 0] * task_point[0] + R[tb, i, 1] * task_point[1]
                        + R[tb, i, 2] * task_point[2])
        legs_det = 1.0
        for a in range(na):
            L = _nn(lmap[a, 0])
            k = legs[1][L]
            if closed:  # the point from the task alone, the coordinate and its row in closed form
                for i in range(3):
                    c[i] = o[i] + RT[i, 0] * crel[a, 0] + RT[i, 1] * crel[a, 1] + RT[i, 2] * crel[a, 2]
                ca = _nn(act[a])
                i0 = _nn(lmap[a, 1])
                th, dl = _actuated(k % LEG_TASK, c, legs[6][L], legs[7][L], legs[8][L], legs[9][L], legs[10][L],
                                   q[ca] - legs[10][L, i0], y, w3)
                if th != th:
                    return _task_fail(st, x, x0, q, q0, NOT_REACHED)
                if dl == 0.0:
                    return _task_fail(st, x, x0, q, q0, SINGULAR)
                q[ca] = legs[10][L, i0] + th
                legs_det *= dl
                for i in range(3):
                    yd[a, i] = y[i]
                yd[a, 3] = dl
            elif k >= LEG_TASK:  # the chain reaches the centre of the ball that carries the task body
                kb = _nn(legs[12][L, 0])
                for i in range(3):
                    c[i] = p[tb, i] + R[tb, i, 0] * tpC[kb, 0] + R[tb, i, 1] * tpC[kb, 1] + R[tb, i, 2] * tpC[kb, 2]
            else:  # the cut joint's point on the task body
                cp = legs[5][L]
                for i in range(3):
                    c[i] = p[tb, i] + R[tb, i, 0] * cp[0] + R[tb, i, 1] * cp[1] + R[tb, i, 2] * cp[2]
            if not closed:
                for j in range(3):
                    cj = _nn(legs[2][L, j])
                    J[0, j] = S[cj, 3] + S[cj, 1] * c[2] - S[cj, 2] * c[1]
                    J[1, j] = S[cj, 4] + S[cj, 2] * c[0] - S[cj, 0] * c[2]
                    J[2, j] = S[cj, 5] + S[cj, 0] * c[1] - S[cj, 1] * c[0]
                dl = _inv3(J[:3], Ji)
                if dl == 0.0:
                    return _task_fail(st, x, x0, q, q0, SINGULAR)
                first = True
                for b in range(a):
                    if lmap[b, 0] == lmap[a, 0]:
                        first = False
                if first:  # each leg's det J_L once
                    legs_det *= dl
                i0 = _nn(lmap[a, 1])
                for i in range(3):
                    y[i] = Ji[i0, i]
            for i in range(3):
                cmo[i] = c[i] - o[i]
            wy[0] = cmo[1] * y[2] - cmo[2] * y[1]
            wy[1] = cmo[2] * y[0] - cmo[0] * y[2]
            wy[2] = cmo[0] * y[1] - cmo[1] * y[0]
            for t in range(nt):
                m = _nn(task_index[t])
                if task_kind[t] == 1:
                    A[a, t] = wy[0] * E[0, m] + wy[1] * E[1, m] + wy[2] * E[2, m]
                else:
                    A[a, t] = y[m]
        big = 0.0
        for a in range(na):
            r[a] = q[act[a]] - s[a]
            big = max(big, abs(r[a]) * scale[a])
        for i in range(nt):
            for j in range(nt):
                LU[i, j] = A[i, j]
        det, ratio = _lu(LU, piv)
        # the branch: det A times the legs' det J_L, or their actuated factors D where closed (A =
        # J_L^-1 ... changes sign through a leg's own singularity too, where the direct kinematics
        # is regular; the product only where the direct kinematics is singular)
        det *= legs_det
        if not ratio > 1e-13:
            return _task_fail(st, x, x0, q, q0, SINGULAR)
        if big <= tol or (big <= 1e3 * tol and big > 0.5 * prev):
            break
        if it >= TASK_STEPS or not big < math.inf:
            return _task_fail(st, x, x0, q, q0, NOT_CONVERGED)
        for a in range(na):
            r[a] = -r[a]
        _lu_solve(LU, piv, r)
        for t in range(nt):
            x[t] += r[t]
        prev = big
        it += 1
    move = 0.0
    for t in range(nt):
        move = max(move, abs(x[t] - x0[t]) * (1.0 if task_kind[t] == 1 else xdp[nt + 1]))
    if move > TASK_MOVE:
        return _task_fail(st, x, x0, q, q0, NOT_CONVERGED)
    if known and det * st[1] < 0.0:
        return _task_fail(st, x, x0, q, q0, CROSSED)
    if closed:  # every TASK_REFRESH calls the legs' other coordinates follow (their branches nearest)
        alone[1] += 1.0
        if alone[1] >= TASK_REFRESH:
            alone[1] = 0.0
            # (every such leg's joint points its rod in every direction, .direct._reaches_around: a
            # leg whose actuated coordinate reached its point places the rest)
            place_fixed_legs(q, body_parent, body_joint, joint_q0, joint_nq, coord_motion, coord_offset, coord_sign,
                             tRP, tpP, tRC, tpC, R, p, S, w33, w3, trig, legs, x, task)
    for a in range(na):
        r[a] = sd[a]
    _lu_solve(LU, piv, r)
    # this call's step (known: 1), for the next call's predictor; its Newton steps and residual
    xdp[nt] = 1.0 if known else 0.0
    xdp[nt + 3] = it
    xdp[nt + 4] = big
    for t in range(nt):
        out[t] = x[t]
        out[nt + t] = r[t]
        xdp[t] = x[t] - x0[t]
        for j in range(nt):
            Ap[t, j] = A[t, j]
    for a in range(na):
        sp[a] = s[a]
    st[0] = ONE_FACTORED
    st[1] = det
    xdp[nt + 2] = ratio
    return OK


@njit(cache=True, _nrt=False)
def _actuated_bias(kind, c, w, axis, point, m0, th, den, y, t3):  # pragma: no cover - compiled
    """The actuated coordinate's acceleration at a still leg end's acceleration, ``d2 th / dt2 -
    y . c_dd``, for its end moving at ``w = c_dot`` (:func:`_actuated`'s closure ``f(th, c) = 0``
    differentiated twice: ``-(f_thth th_d^2 + 2 th_d f_thc . w + w . f_cc w) / f_th``, with
    ``th_d = y . w``; ``t3 (3, 3)`` work space):

    * B2: ``(|w|^2 - th_d^2) / D``;
    * A2 from a slide along ``a``: ``|w - th_d a|^2 / D``;
    * A2 from a turn: ``-(|w - th_d m_th|^2 + th_d^2 (m - c) . m_thth) / D``, with ``m_th = a x (m
      - r)``, ``m_thth = a x m_th``."""
    td = _dot(y, w)
    if kind != LEG_A2:
        return (_dot(w, w) - td * td) / den
    a = axis[0]
    e = t3[0]
    if point[0, 0] != point[0, 0]:  # a slide
        for i in range(3):
            e[i] = w[i] - td * a[i]
        return _dot(e, e) / den
    r = point[0]
    m, mt = t3[1], t3[2]
    _rotate_about(a, r, th, m0, m)
    mt[0] = a[1] * (m[2] - r[2]) - a[2] * (m[1] - r[1])
    mt[1] = a[2] * (m[0] - r[0]) - a[0] * (m[2] - r[2])
    mt[2] = a[0] * (m[1] - r[1]) - a[1] * (m[0] - r[0])
    gm = 0.0  # (m - c) . (a x m_th)
    gm += (m[0] - c[0]) * (a[1] * mt[2] - a[2] * mt[1])
    gm += (m[1] - c[1]) * (a[2] * mt[0] - a[0] * mt[2])
    gm += (m[2] - c[2]) * (a[0] * mt[1] - a[1] * mt[0])
    for i in range(3):
        e[i] = w[i] - td * mt[i]
    return -(_dot(e, e) + td * td * gm) / den


@njit(cache=True, _nrt=False)
def _task_accelerations(pk, d, xd, sdd, xdd):  # pragma: no cover - compiled
    """The task accelerations ``xdd`` at the solution that :func:`direct_task_one` just left in
    ``d`` (by the actuated coordinates alone), at task rates ``xd`` and actuator accelerations
    ``sdd``: ``A xdd = sdd - beta`` with ``A``'s factors, each actuated coordinate's gradient
    ``y`` and closure derivative ``D`` as that call left them and ``beta`` the
    actuated coordinates' accelerations at ``xdd = 0``, per actuator ``y . c_dd0 + b``, where
    the leg end ``c = o + r`` moves at ``w = v_o + omega x r`` with ``c_dd0 = omega_d0 x r + omega x
    (omega x r)``, ``omega = E phi_dot``, ``omega_d0 = phi_dot_1 (phi_dot_0 e_0 x e_1) + phi_dot_2
    ((phi_dot_0 e_0 + phi_dot_1 e_1) x e_2)`` (``e_k`` the columns of ``E``: the rate map's
    derivative), and ``b`` the leg's own term (:func:`_actuated_bias`)."""
    nq, nt = pk[4], pk[5]
    na = nt
    npos = d[TASK_HEAD - 2]
    x = _fview(d, d[1], (nt,))
    o = _fview(d, d[5], (3,))
    lmap = _iview(d, d[6], (na, 2))
    q = _fview(d, d[7], (nq,))
    w33 = _fview(d, d[11], (5, 3, 3))
    w3 = _fview(d, d[12], (20, 3))
    LU = _fview(d, d[15], (nt, nt))
    E = _fview(d, d[17], (3, 3))
    piv = _iview(d, d[19], (nt,))
    crel = _fview(d, d[23], (na, 3))
    yd = _fview(d, d[25], (na, 4))
    task_kind, task_index, euler_axes = _i(pk, 13), _i(pk, 14), _i(pk, 15)
    act = _i(pk, 20)
    kinds, axes, points, m0s, q0s = _i(pk, 35), _f33(pk, 33), _f33(pk, 34), _fn3(pk, 35), _fn3(pk, 37)
    RT = w33[1]
    c, rr, w, cdd, om, omd, vo, phd, ang = w3[5], w3[7], w3[8], w3[9], w3[10], w3[11], w3[12], w3[14], w3[16]
    t3 = w33[4]
    for i in range(3):
        vo[i] = 0.0
        phd[i] = 0.0
    for t in range(nt):
        if task_kind[t] == 1:
            phd[_nn(task_index[t])] = xd[t]
            ang[_nn(task_index[t])] = x[t]
        elif npos == 3:
            vo[_nn(task_index[t])] = xd[t]
    euler_matrix(euler_axes, ang, RT, w33[2], w33[3])  # (a placement of every leg may have used RT's room)
    for i in range(3):
        om[i] = E[i, 0] * phd[0] + E[i, 1] * phd[1] + E[i, 2] * phd[2]
    # omega_d0 = phd1 phd0 (e0 x e1) + phd2 ((phd0 e0 + phd1 e1) x e2)
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        u_j = phd[0] * E[j, 0] + phd[1] * E[j, 1]
        u_k = phd[0] * E[k, 0] + phd[1] * E[k, 1]
        omd[i] = (phd[1] * phd[0] * (E[j, 0] * E[k, 1] - E[k, 0] * E[j, 1])
                  + phd[2] * (u_j * E[k, 2] - u_k * E[j, 2]))
    rhs = _fview(d, d[16], (nt,))
    for a in range(na):
        L = _nn(lmap[a, 0])
        i0 = _nn(lmap[a, 1])
        ca = _nn(act[a])
        for i in range(3):
            rr[i] = RT[i, 0] * crel[a, 0] + RT[i, 1] * crel[a, 1] + RT[i, 2] * crel[a, 2]
            c[i] = o[i] + rr[i]
        y = yd[a, :3]
        # the leg end's velocity and its acceleration at xdd = 0
        for i in range(3):
            j, kk = (i + 1) % 3, (i + 2) % 3
            w[i] = vo[i] + om[j] * rr[kk] - om[kk] * rr[j]
        for i in range(3):
            j, kk = (i + 1) % 3, (i + 2) % 3
            cdd[i] = omd[j] * rr[kk] - omd[kk] * rr[j] + om[j] * (w[kk] - vo[kk]) - om[kk] * (w[j] - vo[j])
        beta = _dot(y, cdd) + _actuated_bias(kinds[L] % LEG_TASK, c, w, axes[L], points[L], m0s[L],
                                              q[ca] - q0s[L, i0], yd[a, 3], y, t3)
        rhs[a] = sdd[a] - beta
    _lu_solve(LU, piv, rhs)
    for t in range(nt):
        xdd[t] = rhs[t]


@njit(cache=True, _nrt=False)
def direct_task_batch(pk, d, s, sd, sdd, work, x_out, xd_out, xdd_out, res_out, it_out, det_out, ratio_out,
                      status):  # pragma: no cover - compiled
    """Every sample of the actuator motion ``s, sd, sdd (n, na)`` in order by
    :func:`direct_task_one` (by the actuated coordinates alone; ``d`` primed with the first
    sample's solution), with the task accelerations (:func:`_task_accelerations`). Stops at the
    first sample that the call does not answer (``status`` its status, -1 after it); ``work
    (2 nt)``."""
    n = s.shape[0]
    nt = pk[5]
    xdp = _fview(d, d[20], (nt + 5,))
    st = _fview(d, d[0], (2,))
    for k in range(n):
        r = direct_task_one(pk, d, s[k], sd[k], work)
        status[k] = r
        if r != OK:
            return
        for t in range(nt):
            x_out[k, t] = work[t]
            xd_out[k, t] = work[nt + t]
        _task_accelerations(pk, d, xd_out[k], sdd[k], xdd_out[k])
        res_out[k] = xdp[nt + 4]
        it_out[k] = int(xdp[nt + 3])
        det_out[k] = st[1]
        ratio_out[k] = xdp[nt + 2]


def _refresh_cache() -> None:
    """The kernels of this module link and inline functions of :mod:`pkmdyn.multibody.kinematics._solve_kernels` and
    :mod:`pkmdyn.multibody.dynamics._sample_kernels`'s views (:mod:`._cache`)."""

    _cache.refresh((direct_sample, direct_batch, direct_starts), (_kernels, _tree_kernels,))
    _cache.refresh((direct_one, _actuated, _task_fail, direct_task_one, _actuated_bias, _task_accelerations,
                    direct_task_batch), (_kernels, _tree_kernels, _one))


_refresh_cache()
