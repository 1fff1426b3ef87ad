"""One sample of a described mechanism's dynamics in one compiled call: the real-time path
behind :meth:`pkmdyn.multibody.dynamics.verbs.MechanismVerbs.forward_dynamics_one` and ``inverse_dynamics_one``.

The model's arrays, the kernel's state and its work space are packed once into one buffer
(:func:`pack`), so that a call passes a handful of arguments whatever the mechanism; the
kernel takes them as views and runs, for task pose ``x`` and rate ``xd``:

1. the tree coordinates and rates at ``xdd = 0`` (:func:`pkmdyn.multibody.kinematics._solve_kernels.solve_sample`, the batched
   solver's own sample): from the previous call's solution, the predictor
   ``q_prev + G_prev dx + s^2 qdd_prev / 2`` (``dx = x - x_prev``; ``qdd_prev`` the previous
   call's bias accelerations at ``xd_prev``, ``s = dx . xd_prev / |xd_prev|^2``: the second
   order along the previous motion), one simplified Newton step with the previous call's
   factors (left out for a few calls after one where it fell short), Newton, which checks
   the solution with one evaluation, then ``G = dq/dx``,
   ``qd = G xd`` and the bias accelerations;
2. the joints' friction of known magnitude from the relative twists;
3. the bodies' required wrenches at the bias motion with gravity and loads (Eq. 1 of
   :mod:`pkmdyn.multibody.dynamics.newton_euler`), the tree forces (Eq. 2) and ``h = G^T Q``;
4. the task mass matrix ``M = sum_b T_b^T I_b T_b``;
5. the drives' rotor inertia, bias and motor friction (:mod:`pkmdyn.multibody.dynamics.actuators`, Eq. A1) added to
   ``M`` and ``h``;
6. forward: ``M xdd = J_ax^T k tau - h``; inverse: ``J_ax^T k tau = M xdd + h`` (``tau`` the
   motor efforts, ``k`` the transmission ratios: 1 for a joint without a drive).

These are the verbs' definitions (idle freedoms held, as the kinematics hold them), with the
joints' Coulomb, viscous and named-load friction (:func:`pkmdyn.multibody.dynamics._dyn_kernels.joint_friction`) and
at most one named load, whose magnitude is the call's ``load``. A mechanism with friction
that depends on the joints' reactions, several named loads, joint springs or more actuators
than task coordinates takes the verbs' own route (:func:`supported`). A call returns a
nonzero status where it cannot answer (no previous solution yet, Newton failed, a singular
matrix); the caller then repeats the sample through the checked verb, which raises the error
or primes the kernel's state (:func:`prime`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic
from numba.np.arrayobj import make_array, populate_array
from numpy.typing import NDArray

from ... import _dense
from ..._dense import solve_in_place
from .. import _cache
from ..kinematics import _solve_kernels as _kernels
from ..kinematics._solve_kernels import _wrap, chord_pause, solve_sample, solver_positions, task_unit_rhs
from ..kinematics.inverse import CHECK_TOLERANCE, MAX_ITER, TOLERANCE, row_scale
from ..model import _tree_kernels
from ..model._tree_kernels import OK, _nn, _point_motion, place_fixed_legs
from ..model.compiler import MechanismModel
from . import _dyn_kernels, friction
from . import newton_euler as dynamics
from ._dyn_kernels import body_wrench, generalised, joint_friction, load_wrench, task_mass
from .actuators import motor_eps
from .friction import EPS_ROTATION as EPS_R
from .friction import EPS_TRANSLATION as EPS_T
from .friction import friction_arrays
from .newton_euler import SINGULAR_ACTUATION, inertia_factors

__all__ = ["pack", "supported", "state", "prime", "solution", "forward_one", "inverse_one", "positions_one",
           "actuator_maps", "COLD", "ALONE"]

Array = NDArray[np.float64]

#: status of a call without a previous solution to start from
COLD = 10
#: status of a singular mass matrix or actuator map
SINGULAR_DYNAMICS = 11
#: status of a non-finite input
BAD_INPUT = 12
#: status of a work space shorter than the kernel's views (a defect of :func:`_sizes`)
SHORT_WORK = 13
#: what a call of the kernel computes: the task accelerations, the efforts, the actuated
#: coordinates alone, the actuated coordinates' rates per task rate (``J_ax``, :func:`actuator_maps`)
FORWARD, INVERSE, POSITIONS, MAP = 1, 0, 2, 3

_INT = ("body_parent", "body_joint", "joint_q0", "joint_nq", "coord_motion", "ancestor_list", "row_loop", "row_kind",
        "row_i", "row_j", "loop_joint", "joint_parent", "joint_child", "task_kind", "task_index", "euler_axes",
        "solver_rows", "solver_prow", "solver_pcol", "solver_blocks", "act_coord", "load_body",
        "fj", "fch", "fpa", "frot", "fslide", "fidx", "fcnt", "eload", "load_named", "solver_rowpos",
        "solver_colpos", "solver_idlepos", "leg_late", "leg_kind", "leg_coord", "leg_base", "leg_placed", "leg_redo",
        "leg_ball", "leg_ball_axes", "leg_fixed", "leg_fixed_coord")
_FLOAT = ("coord_offset", "coord_sign", "tree_R_parent", "tree_p_parent", "tree_R_child", "tree_p_child",
          "joint_R_parent", "joint_p_parent", "joint_R_child", "joint_p_child", "task_point", "solver_idle",
          "row_scale", "mass", "inertia", "com", "gravity", "load_point", "load_force", "load_moment",
          "coef", "fsc", "ecoef", "eoff", "load_direction", "inertia_factor", "task_rhs", "drive_ratio", "drive_rotor",
          "drive_coulomb", "drive_viscous", "drive_eps", "leg_cpt", "leg_axis", "leg_point", "leg_m0", "leg_e0", "leg_q0",
          "leg_ball_offset", "leg_ball_sign", "leg_R_end0")
#: header of the packed buffer: n_int, n_float, task_body, max_iter, nq, nt, and the offsets
#: of the two tolerances, the state, the work space and the integer work space
_HEAD = 10


def supported(model: MechanismModel) -> bool:
    """Whether the kernel answers for ``model`` (module docstring)."""
    known = all(not f or not f.get("coefficient", 0.0) for f in model.joint_friction)
    springs = any(sp is not None for sp in model.joint_spring)  # the generic route carries them
    return known and not springs and model.na == model.nt and len(model.named_loads) <= 1


def _sizes(model: MechanismModel) -> tuple[int, int, int]:
    """Lengths of the state, the work space and the integer work space (:func:`pack`)."""
    nq, nt, nb = model.nq, model.nt, model.nb
    nrow = model.row_loop.shape[0] + nt
    mk = nq
    nstate = 1 + nq + nt + nq * nt + nq + nt + 1
    nwork = (nb * 9 + nb * 3 + nq * 6 + nrow + nrow + mk * mk + mk + mk + mk + 2 * nq + nb * 6
             + nq * 6 + nb * 6 + nrow + 45 + 60 + nb * 6 + nq + nb * 6 * nt + 9 + 9 + 6 * nb * nt + nt * nt + nt * nt
             + 2 * nt + 12 + 3 + mk * nt + nq + nb * 3 + 3 * nq)
    return nstate, nwork, 2 * mk


def pack(model: MechanismModel) -> NDArray[np.int64]:
    """One buffer ``pk`` (int64) with everything a call reads and writes: a header of offsets
    and shapes, the model's integer arrays, its float arrays (their bits), the kernel's state
    (:func:`state`) and its work space. One buffer makes a call pass few arguments, and the
    kernel takes its views by pointer arithmetic (:func:`_fview`), with no allocation."""

    arrays = {k: getattr(model, k) for k in _INT + _FLOAT if hasattr(model, k)}
    arrays["row_scale"] = row_scale(model)
    arrays["inertia_factor"] = inertia_factors(model)
    arrays["task_rhs"] = np.empty((model.nq, model.nt))
    task_unit_rhs(model.solver_rows, model.row_loop.shape[0], arrays["task_rhs"])
    arrays.update(friction_arrays(model))
    arrays["load_named"] = np.array([nm is not None for nm in model.load_name], dtype=np.int64)
    arrays["drive_eps"] = motor_eps(model)
    if not model.has_drives:  # no drive: empty arrays, and the kernel's drive terms do nothing
        for k in ("drive_ratio", "drive_rotor", "drive_coulomb", "drive_viscous", "drive_eps"):
            arrays[k] = np.zeros(0)
    lg = model.legs
    arrays.update({"leg_late": lg.late, "leg_kind": lg.kind, "leg_coord": lg.coord, "leg_base": lg.base,
                   "leg_placed": lg.placed, "leg_redo": lg.redo, "leg_cpt": lg.cpt, "leg_axis": lg.axis,
                   "leg_point": lg.point, "leg_m0": lg.m0, "leg_e0": lg.e0, "leg_q0": lg.q0, "leg_ball": lg.ball,
                   "leg_ball_axes": lg.ball_axes, "leg_ball_offset": lg.ball_offset, "leg_ball_sign": lg.ball_sign,
                   "leg_R_end0": lg.R_end0, "leg_fixed": lg.fixed, "leg_fixed_coord": lg.fixed_coord})
    arrays["solver_rowpos"] = np.empty(model.row_loop.shape[0] + model.nt, dtype=np.int64)
    arrays["solver_colpos"] = np.empty(model.nq, dtype=np.int64)
    arrays["solver_idlepos"] = np.empty(model.solver_idle.shape[0], dtype=np.int64)
    solver_positions(model.solver_rows, model.solver_prow, model.solver_pcol, arrays["solver_rowpos"],
                     arrays["solver_colpos"], arrays["solver_idlepos"])
    nstate, nwork, nwi = _sizes(model)
    head = [len(_INT), len(_FLOAT), int(model.task_body), int(MAX_ITER), int(model.nq), int(model.nt), 0, 0, 0, 0]
    parts: list[NDArray[np.int64]] = []
    at = _HEAD + 4 * (len(_INT) + len(_FLOAT))

    def put(a: NDArray) -> int:
        nonlocal at
        parts.append(a.ravel().view(np.int64))
        at += a.size
        return at - a.size

    for k in _INT:
        a = np.ascontiguousarray(arrays[k], dtype=np.int64)
        head += [put(a), *(list(a.shape) + [1] * (3 - a.ndim))]
    for k in _FLOAT:
        a = np.ascontiguousarray(arrays[k], dtype=float)
        head += [put(a), *(list(a.shape) + [1] * (3 - a.ndim))]
    head[6] = put(np.array([TOLERANCE, CHECK_TOLERANCE]))
    head[7] = put(np.zeros(nstate))
    head[8] = put(np.zeros(nwork))
    head[9] = put(np.zeros(nwi, dtype=np.int64))
    return np.concatenate([np.array(head, dtype=np.int64), *parts])


#: the state's first entry: nothing known, a solution (:func:`prime`), a solution with the
#: factors of its Jacobian in the work space and its bias accelerations (after a call), the
#: legs placed from the task alone solved at the last ``x`` and every other coordinate of an
#: earlier solution (after :func:`positions_one`'s closed forms alone)
COLD_STATE, PRIMED, FACTORED, ALONE = 0.0, 1.0, 2.0, 3.0


def state(pk: NDArray[np.int64]) -> Array:
    """The kernel's state in ``pk`` (a view): ``[flag, q (nq), x (nt), G (nq nt), qdd (nq),
    xd (nt), pause]`` of the last solved sample (``flag`` :data:`COLD_STATE`, :data:`PRIMED` or
    :data:`FACTORED`; ``qdd`` its bias accelerations at ``xd``; ``pause`` the calls left
    without the simplified Newton step, :func:`pkmdyn.multibody.kinematics._solve_kernels.chord_pause`)."""
    nq, nt = int(pk[4]), int(pk[5])
    o = int(pk[7])
    return pk[o:o + 1 + nq + nt + nq * nt + nq + nt + 1].view(np.float64)


def prime(pk: NDArray[np.int64], q: Array, x: Array, G: Array) -> None:
    """Set the kernel's previous solution (after the checked route solved a sample)."""
    st = state(pk)
    nq, nt = q.shape[0], x.shape[0]
    st[0] = PRIMED
    st[1:1 + nq] = q
    st[1 + nq:1 + nq + nt] = x
    st[1 + nq + nt:1 + nq + nt + nq * nt] = G.ravel()


def solution(pk: NDArray[np.int64]) -> Array | None:
    """The tree coordinates of the solved sample the kernel holds (a copy), or None."""
    st = state(pk)
    return st[1:1 + int(pk[4])].copy() if st[0] != COLD_STATE else None


def _view_codegen(nd: int, dtype: types.Type):  # pragma: no cover - compiled
    """Code of a C-contiguous ``nd``-dimensional ``dtype`` view of a buffer from an element
    offset and a shape (:func:`_fview`, :func:`_iview`)."""
    ret = types.Array(dtype, nd, "C")

    def codegen(context, builder, sig, args):
        src = make_array(sig.args[0])(context, builder, value=args[0])
        lty = context.get_data_type(dtype)
        data = builder.bitcast(builder.gep(src.data, [args[1]]), lty.as_pointer())
        shape = cgutils.unpack_tuple(builder, args[2], nd)
        itemsize = context.get_constant(types.intp, context.get_abi_sizeof(lty))
        strides = [itemsize]
        for n in reversed(shape[1:]):
            strides.insert(0, builder.mul(strides[0], n))
        view = make_array(ret)(context, builder)
        populate_array(view, data=data, shape=shape, strides=strides, itemsize=itemsize, meminfo=None)
        return view._getvalue()

    return ret, codegen


@intrinsic
def _fview(typingctx, buf, offset, shape):  # pragma: no cover - compiled
    """A float64 view of the 8-byte buffer ``buf`` from element ``offset``, of ``shape`` (a
    tuple): pointer arithmetic only, where a slice and ``reshape`` call numba's helpers (some
    10 ns per view, and a call takes some 60 views). The caller keeps it within ``buf``."""
    ret, codegen = _view_codegen(len(shape), types.float64)
    return ret(buf, offset, shape), codegen


@intrinsic
def _iview(typingctx, buf, offset, shape):  # pragma: no cover - compiled
    """:func:`_fview` as an int64 view."""
    ret, codegen = _view_codegen(len(shape), types.int64)
    return ret(buf, offset, shape), codegen


@njit(cache=True, inline="always")
def _i(pk, k):  # pragma: no cover - compiled
    h = _HEAD + 4 * k
    return _iview(pk, pk[h], (pk[h + 1] * pk[h + 2] * pk[h + 3],))


@njit(cache=True, inline="always")
def _i2(pk, k):  # pragma: no cover - compiled
    h = _HEAD + 4 * k
    return _iview(pk, pk[h], (pk[h + 1], pk[h + 2]))


@njit(cache=True, inline="always")
def _f(pk, k):  # pragma: no cover - compiled
    h = _HEAD + 4 * (pk[0] + k)
    return _fview(pk, pk[h], (pk[h + 1] * pk[h + 2] * pk[h + 3],))


@njit(cache=True, inline="always")
def _f2(pk, k):  # pragma: no cover - compiled
    h = _HEAD + 4 * (pk[0] + k)
    return _fview(pk, pk[h], (pk[h + 1], pk[h + 2]))


@njit(cache=True, inline="always")
def _f33(pk, k):  # pragma: no cover - compiled
    """The packed (n, 3, 3) array ``k``, its 3s constants of the compiled code (the compiler
    then folds them into the indexing)."""
    h = _HEAD + 4 * (pk[0] + k)
    return _fview(pk, pk[h], (pk[h + 1], 3, 3))


@njit(cache=True, inline="always")
def _fn3(pk, k):  # pragma: no cover - compiled
    """:func:`_f2` of an (n, 3) array, its 3 a constant of the compiled code."""
    h = _HEAD + 4 * (pk[0] + k)
    return _fview(pk, pk[h], (pk[h + 1], 3))


@njit(cache=True, inline="always")
def _take1(pk, o, n):  # pragma: no cover - compiled
    return _fview(pk, o, (n,)), o + n


@njit(cache=True, inline="always")
def _take2(pk, o, a, b):  # pragma: no cover - compiled
    return _fview(pk, o, (a, b)), o + a * b


@njit(cache=True, inline="always")
def _take3(pk, o, a, b, c):  # pragma: no cover - compiled
    return _fview(pk, o, (a, b, c)), o + a * b * c


@njit(cache=True, _nrt=False)
def _dynamics(pk, x, xd, v, load, mode, out):  # pragma: no cover - compiled
    """The kernel (module docstring); ``mode`` :data:`FORWARD`, :data:`INVERSE` or
    :data:`POSITIONS` (step 1 alone: the actuated coordinates into ``out``, ``v`` unused);
    ``v`` is ``u`` (forward) or ``xdd`` (inverse); writes the
    other into ``out``; returns the status (0 OK)."""
    nq, nt = pk[4], pk[5]
    st = _fview(pk, pk[7], (1 + nq + nt + nq * nt + nq + nt + 1,))
    if st[0] == COLD_STATE:
        return COLD
    for t in range(x.shape[0]):
        if not (np.isfinite(x[t]) and np.isfinite(xd[t]) and np.isfinite(v[t])):
            return BAD_INPUT  # the checked verb names it
    # ---- the model's arrays (views of the packed buffers)
    body_parent, body_joint, joint_q0, joint_nq, coord_motion = _i(pk, 0), _i(pk, 1), _i(pk, 2), _i(pk, 3), _i(pk, 4)
    anc = _i2(pk, 5)
    row_loop, row_kind, row_i, row_j = _i(pk, 6), _i(pk, 7), _i(pk, 8), _i(pk, 9)
    loop_joint, joint_parent, joint_child = _i(pk, 10), _i(pk, 11), _i(pk, 12)
    task_kind, task_index, euler_axes = _i(pk, 13), _i(pk, 14), _i(pk, 15)
    sel_rows, prow, pcol, blocks = _i(pk, 16), _i(pk, 17), _i(pk, 18), _i(pk, 19)
    act_coord, load_body = _i(pk, 20), _i(pk, 21)
    fj, fch, fpa, frot, fslide = _i(pk, 22), _i(pk, 23), _i(pk, 24), _i(pk, 25), _i(pk, 26)
    fidx = _i2(pk, 27)
    fcnt = _i(pk, 28)
    eload = _i2(pk, 29)
    load_named = _i(pk, 30)
    rowpos, colpos, idlepos = _i(pk, 31), _i(pk, 32), _i(pk, 33)
    legs = (_i(pk, 34), _i(pk, 35), _i2(pk, 36), _i(pk, 37), _i(pk, 38), _fn3(pk, 32), _f33(pk, 33), _f33(pk, 34),
            _fn3(pk, 35), _fn3(pk, 36), _fn3(pk, 37), _i2(pk, 39), _i2(pk, 40), _i2(pk, 41), _fn3(pk, 38),
            _fn3(pk, 39), _f33(pk, 40), _i(pk, 42), _i(pk, 43))
    nb = body_parent.shape[0]
    nl = load_body.shape[0]
    coord_offset, coord_sign = _f(pk, 0), _f(pk, 1)
    tRP, tpP, tRC, tpC = _f33(pk, 2), _fn3(pk, 3), _f33(pk, 4), _fn3(pk, 5)
    RP, pP, RC, pC = _f33(pk, 6), _fn3(pk, 7), _f33(pk, 8), _fn3(pk, 9)
    task_point = _f(pk, 10)
    idle = _f2(pk, 11)
    row_scale, mass = _f(pk, 12), _f(pk, 13)
    inertia, com, gravity = _f33(pk, 14), _fn3(pk, 15), _f(pk, 16)
    load_point, load_force, load_moment = _fn3(pk, 17), _fn3(pk, 18), _fn3(pk, 19)
    fcoef, fsc, ecoef, eoff, load_direction = _f2(pk, 20), _f2(pk, 21), _f2(pk, 22), _f2(pk, 23), \
        _f2(pk, 24)
    inertia_factor = _f33(pk, 25)
    Gw = _f2(pk, 26)
    ratio, rotor, mcoul, mvisc, meps = _f(pk, 27), _f(pk, 28), _f(pk, 29), _f(pk, 30), _f(pk, 31)
    tol, check_tol = _fview(pk, pk[6], (2,))
    task_body, max_iter = pk[2], pk[3]
    nr = row_loop.shape[0]
    nrow = nr + nt
    mk = nq
    # ---- work space (consecutive views of the buffer)
    o = pk[8]
    R, o = _take3(pk, o, nb, 3, 3)
    p, o = _take2(pk, o, nb, 3)
    S, o = _take2(pk, o, nq, 6)
    val, o = _take1(pk, o, nrow)
    res, o = _take1(pk, o, nrow)
    K, o = _take2(pk, o, mk, mk)
    rhs, o = _take1(pk, o, mk)
    ires = _fview(pk, o, (idle.shape[0],))
    o += mk
    bwork, o = _take1(pk, o, mk)
    qd, o = _take1(pk, o, nq)
    qdd, o = _take1(pk, o, nq)
    V, o = _take2(pk, o, nb, 6)
    Vpre, o = _take2(pk, o, nq, 6)
    A, o = _take2(pk, o, nb, 6)
    gamma, o = _take1(pk, o, nrow)
    w33, o = _take3(pk, o, 5, 3, 3)
    w3, o = _take2(pk, o, 20, 3)
    W, o = _take2(pk, o, nb, 6)
    Q, o = _take1(pk, o, nq)
    T, o = _take3(pk, o, nb, nt, 6)
    Iw, o = _take2(pk, o, 3, 3)
    tmp, o = _take2(pk, o, 3, 3)
    Z, o = _take2(pk, o, nt, 6 * nb)
    M, o = _take2(pk, o, nt, nt)
    Bm, o = _take2(pk, o, nt, nt)
    h, o = _take1(pk, o, nt)
    r, o = _take1(pk, o, nt)
    c3, o = _take1(pk, o, 3)
    pc, o = _take2(pk, o, nb, 3)
    v3, o = _take1(pk, o, 3)
    a3, o = _take1(pk, o, 3)
    f3, o = _take1(pk, o, 3)
    info, o = _take1(pk, o, 3)
    Gw2, o = _take2(pk, o, mk, nt)
    Qf, o = _take1(pk, o, nq)
    trig, o = _take2(pk, o, nq, 3)
    if o > pk[9]:
        return SHORT_WORK  # the views would run past the work space
    wi = _iview(pk, pk[9], (2 * mk,))
    # ---- 1. tree coordinates from the previous solution
    o2 = 1 + nq + nt + nq * nt
    so = pk[7]
    q = _fview(pk, so + 1, (nq,))
    xp = _fview(pk, so + 1 + nq, (nt,))
    Gp = _fview(pk, so + 1 + nq + nt, (nq, nt))
    qddp = _fview(pk, so + o2, (nq,))
    xdp = _fview(pk, so + o2 + nq, (nt,))
    pause = int(st[o2 + nq + nt])
    if mode == POSITIONS:
        # every actuated coordinate set by a leg placed from the task alone: those legs' closed
        # forms alone (the values the full solve keeps), from the previous solution's branch
        alone = legs[1].shape[0] > 0
        for a in range(act_coord.shape[0]):
            if legs[18][act_coord[a]] == 0:
                alone = False
        if alone and place_fixed_legs(q, body_parent, body_joint, joint_q0, joint_nq, coord_motion, coord_offset,
                                      coord_sign, tRP, tpP, tRC, tpC, R, p, S, w33, w3, trig, legs, x,
                                      (task_body, task_point, task_kind, task_index, euler_axes)):
            for a in range(act_coord.shape[0]):
                out[a] = q[act_coord[a]]
            # the other coordinates are those of an earlier sample: a later full solve starts
            # from them as they are (no extrapolation, no simplified step)
            st[0] = ALONE
            for t in range(nt):
                xp[t] = x[t]
            return OK
    factored = st[0] == FACTORED
    chord = factored and pause == 0
    ss = 0.0
    vv = 0.0
    for t in range(nt):
        dx = x[t] - xp[t]
        if task_kind[t] == 1:
            dx = _wrap(dx)
        r[t] = dx
        ss += dx * xdp[t]
        vv += xdp[t] * xdp[t]
    ss = ss / vv if factored and vv > 0.0 else 0.0
    # the map's own second-order term (below) is estimated only over a step along the previous
    # rate, to within 10 % of the step (a path sampled finely, not poses one by one), and used
    # only where it is a correction, smaller than half the first-order step (a curvature estimated
    # over a far shorter step, e.g. at a repeated time, may be mostly rounding); ``step2``: the
    # square of this step in the units of its own rate (1 where the rates are the steps), over
    # which the curvature is measured (0: none measured)
    step2 = 0.0
    if mode == MAP and ss != 0.0:
        off = 0.0
        dd = 0.0
        hh = 0.0
        ww = 0.0
        for t in range(nt):
            off += (r[t] - ss * xdp[t]) ** 2
            dd += r[t] * r[t]
            hh += r[t] * xd[t]
            ww += xd[t] * xd[t]
        hs = hh / ww if ww > 0.0 else 0.0
        if off <= 0.01 * dd and hs * hs > 0.0 and np.isfinite(hs * hs):
            step2 = hs * hs
        big2 = 0.0
        big1 = 0.0
        for c in range(nq):
            v2 = abs(0.5 * ss * ss * qddp[c])
            if not v2 <= big2:  # (NaN or infinity kept: refused below)
                big2 = v2
            lin = 0.0
            for t in range(nt):
                lin += Gp[c, t] * r[t]
            big1 = max(big1, abs(lin))
            Qf[c] = q[c] + lin  # the first-order prediction (the map's curvature below is taken from it)
        if not (step2 > 0.0 and big2 <= 0.5 * big1):
            ss = 0.0
    for c in range(nq):
        acc = 0.5 * ss * ss * qddp[c] if ss != 0.0 else 0.0
        for t in range(nt):
            acc += Gp[c, t] * r[t]
        q[c] += acc
    for t in range(nt):
        r[t] = 0.0  # the rates at xdd = 0
    tree = (body_parent, body_joint, joint_q0, joint_nq, coord_motion, coord_offset, coord_sign, tRP, tpP, tRC, tpC,
            legs)
    loops = (RP, pP, RC, pC, anc, row_loop, row_kind, row_i, row_j, loop_joint, joint_parent, joint_child)
    task = (task_body, task_point, task_kind, task_index, euler_axes)
    solver = (sel_rows, idle, prow, pcol, blocks, row_scale, tol, check_tol, max_iter, rowpos, colpos, idlepos)
    work = (R, p, S, val, res, K, wi, rhs, ires, bwork, qd, qdd, V, Vpre, A, gamma, Gp, w33, w3, Gw, Gw2, trig)
    # the map needs G alone: its solve is told the task is at rest (r is zero), which leaves out the
    # rates, the drift and the accelerations; its predictor's second-order term is then the
    # curvature of the path the solutions took (below)
    status = solve_sample(x, r if mode == MAP else xd, r, q, coord_offset, chord, tree, loops, task, solver, work,
                          info)
    if status != OK:
        st[0] = COLD_STATE
        return status
    st[o2 + nq + nt] = chord_pause(chord, info, pause)
    for t in range(nt):
        xp[t] = x[t]
        xdp[t] = xd[t]
    for c in range(nq):
        qddp[c] = qdd[c]
    if mode == MAP:
        # the bias accelerations along the step, from how far the solution lies from the first-order
        # prediction (q - Qf = qdd h^2 / 2 to the third order in the step h; none for a step not
        # along the previous rate)
        for c in range(nq):
            v2 = 2.0 * (q[c] - Qf[c]) / step2 if step2 > 0.0 else 0.0
            qddp[c] = v2 if np.isfinite(v2) else 0.0
    st[0] = FACTORED  # solve_sample left the factors of K at q in K, wi
    if mode == POSITIONS:
        for a in range(act_coord.shape[0]):
            out[a] = q[act_coord[a]]
        return OK
    if mode == MAP:  # J_ax (na, nt), row by row
        for a in range(act_coord.shape[0]):
            ca = _nn(act_coord[a])
            for t in range(nt):
                out[a * nt + t] = Gp[ca, t]
        return OK
    # ---- 2. friction that does not depend on the reactions, from the rates (V = [w; v_O])
    for c in range(nq):
        Qf[c] = 0.0
    for k in range(fj.shape[0]):
        j, ch, pa = fj[k], fch[k], fpa[k]
        ext = 0.0
        for t in range(eload.shape[1]):
            if eload[k, t] >= 0:
                ext += ecoef[k, t] * abs(load + eoff[k, t])
        w0 = w1 = w2 = u0 = u1 = u2 = 0.0
        if ch >= 0:
            w0, w1, w2, u0, u1, u2 = V[ch, 0], V[ch, 1], V[ch, 2], V[ch, 3], V[ch, 4], V[ch, 5]
            for i in range(3):
                c3[i] = p[ch, i] + R[ch, i, 0] * pC[j, 0] + R[ch, i, 1] * pC[j, 1] + R[ch, i, 2] * pC[j, 2]
        else:
            for i in range(3):
                c3[i] = pC[j, i]
        if pa >= 0:
            w0 -= V[pa, 0]
            w1 -= V[pa, 1]
            w2 -= V[pa, 2]
            u0 -= V[pa, 3]
            u1 -= V[pa, 4]
            u2 -= V[pa, 5]
        joint_friction(w0, w1, w2, u0, u1, u2, c3[0], c3[1], c3[2], frot[k] != 0, fslide[k] != 0, fcoef[k], ext,
                       EPS_R, EPS_T, S, fsc[k], fidx[k], fcnt[k], Qf)
    # ---- 3. required wrenches of the bias motion, loads, h = G^T Q
    for b in range(nb):
        for i in range(3):
            pc[b, i] = p[b, i] + R[b, i, 0] * com[b, 0] + R[b, i, 1] * com[b, 1] + R[b, i, 2] * com[b, 2]
        _point_motion(b, pc[b], V, A, v3, a3)
        body_wrench(R[b], V[b, :3], A[b, :3], pc[b], a3, mass[b], inertia[b], gravity, W[b], tmp, Iw)
    for k in range(nl):
        b = _nn(load_body[k])
        for i in range(3):
            f3[i] = load_direction[k, i] * load if load_named[k] else load_force[k, i]
        load_wrench(R[b], p[b], load_point[k], f3[0], f3[1], f3[2], load_moment[k], W[b])
    generalised(S, W, anc, Q)
    for c in range(nq):
        Q[c] += Qf[c]
    for t in range(nt):
        acc = 0.0
        for c in range(nq):
            acc += Gp[c, t] * Q[c]
        h[t] = acc
    # ---- 4. the task mass matrix
    task_mass(S, Gp, body_parent, body_joint, joint_q0, joint_nq, R, pc, mass, inertia_factor, M, T, Z, tmp)
    # ---- 4b. the drives (multibody.dynamics.actuators, Eq. A1): rotor inertia k^2 I_r along each actuator's
    # row of J_ax, its bias acceleration and the motor friction, in the motor's effort
    nd = ratio.shape[0]  # 0 without drives (pack), else one per actuator
    for a in range(nd):
        ca = _nn(act_coord[a])
        ka = ratio[a]
        thd = ka * qd[ca]
        tf = mcoul[a] * thd / math.sqrt(thd * thd + meps[a] * meps[a]) + mvisc[a] * thd
        ext = ka * (rotor[a] * ka * qdd[ca] + tf)
        ir = rotor[a] * ka * ka
        for t in range(nt):
            h[t] += Gp[ca, t] * ext
            if ir != 0.0:
                for j in range(nt):
                    M[t, j] += ir * Gp[ca, t] * Gp[ca, j]
    # ---- 5. the equation of motion, M xdd + h = J_ax^T k tau (tau the motor efforts)
    if mode == FORWARD:
        for t in range(nt):
            acc = -h[t]
            for a in range(nt):
                acc += Gp[_nn(act_coord[a]), t] * (ratio[a] if nd else 1.0) * v[a]
            out[t] = acc
        big = 0.0
        for t in range(nt):
            for j in range(nt):
                big = max(big, abs(M[t, j]))
        det, small = solve_in_place(M, out)
    else:
        for t in range(nt):
            acc = h[t]
            for j in range(nt):
                acc += M[t, j] * v[j]
            out[t] = acc
            for a in range(nt):
                Bm[t, a] = Gp[_nn(act_coord[a]), t] * (ratio[a] if nd else 1.0)
        # the checked verb's screen: Hadamard ratio |det A| / prod |a_i| of the column-scaled map
        for a in range(nt):
            big = 0.0
            for t in range(nt):
                big = max(big, abs(Bm[t, a]))
            r[a] = big if big > 0.0 else 1.0
        prod = 1.0
        for t in range(nt):
            nrm = 0.0
            for a in range(nt):
                Bm[t, a] /= r[a]
                nrm += Bm[t, a] * Bm[t, a]
            prod *= math.sqrt(nrm)
        det, small = solve_in_place(Bm, out)
        for a in range(nt):
            out[a] /= r[a]
        if not abs(det) > SINGULAR_ACTUATION * prod:  # the checked verb decides (SVD) and names the sample
            return SINGULAR_DYNAMICS
        return OK
    if not small > 1e-12 * big:
        return SINGULAR_DYNAMICS
    return OK


def forward_one(pk: NDArray[np.int64], x: Array, xd: Array, u: Array, load: float, out: Array) -> int:
    """``out = xdd (nt,)`` of one sample (``pk`` from :func:`pack`; ``load`` the named load's
    magnitude [N], if the mechanism has one); returns the status (0 OK). The compiled kernel is
    :func:`_dynamics`, one for both directions (a compiled entry point per direction cost a
    second linking of the whole kernel, some seconds of cold compilation each)."""
    return _dynamics(pk, x, xd, u, load, FORWARD, out)


def inverse_one(pk: NDArray[np.int64], x: Array, xd: Array, xdd: Array, load: float, out: Array) -> int:
    """``out = u (na,)`` of one sample; returns the status (0 OK) (:func:`forward_one`)."""
    return _dynamics(pk, x, xd, xdd, load, INVERSE, out)


def positions_one(pk: NDArray[np.int64], x: Array, xd: Array, out: Array) -> int:
    """``out = q_a (na,)``, the actuated joints' coordinates at task pose ``x`` (one sample of
    the inverse kinematics from the previous call's solution, ``xd`` the pose's rate for the
    predictor: a plant's encoders); returns the status (0 OK) (:func:`forward_one`). Where
    every actuated coordinate is set by a leg placed from the task alone (:mod:`pkmdyn.multibody.model.legs`: the
    Stewart platform's legs, the PUS legs of a 3PUS+S platform), those legs' closed forms alone answer, the
    values the full solve keeps (no Newton, no rates; the state then :data:`ALONE`)."""
    return _dynamics(pk, x, xd, xd, 0.0, POSITIONS, out)


@njit(cache=True, _nrt=False)
def _maps(pk, x, xd, mode, out):  # pragma: no cover - compiled
    """:func:`actuator_maps`' loop (``mode``: :data:`MAP`, as a value)."""
    for k in range(x.shape[0]):
        status = _dynamics(pk, x[k], xd[k], xd[k], 0.0, mode, out[k])
        if status != OK:
            return k
    return x.shape[0]


def actuator_maps(pk: NDArray[np.int64], x: Array, xd: Array, out: Array) -> int:
    """``out[k] = J_ax (na nt,)`` (the actuated coordinates' rates per task rate, row by row)
    at the task poses ``x (n, nt)`` in turn, each call of the kernel starting from the last
    (``xd (n, nt)``: the poses' rates, for the predictor alone); returns the number of samples
    solved (``n`` where all were; the state then holds the last). The batched actuator map of
    a motion without the batched solver's every body and joint point."""
    return int(_maps(pk, x, xd, MAP, out))


def _refresh_cache() -> None:
    """The kernels above inline and link functions of other modules (:mod:`._cache`)."""

    _cache.refresh((_dynamics, _maps), (_kernels, _tree_kernels, _dyn_kernels, _dense, friction, dynamics))


_refresh_cache()
