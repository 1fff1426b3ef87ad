"""Compiled kernels of the loop solver: Newton on loop closure and task, sample by sample and
batched, with block LU factorisations and the chord steps; the tree's kernels
(:mod:`..model._tree_kernels`) place the bodies and give the rows.

Every function takes the flat arrays of :class:`~..model.records.MechanismModel` and is
compiled once (numba, ``cache=True``) for all mechanisms; the per-sample kernels allocate
nothing and are compiled without reference counting (``_nrt=False``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .. import _cache
from ..model import _tree_kernels
from ..model._tree_kernels import (  # noqa: F401
    EULER_SINGULAR,
    LOOP_OPEN,
    NOT_CONVERGED,
    OK,
    ROWS_DRIFT,
    ROWS_JACOBIAN,
    ROWS_VALUES,
    SINGULAR,
    _nn,
    _point_motion,
    _wrap,
    add_joint_accelerations,
    forward_accelerations,
    forward_positions,
    forward_velocities,
    place_legs,
    rows,
)


@njit(cache=True, _nrt=False)
def _fill_idle(K, idle, idlepos, colpos):
    """The idle rows of the permuted Newton matrix: ``K[idlepos[i], colpos[c]] = idle[i, c]``."""
    for i in range(idle.shape[0]):
        r = _nn(idlepos[i])
        for c in range(idle.shape[1]):
            K[r, _nn(colpos[c])] = idle[i, c]


@njit(cache=True, _nrt=False)
def solver_positions(sel_rows, prow, pcol, rowpos, colpos, idlepos):
    """Where the Newton system's rows and columns sit in its permuted matrix ``K[i, j] =
    Kfull[prow[i], pcol[j]]`` (``Kfull = [J[sel_rows]; idle]``): ``rowpos (nr + nt,)`` the row
    of each constraint or task row (-1: not solved, only checked), ``colpos (nq,)`` the column
    of each coordinate, ``idlepos (ni,)`` the row of each idle freedom."""
    m = sel_rows.shape[0]
    for rr in range(rowpos.shape[0]):
        rowpos[rr] = -1
    for i in range(prow.shape[0]):
        r = prow[i]
        if r < m:
            rowpos[sel_rows[r]] = i
        else:
            idlepos[r - m] = i
    for j in range(pcol.shape[0]):
        colpos[pcol[j]] = j


@njit(cache=True, _nrt=False)
def block_lu_factor(M, piv, blocks):
    """LU with partial pivoting inside each diagonal block of a block lower-triangular ``M``
    (``blocks``: block start rows, then ``n``); rows are swapped up to the block's last column
    (right of it the entries are zero), the blocks left of the diagonal are kept as they are
    (swapped with their rows). ``piv (2 n,)``: the row swaps, then each row's extent left
    of its block (the solves skip the zeros past its last nonzero there). False when a pivot
    is below 1e-12 of the largest entry."""
    n = M.shape[0]
    big = 0.0
    for bk in range(blocks.shape[0] - 1):
        for i in range(_nn(blocks[bk]), _nn(blocks[bk + 1])):
            for j in range(_nn(blocks[bk + 1])):
                if abs(M[i, j]) > big:
                    big = abs(M[i, j])
    tol = 1e-12 * big if big > 0 else 1e-300
    for bk in range(blocks.shape[0] - 1):
        s0, s1 = _nn(blocks[bk]), _nn(blocks[bk + 1])
        for k in range(s0, s1):
            pr = k
            pv = abs(M[k, k])
            for i in range(k + 1, s1):
                if abs(M[i, k]) > pv:
                    pv = abs(M[i, k])
                    pr = i
            piv[k] = pr
            if pv <= tol:
                return False
            if pr != k:
                for j in range(s1):
                    tmp = M[k, j]
                    M[k, j] = M[pr, j]
                    M[pr, j] = tmp
            inv = 1.0 / M[k, k]
            for i in range(k + 1, s1):
                f = M[i, k] * inv
                M[i, k] = f
                if f != 0.0:
                    for j in range(k + 1, s1):
                        M[i, j] -= f * M[k, j]
        for i in range(s0, s1):
            e = s0
            while e > 0 and M[i, e - 1] == 0.0:
                e -= 1
            piv[n + i] = e
    return True


@njit(cache=True, _nrt=False)
def block_lu_solve(M, piv, blocks, prow, pcol, b, work):
    """Solve ``Kfull x = b`` in place (``b`` in the rows of ``Kfull``, ``x`` in coordinate
    order) with the factors of :func:`block_lu_factor` of the permuted ``K``: block by block,
    ``A_kk x_k = b_k - A_k,<k x_<k`` (leading blocks with a zero right-hand side are left at
    zero, and the others skip their columns)."""
    n = M.shape[0]
    for i in range(n):
        work[i] = b[_nn(prow[i])]
    lo = 0  # work[:lo] is zero: the leading blocks whose right-hand sides are zero
    for bk in range(blocks.shape[0] - 1):
        s0, s1 = _nn(blocks[bk]), _nn(blocks[bk + 1])
        for k in range(s0, s1):
            pr = _nn(piv[k])
            if pr != k:
                tmp = work[k]
                work[k] = work[pr]
                work[pr] = tmp
        if lo == s0:
            zero = True
            for i in range(s0, s1):
                if work[i] != 0.0:
                    zero = False
            if zero:  # its solution is zero: nothing to solve
                lo = s1
                continue
        for i in range(s0, s1):
            acc = work[i]
            for j in range(lo, _nn(piv[n + i])):
                acc -= M[i, j] * work[j]
            for j in range(s0, i):
                acc -= M[i, j] * work[j]
            work[i] = acc
        for i in range(s1 - 1, s0 - 1, -1):
            acc = work[i]
            for j in range(i + 1, s1):
                acc -= M[i, j] * work[j]
            work[i] = acc / M[i, i]
    for j in range(n):
        b[_nn(pcol[j])] = work[j]


@njit(cache=True, _nrt=False)
def block_lu_solve_columns(M, piv, blocks, prow, pcol, B, X, work):
    """:func:`block_lu_solve` for every column of ``B (n, k)`` at once into ``X (n, k)`` (rows of
    ``B`` in the rows of ``Kfull``, of ``X`` in coordinate order; ``work (n, k)``)."""
    n = M.shape[0]
    k = B.shape[1]
    for i in range(n):
        for t in range(k):
            work[i, t] = B[_nn(prow[i]), t]
    for bk in range(blocks.shape[0] - 1):
        s0, s1 = _nn(blocks[bk]), _nn(blocks[bk + 1])
        for r in range(s0, s1):
            pr = _nn(piv[r])
            if pr != r:
                for t in range(k):
                    tmp = work[r, t]
                    work[r, t] = work[pr, t]
                    work[pr, t] = tmp
        for i in range(s0, s1):
            for j in range(_nn(piv[n + i])):
                m = M[i, j]
                if m != 0.0:
                    for t in range(k):
                        work[i, t] -= m * work[j, t]
            for j in range(s0, i):
                m = M[i, j]
                if m != 0.0:
                    for t in range(k):
                        work[i, t] -= m * work[j, t]
        for i in range(s1 - 1, s0 - 1, -1):
            for j in range(i + 1, s1):
                m = M[i, j]
                if m != 0.0:
                    for t in range(k):
                        work[i, t] -= m * work[j, t]
            d = 1.0 / M[i, i]
            for t in range(k):
                work[i, t] *= d
    for j in range(n):
        for t in range(k):
            X[_nn(pcol[j]), t] = work[j, t]


@njit(cache=True, inline="always")
def bias_motion(G, rate, qd, body_parent, body_joint, joint_q0, joint_nq, S, V, Vpre, A):
    """``qd = G rate`` (tree rates from the rates ``rate`` of the solved coordinates), then the
    bodies' velocities ``V`` and bias accelerations ``A`` (at ``qdd = 0``)."""
    for j in range(qd.shape[0]):
        acc = 0.0
        for t in range(rate.shape[0]):
            acc += G[j, t] * rate[t]
        qd[j] = acc
    forward_velocities(qd, body_parent, body_joint, joint_q0, joint_nq, S, V, Vpre)
    forward_accelerations(qd, body_parent, body_joint, joint_q0, joint_nq, S, Vpre, A)


@njit(cache=True, inline="always")
def _at_rest(xd, xdd):
    """Whether the task rates ``xd`` and accelerations ``xdd`` are all zero."""
    for t in range(xd.shape[0]):
        if xd[t] != 0.0 or xdd[t] != 0.0:
            return False
    return True


@njit(cache=True, inline="always")
def _rest(qd, qdd, V, Vpre, A, gamma):
    """The rates of a pose at rest: ``qd``, ``qdd``, the velocities ``V, Vpre``, the
    accelerations ``A`` and the drift ``gamma`` all zero."""
    for c in range(qd.shape[0]):
        qd[c] = 0.0
        qdd[c] = 0.0
    for b in range(V.shape[0]):
        for i in range(6):
            V[b, i] = 0.0
            A[b, i] = 0.0
    for c in range(Vpre.shape[0]):
        for i in range(6):
            Vpre[c, i] = 0.0
    for r in range(gamma.shape[0]):
        gamma[r] = 0.0


@njit(cache=True, inline="always")
def largest_scaled(res, row_scale, n):
    """The largest scaled residual ``|res[r]| row_scale[r]`` of the first ``n`` rows and its row."""
    big = 0.0
    at = 0
    for rr in range(n):
        sc = abs(res[rr]) * row_scale[rr]
        if sc > big:
            big = sc
            at = rr
    return big, at


@njit(cache=True)
def _residuals(xs, val, nr, task_kind, res):
    """Residuals ``res`` of the rows: loop rows as they are, task rows less the task pose
    ``xs`` (angles wrapped)."""
    for rr in range(val.shape[0]):
        if rr < nr:
            res[rr] = val[rr]
        elif task_kind[rr - nr] == 1:
            res[rr] = _wrap(val[rr] - xs[rr - nr])
        else:
            res[rr] = val[rr] - xs[rr - nr]


@njit(cache=True)
def _idle_residuals(q, q_ref, idle, ires):
    """``ires = idle (q - q_ref)``: how far each idle freedom has moved from its reference."""
    for i in range(idle.shape[0]):
        acc = 0.0
        for c in range(q.shape[0]):
            acc += idle[i, c] * (q[c] - q_ref[c])
        ires[i] = acc


@njit(cache=True, _nrt=False)
def task_unit_rhs(sel_rows, nr, Gw):
    """``Gw (mk, nt)``: the right-hand sides ``(0; I; 0)`` of ``G = K^-1 (0; I; 0)`` in the rows
    of the solved system (selected rows, then idle rows): 1 where selected row i is the task
    row of coordinate t."""
    for i in range(Gw.shape[0]):
        for t in range(Gw.shape[1]):
            Gw[i, t] = 1.0 if (i < sel_rows.shape[0] and sel_rows[i] == nr + t) else 0.0


#: the phases of :func:`solve_sample`
_CHORD, _NEWTON, _RATES = 0, 1, 2
#: samples without the simplified step after one that still needed a Newton step (the
#: predictor is then too far for it to pay: larger time steps, faster motion)
CHORD_PAUSE = 8


@njit(cache=True)
def jerk_factor(tm, s):
    """``dt^3 / (6 dt_prev)``: the factor of ``qdd_{s-1} - qdd_{s-2}`` in the third-order
    predictor of sample ``s`` at times ``tm`` (the jerk by the last step's change of the
    accelerations), where the previous step is at least a quarter of this one (a jump of the
    accelerations over a near-repeated time is no jerk); else 0 (the second order)."""
    dt = tm[s] - tm[s - 1]
    dtp = tm[s - 1] - tm[s - 2] if s > 1 else 0.0
    return dt * dt * dt / (6.0 * dtp) if dtp >= 0.25 * dt and dtp > 0.0 else 0.0


@njit(cache=True)
def along_h2(ss, vv, dd):
    """``h^2 / 2`` of a step ``d`` taken along the previous rate ``r`` (``d = r h`` to first
    order; ``ss = d . r``, ``vv = r . r``, ``dd = d . d``), the factor of the bias accelerations
    in a second-order predictor without times; 0 where the step is not along that rate within
    about 6 degrees (poses with unrelated rates keep the first order)."""
    if vv > 0.0 and dd * vv - ss * ss <= 0.01 * dd * vv:
        return 0.5 * (ss / vv) ** 2
    return 0.0


@njit(cache=True)
def second_order_applies(first, second):
    """Whether a predictor's second-order term (largest entry ``second``) is at most half its
    first-order one (``first``): rates out of scale with the positions' own steps, or a coarse
    sampling, keep the first order."""
    return 0.0 < second <= 0.5 * first


@njit(cache=True, inline="always")
def chord_pause(chord, info, pause):
    """The next sample's count of samples left without the simplified step of
    :func:`solve_sample` (0: take it), from this sample's (``info[2]``: Newton evaluations)."""
    if chord and info[2] > 1.0:
        return CHORD_PAUSE
    return pause - 1 if pause > 0 else 0


def solve_sample(xs, xds, xdds, q, q_ref, chord, tree, loops, task, solver, work, info):
    """One sample's kinematics (see :func:`solve_batch`) from the predictor ``q`` (updated in
    place), in three phases that share one evaluation of the rows:

    1. when ``chord``: one simplified Newton step with the factors ``K, piv`` left by the
       previous sample (rows' values only, no Jacobian, no factorisation); from a close
       predictor it leaves ``q`` within rounding of the solution;
    2. Newton on the square system until the scaled residual of the solved rows is at most
       ``tol`` (or stalls within a factor 1000 of it: the rounding floor of an
       ill-conditioned pose) and that of every row, the redundant directions of an
       over-constrained loop included, at most ``check_tol``;
    3. the rates at the solution: ``K qd = (0; xd)``, ``K qdd = (-gamma_loops; xdd -
       gamma_task)``, ``G = K^-1 (0; I; 0)``, the bodies' velocities ``V`` and accelerations
       ``A`` (``K, piv`` are left holding the factors at the solution).

    The model's arrays and the work space come as five tuples (``tree``, ``loops``, ``task``,
    ``solver``, ``work``, unpacked below in :func:`solve_batch`'s names; ``tree`` ends with the
    explicit legs' table, :mod:`pkmdyn.multibody.model.legs`), so that the call stays short. ``Gw (mk, nt)``: the constant right-hand sides
    ``(0; I; 0)`` (:func:`task_unit_rhs`); ``Gw2 (mk, nt)`` work space; ``trig (nq, 3)`` the
    turning coordinates' cosines and sines (:func:`_cos_sin`). Returns the status (OK,
    NOT_CONVERGED, SINGULAR, EULER_SINGULAR, LOOP_OPEN); ``info[0]`` the worst row, ``info[1]``
    the scaled residual, ``info[2]`` the Newton evaluations (1: the first closed the loops).
    ``info[3]`` (where ``info`` has four entries), when positive: give up (NOT_CONVERGED) once
    Newton has taken that many steps and its residual has not halved over the last three (a
    pose out of reach, where Newton wanders instead of converging; :func:`solve_batch`'s grid).
    On OK the poses ``R, p`` and twists ``S`` are those of the converged ``q``. The Jacobian's
    solved rows go straight into ``K`` at their permuted places (``rowpos``, ``colpos``,
    ``idlepos`` of :func:`solver_positions`, in ``solver``). The poses, the rows, the
    factorisation and the solve are each compiled once, as functions of their own, and called
    from one place each."""
    (body_parent, body_joint, joint_q0, joint_nq, coord_motion, coord_offset, coord_sign, tRP, tpP, tRC,
     tpC, legs) = tree
    RP, pP, RC, pC, anc, row_loop, row_kind, row_i, row_j, loop_joint, joint_parent, joint_child = loops
    task_body, task_point, task_kind, task_index, euler_axes = task
    sel_rows, idle, prow, pcol, blocks, row_scale, tol, check_tol, max_iter, rowpos, colpos, idlepos = solver
    R, p, S, val, res, K, piv, rhs, ires, bwork, qd, qdd, V, Vpre, A, gamma, G, w33, w3, Gw, Gw2, trig = work
    nq = q.shape[0]
    nr = row_loop.shape[0]
    nt = task_kind.shape[0]
    nrow = nr + nt
    m = sel_rows.shape[0]
    ni = idle.shape[0]
    mk = m + ni
    prev = 1e300
    prev2 = 1e300
    prev3 = 1e300
    stall = info[3] if info.shape[0] > 3 else 0.0
    explicit = legs[1].shape[0] > 0
    fixed = nq < 0  # False, typed as a run-time value: whether the legs placed from the task alone are
    # (their closed forms reached the task)
    # every block an explicit leg: the positions are exact at the first evaluation, which is
    # Newton's check; no simplified step before it
    phase = _CHORD if chord and legs[1].shape[0] < blocks.shape[0] - 1 else _NEWTON
    it = 0
    again = nq < 0  # False, typed as a run-time value (jacobians_batch)
    while True:
        # ---- evaluate the rows at q (their values with the Jacobian, or the drift)
        if phase == _RATES:
            # G = K^-1 (0; I) (all task columns in one pass), qd = G xd, bias motion
            block_lu_solve_columns(K, piv, blocks, prow, pcol, Gw, G, Gw2)
            if _at_rest(xds, xdds):
                # a pose held still (a grid's, a pose of its own): every rate, drift and
                # acceleration is zero, as the passes below would find them
                _rest(qd, qdd, V, Vpre, A, gamma)
                return OK
            bias_motion(G, xds, qd, body_parent, body_joint, joint_q0, joint_nq, S, V, Vpre, A)
            mode = ROWS_DRIFT
        else:
            forward_positions(q, body_parent, body_joint, joint_q0, joint_nq, coord_motion, coord_offset,
                              coord_sign, tRP, tpP, tRC, tpC, R, p, S, w33, w3, trig, again, legs[0], explicit)
            if explicit:
                # the legs placed from the task alone once per sample (the task does not change
                # within it), and Newton's steps leave their coordinates as they are
                fixed = place_legs(q, body_parent, body_joint, joint_q0, joint_nq, coord_motion, coord_offset,
                                   coord_sign, tRP, tpP, tRC, tpC, R, p, S, w33, w3, trig, again, legs, xs, task,
                                   fixed) or fixed
            # the pass after the simplified step (a step within rounding of the solution) starts from this
            # one's sines and cosines; a Newton step computes them afresh
            again = phase == _CHORD
            mode = ROWS_VALUES if phase == _CHORD else ROWS_JACOBIAN
        if phase == _CHORD and fixed:
            # the rows that only the legs placed from the task alone move are closed (their
            # closed forms, at this sample's task): not evaluated (NaN), no step for them
            ok = rows(R, p, S, anc, row_loop, row_kind, row_i, row_j, loop_joint, joint_parent, joint_child,
                      RP, pP, RC, pC, task_body, task_point, task_kind, task_index, euler_axes, q,
                      val, K, rowpos, colpos, mode, V, A, gamma, w33, w3, legs[18])
        else:
            ok = rows(R, p, S, anc, row_loop, row_kind, row_i, row_j, loop_joint, joint_parent, joint_child,
                      RP, pP, RC, pC, task_body, task_point, task_kind, task_index, euler_axes, q,
                      val, K, rowpos, colpos, mode, V, A, gamma, w33, w3)
        # ---- the right-hand side
        if phase == _RATES:
            for i in range(mk):
                rhs[i] = 0.0
            for i in range(m):
                rr = _nn(sel_rows[i])
                rhs[i] = (xdds[_nn(rr - nr)] - gamma[rr]) if rr >= nr else -gamma[rr]
        else:
            if phase == _NEWTON and not ok:
                info[0] = nr
                return EULER_SINGULAR
            _residuals(xs, val, nr, task_kind, res)
            _idle_residuals(q, q_ref, idle, ires)
            for i in range(m):
                ri = res[_nn(sel_rows[i])]
                rhs[i] = -ri if ri == ri else 0.0  # (NaN: a row left out of the simplified step)
            for i in range(ni):
                rhs[m + i] = -ires[i]
            if phase == _NEWTON:
                # the solved rows (selected and idle) and every row (redundant ones only checked)
                big_sel = 0.0
                wr = sel_rows[0] if m > 0 else 0
                for i in range(m):
                    sr = _nn(sel_rows[i])
                    sc = abs(res[sr]) * row_scale[sr]
                    if sc > big_sel:
                        big_sel = sc
                        wr = sel_rows[i]
                for i in range(ni):
                    if abs(ires[i]) > big_sel:
                        big_sel = abs(ires[i])
                big_all, wa = largest_scaled(res, row_scale, nrow)
                info[0] = wr
                info[1] = big_sel if big_sel > big_all else big_all
                # converged: at the tolerance, or stalled at the rounding floor (no halving) near it
                done = big_sel <= tol or (big_sel <= 1e3 * tol and big_sel > 0.5 * prev)
                if done and big_all > check_tol:
                    # LOOP_OPEN: the solved rows closed but a redundant direction of a loop stays open
                    info[0] = wa
                    return LOOP_OPEN
                if not done and (it == max_iter or (0.0 < stall <= it and big_sel > 0.5 * prev3)):
                    return NOT_CONVERGED
                prev3 = prev2
                prev2 = prev
                prev = big_sel
                it += 1
                info[2] = it
                _fill_idle(K, idle, idlepos, colpos)
                if not block_lu_factor(K, piv, blocks):
                    return SINGULAR
                if done:
                    phase = _RATES
                    continue
        # ---- one solve with the factors in K, piv
        block_lu_solve(K, piv, blocks, prow, pcol, rhs, bwork)
        if phase == _RATES:
            for j in range(nq):
                qdd[j] = rhs[j]
            add_joint_accelerations(qdd, body_parent, body_joint, joint_q0, joint_nq, S, A)
            return OK
        fixed_coord = legs[18]
        for j in range(mk):
            if not (fixed and fixed_coord[j] != 0):
                q[j] += rhs[j]
        phase = _NEWTON


#: :func:`solve_sample` compiled once, called as a function by the batched loop
#: (:func:`solve_batch`) and by the single-sample kernel (:mod:`pkmdyn.multibody.dynamics._sample_kernels`) alike: inlining it
#: there as well cost a second typing of the whole solver (some 90 s of cold compilation on
#: two cores) for a few tenths of a microsecond per call
solve_sample = njit(cache=True, _nrt=False)(solve_sample)


@njit(cache=True)
def solve_batch(tm, x, xd, xdd, q_start, nbr, root, tree, loops, task, settings, points, out):
    """Kinematics of every sample, warm-started along the motion.

    The model comes in the groups :func:`solve_sample` takes: ``tree`` (``body_parent,
    body_joint, joint_q0, joint_nq, coord_motion, coord_offset, coord_sign, tRP, tpP, tRC, tpC,
    legs``), ``loops`` (``RP, pP, RC, pC, anc, row_loop, row_kind, row_i, row_j, loop_joint,
    joint_parent, joint_child``), ``task`` (``task_body, task_point, task_kind, task_index,
    euler_axes``), with ``settings`` (``sel_rows, idle, prow, pcol, blocks, q_ref, row_scale,
    tol, check_tol, max_iter, stall``), ``points`` (``com, pC_all``) and the per-sample outputs
    ``out`` (``q_out, qd_out, qdd_out, R_out, p_out, V_out, A_out, G_out, res_out, status,
    worst, ov_out, oa_out, cp_out, cv_out, ca_out, jp_out, jv_out, ja_out``); the names below.

    For sample s: Newton on the square system of the selected rows and the idle rows

        rows(q) = 0 (loop closure),  task(q) - x_s = 0 (task coordinates, angles wrapped),
        idle (q - q_ref) = 0         (each idle freedom held along its direction at the reference),

    ``K = [J[sel_rows]; idle]`` (nq, nq), permuted (``prow``, ``pcol``) to block lower-triangular
    form with diagonal blocks starting at ``blocks`` (legs that are independent once the
    platform is placed are solved one by one), starting from
    ``q_{s-1} + qd_{s-1} dt + qdd_{s-1} dt^2 / 2 + (qdd_{s-1} - qdd_{s-2}) dt^3 / (6 dt_{s-1})``
    (Taylor to the third order, the jerk by the last step's difference where that step is at
    least a quarter of this one, else to the second order; it leaves ``q`` close
    enough for the simplified step to close the loops where the second order did not at a
    thousand samples a second) (the explicit legs' coordinates then set in
    closed form at every evaluation, ``legs``: :mod:`pkmdyn.multibody.model.legs`) (``dt = tm_s - tm_{s-1}``; the first-order
    ``q_{s-1} + G_{s-1} (x_s - x_{s-1}) + b_{s-1} h^2 / 2`` when ``tm`` is empty (``b = qdd - G
    xdd`` the bias part of the tree accelerations, ``h = dx . xd_{s-1} / |xd_{s-1}|^2`` the step
    along the previous rate); ``q_start`` for the first
    sample), until the scaled residual of the solved rows is at most ``tol`` (or stalls within
    a factor 1000 of it: the rounding floor of an ill-conditioned pose) and that of every row,
    the redundant directions of an over-constrained loop included, at most ``check_tol``; then
    ``K qd = (0; xd_s)``, ``K qdd = (-gamma_loops; xdd_s - gamma_task)`` and
    ``G = K^-1 (0; I; 0)`` (tree rates per task rate). Writes the per-sample outputs and
    ``status[s]`` (OK, NOT_CONVERGED, SINGULAR, EULER_SINGULAR, LOOP_OPEN) with ``worst[s]``
    the row of the largest residual; stops at the first failed sample. Also the classical
    velocity and acceleration of every body origin (``ov_out, oa_out``), centre of mass
    (``com`` (nb, 3) body frame -> ``cp_out, cv_out, ca_out``) and joint centre (the origin of
    the joint frame on ``joint_child``, ``pC_all`` (nj, 3) -> ``jp_out, jv_out, ja_out``).

    With ``nbr`` (n, k) (empty: the motion's order above), the samples are the poses of a grid
    with ``nbr[s]`` the neighbours of pose s (-1: none), solved by continuation over the grid
    in breadth-first order from pose ``root`` (which starts from ``q_start``): each pose once,
    from the solved neighbour that reached it first, by the first-order predictor
    ``q_p + G_p (x_s - x_p)``; a failed pose does not stop the others, and a pose with no
    solved neighbour is left unsolved (``status`` -1). A grid pose gives up once Newton has
    taken ``stall`` steps without halving its residual over the last three (0: never;
    :func:`solve_sample`, ``info[3]``): most of a grid's time goes to the poses just out of
    reach, each of which would otherwise take ``max_iter`` steps.
    """
    body_parent = tree[0]
    row_loop, joint_child = loops[5], loops[11]
    task_kind = task[2]
    sel_rows, idle, prow, pcol, blocks, q_ref, row_scale, tol, check_tol, max_iter, stall = settings
    com, pC_all = points
    (q_out, qd_out, qdd_out, R_out, p_out, V_out, A_out, G_out, res_out, status, worst,
     ov_out, oa_out, cp_out, cv_out, ca_out, jp_out, jv_out, ja_out) = out
    n = x.shape[0]
    nq = q_start.shape[0]
    nb = body_parent.shape[0]
    nr = row_loop.shape[0]
    nt = task_kind.shape[0]
    nrow = nr + nt
    mk = sel_rows.shape[0] + idle.shape[0]
    q = q_start.copy()
    qd = np.zeros(nq)
    qdd = np.zeros(nq)
    qdd_prev = np.zeros(nq)
    dxs = np.empty(nt)
    bias_q = np.empty(nq)
    R = np.empty((nb, 3, 3))
    p = np.empty((nb, 3))
    S = np.empty((nq, 6))
    V = np.zeros((nb, 6))
    Vpre = np.zeros((nq, 6))
    A = np.zeros((nb, 6))
    val = np.empty(nrow)
    gamma = np.zeros(nrow)
    res = np.empty(nrow)
    K = np.empty((mk, mk))
    piv = np.empty(2 * mk, dtype=np.int64)
    rhs = np.empty(mk)
    ires = np.empty(idle.shape[0])
    bwork = np.empty(mk)
    G = np.zeros((nq, nt))
    w33 = np.empty((5, 3, 3))
    w3 = np.empty((20, 3))
    grid = nbr.shape[0] == n
    info = np.zeros(4)
    info[3] = stall if grid else 0.0
    pause = 0
    Gw = np.empty((mk, nt))
    task_unit_rhs(sel_rows, nr, Gw)
    Gw2 = np.empty((mk, nt))
    rowpos = np.empty(nrow, dtype=np.int64)
    colpos = np.empty(nq, dtype=np.int64)
    idlepos = np.empty(idle.shape[0], dtype=np.int64)
    solver_positions(sel_rows, prow, pcol, rowpos, colpos, idlepos)
    solver = (sel_rows, idle, prow, pcol, blocks, row_scale, tol, check_tol, max_iter, rowpos, colpos, idlepos)
    work = (R, p, S, val, res, K, piv, rhs, ires, bwork, qd, qdd, V, Vpre, A, gamma, G, w33, w3, Gw, Gw2,
            np.zeros((nq, 3)))
    order = np.arange(n)
    came = np.full(n if grid else 0, -2)  # grid: the pose each pose starts from (-1: q_start; -2: none yet)
    tail = n
    if grid and n > 0:
        came[root] = -1
        order[0] = root
        tail = 1
    k = 0
    while k < tail:
        s = order[k]
        k += 1
        if grid:
            pa = came[s]
            for c in range(nq):
                q[c] = q_start[c]
                if pa >= 0:
                    acc = q_out[pa, c]
                    for t in range(nt):
                        dx = x[s, t] - x[pa, t]
                        if task_kind[t] == 1:
                            dx = _wrap(dx)
                        acc += G_out[pa, c, t] * dx
                    q[c] = acc
        elif s > 0 and tm.shape[0] == n:
            dt = tm[s] - tm[s - 1]
            j3 = jerk_factor(tm, s)
            for c in range(nq):
                q[c] += qd[c] * dt + 0.5 * qdd[c] * dt * dt + j3 * (qdd[c] - qdd_prev[c])
        elif s > 0:
            # along the previous sample's rate: x_s - x_{s-1} = xd_{s-1} h to first order, and
            # q_s = q_{s-1} + G dx + b h^2 / 2 to second (b = qdd - G xdd, the bias part of the
            # tree accelerations)
            ss = 0.0
            vv = 0.0
            dd = 0.0
            for t in range(nt):
                dx = x[s, t] - x[s - 1, t]
                if task_kind[t] == 1:
                    dx = _wrap(dx)
                dxs[t] = dx
                ss += dx * xd[s - 1, t]
                vv += xd[s - 1, t] * xd[s - 1, t]
                dd += dx * dx
            h2 = along_h2(ss, vv, dd)
            first = 0.0
            second = 0.0
            for c in range(nq):
                acc = 0.0
                bias = qdd[c]
                for t in range(nt):
                    acc += G[c, t] * dxs[t]
                    bias -= G[c, t] * xdd[s - 1, t]
                q[c] += acc
                bias_q[c] = bias
                first = max(first, abs(acc))
                second = max(second, h2 * abs(bias))
            if second_order_applies(first, second):
                for c in range(nq):
                    q[c] += h2 * bias_q[c]
        for c in range(nq):
            qdd_prev[c] = qdd[c]
        info[1] = 0.0
        # the predictor is close enough for a first step with the previous factors
        chord = s > 0 and tm.shape[0] == n and pause == 0 and not grid
        st = solve_sample(x[s], xd[s], xdd[s], q, q_ref, chord, tree, loops, task, solver, work, info)
        pause = chord_pause(chord, info, pause)
        worst[s] = int(info[0])
        res_out[s] = info[1]
        if st != OK:
            status[s] = st
            if st != EULER_SINGULAR:
                for c in range(nq):
                    q_out[s, c] = q[c]
            if grid:
                continue
            return
        for c in range(nq):
            q_out[s, c] = q[c]
            qd_out[s, c] = qd[c]
            qdd_out[s, c] = qdd[c]
            for t in range(nt):
                G_out[s, c, t] = G[c, t]
        for b in range(nb):
            for i in range(3):
                p_out[s, b, i] = p[b, i]
                for j in range(3):
                    R_out[s, b, i, j] = R[b, i, j]
            for i in range(6):
                V_out[s, b, i] = V[b, i]
                A_out[s, b, i] = A[b, i]
            _point_motion(b, p[b], V, A, ov_out[s, b], oa_out[s, b])
            for i in range(3):
                cp_out[s, b, i] = p[b, i] + R[b, i, 0] * com[b, 0] + R[b, i, 1] * com[b, 1] + R[b, i, 2] * com[b, 2]
            _point_motion(b, cp_out[s, b], V, A, cv_out[s, b], ca_out[s, b])
        for j in range(joint_child.shape[0]):
            b = joint_child[j]
            if b < 0:
                for i in range(3):
                    jp_out[s, j, i] = pC_all[j, i]
                    jv_out[s, j, i] = 0.0
                    ja_out[s, j, i] = 0.0
            else:
                for i in range(3):
                    jp_out[s, j, i] = (p[b, i] + R[b, i, 0] * pC_all[j, 0] + R[b, i, 1] * pC_all[j, 1]
                                       + R[b, i, 2] * pC_all[j, 2])
                _point_motion(b, jp_out[s, j], V, A, jv_out[s, j], ja_out[s, j])
        status[s] = OK
        if grid:
            for i in range(nbr.shape[1]):
                u = nbr[s, i]
                if u >= 0 and came[u] == -2:
                    came[u] = s
                    order[tail] = u
                    tail += 1


def _refresh_cache() -> None:
    """The loop solver's kernels link and inline the tree's kernels (:mod:`.._cache`)."""

    _cache.refresh((_fill_idle, solver_positions, block_lu_factor, block_lu_solve, block_lu_solve_columns, bias_motion, _at_rest, _rest, largest_scaled, _residuals, _idle_residuals, task_unit_rhs, jerk_factor, along_h2, second_order_applies, chord_pause, solve_sample, solve_batch), (_tree_kernels,))


_refresh_cache()
