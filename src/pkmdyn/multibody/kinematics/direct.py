"""Direct kinematics of any described mechanism: the pose from the actuator coordinates.

A parallel robot is driven and measured at its actuators. For actuator coordinates ``s``
(``model.actuator_names`` order; [m] for a prismatic joint, [rad] for a revolute one) the tree
coordinates ``q`` solve the loop closure with the actuated coordinates held at ``s`` and the
idle freedoms held as the inverse kinematics holds them (:mod:`pkmdyn.multibody.kinematics._direct_kernels`, the equations); the
task coordinates are then the task body's pose. Two routes:

- :func:`direct_kinematics`: along an actuator motion, each sample by Newton from the
  previous one (continuation), the first from the reference configuration by continuation
  along the straight actuator path (or from ``q_start``): the assembly mode connected to the
  description's reference pose. Each sample reports its residual, Newton steps, the
  determinant of the direct kinematics Jacobian (its sign is the assembly branch; a change of
  sign between two samples is a crossed singularity, refused) and its smallest-to-largest
  pivot ratio (near zero next to a singularity).
- :func:`assembly_modes`: every assembly mode found at one actuator configuration, by damped
  Newton from many random configurations (multi-start), each solution verified by the inverse
  kinematics (its actuator coordinates back to ``s`` within ``1e-10``) and duplicates merged by
  the task body's pose. What it guarantees: every mode listed is a real, verified solution, and
  modes are distinct poses of the task body. What it does not: that none is missing (a mode
  whose basin of attraction no start falls into stays unfound; ``hits`` counts the starts
  that reached each mode, and a mode found once suggests more starts). A general
  Gough-Stewart platform has up to 40 assembly modes (Husty 1996; Dietmaier 1998).
"""

from __future__ import annotations

import time
import weakref
from dataclasses import dataclass, fields, replace
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ..._lazy import lazy_module
from ...errors import (
    MotionError,
    ParameterError,
    SingularityError,
    UnreachablePoseError,
    as_array,
    at_sample,
)
from ..dynamics import _sample_kernels as _one
from ..model.compiler import MechanismModel
from ..model.legs import explicit_legs
from ..model.poses import body_poses
from ..model.topology import column_scale, constraint_jacobian, row_labels, row_scale
from . import _direct_kernels as D
from . import _solve_kernels as K
from .inverse import CHECK_TOLERANCE, MAX_ITER, TOLERANCE, reference_task, solve_kinematics
from .motion import ActuatorMotion, TaskMotion
from .singularity.measures import singularity_measures

if TYPE_CHECKING:
    import scipy.linalg as linalg
else:  # loaded by the first redundantly actuated mechanism's square subset
    linalg = lazy_module("scipy.linalg")

__all__ = ["DirectKinematics", "Assembly", "AssemblyModes", "direct_kinematics", "assembly_modes", "task_motion",
           "actuator_reference", "parse_actuators", "ROUND_TRIP_TOLERANCE"]

Array = NDArray[np.float64]

#: largest scaled difference (lengths over the mechanism's size) between the actuator
#: coordinates and those the inverse kinematics gives back at a verified assembly mode
ROUND_TRIP_TOLERANCE = 1e-10
#: Newton steps of a search from a random configuration (each may be halved; :mod:`pkmdyn.multibody.kinematics._direct_kernels`)
SEARCH_ITER = 60
#: two solutions whose task body poses differ by less than this (rotation matrix entries, and
#: positions over the mechanism's size) are one assembly mode
SAME_POSE = 1e-6


@dataclass(frozen=True)
class DirectKinematics:
    """The direct kinematics along an actuator motion, per sample.

    ``t (n,)`` [s] or None; ``s, sd, sdd (n, na)``: actuator coordinates and their rates (SI);
    ``x, xd, xdd (n, nt)``: task coordinates ([m], Euler angles [rad], continuous along the
    motion) and their rates; ``q, qd, qdd (n, nq)``: tree coordinates (None where the call
    asked for the task motion alone, :func:`direct_kinematics`); ``residual (n,)``: the
    largest scaled loop residual; ``iterations (n,)``: Newton steps; ``det (n,)``: determinant
    of the direct kinematics Jacobian ``K`` (its sign: the assembly branch); ``pivot_ratio
    (n,)``: the smallest over the largest pivot of ``K``'s factorisation (near 0 close to a
    singularity). Where the task motion alone came by the actuated coordinates' closed forms,
    ``residual`` is the largest scaled difference of the actuated coordinates, ``det`` is ``det A``
    (``A = ds/dx``) times the legs' actuated factors, of the sign ``det K`` has at the first
    sample, and ``pivot_ratio`` is that of ``A``."""

    t: Array | None
    s: Array
    sd: Array
    sdd: Array
    x: Array
    xd: Array
    xdd: Array
    q: Array | None
    qd: Array | None
    qdd: Array | None
    residual: Array
    iterations: NDArray[np.int64]
    det: Array
    pivot_ratio: Array

    def __len__(self) -> int:
        return int(self.s.shape[0])


@dataclass(frozen=True)
class Assembly:
    """One assembly mode: task coordinates ``x (nt,)`` (angles the branch nearest the reference
    pose's), tree coordinates ``q (nq,)``, the scaled loop ``residual``, the scaled actuator
    difference of the inverse kinematics round trip, the sign of the direct kinematics
    Jacobian's determinant, the singularity measures (:func:`pkmdyn.multibody.kinematics.singularity.measures.singularity_measures`:
    ``inverse``, ``direct``, ``constraint``) and the starts that reached it (``hits``)."""

    x: Array
    q: Array
    residual: float
    round_trip: float
    det_sign: int
    inverse: float
    direct: float
    constraint: float
    hits: int


@dataclass(frozen=True)
class AssemblyModes:
    """The assembly modes found at actuator coordinates ``s``: ``modes`` nearest the reference
    pose first; ``starts`` the starts tried in all (the reference configuration and the
    continuation from it among them), ``converged`` those whose Newton search converged."""

    s: Array
    modes: tuple[Assembly, ...]
    starts: int
    converged: int
    #: the adaptive search's stopping rule (consecutive starts without a new mode), None for a
    #: fixed count of starts
    patience: int | None = None
    #: the start (1-based, in the order tried) that found the last new mode
    last_new_mode_at: int = 0
    method: str = ("damped Newton from random configurations (multi-start), each solution verified by the inverse "
                   "kinematics and duplicates merged by the task body's pose; every mode listed is real, none is "
                   "guaranteed to be the last")


def _check(model: MechanismModel) -> None:
    if not isinstance(model, MechanismModel):
        raise ParameterError(f"model: expected a MechanismModel, got {type(model).__name__}")
    if model.na < model.nt:
        raise ParameterError(f"{model.name}: direct kinematics needs at least as many actuated joints as degrees of "
                             f"freedom ({model.na} actuated, {model.nt} degrees of freedom)")


#: a redundantly actuated mechanism's actuated coordinates must agree with its direct
#: kinematics' pose to this [rad, or times the model's length scale in m], or to two counts of
#: their encoders (:func:`_agreement`)
REDUNDANT_TOLERANCE = 1e-7
_SQUARE: dict[int, tuple] = {}


def square_subset(model: MechanismModel) -> tuple[MechanismModel, Array]:
    """A redundantly actuated mechanism (``na > nt``) seen through ``nt`` of its actuated joints:
    the model with the others passive, and the kept actuators' indices. The kept ones are the
    best-conditioned at the reference configuration (pivoted QR of ``J_ax``): the direct
    kinematics' first guess and assembly branch (:func:`_redundant`), the assembly modes' and
    the single-sample readings' solve, the others checked (:data:`REDUNDANT_TOLERANCE`)."""
    hit = _SQUARE.get(id(model))
    if hit is not None and hit[0]() is model:
        return hit[1], hit[2]
    x = reference_task(model)[None]
    z = np.zeros_like(x)
    J = solve_kinematics(model, x, z, z).J_ax[0]  # (na, nt)
    _, _, piv = linalg.qr(J.T / np.maximum(np.abs(J).max(axis=1), 1e-300)[None, :], pivoting=True)
    keep = np.sort(piv[:model.nt])
    cut = {}
    for f in fields(model):
        v = getattr(model, f.name)
        if f.name.startswith(("drive_", "act_")) and isinstance(v, (np.ndarray, tuple)) and len(v) == model.na:
            cut[f.name] = v[keep] if isinstance(v, np.ndarray) else tuple(v[k] for k in keep)
    sub = replace(model, **cut)
    sub = replace(sub, legs=explicit_legs(sub))
    _SQUARE.clear()  # one model at a time (a sweep's designs replace each other)
    _SQUARE[id(model)] = (weakref.ref(model), sub, keep)
    return sub, keep


def _agreement(model: MechanismModel, idx: Array) -> Array:
    """How far the actuated joints ``idx`` may sit from the direct kinematics' pose [m or
    rad] (the weight of each in its least squares): :data:`REDUNDANT_TOLERANCE` (times the length scale in m), or two counts of the
    drive's encoder where it has one (a measured reading agrees to its resolution)."""
    scale = np.where(np.array([model.actuator_units[k] for k in idx]) == "m", model.length_scale, 1.0)
    counts = 2.0 * model.drive_encoder[idx] / model.drive_ratio[idx]
    return np.maximum(REDUNDANT_TOLERANCE * scale, counts)


#: Gauss-Newton steps of a redundantly actuated mechanism's least-squares pose (:func:`_redundant`)
REDUNDANT_STEPS = 8


def _least_squares(J: Array, r: Array) -> Array:
    """``dx (n, nt)``: the least-squares solution of ``J dx = r`` per sample (``J (n, na, nt)`` of
    full column rank)."""
    return np.einsum("nta,na->nt", np.linalg.pinv(J), r)


#: samples a redundantly actuated mechanism's least squares takes at a time (:func:`_redundant`:
#: its passes hold every body's kinematics of that many samples, not of the whole motion)
REDUNDANT_CHUNK = 2048


def _redundant(model: MechanismModel, s: Array, sd: Array, sdd: Array, t: Array | None, q_start: Array | None,
               sample_offset: int) -> DirectKinematics:
    """:func:`direct_kinematics` of a redundantly actuated mechanism: the pose its square subset
    gives (:func:`square_subset`: the assembly branch, the first guess), then the weighted
    least-squares pose over every actuated joint by Gauss-Newton, ``min sum_k ((s_k - q_k(x)) /
    a_k)^2`` (``a_k`` each joint's :func:`_agreement`), and the rates and accelerations by the
    same weighted least squares, ``J_ax xd = sd`` and ``J_ax xdd = sdd - (J_ax xd)'``, in
    chunks of :data:`REDUNDANT_CHUNK` samples. Every actuated coordinate must then agree with
    the pose to its ``a_k`` (a measured reading to two counts of its encoder); a disagreement is
    refused, naming the sample and a joint (the one the square subset's pose disagrees with where
    the least squares leaves the workspace). ``iterations``, ``det`` and ``pivot_ratio`` are
    the square subset's solve's."""
    sub, keep = square_subset(model)
    dk = direct_kinematics(sub, s[:, keep], sd[:, keep], sdd[:, keep], t, q_start=q_start,
                           sample_offset=sample_offset, bodies=True)
    a = _agreement(model, np.arange(model.na))
    n = s.shape[0]
    parts = []
    for lo in range(0, n, REDUNDANT_CHUNK):
        hi = min(n, lo + REDUNDANT_CHUNK)
        tc = None if t is None else t[lo:hi]
        try:
            parts.append(_least_squares_pose(model, a, dk.x[lo:hi], dk.q[lo], s[lo:hi], sd[lo:hi], sdd[lo:hi], tc,
                                             sample_offset + lo))
        except (UnreachablePoseError, SingularityError):
            # (a reading far off pushes the least squares out of the workspace: the square subset's
            # pose names the joint that disagrees)
            _check_agreement(model, a, s, dk.q[lo:hi][:, model.act_coord], lo, t, sample_offset,
                             f"the pose of {', '.join(model.actuator_names[j] for j in keep)} (the least squares of every "
                             "actuated joint found none there)")
            raise
        _check_agreement(model, a, s, parts[-1][7], lo, t, sample_offset, "the least-squares pose of every actuated joint")
    x, xd, xdd, q, qd, qdd, res = (np.concatenate([p[j] for p in parts]) for j in range(7))
    return replace(dk, s=s, sd=sd, sdd=sdd, x=x, xd=xd, xdd=xdd, q=q, qd=qd, qdd=qdd, residual=res)


def _check_agreement(model: MechanismModel, a: Array, s: Array, got: Array, lo: int, t: Array | None,
                     sample_offset: int, pose: str) -> None:
    """Refuse the first sample of ``got (k, na)`` (the actuated coordinates of ``pose`` from sample
    ``lo`` on) whose actuated joint sits beyond its agreement ``a`` from its reading in ``s``."""
    bad = np.argwhere(~(np.abs(got - s[lo:lo + got.shape[0]]) <= a))
    if bad.size:
        i, k = (int(v) for v in bad[0])
        raise UnreachablePoseError(
            f"{at_sample(lo + i, t, sample_offset)}: actuated joint {model.actuator_names[k]} is at {s[lo + i, k]:.9g} "
            f"but {pose} puts it at {got[i, k]:.9g} [m or rad], beyond {a[k]:.3g}: a redundantly actuated "
            "mechanism's actuator coordinates must agree")


def _least_squares_pose(model: MechanismModel, a: Array, x: Array, q0: Array, s: Array, sd: Array, sdd: Array,
                        t: Array | None, sample_offset: int) -> tuple[Array, ...]:
    """One chunk of :func:`_redundant`'s least squares from the poses ``x`` (the first sample's
    tree coordinates ``q0``, the branch): ``x, xd, xdd, q, qd, qdd, residual`` and the actuated
    coordinates of the chunk's least-squares motion."""
    z = np.zeros_like(x)
    for _ in range(REDUNDANT_STEPS):
        kin = solve_kinematics(model, x, z, z, t, q_start=q0, sample_offset=sample_offset)
        dx = _least_squares(kin.J_ax / a[None, :, None], (s - kin.act_q) / a)
        x = x + dx
        if not np.abs(dx).max() > 1e-13 * max(float(np.abs(x).max()), 1.0):
            break
    kin = solve_kinematics(model, x, z, z, t, q_start=q0, sample_offset=sample_offset)
    Jw = kin.J_ax / a[None, :, None]
    xd = _least_squares(Jw, sd / a)
    bias = solve_kinematics(model, x, xd, z, t, q_start=q0, sample_offset=sample_offset).act_qdd
    xdd = _least_squares(Jw, (sdd - bias) / a)
    kin = solve_kinematics(model, x, xd, xdd, t, q_start=q0, sample_offset=sample_offset)
    return kin.x, kin.xd, kin.xdd, kin.q, kin.qd, kin.qdd, kin.residual, kin.act_q


def _arrays(model: MechanismModel, damped: bool = False, max_iter: int = MAX_ITER) -> tuple:
    """The kernels' model tuples (:mod:`pkmdyn.multibody.kinematics._direct_kernels`)."""
    nr = model.row_loop.shape[0]
    act = np.ascontiguousarray(model.act_coord, dtype=np.int64)
    unk = np.ascontiguousarray(np.setdiff1d(np.arange(model.nq), act), dtype=np.int64)
    rows = model.solver_rows
    cut = np.ascontiguousarray(rows[rows < nr], dtype=np.int64)
    tree = (model.body_parent, model.body_joint, model.joint_q0, model.joint_nq, model.coord_motion,
            model.coord_offset, model.coord_sign, model.tree_R_parent, model.tree_p_parent, model.tree_R_child,
            model.tree_p_child)
    loops = (model.joint_R_parent, model.joint_p_parent, model.joint_R_child, model.joint_p_child,
             model.ancestor_list, model.row_loop, model.row_kind, model.row_i, model.row_j, model.loop_joint,
             model.joint_parent, model.joint_child)
    task = (model.task_body, model.task_point, model.task_kind, model.task_index, model.euler_axes)
    sol = (act, unk, cut, np.ascontiguousarray(model.solver_idle), model.coord_offset, row_scale(model),
           float(TOLERANCE), float(CHECK_TOLERANCE), int(max_iter), bool(damped))
    return tree, loops, task, sol


def pack_one(model: MechanismModel) -> NDArray[np.int64]:
    """The packed buffer of :func:`pkmdyn.multibody.kinematics._direct_kernels.direct_one` (its ``ONE_ARRAYS``): a header of
    ``(offset, d0, d1, d2)`` per array, then each array's bits; the state cold."""
    tree, loops, task, sol = _arrays(model)
    act, unk, cut, idle, q_ref, rs, tol, check_tol, max_iter, _ = sol
    nq, nb, na, nt = model.nq, model.body_parent.shape[0], model.na, model.nt
    nrow, nu = model.row_loop.shape[0] + nt, unk.shape[0]
    scalars = np.array([tol, check_tol, task[0], max_iter], dtype=float)
    work = D._work(nq, nb, nrow, nu, na)  # the batched route's own work space
    arrays = [*tree, *loops, *task[1:], act, unk, cut, idle, q_ref, rs, scalars, *work,
              np.zeros(2 + nq + nt + 2 * na + 2 + nq), np.zeros(5), np.zeros(na), np.zeros(nq)]
    if len(arrays) != len(D.ONE_ARRAYS):
        raise RuntimeError(f"internal error: {len(arrays)} arrays packed, the kernel takes {len(D.ONE_ARRAYS)}")
    head = np.zeros(4 * len(arrays), dtype=np.int64)
    parts, at = [], head.size
    for i, (a, (name, kind, ndim)) in enumerate(zip(arrays, D.ONE_ARRAYS)):
        a = np.ascontiguousarray(a, dtype=np.int64 if kind == "i" else float)
        if a.ndim != ndim:
            raise RuntimeError(f"internal error: {name} has {a.ndim} dimensions, the kernel takes {ndim}")
        head[4 * i:4 * i + 4] = [at, *a.shape, *[1] * (3 - a.ndim)]
        parts.append(a.ravel().view(np.int64))
        at += a.size
    return np.concatenate([head, *parts])


def one_state(pk: NDArray[np.int64]) -> Array:
    """The state of a packed buffer (:func:`pack_one`; a view): ``[flag, det K, q (nq), x (nt),
    s (na), sd (na), step known, pivot ratio, step of q (nq)]`` of the last solved sample."""
    k = len(D.ONE_ARRAYS) - 4
    o, n = int(pk[4 * k]), int(pk[4 * k + 1])
    return pk[o:o + n].view(np.float64)


def prime_one(pk: NDArray[np.int64], q: Array, x: Array, s: Array, det: float) -> None:
    """Set the solution a packed buffer's next call starts from (Newton alone, no predictor)."""
    st = one_state(pk)
    nq, nt = q.shape[0], x.shape[0]
    st[0], st[1] = D.ONE_PRIMED, det
    na = s.shape[0]
    st[2:2 + nq], st[2 + nq:2 + nq + nt], st[2 + nq + nt:2 + nq + nt + na] = q, x, s
    st[2 + nq + nt + na:] = 0.0  # no rate: the next call's predictor is of the first order


def task_route_map(model: MechanismModel) -> NDArray[np.int64] | None:
    """``(na, 2)``: for each actuated coordinate, the explicit leg that sets it and its place in
    that leg's chain, where :func:`pkmdyn.multibody.kinematics._direct_kernels.direct_task_one` answers for ``model``: as many
    actuators as task coordinates; a task of three Euler angles with three positions, or none
    (a task body on a ball fixed to the ground); every actuated coordinate in the chain of a leg
    placed from the task alone (:mod:`pkmdyn.multibody.model.legs`) with three coordinates (patterns A2, B2), from
    the ground, either the leg that carries the task body (T+A2, T+B2) or one that meets it.
    None otherwise (the tree-space route answers)."""
    lg = model.legs
    n_ang, n_pos = int(np.sum(model.task_kind == 1)), int(np.sum(model.task_kind == 0))
    if lg.count == 0 or model.na != model.nt or n_ang != 3 or n_pos not in (0, 3) or np.any(model.task_kind == 2):
        return None
    if not any(lg.kind[L] >= 10 and lg.fixed[L] for L in range(lg.count)):
        return None  # the task body is not placed by a leg from the task alone
    out = np.zeros((model.na, 2), dtype=np.int64)
    for a, c in enumerate(model.act_coord):
        hit = None
        for L in range(lg.count):
            if not lg.fixed[L] or lg.kind[L] % 10 not in (2, 4) or lg.base[L] != -1:
                continue
            if lg.kind[L] < 10 and lg.placed[L] != model.task_body:
                continue
            where = np.flatnonzero(lg.coord[L] == c)
            if where.size:
                hit = (L, int(where[0]))
                break
        if hit is None:
            return None
        out[a] = hit
    return out


def _actuated_points(model: MechanismModel, lmap: NDArray[np.int64], npos: int) -> tuple[Array, bool]:
    """For :func:`pack_task`: each actuator's leg end on the task body (the cut joint's point, or
    the centre of the ball that carries the task body) less the task point (or, without task
    positions, the centre of the task body's ball on the ground), in the task body's frame
    ``(na, 3)``; and whether each actuated coordinate is one that its leg's closed form gives
    before the others (A2's first joint, B2's slide: :func:`pkmdyn.multibody.kinematics._direct_kernels._actuated`), so that the
    route needs the other coordinates of no leg."""
    lg = model.legs
    origin = model.task_point if npos == 3 else model.tree_p_child[model.body_joint[model.task_body]]
    crel = np.zeros((model.na, 3))
    alone = True
    for a, (L, i) in enumerate(lmap):
        end = model.tree_p_child[lg.ball[L, 0]] if lg.kind[L] >= 10 else lg.cpt[L]
        crel[a] = end - origin
        alone = alone and (lg.kind[L] % 10, int(i)) in ((2, 0), (4, 2)) and _reaches_around(lg, L)
    return crel, alone


def _reaches_around(lg, L: int) -> bool:
    """Whether leg ``L``'s two turns about ``m0`` (its universal joint, or its ball with the spin
    held) point its rod in every direction, so that the actuated coordinate alone tells whether
    the leg reaches its point: the two axes normal to each other and the rod normal to the
    second (A2: axes 1, 2; B2: axes 0, 1, the slide normal to the second too). Elsewhere a rod
    length in reach may still be a direction out of reach (the route placing every leg says
    so)."""
    ax, rod = lg.axis[L], lg.e0[L] - lg.m0[L]
    size = max(float(np.linalg.norm(rod)), 1e-300)
    tol = 1e-9
    if lg.kind[L] % 10 == 2:
        return abs(ax[1] @ ax[2]) < tol and abs(rod @ ax[2]) < tol * size
    return abs(ax[0] @ ax[1]) < tol and abs(ax[2] @ ax[1]) < tol and abs(rod @ ax[1]) < tol * size


def pack_task(model: MechanismModel) -> NDArray[np.int64] | None:
    """The state and work of :func:`pkmdyn.multibody.kinematics._direct_kernels.direct_task_one` (a header of offsets, then the
    parts; the state cold), or None where that route does not answer (:func:`task_route_map`)."""
    lmap = task_route_map(model)
    if lmap is None:
        return None
    nq, nt, na, nb = model.nq, model.nt, model.na, model.nb
    npos = int(np.sum(model.task_kind == 0))
    o = np.zeros(3)
    if npos == 0:  # the centre of the ball on the ground that carries the task body
        R, p, _ = body_poses(model, model.coord_offset)
        k = int(model.body_joint[model.task_body])
        o = p[model.task_body] + R[model.task_body] @ model.tree_p_child[k]
    scale = np.where(model.coord_motion[model.act_coord] >= 3, 1.0 / model.length_scale, 1.0)
    crel, alone = _actuated_points(model, lmap, npos)
    parts = [np.zeros(2), np.zeros(nt), np.zeros(na), np.zeros(nt * nt), scale, o, lmap.ravel(),
             np.zeros(nq), np.zeros(nb * 9), np.zeros(nb * 3), np.zeros(nq * 6), np.zeros(45), np.zeros(60),
             np.zeros(nq * 3), np.zeros(nt * nt), np.zeros(nt * nt), np.zeros(nt), np.zeros(9), np.zeros(18),
             np.zeros(nt, dtype=np.int64),
             np.concatenate([np.zeros(nt + 1), [1.0 / model.length_scale, 1.0, 0.0, 0.0]]),
             np.zeros(nt), np.zeros(nq), crel.ravel(), np.array([1.0 if alone else 0.0, 0.0]), np.zeros(4 * na)]
    head = np.zeros(D.TASK_HEAD, dtype=np.int64)
    head[D.TASK_HEAD - 2], head[D.TASK_HEAD - 1] = npos, nb
    at, bits = D.TASK_HEAD, []
    for i, a in enumerate(parts):
        head[i] = at
        bits.append(np.ascontiguousarray(a).view(np.int64))
        at += a.size
    return np.concatenate([head, *bits])


def prime_task(d: NDArray[np.int64], q: Array, x: Array, s: Array) -> None:
    """Set the solution the task-space route's next call starts from (no predictor)."""
    f = d.view(np.float64)
    f[d[0]] = D.ONE_PRIMED
    f[d[1]:d[1] + x.shape[0]] = x
    f[d[2]:d[2] + s.shape[0]] = s
    f[d[7]:d[7] + q.shape[0]] = q
    f[d[20]:d[20] + x.shape[0] + 1] = 0.0  # no step known: the next call's predictor uses the Jacobian


def task_state(d: NDArray[np.int64]) -> Array:
    """The task-space route's ``[flag, det A]`` (a view)."""
    return d.view(np.float64)[d[0]:d[0] + 2]


def actuator_reference(model: MechanismModel) -> Array:
    """The actuator coordinates (na,) at the reference configuration."""
    return model.coord_offset[model.act_coord].copy()


def _outputs(model: MechanismModel, n: int) -> dict:
    """The kernel's output arrays for ``n`` samples (:func:`pkmdyn.multibody.kinematics._direct_kernels.direct_batch`, in its order)."""
    nq, nt = model.nq, model.nt
    return {"q": np.zeros((n, nq)), "qd": np.zeros((n, nq)), "qdd": np.zeros((n, nq)), "x": np.zeros((n, nt)),
            "xd": np.zeros((n, nt)), "xdd": np.zeros((n, nt)), "res": np.zeros(n), "it": np.zeros(n, dtype=np.int64),
            "det": np.zeros(n), "ratio": np.zeros(n), "status": np.full(n, -1, dtype=np.int64),
            "worst": np.zeros(n, dtype=np.int64)}


def _batch(model: MechanismModel, s: Array, sd: Array, sdd: Array, q_start: Array, x_start: Array,
           t: Array | None, out: dict | None = None, args: tuple | None = None) -> dict:
    """The kernel along ``s, sd, sdd`` into ``out`` (new arrays unless given, as a caller that
    solves one sample at a time keeps them) with the model's tuples ``args`` (:func:`_arrays`)."""
    out = _outputs(model, s.shape[0]) if out is None else out
    tm = np.zeros(0) if t is None else np.ascontiguousarray(t, dtype=float)
    D.direct_batch(tm, s, sd, sdd, np.ascontiguousarray(q_start, dtype=float), np.ascontiguousarray(x_start),
                   *(_arrays(model) if args is None else args), *out.values())
    return out


def _straight(a: Array, b: Array, steps: int) -> Array:
    """``steps`` points from ``a`` (left out) to ``b`` along the straight line."""
    return np.ascontiguousarray(a + np.linspace(0.0, 1.0, steps + 1)[1:, None] * (b - a))


def _values(model: MechanismModel, s: Array) -> str:
    return ", ".join(f"{a} = {v + 0.0:.6g} {'m' if model.coord_motion[c] >= 3 else 'rad'}"
                     for a, c, v in zip(model.actuator_names, model.act_coord, s))


def _acting(model: MechanismModel, q: Array, row: int) -> str:
    """The actuator whose coordinate moves row ``row`` the most at ``q`` (scaled)."""
    _, J = constraint_jacobian(model, q[None])
    if not np.all(np.isfinite(J)):
        return model.actuator_names[0]
    w = np.abs(J[0, row, model.act_coord]) * column_scale(model)[model.act_coord]
    return model.actuator_names[int(np.argmax(w))]


def _fail(model: MechanismModel, out: dict, k: int, s: Array, t: Array | None, offset: int) -> None:
    """Raise the error of sample ``k`` of ``out`` (a :func:`_batch` result)."""
    when = at_sample(k, t, offset)
    _raise(model, int(out["status"][k]), int(out["worst"][k]), float(out["res"][k]), out["q"][k], s[k], when)


def _raise(model: MechanismModel, st: int, worst: int, res: float, q: Array, s: Array, when: str) -> None:
    if st == D.CROSSED:
        raise SingularityError(f"{when}: the actuator motion crosses a singularity of the direct kinematics (the "
                               f"determinant of its Jacobian changes sign since the sample before; actuators "
                               f"{_values(model, s)}): the pose would jump between assembly modes")
    if st == K.SINGULAR:
        raise SingularityError(f"{when}: singular direct kinematics at actuators {_values(model, s)} (the "
                               f"actuators do not determine the pose: a type II singularity)")
    if st == D.EULER_SINGULAR_RATES:
        raise SingularityError(f"{when}: the Euler angles ({model.euler_sequence}) of task body "
                               f"{model.body_names[model.task_body]!r} are at their singularity (actuators "
                               f"{_values(model, s)})")
    actuator = _acting(model, q, worst)
    raise UnreachablePoseError(f"{when}: actuator {actuator!r}: the actuator coordinates {_values(model, s)} reach "
                               f"no pose: {row_labels(model)[worst]} does not close (residual {res:.3g} of the "
                               "length scale)")


def _start(model: MechanismModel, s0: Array, t: Array | None, offset: int) -> Array:
    """Tree coordinates at actuator coordinates ``s0`` connected to the reference configuration:
    continuation from the reference actuator coordinates in 1, then 8, then 64 steps."""
    s_ref = actuator_reference(model)
    x_ref = reference_task(model)
    last = None
    for steps in (1, 8, 64):
        path = _straight(s_ref, s0, steps)
        zero = np.zeros_like(path)
        out = _batch(model, path, zero, zero, model.coord_offset, x_ref, None)
        if out["status"][-1] == K.OK:
            return out["q"][-1].copy()
        last = out
    assert last is not None
    k = int(np.flatnonzero(last["status"] != K.OK)[0])
    when = at_sample(0, t, offset)
    _raise(model, int(last["status"][k]), int(last["worst"][k]), float(last["res"][k]), last["q"][k], s0, when)
    raise AssertionError  # pragma: no cover - _raise raises


def _bridge(model: MechanismModel, s: Array, out: dict, k: int) -> Array | None:
    """Tree coordinates at sample ``k`` followed from the solved sample ``k - 1`` in 8, then 64
    small actuator steps, on the same branch (a coarsely sampled motion, or a sample whose
    Newton solve took many steps and may have jumped to another assembly mode); None where
    that fails too. A step in which the Jacobian's determinant changes sign is a singularity
    crossed: status :data:`pkmdyn.multibody.kinematics._direct_kernels.CROSSED` at ``k``."""
    if k == 0:
        return None
    for steps in (8, 64):
        path = _straight(s[k - 1], s[k], steps)
        zero = np.zeros_like(path)
        b = _batch(model, path, zero, zero, out["q"][k - 1], out["x"][k - 1], None)
        if np.all(b["status"] == K.OK):
            if np.any(b["det"] * out["det"][k - 1] < 0):
                out["status"][k] = D.CROSSED
                return None
            return b["q"][-1].copy()
    return None


#: Newton steps beyond the simplified one after which a sample is followed again in small
#: steps (:func:`_bridge`): from a close predictor one step suffices, many suggest a jump
JUMP_STEPS = 3
#: a sample whose Jacobian's smallest-to-largest pivot ratio is below this sits on a
#: singularity; where the next sample then needs many Newton steps, the branch that follows
#: cannot be told from the actuators, and the motion is refused there as a crossing
NEAR_SINGULAR = 1e-4


def _by_the_actuated_coordinates(model: MechanismModel, s: Array, sd: Array, sdd: Array, q0: Array,
                                 x0: Array) -> dict | None:
    """The task motion along ``s, sd, sdd`` by the task-space route of one sample
    (:func:`pkmdyn.multibody.kinematics._direct_kernels.direct_task_batch`), each actuated coordinate from its leg's closed form
    alone, from the first sample's solution ``q0, x0``; None where that route does not apply
    (:func:`pack_task`, its flag) or any sample is not a plain continuation step (a call it does
    not answer, more than :data:`JUMP_STEPS` Newton steps, a Jacobian whose pivot ratio is below
    :data:`pkmdyn.multibody.kinematics._direct_kernels.TASK_NEAR`): the tree-space route then answers, with its checks."""
    d = pack_task(model)
    if d is None or d.view(np.float64)[d[24]] != 1.0:
        return None
    d.view(np.float64)[d[24] + 1] = -1e18  # no placement of the legs' other coordinates on the way
    prime_task(d, q0, x0, s[0])
    n, nt = s.shape[0], model.nt
    out = {"x": np.zeros((n, nt)), "xd": np.zeros((n, nt)), "xdd": np.zeros((n, nt)), "res": np.zeros(n),
           "it": np.zeros(n, dtype=np.int64), "det": np.zeros(n), "ratio": np.zeros(n),
           "status": np.full(n, -1, dtype=np.int64)}
    D.direct_task_batch(_one.pack(model), d, s, sd, sdd, np.zeros(2 * nt), *out.values())
    if np.any(out["status"] != K.OK) or out["it"].max() > JUMP_STEPS or out["ratio"].min() < D.TASK_NEAR:
        return None
    return out


def direct_kinematics(model: MechanismModel, s: Array, sd: Array | None = None, sdd: Array | None = None,
                      t: Array | None = None, q_start: Array | None = None,
                      sample_offset: int = 0, bodies: bool = True) -> DirectKinematics:
    """The direct kinematics along the actuator motion ``s, sd, sdd (n, na)`` (SI; module
    docstring): each sample warm-started from the one before (``t`` (n,) [s] gives the
    third-order predictor and the messages' times), the first from ``q_start`` (nq,) or else
    by continuation from the reference configuration. Refused, naming the sample (counted from
    ``sample_offset``) and an actuator, where the actuator coordinates reach no pose
    (:class:`~pkmdyn.errors.UnreachablePoseError`) or the motion crosses a singularity or meets
    one (:class:`~pkmdyn.errors.SingularityError`).

    Without ``bodies`` the result holds the task motion alone (``q, qd, qdd`` None): where each
    actuated coordinate is the one its leg's closed form gives first (the task-space route of
    one sample, ``docs/mechanism_format.md``: the Gough-Stewart platform, a 3-PUS platform, R-U-S,
    P-U-S and U-P-S platforms), the samples after the first then come from the actuated
    coordinates' closed forms alone (:func:`pkmdyn.multibody.kinematics._direct_kernels.direct_task_batch`; ``det`` is then
    ``det A`` times the legs' actuated factors, of the same sign along a motion, and
    ``pivot_ratio`` that of ``A = ds/dx``), and from the tree-space route wherever that route
    meets anything but a plain continuation step. That route does not see the legs' passive
    joints: a universal joint at its own singularity (its two axes in line), which the
    tree-space route refuses, passes there."""
    _check(model)
    na = model.na
    s = np.ascontiguousarray(as_array(s, (None, na), "s", MotionError))
    n = s.shape[0]
    sd = np.zeros_like(s) if sd is None else np.ascontiguousarray(as_array(sd, (n, na), "sd", MotionError))
    sdd = np.zeros_like(s) if sdd is None else np.ascontiguousarray(as_array(sdd, (n, na), "sdd", MotionError))
    if t is not None:
        t = np.ascontiguousarray(as_array(t, (n,), "t", MotionError))
    for name, arr in (("s", s), ("sd", sd), ("sdd", sdd)):
        bad = np.flatnonzero(~np.all(np.isfinite(arr), axis=1))
        if bad.size:
            raise MotionError(f"{name}: sample {int(bad[0]) + sample_offset} is not finite")
    if n == 0:
        raise MotionError("s: the actuator motion has no samples")
    if na > model.nt:
        return _redundant(model, s, sd, sdd, t, q_start, sample_offset)
    q0 = _start(model, s[0], t, sample_offset) if q_start is None else \
        np.ascontiguousarray(as_array(q_start, (model.nq,), "q_start"))
    if not bodies and n > 1:
        first = _batch(model, s[:1], sd[:1], sdd[:1], q0, reference_task(model), None if t is None else t[:1])
        fast = None if first["status"][0] != K.OK else \
            _by_the_actuated_coordinates(model, s, sd, sdd, first["q"][0], first["x"][0])
        if fast is not None:
            # the branch's sign as the tree-space route gives it (its det K at the first sample)
            fast["det"] *= np.sign(first["det"][0] * fast["det"][0])
            return DirectKinematics(t=t, s=s, sd=sd, sdd=sdd, x=fast["x"], xd=fast["xd"], xdd=fast["xdd"], q=None,
                                    qd=None, qdd=None, residual=fast["res"], iterations=fast["it"], det=fast["det"],
                                    pivot_ratio=fast["ratio"])
    out = _batch(model, s, sd, sdd, q0, reference_task(model), t)
    if out["status"][0] != K.OK:
        _fail(model, out, 0, s, t, sample_offset)
    settled = 1  # samples before this one are final
    while True:
        failed = out["status"][settled:] != K.OK
        slow = (out["it"][settled:] > JUMP_STEPS) & ~failed
        pending = np.flatnonzero(failed | slow)
        if pending.size == 0:
            break
        k = settled + int(pending[0])
        if out["status"][k] == K.OK and out["ratio"][k - 1] < NEAR_SINGULAR:
            out["status"][k] = D.CROSSED  # the sample before sat on a singularity: which branch follows is unknown
        if out["status"][k] == D.CROSSED:  # the predictor carried the solution through a singularity
            _fail(model, out, k, s, t, sample_offset)
        q_k = _bridge(model, s, out, k)
        if q_k is None:
            if out["status"][k] == K.OK:  # solved in many steps, but not reached by following the branch
                out["status"][k] = K.NOT_CONVERGED
            _fail(model, out, k, s, t, sample_offset)
        if not failed[k - settled] and np.abs(q_k - out["q"][k]).max() <= 1e-8:
            settled = k + 1  # the many steps did land on the same branch
            continue
        rest = _batch(model, s[k:], sd[k:], sdd[k:], q_k, out["x"][k - 1], None if t is None else t[k:])
        for key, arr in rest.items():
            out[key][k:] = arr
        if out["status"][k] != K.OK:
            _fail(model, out, k, s, t, sample_offset)
        settled = k + 1
    if n > 1:
        flip = np.flatnonzero(out["det"][1:] * out["det"][:-1] < 0)
        if flip.size:
            out["status"][flip[0] + 1] = D.CROSSED
            _fail(model, out, int(flip[0]) + 1, s, t, sample_offset)
    keep = (out["q"], out["qd"], out["qdd"]) if bodies else (None, None, None)
    return DirectKinematics(t=t, s=s, sd=sd, sdd=sdd, x=out["x"], xd=out["xd"], xdd=out["xdd"], q=keep[0],
                            qd=keep[1], qdd=keep[2], residual=out["res"], iterations=out["it"], det=out["det"],
                            pivot_ratio=out["ratio"])


def task_motion(model: MechanismModel, motion: ActuatorMotion,
                q_start: Array | None = None) -> tuple[TaskMotion, DirectKinematics]:
    """The task motion of an actuator motion (:func:`pkmdyn.multibody.kinematics.motion.read_actuator_motion`) by the
    direct kinematics along it (:func:`direct_kinematics`, the task motion alone), with its named
    loads; and the direct kinematics itself (residuals, iterations, branch; no tree coordinates)."""
    dk = direct_kinematics(model, motion.s, motion.sd, motion.sdd, motion.t, q_start=q_start, bodies=False)
    return TaskMotion(motion.t, dk.x, dk.xd, dk.xdd, dict(motion.loads)), dk


def _random_starts(model: MechanismModel, m: int, rng: np.random.Generator) -> Array:
    """``m`` tree configurations: turning coordinates uniform over a turn, sliding ones within
    two length scales of their reference (the actuated ones are set by the solve)."""
    turn = model.coord_motion < 3
    q = np.empty((m, model.nq))
    q[:, turn] = rng.uniform(-np.pi, np.pi, (m, int(turn.sum())))
    q[:, ~turn] = model.coord_offset[~turn] + rng.uniform(-2.0, 2.0, (m, int((~turn).sum()))) * model.length_scale
    return q


#: the adaptive search's default: stop once this many consecutive starts found no new mode
PATIENCE = 5000
#: at most this many starts in one search (fixed or adaptive)
MAX_STARTS = 1_000_000
#: the first call's starts; later calls are sized to last about :data:`_CALL_S` seconds, so that
#: Ctrl-C (answered between calls) is answered within a second
_BATCH = 200
_CALL_S = 0.25
_BLOCK = 64


def assembly_modes(model: MechanismModel, s: Array, starts: int | None = None, seed: int = 0,
                   patience: int = PATIENCE) -> AssemblyModes:
    """The assembly modes found at actuator coordinates ``s (na,)`` (module docstring): damped
    Newton from the reference configuration, the continuation from it and random configurations
    (``seed``), the converged ones verified by the inverse kinematics round trip to
    :data:`ROUND_TRIP_TOLERANCE` and merged by the task body's pose. ``starts``: that many starts
    in all (the reference configuration and the continuation count among them); None (the
    default): starts until ``patience`` consecutive ones found no new mode (at most
    :data:`MAX_STARTS`), so the search lasts as long as the mechanism needs. Refused where no
    start reaches a solution (the actuators reach no pose)."""
    _check(model)
    s = np.ascontiguousarray(as_array(s, (model.na,), "s", MotionError))
    if not np.all(np.isfinite(s)):
        raise MotionError("s: not finite")
    if model.na > model.nt:  # the square subset's modes that the other actuated coordinates agree with
        sub, keep = square_subset(model)
        found = assembly_modes(sub, s[keep], starts, seed, patience)
        other = np.setdiff1d(np.arange(model.na), keep)
        modes = tuple(a for a in found.modes
                      if np.all(np.abs(a.q[model.act_coord[other]] - s[other]) <= _agreement(model, other)))
        if not modes:
            raise UnreachablePoseError(
                f"actuator coordinates {', '.join(f'{n}={v:.9g}' for n, v in zip(model.actuator_names, s))}: none of "
                f"the {len(found.modes)} assembly mode(s) of {', '.join(model.actuator_names[j] for j in keep)} puts "
                f"{', '.join(model.actuator_names[j] for j in other)} there (a redundantly actuated mechanism's "
                "actuator coordinates must agree)")
        return replace(found, s=s, modes=modes)
    for name, v, lo in (("starts", starts, 1), ("patience", patience, 1)):
        if v is None and name == "starts":
            continue
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not lo <= v <= MAX_STARTS:
            raise ParameterError(f"{name}: expected an integer from {lo} to {MAX_STARTS:,}, got {v!r}")
    rng = np.random.default_rng(seed)
    seeds = [model.coord_offset[None]]
    try:
        seeds.append(_start(model, s, None, 0)[None])
    except (UnreachablePoseError, SingularityError):
        pass
    total = MAX_STARTS if starts is None else int(starts)
    # the starts in one fixed order whatever the calls' sizes (drawn in blocks of _BLOCK): a seed
    # gives the same starts, and the search stops at the same one, on any machine and under any load
    pool = np.concatenate(seeds)

    def take(k: int) -> Array:
        nonlocal pool
        while pool.shape[0] < k:
            pool = np.concatenate([pool, _random_starts(model, _BLOCK, rng)])
        out, pool = pool[:k], pool[k:]
        return np.ascontiguousarray(out)

    L = model.length_scale
    tb = model.task_body
    groups: list[dict] = []
    m = converged = last_new = 0
    size = _BATCH
    while m < total and (starts is not None or m - last_new < patience or m == 0):
        k = min(size, total - m) if starts is not None else min(size, total - m, patience - (m - last_new))
        batch = take(max(k, 1))
        k = batch.shape[0]
        t0 = time.perf_counter()
        q_out = np.zeros_like(batch)
        res, det, ratio = np.zeros(k), np.zeros(k), np.zeros(k)
        status = np.full(k, -1, dtype=np.int64)
        D.direct_starts(s, batch, *_arrays(model, damped=True, max_iter=SEARCH_ITER), q_out, res, det, ratio, status)
        size = int(np.clip(k * _CALL_S / max(time.perf_counter() - t0, 1e-6), 50, 20_000))
        good = np.flatnonzero((status == K.OK) | (status == D.EULER_SINGULAR_RATES))
        converged += int(good.size)
        for i in good:
            R, p, _ = body_poses(model, q_out[i])
            key = np.concatenate([R[tb].ravel(), p[tb] / L])
            if not np.all(np.isfinite(key)):
                continue
            for g in groups:
                if np.abs(g["key"] - key).max() < SAME_POSE:
                    g["hits"] += 1
                    if res[i] < g["res"]:
                        g["res"], g["q"], g["det"] = float(res[i]), q_out[i].copy(), float(det[i])
                    break
            else:
                groups.append({"key": key, "hits": 1, "res": float(res[i]), "q": q_out[i].copy(),
                               "det": float(det[i])})
                last_new = m + int(i) + 1
        m += k
    if converged == 0:
        raise UnreachablePoseError(f"actuator {model.actuator_names[0]!r}: the actuator coordinates {_values(model, s)} "
                                   f"reach no pose ({m} starts, none converged)")
    x_ref = reference_task(model)
    nr = model.row_loop.shape[0]
    modes = []
    for g in groups:
        q = g["q"]
        val, _ = constraint_jacobian(model, q[None])
        x = val[0, nr:].copy()
        ang = model.task_kind == 1
        x[ang] = x_ref[ang] + (x[ang] - x_ref[ang] + np.pi) % (2 * np.pi) - np.pi
        try:
            kin = solve_kinematics(model, x[None], q_start=q)
            back = kin.act_q[0]
        except (UnreachablePoseError, SingularityError):
            continue
        scale = np.where(model.coord_motion[model.act_coord] >= 3, 1.0 / L, 1.0)
        trip = float(np.abs((back - s) * scale).max())
        if not trip <= ROUND_TRIP_TOLERANCE:
            continue
        sm = singularity_measures(model, q[None])
        modes.append(Assembly(x=x, q=q.copy(), residual=g["res"], round_trip=trip, det_sign=int(np.sign(g["det"])),
                              inverse=float(sm.inverse[0]), direct=float(sm.direct[0]),
                              constraint=float(sm.constraint[0]), hits=int(g["hits"])))
    if not modes:
        raise UnreachablePoseError(f"actuator {model.actuator_names[0]!r}: no solution at {_values(model, s)} passed "
                                   "the inverse kinematics check")
    scale_x = np.where(model.task_length, 1.0 / L, 1.0)
    modes.sort(key=lambda a: float(np.abs((a.x - x_ref) * scale_x).max()))
    return AssemblyModes(s=s, modes=tuple(modes), starts=m, converged=converged,
                         patience=None if starts is not None else int(patience), last_new_mode_at=last_new)


def parse_actuators(model: MechanismModel, text: str) -> Array:
    """Actuator coordinates from ``"P_1=0.41,P_2=0.40,..."`` (every actuated joint once, SI
    units of its coordinate: m or rad); errors name the key."""
    vals: dict[str, float] = {}
    for item in str(text).split(","):
        item = item.strip()
        if not item:
            continue
        name, eq, v = item.partition("=")
        name = name.strip()
        if not eq:
            raise ParameterError(f"--actuators: {item!r}: expected NAME=VALUE")
        if name not in model.actuator_names:
            raise ParameterError(f"--actuators: {name!r}: not an actuated joint of {model.name!r} (those are: "
                                 f"{', '.join(model.actuator_names)})")
        if name in vals:
            raise ParameterError(f"--actuators: {name!r}: given twice")
        try:
            f = float(v)
        except ValueError:
            raise ParameterError(f"--actuators: {name}: {v.strip()!r} is not a number") from None
        if not np.isfinite(f) or abs(f) > 1e6 * max(model.length_scale, 1.0):
            raise ParameterError(f"--actuators: {name}: {v.strip()!r} is not a finite value of a plausible size")
        vals[name] = f
    missing = [a for a in model.actuator_names if a not in vals]
    if missing:
        raise ParameterError(f"--actuators: {missing[0]!r}: missing (give every actuated joint: "
                             f"{', '.join(model.actuator_names)})")
    return np.array([vals[a] for a in model.actuator_names])
