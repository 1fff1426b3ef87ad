"""Kinematics of any described mechanism, batched over samples.

Problem solved per sample s (tree coordinates q (nq,), task coordinates x_s (nt,)):

    Phi(q) = 0                     loop closure: the constraint rows of every cut joint
    tau(q) = x_s                   task: base-frame components of the task point and Euler
                                   angles of the task body (angles wrapped to (-pi, pi])

by Newton's method on the square system of the model's ``solver_rows`` (redundant
constraint directions of an over-constrained mechanism are checked, not solved) and its
``solver_idle`` rows (each idle freedom held, ``n_k . (q - q_ref) = 0`` along its direction
at the reference configuration), warm-started along the motion by the first-order predictor
``q_s = q_{s-1} + G_{s-1} (x_s - x_{s-1})``. Rates and accelerations follow from the
linear systems ``[Phi_q; tau_q] qd = [0; xd]`` and
``[Phi_q; tau_q] qdd = [-gamma_Phi; xdd - gamma_tau]`` with the drift
``gamma = (d/dt [Phi_q; tau_q]) qd`` (the rows' second derivative at ``qdd = 0``), the
gamma_q form of Featherstone (2008, section 8.2). ``G = dq/dx`` is the matrix of that
solve; the actuator rates are its actuated rows (``J_ax = dq_a/dx``).

The first sample starts from the reference configuration (all joint coordinates at their
reference values), stepping the task from its reference value when one Newton solve does
not reach it.

Joint limits (``limits_m`` / ``limits_rad`` of a revolute or prismatic joint) bound the joint's
coordinate: a tree joint's is its tree coordinate, a cut joint's the reference value plus
the child frame's rotation about (displacement along) the joint axis relative to the parent
frame (:func:`joint_coordinates`). :func:`limit_violation` finds the first sample beyond a
limit; :func:`reachable` counts such a pose as out of the workspace, and
:func:`solve_kinematics` refuses it when asked (``limits=True``).
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np
from numpy.typing import NDArray

from ...errors import MotionError, SingularityError, UnreachablePoseError, as_array, at_sample
from ..description.joint_types import JOINT_TYPES
from ..model.compiler import MechanismModel
from ..model.topology import column_scale, constraint_jacobian, row_labels, row_scale
from . import _solve_kernels as K

__all__ = ["MechanismKinematics", "solve_kinematics", "reference_task", "loop_residuals", "reachable", "TOLERANCE",
           "joint_coordinates",
           "limited_joints", "limit_violation", "limit_message", "limit_hit", "limit_line", "joint_frame",
           "solve_graph", "neighbour_pairs", "limit_bounds"]

Array = NDArray[np.float64]

#: Newton stops when every solved row's dimensionless residual (lengths divided by the
#: model's length scale) is at most this
TOLERANCE = 1e-13
#: every row, the redundant directions of an over-constrained loop included, must close to this
CHECK_TOLERANCE = 1e-9
MAX_ITER = 30
#: a workspace grid's pose is given up once Newton has taken this many steps without halving its
#: residual over the last three (:func:`solve_grid`): a pose just out of reach, where Newton
#: wanders; a reachable pose, predicted from a solved neighbour, converges in fewer steps
GRID_STALL = 8
#: a joint coordinate may pass its limit by this (times the length scale for a sliding
#: joint; radians for a turning one) before the sample counts as beyond it: rounding at a
#: limit reached exactly is not a violation
LIMIT_TOLERANCE = 1e-9


@dataclass(frozen=True)
class MechanismKinematics:
    """Kinematics of every body and joint over n samples (base frame, SI units).

    ``t`` (n,) [s] or None; ``x, xd, xdd`` (n, nt): the task coordinates ([m] or [rad]) and
    their first and second time derivatives; ``q, qd, qdd`` (n, nq): tree coordinates
    (reference offsets included) and derivatives; ``R`` (n, nb, 3, 3): body-to-base
    rotation; ``origin, origin_v, origin_a`` (n, nb, 3): body frame origin [m], its velocity
    [m/s] and acceleration [m/s^2]; ``w, wd`` (n, nb, 3): angular velocity [rad/s] and
    acceleration [rad/s^2]; ``p, v, a`` (n, nb, 3): centre of mass and its velocity and
    acceleration; ``joint_point, joint_point_v, joint_point_a`` (n, nj, 3): each joint's
    centre (the origin of its frame on the child body) and that point's velocity and
    acceleration; ``act_q, act_qd, act_qdd`` (n, na): actuator coordinates [m or rad] and
    rates; ``J_ax`` (n, na, nt): actuator rates per task rate; ``G`` (n, nq, nt): tree rates
    per task rate; ``residual`` (n,): the largest dimensionless loop/task residual."""

    t: Array | None
    x: Array
    xd: Array
    xdd: Array
    q: Array
    qd: Array
    qdd: Array
    R: Array
    origin: Array
    origin_v: Array
    origin_a: Array
    w: Array
    wd: Array
    p: Array
    v: Array
    a: Array
    joint_point: Array
    joint_point_v: Array
    joint_point_a: Array
    act_q: Array
    act_qd: Array
    act_qdd: Array
    J_ax: Array
    G: Array
    residual: Array

    def __len__(self) -> int:
        return int(self.x.shape[0])

    def rows(self, start: int, stop: int | None = None) -> "MechanismKinematics":
        """Samples ``start .. stop - 1`` (views of the arrays)."""
        sl = slice(start, stop)
        return replace(self, **{f.name: getattr(self, f.name)[sl] for f in fields(self)
                                if getattr(self, f.name) is not None})


def reference_task(model: MechanismModel) -> Array:
    """Task coordinates (nt,) at the reference configuration."""
    val, _ = constraint_jacobian(model, model.coord_offset)
    return val[0, model.row_loop.shape[0]:].copy()


def loop_residuals(model: MechanismModel, q: Array) -> Array:
    """Constraint residuals (n, nr) of every cut joint's rows at ``q (n, nq)`` ([m] for
    translation rows, dimensionless for rotation rows)."""
    val, _ = constraint_jacobian(model, q)
    return val[:, : model.row_loop.shape[0]]


def _run(model: MechanismModel, x: Array, xd: Array, xdd: Array, q_start: Array, t: Array | None = None,
         nbr: NDArray[np.int64] | None = None, root: int = 0, stall: int = 0) -> dict:
    n, nq, nb, nt = x.shape[0], model.nq, model.nb, model.nt
    nj = len(model.joint_names)
    shapes = {"q": (nq,), "qd": (nq,), "qdd": (nq,), "R": (nb, 3, 3), "p": (nb, 3), "V": (nb, 6), "A": (nb, 6),
              "G": (nq, nt), "res": (), "ov": (nb, 3), "oa": (nb, 3), "cp": (nb, 3), "cv": (nb, 3), "ca": (nb, 3),
              "jp": (nj, 3), "jv": (nj, 3), "ja": (nj, 3)}
    # the outputs are views of one buffer: one large allocation is mapped in few (huge) pages
    # where the system allows, where many separate arrays of a long motion cost a page fault
    # every 4 KiB on first write
    size = {k: n * int(np.prod(sh)) for k, sh in shapes.items()}
    buf = np.zeros(sum(size.values()))
    out, pos = {}, 0
    for k, sh in shapes.items():
        out[k] = buf[pos:pos + size[k]].reshape((n, *sh))
        pos += size[k]
    out["status"] = np.full(n, -1, dtype=np.int64)
    out["worst"] = np.zeros(n, dtype=np.int64)
    tt = np.zeros(0) if t is None else np.ascontiguousarray(t, dtype=float)
    grid_nbr = np.zeros((0, 0), dtype=np.int64) if nbr is None else np.ascontiguousarray(nbr, dtype=np.int64)
    tree = (model.body_parent, model.body_joint, model.joint_q0, model.joint_nq, model.coord_motion,
            model.coord_offset, model.coord_sign, model.tree_R_parent, model.tree_p_parent, model.tree_R_child,
            model.tree_p_child, model.legs.arrays())
    loops = (model.joint_R_parent, model.joint_p_parent, model.joint_R_child, model.joint_p_child,
             model.ancestor_list, model.row_loop, model.row_kind, model.row_i, model.row_j, model.loop_joint,
             model.joint_parent, model.joint_child)
    task = (model.task_body, model.task_point, model.task_kind, model.task_index, model.euler_axes)
    settings = (model.solver_rows, model.solver_idle, model.solver_prow, model.solver_pcol, model.solver_blocks,
                model.coord_offset, row_scale(model), TOLERANCE, CHECK_TOLERANCE, MAX_ITER, float(stall))
    outputs = (out["q"], out["qd"], out["qdd"], out["R"], out["p"], out["V"], out["A"], out["G"], out["res"],
               out["status"], out["worst"], out["ov"], out["oa"], out["cp"], out["cv"], out["ca"],
               out["jp"], out["jv"], out["ja"])
    K.solve_batch(tt, x, xd, xdd, q_start, grid_nbr, root, tree, loops, task, settings,
                  (model.com, model.joint_p_child), outputs)
    return out


def _start(model: MechanismModel, x0: Array) -> Array:
    """Tree coordinates solving the first sample's task ``x0``: from the reference
    configuration, in 1, then 8, then 64 steps along the straight task path."""
    q_ref = model.coord_offset.copy()
    x_ref = reference_task(model)
    d = x0 - x_ref
    ang = model.task_kind == 1
    d[ang] = (d[ang] + np.pi) % (2 * np.pi) - np.pi
    last = None
    for steps in (1, 8, 64):
        s = np.linspace(0.0, 1.0, steps + 1)[1:, None]
        path = x_ref + s * d
        zero = np.zeros_like(path)
        out = _run(model, np.ascontiguousarray(path), zero, zero, q_ref)
        if out["status"][-1] == K.OK:
            return out["q"][-1]
        last = out
    return q_ref if last is None else q_ref


def solve_grid(model: MechanismModel, x: Array, shape: tuple[int, ...], roots: Array,
               tries: int = 16, stall: int = GRID_STALL) -> tuple[MechanismKinematics, NDArray[np.bool_]]:
    """Kinematics at every pose ``x (n, nt)`` of a grid of ``shape`` (``prod(shape) = n``, the
    first axis slowest) by continuation over the grid: the first pose of ``roots`` (grid
    indices in order of preference) that the reference configuration reaches (along the
    straight task path, as the first sample of :func:`solve_kinematics`; at most ``tries`` of
    them) is solved first, and every other pose from a solved neighbour along a grid axis,
    breadth-first (``_kernels.solve_batch``), so each pose on the root's assembly branch. A
    pose is given up as out of reach once Newton has taken ``stall`` steps (0: never, only
    after ``MAX_ITER``) without halving its residual over the last three.
    Returns the kinematics (n rows; zeros where not solved) and which poses were solved (n,)."""
    nbr = np.full((x.shape[0], 2 * len(shape)), -1, dtype=np.int64)
    for ax, (i, j) in enumerate(neighbour_pairs(shape)):
        nbr[j, 2 * ax] = i
        nbr[i, 2 * ax + 1] = j
    x = np.ascontiguousarray(x)
    for root in list(roots)[:tries]:
        kin, ok = solve_graph(model, x, nbr, int(root), _start(model, x[root]), stall)
        if ok[root]:
            break
    return kin, ok


def neighbour_pairs(shape: tuple[int, ...]) -> list[tuple[NDArray[np.int64], NDArray[np.int64]]]:
    """The neighbours along each axis of a grid of ``shape`` (the first axis slowest): per axis,
    the flat indices ``i`` and ``j`` of every pose and of the next one along the axis."""
    idx = np.arange(int(np.prod(shape))).reshape(shape)
    pairs = []
    for ax in range(len(shape)):
        lo = [slice(None)] * len(shape)
        hi = [slice(None)] * len(shape)
        lo[ax], hi[ax] = slice(0, -1), slice(1, None)
        pairs.append((idx[tuple(lo)].reshape(-1), idx[tuple(hi)].reshape(-1)))
    return pairs


def solve_graph(model: MechanismModel, x: Array, nbr: NDArray[np.int64], root: int, q_root: Array,
                stall: int = GRID_STALL) -> tuple[MechanismKinematics, NDArray[np.bool_]]:
    """Tree coordinates at task poses ``x (n, nt)`` joined by the directed graph ``nbr (n, k)``
    (``nbr[s]`` the poses that pose s leads to; -1: none), by continuation from pose ``root``
    (solved from ``q_root``), each pose from the solved pose that reached it first, as
    :func:`solve_grid` over its grid. Returns the kinematics (n rows; zeros where not solved) and
    which poses were solved (n,)."""
    zero = np.zeros((x.shape[0], model.nt))
    out = _run(model, np.ascontiguousarray(x), zero, zero, np.asarray(q_root, dtype=float), nbr=nbr, root=int(root),
               stall=stall)
    return _assemble(model, None, x, zero, zero, out), out["status"] == K.OK


def _fail(model: MechanismModel, out: dict, t: Array | None, x: Array, offset: int = 0) -> None:
    """Raise the error of the first failed sample, naming the sample, its time and the loop."""
    bad = int(np.flatnonzero(out["status"] != K.OK)[0])
    st = int(out["status"][bad])
    when = at_sample(bad, t, offset)
    pose = ", ".join(f"{nm} = {v + 0.0:.6g} {u}" for nm, u, v in zip(model.task_names, model.task_units, x[bad]))
    labels = row_labels(model)
    where = labels[int(out["worst"][bad])]
    if st == K.EULER_SINGULAR:
        raise SingularityError(f"{when}: the Euler angles ({model.euler_sequence}) of task body "
                               f"{model.body_names[model.task_body]!r} are at their singularity (task pose {pose})")
    if st == K.SINGULAR:
        where = _singular_row(model, out["q"][bad])
        raise SingularityError(f"{when}: singular configuration, the loop-closure and task equations lose rank "
                               f"(at {where}; task pose {pose})")
    if st == K.LOOP_OPEN:
        raise UnreachablePoseError(f"{when}: {where} cannot close (residual {out['res'][bad]:.3g} of the length scale "
                                   f"in a redundant direction): the geometry does not keep the over-constrained "
                                   f"loop closed (task pose {pose})")
    raise UnreachablePoseError(f"{when}: the task pose is unreachable: {where} does not close (residual "
                               f"{out['res'][bad]:.3g} of the length scale after {MAX_ITER} Newton steps; task pose {pose})")


def _singular_row(model: MechanismModel, q: Array) -> str:
    """The row that carries the most of the null direction of the Newton matrix at ``q``."""
    _, J = constraint_jacobian(model, q)
    Ks = (J[0] * row_scale(model)[:, None] * column_scale(model)[None, :])[model.solver_rows]
    Ks = np.concatenate([Ks, model.solver_idle * column_scale(model)[None, :]])
    if not np.all(np.isfinite(Ks)):
        return "an unknown row"
    u, _, _ = np.linalg.svd(Ks)
    return row_labels(model)[int(model.solver_rows[int(np.argmax(np.abs(u[:, -1])))])]


def solve_kinematics(model: MechanismModel, x: Array, xd: Array | None = None, xdd: Array | None = None,
                     t: Array | None = None, q_start: Array | None = None, limits: bool = False,
                     sample_offset: int = 0) -> MechanismKinematics:
    """Kinematics of every body and joint for the task motion ``x, xd, xdd`` (n, nt).

    ``x``: task coordinates in the order of ``model.task_names`` ([m], Euler angles [rad]);
    ``xd``, ``xdd``: their time derivatives (zero when omitted); ``t`` (n,) [s]: times, only
    for messages and the result; ``q_start`` (nq,): tree coordinates near the first sample's
    solution (default, and where the first sample is out of its reach: found from the
    reference configuration). Samples are solved in order,
    each warm-started from the previous one; where one Newton solve does not reach the next
    sample (a coarsely sampled motion), the step is bridged by 8, then 64, small task steps.

    Raises :class:`~pkmdyn.errors.UnreachablePoseError` (a loop that does not close, or with
    ``limits`` a joint beyond its limits, module docstring; without, :func:`limit_violation`
    tells) or
    :class:`~pkmdyn.errors.SingularityError`, naming the sample, its time and the loop or joint;
    ``sample_offset``: the number of the first sample in a longer motion (for the messages of
    a motion solved in chunks).
    """
    nt = model.nt
    x = np.ascontiguousarray(as_array(x, (None, nt), "x", MotionError))
    n = x.shape[0]
    xd = np.zeros_like(x) if xd is None else np.ascontiguousarray(as_array(xd, (n, nt), "xd", MotionError))
    xdd = np.zeros_like(x) if xdd is None else np.ascontiguousarray(as_array(xdd, (n, nt), "xdd", MotionError))
    if t is not None:
        t = as_array(t, (n,), "t", MotionError)
    for name, arr in (("x", x), ("xd", xd), ("xdd", xdd)):
        if not np.all(np.isfinite(arr)):
            raise MotionError(f"{name}: contains a non-finite value")
    if n == 0:
        raise MotionError("x: the motion has no samples")
    q0 = _start(model, x[0]) if q_start is None else np.ascontiguousarray(as_array(q_start, (model.nq,), "q_start"))
    out = _run(model, x, xd, xdd, q0, t)
    if q_start is not None and out["status"][0] not in (K.OK, K.EULER_SINGULAR):
        # the first sample out of the warm start's reach (a start from another part of the
        # motion): found from the reference configuration instead, as without a start
        out = _run(model, x, xd, xdd, _start(model, x[0]), t)
    while np.any(out["status"] != K.OK):
        s = int(np.flatnonzero(out["status"] != K.OK)[0])
        q_s = _bridge(model, x, out, s)
        if q_s is None:
            _fail(model, out, t, x, sample_offset)
        rest = _run(model, x[s:], xd[s:], xdd[s:], q_s, None if t is None else t[s:])
        for key, arr in rest.items():
            out[key][s:] = arr
    kin = _assemble(model, t, x, xd, xdd, out)
    if limits:
        _limit_error(model, kin)
    return kin


def _bridge(model: MechanismModel, x: Array, out: dict, s: int) -> Array | None:
    """Tree coordinates at sample ``s`` reached from the solved sample ``s - 1`` in 8, then 64,
    small task steps (a motion sampled too coarsely for one Newton solve per sample), or None
    when ``s`` is the first sample or the steps do not get there either (a real failure)."""
    if s == 0 or out["status"][s] == K.EULER_SINGULAR:
        return None
    d = x[s] - x[s - 1]
    ang = model.task_kind == 1
    d[ang] = (d[ang] + np.pi) % (2 * np.pi) - np.pi
    for steps in (8, 64):
        path = np.ascontiguousarray(x[s - 1] + np.linspace(0.0, 1.0, steps + 1)[1:, None] * d)
        zero = np.zeros_like(path)
        b = _run(model, path, zero, zero, out["q"][s - 1].copy())
        if b["status"][-1] == K.OK:
            return b["q"][-1].copy()
    return None


def _assemble(model: MechanismModel, t: Array | None, x: Array, xd: Array, xdd: Array, out: dict) -> MechanismKinematics:
    V, A = out["V"], out["A"]
    ac = model.act_coord
    return MechanismKinematics(
        t=t, x=x, xd=xd, xdd=xdd, q=out["q"], qd=out["qd"], qdd=out["qdd"], R=out["R"], origin=out["p"],
        origin_v=out["ov"], origin_a=out["oa"], w=V[..., :3], wd=A[..., :3], p=out["cp"], v=out["cv"], a=out["ca"],
        joint_point=out["jp"], joint_point_v=out["jv"], joint_point_a=out["ja"],
        act_q=out["q"][:, ac], act_qd=out["qd"][:, ac], act_qdd=out["qdd"][:, ac], J_ax=out["G"][:, ac, :],
        G=out["G"], residual=out["res"],
    )


def limited_joints(model: MechanismModel) -> list[int]:
    """The joints with limits (revolute and prismatic joints only carry them)."""
    return [j for j, lim in enumerate(model.joint_limits) if lim is not None]


def joint_frame(model: MechanismModel, kin: MechanismKinematics, j: int, child: bool) -> tuple[Array, Array]:
    """Joint j's frame on its child body (``child``) or its parent body in the base frame, every
    sample: ``R (n, 3, 3), o (n, 3)`` (the ground's fixed)."""
    if child:
        body, Rl, pl = model.joint_child[j], model.joint_R_child[j], model.joint_p_child[j]
    else:
        body, Rl, pl = model.joint_parent[j], model.joint_R_parent[j], model.joint_p_parent[j]
    if body < 0:
        n = len(kin)
        return np.broadcast_to(Rl, (n, 3, 3)), np.broadcast_to(pl, (n, 3))
    return kin.R[:, body] @ Rl, kin.origin[:, body] + kin.R[:, body] @ pl


def joint_coordinates(model: MechanismModel, kin: MechanismKinematics, joints: list[int] | None = None,
                      previous: Array | None = None, along: bool = True) -> Array:
    """Coordinate (n, k) of each one-coordinate joint in ``joints`` (default:
    :func:`limited_joints`), [rad] for a revolute, [m] for a prismatic joint, the description's
    sense and reference value included. A tree joint's is its tree coordinate; a cut joint's
    is its reference value plus the child frame's rotation about (displacement along) the
    joint frame's z axis relative to the parent frame, the angle unwrapped along the samples
    from the first sample's, taken within pi of the reference value, or within pi of
    ``previous`` (k,), the coordinates of the sample before (a motion taken in chunks);
    ``along=False`` (the poses of a grid, not a motion): each angle within pi of the
    reference value."""
    joints = limited_joints(model) if joints is None else list(joints)
    n = len(kin)
    out = np.empty((n, len(joints)))
    for i, j in enumerate(joints):
        if model.joint_nq[j] != 1:
            raise ValueError(f"joint {model.joint_names[j]!r} has {int(model.joint_nq[j])} coordinates, not one")
        if not model.joint_cut[j]:
            out[:, i] = kin.q[:, model.joint_q0[j]]
            continue
        RP, oP = joint_frame(model, kin, j, child=False)
        RC, oC = joint_frame(model, kin, j, child=True)
        if JOINT_TYPES[model.joint_type[j]].motions[0] == "RZ":
            rel = np.einsum("nki,nkj->nij", RP, RC)  # child frame in the parent frame
            ang = np.arctan2(rel[:, 1, 0], rel[:, 0, 0])
            if not along:
                out[:, i] = model.joint_offset[j] + ang
            elif previous is None:
                out[:, i] = model.joint_offset[j] + np.unwrap(ang)
            else:
                before = float(previous[i]) - model.joint_offset[j]
                out[:, i] = model.joint_offset[j] + np.unwrap(np.concatenate([[before], ang]))[1:]
        else:
            out[:, i] = model.joint_offset[j] + np.einsum("ni,ni->n", RP[:, :, 2], oC - oP)
    return out


def limit_bounds(model: MechanismModel, joints: list[int]) -> tuple[Array, Array]:
    """The lower and upper limits ``(k,)`` of the limited joints ``joints``
    (:func:`limited_joints`), in their coordinates' units."""
    return (np.array([model.joint_limits[j][0] for j in joints]),
            np.array([model.joint_limits[j][1] for j in joints]))


def beyond_limits(model: MechanismModel, c: Array, joints: list[int]) -> NDArray[np.bool_]:
    """Whether each coordinate ``c (n, k)`` (:func:`joint_coordinates`) lies beyond its joint's
    limits by more than :data:`LIMIT_TOLERANCE` (n, k)."""
    lo, hi = limit_bounds(model, joints)
    tol = np.array([LIMIT_TOLERANCE * (model.length_scale if JOINT_TYPES[model.joint_type[j]].units[0] == "m" else 1.0)
                    for j in joints])
    return (c < lo - tol) | (c > hi + tol)


def limit_hit(model: MechanismModel, c: Array, joints: list[int]) -> tuple[int, int] | None:
    """The first sample and the index into ``joints`` of a coordinate ``c (n, k)``
    (:func:`joint_coordinates`) beyond its joint's limits by more than :data:`LIMIT_TOLERANCE`,
    or None."""
    bad = beyond_limits(model, c, joints)
    if not bad.any():
        return None
    s = int(np.flatnonzero(bad.any(axis=1))[0])
    return s, int(np.flatnonzero(bad[s])[0])


def limit_line(model: MechanismModel, kin: MechanismKinematics, s: int, j: int, v: float,
               sample_offset: int = 0) -> str:
    """One line: sample ``s`` (its number ``s + sample_offset`` in a longer motion), joint ``j`` at
    ``v`` beyond its limits, the task pose."""
    unit = JOINT_TYPES[model.joint_type[j]].units[0]
    lo, hi = model.joint_limits[j]
    when = at_sample(s, kin.t, sample_offset)
    pose = ", ".join(f"{nm} = {x + 0.0:.6g} {u}" for nm, u, x in zip(model.task_names, model.task_units, kin.x[s]))
    return (f"{when}: joint {model.joint_names[j]!r} is at {v:.6g} {unit}, beyond its limits [{lo:g}, {hi:g}] {unit} "
            f"(task pose {pose})")


def limit_violation(model: MechanismModel, kin: MechanismKinematics) -> tuple[int, int, float] | None:
    """The first sample and joint whose coordinate lies beyond the joint's limits (by more than
    :data:`LIMIT_TOLERANCE`), and the coordinate: ``(sample, joint, value)``, or None."""
    joints = limited_joints(model)
    if not joints:
        return None
    c = joint_coordinates(model, kin, joints)
    hit = limit_hit(model, c, joints)
    if hit is None:
        return None
    s, k = hit
    return s, joints[k], float(c[s, k])


def limit_message(model: MechanismModel, kin: MechanismKinematics) -> str | None:
    """One line naming the first sample and joint beyond the joint's limits, or None."""
    hit = limit_violation(model, kin)
    return None if hit is None else limit_line(model, kin, *hit)


def _limit_error(model: MechanismModel, kin: MechanismKinematics) -> None:
    """Raise :class:`~pkmdyn.errors.UnreachablePoseError` naming the first joint beyond its limits."""
    msg = limit_message(model, kin)
    if msg is not None:
        raise UnreachablePoseError(f"unreachable within the joint limits: {msg}")


def reachable(model: MechanismModel, x: Array, steps: int = 16) -> NDArray[np.bool_]:
    """Workspace test: whether each task pose ``x (n, nt)`` is reached from the reference
    configuration along the straight task path in ``steps`` steps (each bridged further when
    needed), without a singular or open loop or a joint beyond its limits on the way.
    Conservative: a pose reachable only along another path, or only on another assembly
    branch, reads False. Returns (n,) bool."""
    x = np.atleast_2d(np.asarray(x, dtype=float))
    x_ref = reference_task(model)
    q_ref = model.coord_offset.copy()
    ang = model.task_kind == 1
    out = np.zeros(x.shape[0], dtype=bool)
    s = np.linspace(0.0, 1.0, steps + 1)[1:, None]
    for k in range(x.shape[0]):
        d = x[k] - x_ref
        d[ang] = (d[ang] + np.pi) % (2 * np.pi) - np.pi
        path = np.ascontiguousarray(x_ref + s * d)
        zero = np.zeros_like(path)
        res = _run(model, path, zero, zero, q_ref)
        while not np.all(res["status"] == K.OK):
            i = int(np.flatnonzero(res["status"] != K.OK)[0])
            q_i = _bridge(model, path, res, i)
            if q_i is None:
                break
            rest = _run(model, path[i:], zero[i:], zero[i:], q_i)
            for key, arr in rest.items():
                res[key][i:] = arr
        out[k] = bool(np.all(res["status"] == K.OK))
        if out[k] and limited_joints(model):  # every pose on the way within the joint limits
            kin = _assemble(model, None, path, zero, zero, res)
            out[k] = limit_violation(model, kin) is None
    return out
