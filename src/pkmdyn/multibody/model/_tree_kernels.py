"""Compiled kernels of the tree, driven by the model's arrays only: elementary joint motions,
body placement, velocities and accelerations along the tree, the explicit legs' closed forms,
Euler angles and their rate maps, and the constraint rows of the cut joints and the task.

Below the loop solver (:mod:`..kinematics._solve_kernels`): the compiler's rank tests and leg
recognition (:mod:`pkmdyn.multibody.model.topology`, :mod:`pkmdyn.multibody.model.legs`) and the body poses (:mod:`pkmdyn.multibody.model.poses`) use these
without the solver.

Nothing here knows a mechanism: every function takes the flat arrays of
:class:`~pkmdyn.multibody.model.compiler.MechanismModel` and is compiled once (numba, ``cache=True``) for all of them.
The per-sample kernels allocate nothing (their work space comes in as arguments) and are
compiled without reference counting (``_nrt=False``): passing an array or taking a view of
one then costs nothing, where a counted view costs some 15 ns, more than a row of the loop
equations.

Notation (world = base frame): body b has rotation ``R[b]`` (3, 3) and frame origin ``p[b]``
(3,) [m]; its spatial velocity ``V[b] = (omega; v_O)`` (6,) (angular velocity [rad/s] and the
velocity [m/s] of the body point at the world origin, Plücker coordinates) and spatial
acceleration ``A[b] = (omega_dot; a_O)`` (Featherstone 2008, ch. 2). Tree coordinate c has
the world unit twist ``S[c]`` (6,); ``V[b] = V[parent] + sum_c S[c] qd[c]`` and
``A[b] = A[parent] + sum_c (S[c] qdd[c] + V_pre[c] x S[c] qd[c])`` (Eq. 3.40 and 2.x of the
book: the derivative of a twist fixed in a moving frame is ``V x S``), with ``V_pre[c]``
the velocity of the frame in which ``S[c]`` is fixed. A point x fixed in body b moves with
``v = v_O + omega x x`` and ``a = a_O + omega_dot x x + omega x v``.

Rows: the constraint rows of the cut joints (``row_*`` arrays, residuals of
:mod:`pkmdyn.multibody.description.joint_types`) followed by the task rows (``task_*``). ``_rows`` gives each row's
value, its Jacobian row over the tree coordinates and, on request, its drift
``gamma = d2/dt2 (row) at qdd = 0``, so that the acceleration equations are
``J qdd = -gamma`` (loops) and ``J qdd = x_dd - gamma`` (task).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numba.extending import intrinsic

OK, NOT_CONVERGED, SINGULAR, EULER_SINGULAR, LOOP_OPEN = 0, 1, 2, 3, 4
#: what :func:`rows` computes beside the values: the Jacobian, the drift, or nothing
ROWS_JACOBIAN, ROWS_DRIFT, ROWS_VALUES = 0, 1, 2


@intrinsic
def _nn(typingctx, i):  # pragma: no cover - compiled
    """``i``, an index the model guarantees to be >= 0, with the compiler told so: indexing
    with it then needs no code for negative (from the end) indices."""
    def codegen(context, builder, sig, args):
        v = args[0]
        builder.assume(builder.icmp_signed(">=", v, v.type(0)))
        return v

    return i(i), codegen


@njit(cache=True, inline="always")
def _wrap(a):
    return a - 2.0 * math.pi * math.floor((a + math.pi) / (2.0 * math.pi))


@njit(cache=True, inline="always")
def _rot(m, ang, out):
    """Elementary rotation about axis m (0, 1, 2) by ang [rad] into out (3, 3)."""
    c, s = math.cos(ang), math.sin(ang)
    for i in range(3):
        for j in range(3):
            out[i, j] = 0.0
    i, j = (m + 1) % 3, (m + 2) % 3
    out[m, m] = 1.0
    out[i, i] = c
    out[j, j] = c
    out[i, j] = -s
    out[j, i] = s


@njit(cache=True, inline="always")
def _matmul3(a, b, out):
    for i in range(3):
        for j in range(3):
            out[i, j] = a[i, 0] * b[0, j] + a[i, 1] * b[1, j] + a[i, 2] * b[2, j]


@njit(cache=True, inline="always")
def _cross(a, b, out):
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


@njit(cache=True, inline="always")
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True, inline="always")
def _unit_twist(S, c, sg, turns, a0, a1, a2, o0, o1, o2):
    """``S[c] (6,)``: the world unit twist of coordinate c, which turns about (``turns``) or
    slides along the unit axis ``a`` through the point ``o``, with the sign ``sg``."""
    if turns:
        S[c, 0], S[c, 1], S[c, 2] = sg * a0, sg * a1, sg * a2
        S[c, 3] = sg * (o1 * a2 - o2 * a1)
        S[c, 4] = sg * (o2 * a0 - o0 * a2)
        S[c, 5] = sg * (o0 * a1 - o1 * a0)
    else:
        S[c, 0] = 0.0
        S[c, 1] = 0.0
        S[c, 2] = 0.0
        S[c, 3], S[c, 4], S[c, 5] = sg * a0, sg * a1, sg * a2


@njit(cache=True, inline="always")
def _turn(Rf, m, cq, sq):
    """``Rf <- Rf Rot_m(q)`` (m < 3) from ``cq, sq = cos q, sin q``: only the two columns normal
    to axis m turn."""
    i1, j1 = (m + 1) % 3, (m + 2) % 3
    for r in range(3):
        ci, cj = Rf[r, i1], Rf[r, j1]
        Rf[r, i1] = cq * ci + sq * cj
        Rf[r, j1] = -sq * ci + cq * cj


@njit(cache=True, inline="always")
def _slide(Rf, o, m, qc):
    """``o += qc Rf[:, m - 3]`` (m >= 3): the origin slides along axis m - 3."""
    for i in range(3):
        o[i] += Rf[i, _nn(m - 3)] * qc


@njit(cache=True, inline="always")
def _advance(Rf, o, m, qc):
    """Move a joint's frame (axes ``Rf (3, 3)``, origin ``o (3,)``) by one coordinate of motion
    ``m`` through ``qc``: ``Rf <- Rf Rot_m(qc)`` (m < 3, :func:`_turn`), or a slide
    (:func:`_slide`)."""
    if m < 3:
        _turn(Rf, m, math.cos(qc), math.sin(qc))
    else:
        _slide(Rf, o, m, qc)


@njit(cache=True, inline="always")
def _cos_sin(trig, c, qc, reuse):
    """``cos qc, sin qc`` of coordinate c, kept in ``trig[c] = (cos, sin, qc)``. With ``reuse``
    and ``qc`` within 1e-3 of the kept angle, from the kept values by the angle-addition
    formulas with the series of ``cos d``, ``sin d`` to ``d^4``, ``d^5`` (left out: below
    ``d^6 / 720 < 2e-21``): exact to rounding, without the library's sine and cosine."""
    if reuse:
        d = qc - trig[c, 2]
        if abs(d) < 1e-3:
            d2 = d * d
            cd = 1.0 - d2 * (0.5 - d2 * (1.0 / 24.0))
            sd = d * (1.0 - d2 * (1.0 / 6.0 - d2 * (1.0 / 120.0)))
            c0, s0 = trig[c, 0], trig[c, 1]
            cq, sq = c0 * cd - s0 * sd, s0 * cd + c0 * sd
            trig[c, 0], trig[c, 1], trig[c, 2] = cq, sq, qc
            return cq, sq
    cq, sq = math.cos(qc), math.sin(qc)
    trig[c, 0], trig[c, 1], trig[c, 2] = cq, sq, qc
    return cq, sq


# ---- explicit leg closure (:mod:`pkmdyn.multibody.model.legs`): Paden-Kahan subproblems on a leg's product of exponentials
#: leg patterns (:mod:`pkmdyn.multibody.model.legs`): a first joint then a ball of one or two turns about a point ``m0``;
#: one or two turns about ``m0`` then a slide
LEG_A1, LEG_A2, LEG_B1, LEG_B2 = 1, 2, 3, 4
#: a leg that carries the task body (:mod:`pkmdyn.multibody.model.legs`): ``LEG_TASK + pattern`` of the chain that places
#: its ball joint's centre (0: the ball sits on the ground)
LEG_TASK = 10


@njit(cache=True, _nrt=False)
def _rotate_about(w, r, th, x, out):  # pragma: no cover - compiled
    """``out``: the point ``x`` turned by ``th`` about the unit axis ``w`` through ``r``
    (Rodrigues)."""
    c, s = math.cos(th), math.sin(th)
    d0, d1, d2 = x[0] - r[0], x[1] - r[1], x[2] - r[2]
    wd = w[0] * d0 + w[1] * d1 + w[2] * d2
    k0 = w[1] * d2 - w[2] * d1
    k1 = w[2] * d0 - w[0] * d2
    k2 = w[0] * d1 - w[1] * d0
    out[0] = r[0] + c * d0 + s * k0 + (1.0 - c) * wd * w[0]
    out[1] = r[1] + c * d1 + s * k1 + (1.0 - c) * wd * w[1]
    out[2] = r[2] + c * d2 + s * k2 + (1.0 - c) * wd * w[2]


@njit(cache=True, _nrt=False)
def _sp1(w, u, v):  # pragma: no cover - compiled
    """Paden-Kahan subproblem 1: the angle that turns the vector ``u`` into ``v`` about the
    unit axis ``w`` (both taken normal to ``w``)."""
    uw = _dot(w, u)
    vw = _dot(w, v)
    a0, a1, a2 = u[0] - uw * w[0], u[1] - uw * w[1], u[2] - uw * w[2]
    b0, b1, b2 = v[0] - vw * w[0], v[1] - vw * w[1], v[2] - vw * w[2]
    cr = w[0] * (a1 * b2 - a2 * b1) + w[1] * (a2 * b0 - a0 * b2) + w[2] * (a0 * b1 - a1 * b0)
    return math.atan2(cr, a0 * b0 + a1 * b1 + a2 * b2)


@njit(cache=True, _nrt=False)
def _near(th, cur):  # pragma: no cover - compiled
    """The angle ``th`` moved by whole turns to lie within half a turn of ``cur``."""
    return cur + _wrap(th - cur)


@njit(cache=True, _nrt=False)
def _quadratic_nearest(b, c, cur, tol):  # pragma: no cover - compiled
    """The root of ``t^2 + 2 b t + c = 0`` nearest ``cur``; ``nan`` when there is none (a
    negative discriminant beyond ``tol``: out of reach)."""
    disc = b * b - c
    if disc < 0.0:
        if disc < -tol:
            return math.nan
        disc = 0.0
    sq = math.sqrt(disc)
    t1, t2 = -b + sq, -b - sq
    return t1 if abs(t1 - cur) <= abs(t2 - cur) else t2


@njit(cache=True, _nrt=False)
def _sp2(w1, w2, u, v, cur1, cur2, z, t3):  # pragma: no cover - compiled
    """Paden-Kahan subproblem 2: angles ``(th1, th2)`` with ``Rot(w1, th1) Rot(w2, th2) u = v``
    about two unit axes through one point (``|u| = |v|``): ``z = Rot(w2, th2) u`` lies on
    both cones, ``z = al w1 + be w2 + ga (w1 x w2)``. Of the two solutions (the sign of
    ``ga``) the one nearest ``(cur1, cur2)``; ``(nan, nan)`` when ``v`` is out of reach."""
    c12 = _dot(w1, w2)
    den = 1.0 - c12 * c12
    w1v = _dot(w1, v)
    w2u = _dot(w2, u)
    al = (w1v - c12 * w2u) / den
    be = (w2u - c12 * w1v) / den
    _cross(w1, w2, t3)
    g2 = (_dot(u, u) - al * al - be * be - 2.0 * al * be * c12) / _dot(t3, t3)
    if g2 < 0.0:
        if g2 < -1e-10 * _dot(u, u) / _dot(t3, t3):
            return math.nan, math.nan
        g2 = 0.0
    ga = math.sqrt(g2)
    best1, best2, bestd = math.nan, math.nan, math.inf
    for sg in (1.0, -1.0):
        for i in range(3):
            z[i] = al * w1[i] + be * w2[i] + sg * ga * t3[i]
        th2 = _near(_sp1(w2, u, z), cur2)
        th1 = _near(_sp1(w1, z, v), cur1)
        d = (th1 - cur1) ** 2 + (th2 - cur2) ** 2
        if d < bestd:
            best1, best2, bestd = th1, th2, d
    return best1, best2


@njit(cache=True, _nrt=False)
def _explicit_leg(L, q, R, p, legs, w3):  # pragma: no cover - compiled
    """Set leg ``L``'s coordinates in ``q`` in closed form from the pose of the body it meets
    (:mod:`pkmdyn.multibody.model.legs`): the cut joint's point on that body, ``c``, taken into the leg's base frame,
    is reached by the leg's end point (:func:`_reach`). Returns False (``q`` left as it is, for
    Newton) where ``c`` is out of the leg's reach."""
    leg_base, leg_placed, leg_cpt = legs[3], legs[4], legs[5]
    c, cb = w3[0], w3[1]
    P = leg_placed[L]
    for i in range(3):
        c[i] = leg_cpt[L, i]
    if P >= 0:
        P = _nn(P)
        for i in range(3):
            c[i] = p[P, i] + R[P, i, 0] * leg_cpt[L, 0] + R[P, i, 1] * leg_cpt[L, 1] + R[P, i, 2] * leg_cpt[L, 2]
    B = leg_base[L]
    if B >= 0:  # into the base body's frame
        B = _nn(B)
        for i in range(3):
            cb[i] = ((c[0] - p[B, 0]) * R[B, 0, i] + (c[1] - p[B, 1]) * R[B, 1, i]
                     + (c[2] - p[B, 2]) * R[B, 2, i])
        for i in range(3):
            c[i] = cb[i]
    return _reach(legs[1][L], q, legs[2][L], legs[6][L], legs[7][L], legs[8][L], legs[9][L], legs[10][L], w3)


@njit(cache=True, _nrt=False)
def first_joint(a0, r, m0, c, d2, cur, scale, u, v):  # pragma: no cover - compiled
    """The first joint of an A1 or A2 leg (:func:`_reach`): the value that brings the point
    ``m0`` to the distance ``sqrt(d2)`` from ``c``, for a slide along ``a0`` (``r`` NaN:
    ``|m0 + t a0 - c|^2 = d2``) or a turn about ``a0`` through ``r`` (``cos(th - th_c) = (|u'|^2 +
    |v'|^2 - d'^2) / (2 |u'| |v'|)``), on the branch nearest ``cur``; NaN out of reach
    (``u, v (3,)`` work space)."""
    if r[0] != r[0]:
        bq = 0.0
        cq = -d2
        for i in range(3):
            bq += a0[i] * (m0[i] - c[i])
            cq += (m0[i] - c[i]) ** 2
        return _quadratic_nearest(bq, cq, cur, 1e-12 * scale)
    for i in range(3):
        u[i] = m0[i] - r[i]
        v[i] = c[i] - r[i]
    ua, va = _dot(a0, u), _dot(a0, v)
    for i in range(3):
        u[i] -= ua * a0[i]
        v[i] -= va * a0[i]
    nu, nv = math.sqrt(_dot(u, u)), math.sqrt(_dot(v, v))
    dd = d2 - (ua - va) ** 2
    if nu * nv == 0.0:
        return math.nan
    cs = (nu * nu + nv * nv - dd) / (2.0 * nu * nv)
    if abs(cs) > 1.0:
        if abs(cs) > 1.0 + 1e-10:
            return math.nan
        cs = 1.0 if cs > 0 else -1.0
    thc = _sp1(a0, u, v)
    h = math.acos(cs)
    t1, t2 = _near(thc + h, cur), _near(thc - h, cur)
    return t1 if abs(t1 - cur) <= abs(t2 - cur) else t2


@njit(cache=True, _nrt=False)
def _reach(kind, q, coord, axis, point, m0, e0, q0, w3):  # pragma: no cover - compiled
    """A leg's coordinates in ``q`` such that its end point reaches ``c = w3[0]`` (base frame),
    by pattern ``kind`` (:mod:`pkmdyn.multibody.model.legs`; the leg's rows of the table: ``coord (3,)``, ``axis,
    point (3, 3)``, ``m0, e0, q0 (3,)``): along the product of exponentials about the
    reference configuration, ``e(th) = exp(xi_1 th_1) ... exp(xi_k th_k) e0`` (``th = q -
    q_ref``; Paden & Kahan's subproblems, Murray, Li & Sastry 1994, ch. 3). Of two
    assembly branches, the one nearest the present ``q``. False where ``c`` is out of reach."""
    c, cb, u, v, z, t3 = w3[0], w3[1], w3[2], w3[3], w3[4], w3[5]
    c0, c1 = _nn(coord[0]), _nn(coord[1])
    cur0, cur1 = q[c0] - q0[0], q[c1] - q0[1]
    a0 = axis[0]
    a1 = axis[1]
    scale = _dot(e0, e0) + _dot(m0, m0) + _dot(c, c) + 1e-300
    if kind == LEG_A1 or kind == LEG_A2:
        # 1. the first joint brings m0 to the distance |e0 - m0| from c
        d2 = 0.0
        for i in range(3):
            d2 += (e0[i] - m0[i]) ** 2
        th0 = first_joint(a0, point[0], m0, c, d2, cur0, scale, u, v)
        if th0 != th0:
            return False
        if point[0, 0] != point[0, 0]:
            for i in range(3):
                cb[i] = c[i] - th0 * a0[i]  # c taken back through the first joint
        else:
            _rotate_about(a0, point[0], -th0, c, cb)
        q[c0] = q0[0] + th0
        # 2. the ball about m0 turns e0 - m0 into cb - m0
        for i in range(3):
            u[i] = e0[i] - m0[i]
            v[i] = cb[i] - m0[i]
        if kind == LEG_A1:
            q[c1] = q0[1] + _near(_sp1(a1, u, v), cur1)
        else:
            c2 = _nn(coord[2])
            th1, th2 = _sp2(a1, axis[2], u, v, cur1, q[c2] - q0[2], z, t3)
            if th1 != th1:
                return False
            q[c1] = q0[1] + th1
            q[c2] = q0[2] + th2
        return True
    # LEG_B1, LEG_B2: the slide last, |e0 + t a - m0| = |c - m0| (normal to the turn's axis for B1)
    ks = 1 if kind == LEG_B1 else 2
    cs_ = _nn(coord[ks])
    a = axis[ks]
    for i in range(3):
        u[i] = e0[i] - m0[i]
        v[i] = c[i] - m0[i]
    if kind == LEG_B1:
        ua, va = _dot(a0, u), _dot(a0, v)
        for i in range(3):
            u[i] -= ua * a0[i]
            v[i] -= va * a0[i]
    bq = _dot(a, u)
    cq = _dot(u, u) - _dot(v, v)
    ts = _quadratic_nearest(bq, cq, q[cs_] - q0[ks], 1e-12 * scale)
    if ts != ts:
        return False
    for i in range(3):
        u[i] = e0[i] - m0[i] + ts * a[i]
        v[i] = c[i] - m0[i]
    if kind == LEG_B1:
        q[c0] = q0[0] + _near(_sp1(a0, u, v), cur0)
    else:
        th0, th1 = _sp2(a0, a1, u, v, cur0, cur1, z, t3)
        if th0 != th0:
            return False
        q[c0] = q0[0] + th0
        q[c1] = q0[1] + th1
    q[cs_] = q0[ks] + ts
    return True


@njit(cache=True, _nrt=False)
def forward_positions(q, body_parent, body_joint, joint_q0, joint_nq, coord_motion, coord_offset, coord_sign,
                      RP, pP, RC, pC, R, p, S, w33, w3, trig, reuse, late, explicit):
    """Body poses ``R (nb, 3, 3)``, ``p (nb, 3)`` and coordinate twists ``S (nq, 6)`` at ``q``
    (frames ``RP, pP, RC, pC`` in tree order; coordinate c moves by ``coord_sign[c] (q - offset)``;
    ``w33 (5, 3, 3)``, ``w3 (20, 3)``: work space). ``trig (nq, 3)`` keeps each turning
    coordinate's cosine and sine (:func:`_cos_sin`); with ``reuse`` they are taken from the last
    pass where ``q`` moved little since (a Newton step). With ``explicit``, the bodies that an
    explicit leg moves (``late[b] >= 0``, :mod:`pkmdyn.multibody.model.legs`) are left for :func:`place_legs`."""
    Rf = w33[0]
    o = w3[18]
    for b in range(body_parent.shape[0]):
        if explicit and late[b] >= 0:
            continue
        _forward_body(b, q, body_parent, body_joint, joint_q0, joint_nq, coord_motion, coord_offset, coord_sign,
                      RP, pP, RC, pC, R, p, S, Rf, o, trig, reuse)


@njit(cache=True, _nrt=False)
def place_legs(q, body_parent, body_joint, joint_q0, joint_nq, coord_motion, coord_offset, coord_sign,
               RP, pP, RC, pC, R, p, S, w33, w3, trig, reuse, legs, xs, task, skip):  # pragma: no cover - compiled
    """After :func:`forward_positions` with ``explicit``: each leg of ``legs`` (:mod:`pkmdyn.multibody.model.legs`) in
    turn has its coordinates in ``q`` set in closed form, the leg that carries the task body
    from the task coordinates ``xs`` (:func:`_task_leg`; ``task`` the model's task arrays), the
    others from the body they meet (:func:`_explicit_leg`), and the bodies it moves placed.
    With ``skip``, the legs placed from the task alone (``fixed``) keep their coordinates, set
    by an earlier pass at the same ``xs``; of their bodies, those that only such coordinates move
    keep their poses, the others (hanging on coordinates that Newton moved) are placed again.
    Returns whether every such leg
    reached its point (False: one is left to Newton)."""
    redo, kind, fixed, fixed_coord = legs[11], legs[1], legs[17], legs[18]
    reached = True
    for L in range(redo.shape[0]):
        if skip and fixed[L] != 0:
            pass
        elif kind[L] >= LEG_TASK:
            if not _task_leg(L, xs, q, legs, task, RP, RC, pC, w3, w33) and fixed[L] != 0:
                reached = False
        elif not _explicit_leg(L, q, R, p, legs, w3) and fixed[L] != 0:
            reached = False
        Rf = w33[0]
        o = w3[18]
        for i in range(1, _nn(redo[L, 0] + 1)):
            b = redo[L, i]
            if skip and fixed[L] != 0 and _held_body(b, body_parent, body_joint, joint_q0, joint_nq, fixed_coord):
                continue  # only kept coordinates move it: placed by the earlier pass as it stands
            _forward_body(b, q, body_parent, body_joint, joint_q0, joint_nq, coord_motion, coord_offset,
                          coord_sign, RP, pP, RC, pC, R, p, S, Rf, o, trig, reuse)
    return reached


@njit(cache=True, inline="always")
def _held_body(b, body_parent, body_joint, joint_q0, joint_nq, fixed_coord):  # pragma: no cover - compiled
    """Whether every coordinate that moves body ``b`` is one the legs placed from the task
    alone set (``fixed_coord``)."""
    while b >= 0:
        b = _nn(b)
        k = _nn(body_joint[b])
        for c in range(_nn(joint_q0[k]), _nn(joint_q0[k] + joint_nq[k])):
            if fixed_coord[c] == 0:
                return False
        b = body_parent[b]
    return True


@njit(cache=True, _nrt=False)
def place_fixed_legs(q, body_parent, body_joint, joint_q0, joint_nq, coord_motion, coord_offset, coord_sign,
                     RP, pP, RC, pC, R, p, S, w33, w3, trig, legs, xs, task):  # pragma: no cover - compiled
    """The legs placed from the task alone (``fixed``, :mod:`pkmdyn.multibody.model.legs`) and nothing else: each in
    turn has its coordinates in ``q`` set in closed form from the task coordinates ``xs`` (the
    task leg) or from the body it meets (placed by an earlier such leg), and its bodies placed;
    the branch nearest the coordinates ``q`` holds. The coordinates such a leg sets are the
    ones the full solve gives (it solves these legs once per sample and keeps them). Returns
    False at the first that does not reach its point (``q`` then partly set)."""
    redo, kind, fixed = legs[11], legs[1], legs[17]
    Rf = w33[0]
    o = w3[18]
    for L in range(redo.shape[0]):
        if fixed[L] == 0:
            continue
        if kind[L] >= LEG_TASK:
            if not _task_leg(L, xs, q, legs, task, RP, RC, pC, w3, w33):
                return False
        elif not _explicit_leg(L, q, R, p, legs, w3):
            return False
        for i in range(1, _nn(redo[L, 0] + 1)):
            _forward_body(redo[L, i], q, body_parent, body_joint, joint_q0, joint_nq, coord_motion, coord_offset,
                          coord_sign, RP, pP, RC, pC, R, p, S, Rf, o, trig, False)
    return True


@njit(cache=True, inline="always")
def euler_matrix(axes, ang, out, t1, t2):  # pragma: no cover - compiled
    """``out = Rot_a1(ang_0) Rot_a2(ang_1) Rot_a3(ang_2)`` (intrinsic Euler angles about the axes
    ``axes``; ``t1, t2 (3, 3)`` work space): the task body's rotation from its task angles."""
    _rot(axes[0], ang[0], out)
    _rot(axes[1], ang[1], t1)
    _matmul3(out, t1, t2)
    _rot(axes[2], ang[2], t1)
    _matmul3(t2, t1, out)


@njit(cache=True, _nrt=False)
def _task_leg(L, xs, q, legs, task, RP, RC, pC, w3, w33):  # pragma: no cover - compiled
    """The leg ``L`` that carries the task body, in closed form from the task coordinates ``xs``
    (:mod:`pkmdyn.multibody.model.legs`): the task body's rotation ``R_T = Rot_a1(phi_1) Rot_a2(phi_2) Rot_a3(phi_3)``
    from its Euler angles; where the task gives the position too, the centre of the ball (the
    spherical joint that carries the task body) ``x - R_T t + R_T c`` (``t`` the task point,
    ``c`` the centre, task body frame) reached by the chain before the ball (:func:`_reach`),
    whose end body then has the rotation ``R_e`` (the product of its turns' exponentials times
    its reference rotation); the ball's three angles are the Euler angles, about its own axes,
    of ``R_b = (R_e R_P)^T R_T R_C`` (``R_P, R_C`` its frames on the two bodies, since the task
    body's rotation is ``R_e R_P R_b R_C^T``): of the two solutions, the one nearest the present
    ``q``. False where the ball's centre is out of reach (``q`` left to Newton)."""
    task_point, task_kind, task_index, euler_axes = task[1], task[2], task[3], task[4]
    kind, coord, axis, point, q0 = legs[1], legs[2], legs[6], legs[7], legs[10]
    ball, bax, boff, bsg, Rend0 = legs[12], legs[13], legs[14], legs[15], legs[16]
    RT, Re, Rt, Rb = w33[1], w33[2], w33[3], w33[4]
    ang, pos = w3[10], w3[11]
    for i in range(3):
        ang[i] = 0.0
        pos[i] = 0.0
    for t in range(task_kind.shape[0]):
        if task_kind[t] == 1:
            ang[_nn(task_index[t])] = xs[t]
        else:
            pos[_nn(task_index[t])] = xs[t]
    euler_matrix(euler_axes, ang, RT, Rt, Rb)
    k = _nn(ball[L, 0])
    for i in range(3):
        for j in range(3):
            Re[i, j] = Rend0[L, i, j]
    pk = kind[L] - LEG_TASK
    if pk > 0:
        c = w3[0]
        for i in range(3):
            c[i] = pos[i] + (RT[i, 0] * (pC[k, 0] - task_point[0]) + RT[i, 1] * (pC[k, 1] - task_point[1])
                             + RT[i, 2] * (pC[k, 2] - task_point[2]))
        if not _reach(pk, q, coord[L], axis[L], point[L], legs[8][L], legs[9][L], q0[L], w3):
            return False
        # R_e = exp(w_1 th_1) ... exp(w_n th_n) R_e0: the turns applied from the last
        n = 2 if pk == LEG_A1 or pk == LEG_B1 else 3
        for jj in range(n):
            j = n - 1 - jj
            if point[L, j, 0] == point[L, j, 0]:  # a turn (a slide has no axis point)
                _rot_axis(axis[L, j], q[_nn(coord[L, j])] - q0[L, j], Rt)
                _matmul3(Rt, Re, Rb)
                for i1 in range(3):
                    for i2 in range(3):
                        Re[i1, i2] = Rb[i1, i2]
    _matmul3(Re, RP[k], Rt)  # R_e R_P
    _matmul3(RT, RC[k], Re)  # R_T R_C
    for i in range(3):
        for j in range(3):
            Rb[i, j] = Rt[0, i] * Re[0, j] + Rt[1, i] * Re[1, j] + Rt[2, i] * Re[2, j]
    out = w3[12]
    euler_angles(Rb, bax[L], out)
    i0, i2 = bax[L, 0], bax[L, 2]
    # the second solution: (a1 + pi, pi - a2, a3 + pi) for three distinct axes, (a1 + pi, -a2, a3 + pi)
    # for a repeated one; the nearest to the present angles
    alt1 = (math.pi - out[1]) if i0 != i2 else -out[1]
    d1 = 0.0
    d2 = 0.0
    for i in range(3):
        cur = bsg[L, i] * (q[_nn(ball[L, 1 + i])] - boff[L, i])
        s1 = out[i]
        s2 = alt1 if i == 1 else out[i] + math.pi
        d1 += _wrap(s1 - cur) ** 2
        d2 += _wrap(s2 - cur) ** 2
    for i in range(3):
        cb = _nn(ball[L, 1 + i])
        cur = bsg[L, i] * (q[cb] - boff[L, i])
        th = out[i] if d1 <= d2 else (alt1 if i == 1 else out[i] + math.pi)
        q[cb] = boff[L, i] + bsg[L, i] * _near(th, cur)
    return True


@njit(cache=True, _nrt=False)
def _rot_axis(w, th, out):  # pragma: no cover - compiled
    """``out (3, 3)``: the rotation by ``th`` about the unit axis ``w`` (Rodrigues)."""
    c, s = math.cos(th), math.sin(th)
    v = 1.0 - c
    out[0, 0] = c + v * w[0] * w[0]
    out[1, 1] = c + v * w[1] * w[1]
    out[2, 2] = c + v * w[2] * w[2]
    out[0, 1] = v * w[0] * w[1] - s * w[2]
    out[1, 0] = v * w[0] * w[1] + s * w[2]
    out[0, 2] = v * w[0] * w[2] + s * w[1]
    out[2, 0] = v * w[0] * w[2] - s * w[1]
    out[1, 2] = v * w[1] * w[2] - s * w[0]
    out[2, 1] = v * w[1] * w[2] + s * w[0]


@njit(cache=True, _nrt=False, inline='always')
def _forward_body(b, q, body_parent, body_joint, joint_q0, joint_nq, coord_motion, coord_offset, coord_sign,
                  RP, pP, RC, pC, R, p, S, Rf, o, trig, reuse):
    """Body b's pose and its joint's coordinate twists (:func:`forward_positions`), its parent
    placed."""
    b = _nn(b)
    k = _nn(body_joint[b])
    _frame(body_parent[b], R, p, RP[k], pP[k], Rf, o)  # the joint frame on the parent, world
    for c in range(_nn(joint_q0[k]), _nn(joint_q0[k] + joint_nq[k])):
        m = _nn(coord_motion[c])
        mm = m % 3
        _unit_twist(S, c, coord_sign[c], m < 3, Rf[0, mm], Rf[1, mm], Rf[2, mm], o[0], o[1], o[2])
        qc = coord_sign[c] * (q[c] - coord_offset[c])
        if m < 3:
            cq, sq = _cos_sin(trig, c, qc, reuse)
            _turn(Rf, m, cq, sq)
        else:
            _slide(Rf, o, m, qc)
    for i in range(3):
        for j in range(3):
            R[b, i, j] = Rf[i, 0] * RC[k, j, 0] + Rf[i, 1] * RC[k, j, 1] + Rf[i, 2] * RC[k, j, 2]
    for i in range(3):
        p[b, i] = o[i] - (R[b, i, 0] * pC[k, 0] + R[b, i, 1] * pC[k, 1] + R[b, i, 2] * pC[k, 2])


@njit(cache=True, _nrt=False)
def forward_velocities(qd, body_parent, body_joint, joint_q0, joint_nq, S, V, Vpre):
    """Spatial velocities ``V (nb, 6)`` and the velocity ``Vpre (nq, 6)`` of the frame that
    carries each coordinate's twist."""
    for b in range(body_parent.shape[0]):
        k = _nn(body_joint[b])
        a = body_parent[b]
        for i in range(6):
            V[b, i] = V[_nn(a), i] if a >= 0 else 0.0
        for c in range(_nn(joint_q0[k]), _nn(joint_q0[k] + joint_nq[k])):
            for i in range(6):
                Vpre[c, i] = V[b, i]
                V[b, i] += S[c, i] * qd[c]


@njit(cache=True, _nrt=False)
def forward_accelerations(qd, body_parent, body_joint, joint_q0, joint_nq, S, Vpre, A):
    """The bias accelerations ``A (nb, 6)`` (those at ``qdd = 0``; :func:`add_joint_accelerations`
    adds the rest)."""
    for b in range(body_parent.shape[0]):
        k = _nn(body_joint[b])
        a = body_parent[b]
        for i in range(6):
            A[b, i] = A[_nn(a), i] if a >= 0 else 0.0
        for c in range(_nn(joint_q0[k]), _nn(joint_q0[k] + joint_nq[k])):
            w0, w1, w2 = Vpre[c, 0], Vpre[c, 1], Vpre[c, 2]
            v0, v1, v2 = Vpre[c, 3], Vpre[c, 4], Vpre[c, 5]
            s0, s1, s2 = S[c, 0], S[c, 1], S[c, 2]
            t0, t1, t2 = S[c, 3], S[c, 4], S[c, 5]
            d = qd[c]
            A[b, 0] += (w1 * s2 - w2 * s1) * d
            A[b, 1] += (w2 * s0 - w0 * s2) * d
            A[b, 2] += (w0 * s1 - w1 * s0) * d
            A[b, 3] += (w1 * t2 - w2 * t1 + v1 * s2 - v2 * s1) * d
            A[b, 4] += (w2 * t0 - w0 * t2 + v2 * s0 - v0 * s2) * d
            A[b, 5] += (w0 * t1 - w1 * t0 + v0 * s1 - v1 * s0) * d


@njit(cache=True, _nrt=False)
def add_joint_accelerations(qdd, body_parent, body_joint, joint_q0, joint_nq, S, A):
    """``A += `` the accelerations that ``qdd`` adds to the bias accelerations ``A (nb, 6)`` of
    :func:`forward_accelerations` (``sum S_c qdd_c`` over the coordinates of every joint from
    the body down to the ground)."""
    for b in range(body_parent.shape[0]):
        a = b
        while a >= 0:
            k = _nn(body_joint[_nn(a)])
            for c in range(_nn(joint_q0[k]), _nn(joint_q0[k] + joint_nq[k])):
                d = qdd[c]
                for i in range(6):
                    A[b, i] += S[c, i] * d
            a = body_parent[a]


@njit(cache=True, inline="always")
def _parity(i, j, k):
    return 1.0 if (i, j, k) in ((0, 1, 2), (1, 2, 0), (2, 0, 1)) else -1.0


@njit(cache=True, _nrt=False)
def euler_angles(Rm, axes, out):
    """Intrinsic Euler angles (3,) [rad] of ``Rm = R_a1(out0) R_a2(out1) R_a3(out2)``."""
    i, j, k = _nn(axes[0]), _nn(axes[1]), _nn(axes[2])
    if i != k:
        eps = _parity(i, j, k)
        x = eps * Rm[i, k]
        x = min(1.0, max(-1.0, x))
        out[1] = math.asin(x)
        out[0] = math.atan2(-eps * Rm[j, k], Rm[k, k])
        out[2] = math.atan2(-eps * Rm[i, j], Rm[i, i])
    else:
        kk = 3 - i - j
        eps = _parity(i, j, kk)
        x = min(1.0, max(-1.0, Rm[i, i]))
        out[1] = math.acos(x)
        out[0] = math.atan2(Rm[j, i], -eps * Rm[kk, i])
        out[2] = math.atan2(Rm[i, j], eps * Rm[i, kk])


@njit(cache=True, _nrt=False)
def euler_rate_map(ang, axes, E):
    """``E (3, 3)``: omega = E phi_dot, columns ``k1, R1 k2, R1 R2 k3`` (base frame)."""
    i1, i2, i3 = _nn(axes[0]), _nn(axes[1]), _nn(axes[2])
    c1, s1 = math.cos(ang[0]), math.sin(ang[0])
    c2, s2 = math.cos(ang[1]), math.sin(ang[1])
    for r in range(3):
        E[r, 0] = 1.0 if r == i1 else 0.0
        E[r, 1] = 1.0 if r == i2 else 0.0
        E[r, 2] = 1.0 if r == i3 else 0.0
    # column 1: R1 k2
    j, k = (i1 + 1) % 3, (i1 + 2) % 3
    xj, xk = E[j, 1], E[k, 1]
    E[j, 1] = c1 * xj - s1 * xk
    E[k, 1] = s1 * xj + c1 * xk
    # column 2: R1 (R2 k3)
    j, k = (i2 + 1) % 3, (i2 + 2) % 3
    xj, xk = E[j, 2], E[k, 2]
    E[j, 2] = c2 * xj - s2 * xk
    E[k, 2] = s2 * xj + c2 * xk
    j, k = (i1 + 1) % 3, (i1 + 2) % 3
    xj, xk = E[j, 2], E[k, 2]
    E[j, 2] = c1 * xj - s1 * xk
    E[k, 2] = s1 * xj + c1 * xk


@njit(cache=True, inline="always")
def _inv3(M, out):
    """Inverse of a 3 x 3 matrix; returns the determinant (out untouched when it is 0)."""
    det = (M[0, 0] * (M[1, 1] * M[2, 2] - M[1, 2] * M[2, 1]) - M[0, 1] * (M[1, 0] * M[2, 2] - M[1, 2] * M[2, 0])
           + M[0, 2] * (M[1, 0] * M[2, 1] - M[1, 1] * M[2, 0]))
    if det == 0.0:
        return det
    out[0, 0] = (M[1, 1] * M[2, 2] - M[1, 2] * M[2, 1]) / det
    out[0, 1] = (M[0, 2] * M[2, 1] - M[0, 1] * M[2, 2]) / det
    out[0, 2] = (M[0, 1] * M[1, 2] - M[0, 2] * M[1, 1]) / det
    out[1, 0] = (M[1, 2] * M[2, 0] - M[1, 0] * M[2, 2]) / det
    out[1, 1] = (M[0, 0] * M[2, 2] - M[0, 2] * M[2, 0]) / det
    out[1, 2] = (M[0, 2] * M[1, 0] - M[0, 0] * M[1, 2]) / det
    out[2, 0] = (M[1, 0] * M[2, 1] - M[1, 1] * M[2, 0]) / det
    out[2, 1] = (M[0, 1] * M[2, 0] - M[0, 0] * M[2, 1]) / det
    out[2, 2] = (M[0, 0] * M[1, 1] - M[0, 1] * M[1, 0]) / det
    return det


@njit(cache=True, inline="always")
def _frame(b, R, p, Rj, pj, e, o):
    """Joint frame axes ``e (3, 3)`` (columns) and origin ``o (3,)`` in the world, on body b."""
    if b < 0:
        for i in range(3):
            o[i] = pj[i]
            for j in range(3):
                e[i, j] = Rj[i, j]
    else:
        b = _nn(b)
        _matmul3(R[b], Rj, e)
        for i in range(3):
            o[i] = p[b, i] + R[b, i, 0] * pj[0] + R[b, i, 1] * pj[1] + R[b, i, 2] * pj[2]


@njit(cache=True, inline="always")
def _direction_motion(b, u, V, A, ud, udd, t3):  # pragma: no cover - compiled
    """Rate ``ud = w x u`` and acceleration ``udd = wd x u + w x (w x u)`` of a direction ``u``
    fixed in body ``b`` (twist ``V[b]``, its rate ``A[b]``, angular part first); zero for the
    ground (``b < 0``). ``t3``: work space."""
    if b >= 0:
        b = _nn(b)
        _cross(V[b, :3], u, ud)
        _cross(V[b, :3], ud, t3)
        _cross(A[b, :3], u, udd)
        for m in range(3):
            udd[m] += t3[m]
    else:
        for m in range(3):
            ud[m] = 0.0
            udd[m] = 0.0


@njit(cache=True, inline="always")
def _point_motion(b, x, V, A, v, a):
    """Velocity ``v`` and acceleration ``a`` of the world point ``x`` fixed in body b."""
    if b < 0:
        for i in range(3):
            v[i] = 0.0
            a[i] = 0.0
        return
    b = _nn(b)
    w = V[b, :3]
    wd = A[b, :3]
    v[0] = V[b, 3] + w[1] * x[2] - w[2] * x[1]
    v[1] = V[b, 4] + w[2] * x[0] - w[0] * x[2]
    v[2] = V[b, 5] + w[0] * x[1] - w[1] * x[0]
    a[0] = A[b, 3] + wd[1] * x[2] - wd[2] * x[1] + w[1] * v[2] - w[2] * v[1]
    a[1] = A[b, 4] + wd[2] * x[0] - wd[0] * x[2] + w[2] * v[0] - w[0] * v[2]
    a[2] = A[b, 5] + wd[0] * x[1] - wd[1] * x[0] + w[0] * v[1] - w[1] * v[0]


@njit(cache=True, inline="always")
def _jrow(J, i, colpos, wa, wb, S, anc, a, b, coef_a, coef_b):
    """Jacobian row ``J[i, colpos[c]] = (coef_b [c moves b] + coef_a [c moves a]) (wa . S_w + wb .
    S_v)`` (nothing where ``i < 0``: a row the Newton system leaves out); ``anc[b] = (count,
    coordinates moving body b...)``."""
    if i < 0:
        return
    i = _nn(i)
    for j in range(J.shape[1]):
        J[i, j] = 0.0
    for body, coef in ((a, coef_a), (b, coef_b)):
        if body < 0 or coef == 0.0:
            continue
        body = _nn(body)
        for k in range(1, _nn(anc[body, 0] + 1)):
            c = _nn(anc[body, k])
            J[i, _nn(colpos[c])] += coef * (wa[0] * S[c, 0] + wa[1] * S[c, 1] + wa[2] * S[c, 2]
                                             + wb[0] * S[c, 3] + wb[1] * S[c, 4] + wb[2] * S[c, 5])


@njit(cache=True, inline="always")
def _settled(b, anc, settled):
    """Whether only coordinates with ``settled[c] != 0`` move body ``b`` (the ground: True)."""
    if b < 0:
        return True
    b = _nn(b)
    for k in range(1, _nn(anc[b, 0] + 1)):
        if settled[_nn(anc[b, k])] == 0:
            return False
    return True


@njit(cache=True, _nrt=False)
def rows(R, p, S, anc, row_loop, row_kind, row_i, row_j, loop_joint, joint_parent, joint_child,
         RP, pP, RC, pC, task_body, task_point, task_kind, task_index, euler_axes, q,
         val, J, rowpos, colpos, mode, V, A, gamma, w33, w3, settled=None):
    """Values ``val (nr + nt,)`` and, by ``mode``: the Jacobian (``ROWS_JACOBIAN``), row ``rr``
    and column ``c`` at ``J[rowpos[rr], colpos[c]]`` (rows with ``rowpos < 0`` left out: the
    solver writes the rows it solves straight into its permuted matrix); the drift ``gamma
    (nr + nt,)`` from the bias accelerations ``A`` (qdd = 0) and velocities ``V``
    (``ROWS_DRIFT``); nothing more (``ROWS_VALUES``).

    Jacobian rows in Plücker form: a translation row ``e . (o_C - o_P)`` changes with tree
    rate c by ``(s_b - s_a) (e . S_v - (e x o_C) . S_w)`` (s_a, s_b: 1 where c moves body a, b;
    the terms of ``o_P`` and of the turning ``e`` cancel into this), a rotation row
    ``e . c_j`` by ``(s_a - s_b) (e x c_j) . S_w``, a task position component m of point x by
    ``S_v[m] + (x x e_m) . S_w``, a task Euler angle by ``(E^-1 S_w)[m]``, a task joint
    coordinate ``q[c]`` (``q`` the tree coordinates) by the unit row of c, with no drift.

    With ``settled (nq,)`` (``ROWS_VALUES`` only): the rows of a joint, or the task rows, whose
    bodies only coordinates with ``settled[c] != 0`` move (legs placed from the task alone,
    :mod:`pkmdyn.multibody.model.legs`) are not evaluated: their values are NaN.

    Returns False where an Euler task angle is at its sequence's singularity."""
    nr = row_loop.shape[0]
    eP = w33[3]
    eC = w33[4]
    wk = w3
    oP, oC, r, t3, e, cj = wk[0], wk[1], wk[2], wk[3], wk[4], wk[5]
    vP, aP, vC, aC, ed, edd = wk[6], wk[7], wk[8], wk[9], wk[10], wk[11]
    cd, cdd, x, wa, wb, t4 = wk[12], wk[13], wk[14], wk[15], wk[16], wk[17]
    last = -1
    for rr in range(nr):
        k = _nn(loop_joint[_nn(row_loop[rr])])
        a = joint_parent[k]
        b = joint_child[k]
        if settled is not None and _settled(a, anc, settled) and _settled(b, anc, settled):
            val[rr] = np.nan
            continue
        if k != last:
            _frame(a, R, p, RP[k], pP[k], eP, oP)
            _frame(b, R, p, RC[k], pC[k], eC, oC)
            if mode == ROWS_DRIFT:  # the joint points' motion, shared by the joint's rows
                _point_motion(a, oP, V, A, vP, aP)
                _point_motion(b, oC, V, A, vC, aC)
            last = k
        i = _nn(row_i[rr])
        for m in range(3):
            e[m] = eP[m, i]
            r[m] = oC[m] - oP[m]
        if row_kind[rr] == 0:
            val[rr] = _dot(e, r)
            _cross(e, oC, t3)
            for m in range(3):
                wa[m] = -t3[m]
                wb[m] = e[m]
            if mode == ROWS_JACOBIAN:
                _jrow(J, rowpos[rr], colpos, wa, wb, S, anc, a, b, -1.0, 1.0)
        else:
            for m in range(3):
                cj[m] = eC[m, _nn(row_j[rr])]
            val[rr] = _dot(e, cj)
            _cross(e, cj, wa)
            for m in range(3):
                wb[m] = 0.0
            if mode == ROWS_JACOBIAN:
                _jrow(J, rowpos[rr], colpos, wa, wb, S, anc, a, b, 1.0, -1.0)
        if mode == ROWS_DRIFT:
            _direction_motion(a, e, V, A, ed, edd, t3)
            if row_kind[rr] == 0:
                g = _dot(edd, r)
                for m in range(3):
                    g += 2.0 * ed[m] * (vC[m] - vP[m]) + e[m] * (aC[m] - aP[m])
                gamma[rr] = g
            else:
                _direction_motion(b, cj, V, A, cd, cdd, t3)
                gamma[rr] = _dot(edd, cj) + 2.0 * _dot(ed, cd) + _dot(e, cdd)
    # task rows: a joint's coordinate first, then the task body's (none where its body is settled)
    body_rows = False
    for t in range(task_kind.shape[0]):
        rr = nr + t
        if task_kind[t] != 2:
            body_rows = True
            continue
        c = _nn(task_index[t])
        if settled is not None and settled[c] != 0:
            val[rr] = np.nan
            continue
        val[rr] = q[c]
        if mode == ROWS_JACOBIAN and rowpos[rr] >= 0:
            i = _nn(rowpos[rr])
            for j in range(J.shape[1]):
                J[i, j] = 0.0
            J[i, _nn(colpos[c])] = 1.0
        if mode == ROWS_DRIFT:
            gamma[rr] = 0.0
    tb = _nn(task_body)
    if not body_rows:
        return True
    if settled is not None and _settled(tb, anc, settled):
        for t in range(task_kind.shape[0]):
            if task_kind[t] != 2:
                val[nr + t] = np.nan
        return True
    for m in range(3):
        x[m] = p[tb, m] + R[tb, m, 0] * task_point[0] + R[tb, m, 1] * task_point[1] + R[tb, m, 2] * task_point[2]
    ang = w33[2, 0]  # not shared with the row work space
    Em = eP
    Ei = eC
    have_euler = False
    for t in range(task_kind.shape[0]):
        if task_kind[t] == 1:
            have_euler = True
    ok = True
    if have_euler:
        euler_angles(R[tb], euler_axes, ang)
    if have_euler and mode != ROWS_VALUES:
        euler_rate_map(ang, euler_axes, Em)
        det = _inv3(Em, Ei)
        if abs(det) < 1e-9:
            ok = False
            for i in range(3):
                for j in range(3):
                    Ei[i, j] = 0.0
    for t in range(task_kind.shape[0]):
        rr = nr + t
        m = _nn(task_index[t])
        if task_kind[t] == 2:
            continue
        if task_kind[t] == 0:
            val[rr] = x[m]
            # (x x e_m) . S_w + S_v[m]
            for i in range(3):
                t4[i] = 0.0
                wb[i] = 0.0
            t4[m] = 1.0
            _cross(x, t4, wa)
            wb[m] = 1.0
            if mode == ROWS_JACOBIAN:
                _jrow(J, rowpos[rr], colpos, wa, wb, S, anc, -1, tb, 0.0, 1.0)
            if mode == ROWS_DRIFT:
                _point_motion(tb, x, V, A, vC, aC)
                gamma[rr] = aC[m]
        else:
            val[rr] = ang[m]
            for i in range(3):
                wa[i] = Ei[m, i]
                wb[i] = 0.0
            if mode == ROWS_JACOBIAN:
                _jrow(J, rowpos[rr], colpos, wa, wb, S, anc, -1, tb, 0.0, 1.0)
            if mode == ROWS_DRIFT:
                # phi_dd = E^-1 (omega_dot - Edot phi_dot), Edot phi_dot = (k1 f1) x (e2 f2) + (k1 f1 + e2 f2) x (e3 f3)
                w = V[tb, :3]
                f = wk[10]
                for i in range(3):
                    f[i] = Ei[i, 0] * w[0] + Ei[i, 1] * w[1] + Ei[i, 2] * w[2]
                u1, u2, u12 = wk[11], wk[12], wk[13]
                for i in range(3):
                    u1[i] = Em[i, 0] * f[0]
                    u2[i] = Em[i, 1] * f[1]
                    u12[i] = u1[i] + u2[i]
                    e[i] = Em[i, 2] * f[2]
                _cross(u1, u2, t3)
                _cross(u12, e, cd)
                for i in range(3):
                    cdd[i] = A[tb, i] - t3[i] - cd[i]
                gamma[rr] = Ei[m, 0] * cdd[0] + Ei[m, 1] * cdd[1] + Ei[m, 2] * cdd[2]
    return ok



@njit(cache=True)
def jacobians_batch(q, body_parent, body_joint, joint_q0, joint_nq, coord_motion, coord_offset, coord_sign,
                    tRP, tpP, tRC, tpC, RP, pP, RC, pC, anc,
                    row_loop, row_kind, row_i, row_j, loop_joint, joint_parent, joint_child,
                    task_body, task_point, task_kind, task_index, euler_axes, val_out, J_out):
    """Row values ``val_out (n, nr + nt)`` and Jacobians ``J_out (n, nr + nt, nq)`` at ``q (n, nq)``."""
    nb = body_parent.shape[0]
    nq = q.shape[1]
    R = np.empty((nb, 3, 3))
    p = np.empty((nb, 3))
    S = np.empty((nq, 6))
    V = np.zeros((nb, 6))
    A = np.zeros((nb, 6))
    gamma = np.zeros(val_out.shape[1])
    w33 = np.empty((5, 3, 3))
    w3 = np.empty((20, 3))
    rowpos = np.arange(val_out.shape[1])
    colpos = np.arange(nq)
    trig = np.empty((nq, 3))
    late = np.full(nb, -1, dtype=np.int64)
    # flags and modes as run-time values, not constants: a constant argument is typed as a
    # literal, and each literal would compile another copy of the callee
    off = nq < 0
    jac = ROWS_JACOBIAN + 0 * nq
    for s in range(q.shape[0]):
        forward_positions(q[s], body_parent, body_joint, joint_q0, joint_nq, coord_motion, coord_offset,
                          coord_sign, tRP, tpP, tRC, tpC, R, p, S, w33, w3, trig, off, late, off)
        rows(R, p, S, anc, row_loop, row_kind, row_i, row_j, loop_joint, joint_parent, joint_child,
             RP, pP, RC, pC, task_body, task_point, task_kind, task_index, euler_axes, q[s],
             val_out[s], J_out[s], rowpos, colpos, jac, V, A, gamma, w33, w3)
