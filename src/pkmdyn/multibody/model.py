"""The compiled mechanism model: flat arrays of a spanning tree plus loop records.

``compile_model(description)`` turns a validated :class:`~.description.Description` into a
:class:`MechanismModel`, a frozen record of plain arrays in the spirit of Featherstone's
``model`` (``parent``, ``jtype``, ``Xtree``, ``I``) and MuJoCo's ``mjModel``: the kernels
loop over these arrays and know nothing else, so they are compiled once for every mechanism.

Spanning tree and cut joints (automatic unless ``[mechanism] cut_joints`` names them): the
tree is grown from the ground one joint at a time (Prim's order), always taking the frontier
joint that is actuated first, then one reached from its parent's side (a joint described
child-to-parent is traversed backwards only when needed), then the one with the fewest
freedoms, then the first in the file. Every joint left over closes a loop and is *cut*: it becomes a :class:`LoopRecord` (the
two bodies, a frame on each, the constrained relative directions of its type). Preferring
few freedoms in the tree cuts the joints with many (spherical first), which gives the fewest
constraint equations and unknowns; actuated joints are always tree joints, so every actuator
coordinate is a tree coordinate.

Frames: every body frame, joint frame and point is stored in the body's own frame; at the
reference configuration (all tree coordinates zero) each joint's two frames coincide.
"""

from __future__ import annotations

import heapq
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import ParameterError
from .description import GROUND, Description, load_description
from .joint_types import MOTION_CODES, joint_type, type_code
from .legs import explicit_legs
from .records import LoopRecord, MechanismModel
from .topology import block_structure, solver_selection

__all__ = ["MechanismModel", "LoopRecord", "compile_model", "load_mechanism", "spanning_tree"]

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]


def spanning_tree(desc: Description) -> tuple[list[int], list[int]]:
    """Tree joints (in the order they were added, i.e. parents first) and cut joints (indices
    into ``desc.joints``); see the module docstring for the rule."""
    forced_cut = set(desc.cut_joints or ())
    adj: dict[str, list[int]] = {GROUND: [], **{b.name: [] for b in desc.bodies}}
    for k, j in enumerate(desc.joints):
        adj[j.parent].append(k)
        adj[j.child].append(k)
    reached = {GROUND}
    tree: list[int] = []
    heap: list[tuple[int, int, int, int]] = []

    def push(body: str) -> None:
        for k in adj[body]:
            j = desc.joints[k]
            if j.name not in forced_cut:
                backwards = 1 if j.child == body else 0  # reaching the parent through the child
                heapq.heappush(heap, (0 if j.actuated else 1, backwards, joint_type(j.type).freedoms, k))

    push(GROUND)
    while heap:
        _, _, _, k = heapq.heappop(heap)
        j = desc.joints[k]
        new = [b for b in (j.parent, j.child) if b not in reached]
        if not new:
            continue
        tree.append(k)
        reached.add(new[0])
        push(new[0])
    missing = [b.name for b in desc.bodies if b.name not in reached]
    if missing:
        raise ParameterError(f"[mechanism] cut_joints: cutting {', '.join(sorted(forced_cut))} disconnects body "
                             f"{missing[0]!r} from the ground")
    tset = set(tree)
    cuts = [k for k in range(len(desc.joints)) if k not in tset]
    for k in cuts:
        if desc.joints[k].actuated:
            raise ParameterError(f"[joints] {desc.joints[k].name}: the actuated joints form a loop; "
                                 "one of them would have to be cut")
    return tree, cuts


def _frame_in(R0: Array, p0: Array, frame: Array, point: Array) -> tuple[Array, Array]:
    """A base-frame joint frame (axes ``frame``, origin ``point``) in a body frame (R0, p0)."""
    return R0.T @ frame, R0.T @ (point - p0)


def compile_model(desc: Description, *, topology_only: bool = False) -> MechanismModel:
    """Compile a description into the arrays of :class:`MechanismModel` (see there).
    ``topology_only``: the tree, loops and task rows alone, before the solver's equations are
    chosen (for :func:`~.topology.analyse_topology` of a task that does not match yet).

    Raises :class:`~pkmdyn.errors.ParameterError` when the cut joints named in the file
    disconnect a body or an actuated joint would have to be cut.
    """
    tree, cuts = spanning_tree(desc)
    bspec = {b.name: b for b in desc.bodies}
    # body order: the order in which the tree reached them
    order = []
    child_of_joint = {}
    for k in tree:
        j = desc.joints[k]
        reached_before = {GROUND, *order}
        child = j.child if j.child not in reached_before else j.parent
        order.append(child)
        child_of_joint[k] = child
    bidx = {name: i for i, name in enumerate(order)}
    bidx[GROUND] = -1
    nb, nj = len(order), len(desc.joints)
    # a tree joint reached from its child side is traversed backwards ("flipped"): its motion is
    # the inverse, X_J(q)^-1 = M_k(-q_k) ... M_1(-q_1), with the two frames exchanged
    flipped = {k for k in tree if child_of_joint[k] == desc.joints[k].parent}
    parent_name = {}
    for k in tree:
        j = desc.joints[k]
        parent_name[child_of_joint[k]] = j.child if k in flipped else j.parent
    R0 = np.stack([bspec[n].R0 for n in order])
    p0 = np.stack([bspec[n].p0 for n in order])

    def pose(name: str) -> tuple[Array, Array]:
        if name == GROUND:
            return np.eye(3), np.zeros(3)
        return bspec[name].R0, bspec[name].p0

    jt = np.array([type_code(j.type) for j in desc.joints], dtype=np.int64)
    jp = np.array([bidx[j.parent] for j in desc.joints], dtype=np.int64)
    jc = np.array([bidx[j.child] for j in desc.joints], dtype=np.int64)
    RP, pP, RC, pC = (np.zeros((nj, 3, 3)), np.zeros((nj, 3)), np.zeros((nj, 3, 3)), np.zeros((nj, 3)))
    for k, j in enumerate(desc.joints):
        RP[k], pP[k] = _frame_in(*pose(j.parent), j.frame, j.point)
        RC[k], pC[k] = _frame_in(*pose(j.child), j.frame, j.point)
    body_joint = np.array([next(k for k in tree if child_of_joint[k] == n) for n in order], dtype=np.int64)
    body_parent = np.array([bidx[parent_name[n]] for n in order], dtype=np.int64)
    q0 = np.full(nj, -1, dtype=np.int64)
    nqj = np.array([joint_type(j.type).freedoms for j in desc.joints], dtype=np.int64)
    coord_joint, coord_motion, coord_offset, coord_sign = [], [], [], []
    for b in range(nb):
        k = int(body_joint[b])
        q0[k] = len(coord_joint)
        motions = joint_type(desc.joints[k].type).motions
        for m in (motions[::-1] if k in flipped else motions):
            coord_joint.append(k)
            coord_motion.append(MOTION_CODES[m])
            coord_offset.append(desc.joints[k].offset if nqj[k] == 1 else 0.0)
            coord_sign.append(-1.0 if k in flipped else 1.0)
    tRP, tpP, tRC, tpC = RP.copy(), pP.copy(), RC.copy(), pC.copy()
    for k in flipped:
        tRP[k], tpP[k], tRC[k], tpC[k] = RC[k], pC[k], RP[k], pP[k]
    nq = len(coord_joint)
    anc = np.zeros((nb, nq), dtype=bool)
    for b in range(nb):
        k = int(body_joint[b])
        par = int(body_parent[b])
        if par >= 0:
            anc[b] = anc[par]
        anc[b, q0[k]:q0[k] + nqj[k]] = True
    loops, row_loop, row_kind, row_i, row_j = [], [], [], [], []
    for li, k in enumerate(cuts):
        j = desc.joints[k]
        t = joint_type(j.type)
        for c in t.constraints:
            row_loop.append(li)
            row_kind.append(0 if c[0] == "T" else 1)
            row_i.append(c[1])
            row_j.append(c[2] if c[0] == "R" else 0)
        loops.append(LoopRecord(
            name=f"loop {li + 1} (cut {j.name})", joint=j.name, type=j.type, body_a=j.parent, body_b=j.child,
            R_a=RP[k], p_a=pP[k], R_b=RC[k], p_b=pC[k], constraints=t.constraints, directions=t.directions,
            path=_loop_path(desc, tree, child_of_joint, parent_name, j.parent, j.child),
        ))
    task = desc.task
    tb = bidx[task.body]
    seq = task.sequence
    if seq.isupper():
        axes = [{"X": 0, "Y": 1, "Z": 2}[c] for c in seq]
        perm = [0, 1, 2]
    else:
        axes = [{"x": 0, "y": 1, "z": 2}[c] for c in reversed(seq)]
        perm = [2, 1, 0]  # user angle k is intrinsic angle perm[k]
    task_kind = [0] * len(task.position) + [1] * len(task.orientation)
    task_index = list(task.position) + [perm[k] for k in task.orientation]
    act = [k for k in tree if desc.joints[k].actuated]
    act = sorted(act)
    lengths = [np.linalg.norm(j.point) for j in desc.joints] + [np.linalg.norm(b.p0) for b in desc.bodies]
    for j in desc.joints:
        lengths += [np.linalg.norm(j.point - o.point) for o in desc.joints[:50]]
    scale = float(max(max(lengths), 1e-3))
    lb = np.array([bidx[ld.body] for ld in desc.loads], dtype=np.int64)
    model = MechanismModel(
        name=desc.name, source=desc.source, path=desc.path, gravity=desc.gravity.copy(),
        body_names=tuple(order), body_parent=body_parent, body_joint=body_joint,
        mass=np.array([bspec[n].mass for n in order]), com=np.stack([bspec[n].com for n in order]),
        inertia=np.stack([bspec[n].inertia for n in order]), R0=R0, p0=p0,
        body_extra=tuple({"section": bspec[n].section, "material": bspec[n].material, "shape": bspec[n].shape}
                         for n in order),
        joint_names=tuple(j.name for j in desc.joints), joint_type=jt, joint_parent=jp, joint_child=jc,
        joint_R_parent=RP, joint_p_parent=pP, joint_R_child=RC, joint_p_child=pC,
        joint_cut=np.isin(np.arange(nj), cuts), joint_actuated=np.array([j.actuated for j in desc.joints]),
        joint_q0=q0, joint_nq=nqj, joint_offset=np.array([j.offset for j in desc.joints]),
        joint_limits=tuple(j.limits for j in desc.joints), joint_friction=tuple(j.friction for j in desc.joints),
        joint_stiffness=tuple(j.stiffness for j in desc.joints),
        coord_joint=np.array(coord_joint, dtype=np.int64), coord_motion=np.array(coord_motion, dtype=np.int64),
        coord_offset=np.array(coord_offset, dtype=float), coord_sign=np.array(coord_sign, dtype=float),
        joint_flipped=np.isin(np.arange(nj), sorted(flipped)), tree_R_parent=tRP, tree_p_parent=tpP,
        tree_R_child=tRC, tree_p_child=tpC, ancestors=anc, ancestor_list=_ancestor_list(anc),
        loops=tuple(loops), loop_joint=np.array(cuts, dtype=np.int64),
        row_loop=np.array(row_loop, dtype=np.int64), row_kind=np.array(row_kind, dtype=np.int64),
        row_i=np.array(row_i, dtype=np.int64), row_j=np.array(row_j, dtype=np.int64),
        task_body=tb, task_point=bspec[task.body].R0.T @ (task.point - bspec[task.body].p0),
        task_kind=np.array(task_kind, dtype=np.int64), task_index=np.array(task_index, dtype=np.int64),
        euler_sequence=seq, euler_axes=np.array(axes, dtype=np.int64), euler_perm=np.array(perm, dtype=np.int64),
        task_names=task.names, task_units=task.units,
        act_joint=np.array(act, dtype=np.int64), act_coord=np.array([q0[k] for k in act], dtype=np.int64),
        load_body=lb, load_force=np.array([ld.force for ld in desc.loads]).reshape(-1, 3),
        load_moment=np.array([ld.moment for ld in desc.loads]).reshape(-1, 3),
        load_point=np.array([bspec[ld.body].R0.T @ (ld.point - bspec[ld.body].p0) for ld in desc.loads]).reshape(-1, 3),
        length_scale=scale, motion=desc.motion,
        load_name=tuple(ld.name for ld in desc.loads),
        load_direction=np.array([ld.direction if ld.direction is not None else np.zeros(3)
                                 for ld in desc.loads]).reshape(-1, 3),
        load_magnitude=np.array([ld.magnitude for ld in desc.loads], dtype=float),
        named_loads=tuple(dict.fromkeys(ld.name for ld in desc.loads if ld.name is not None)),
    )
    if topology_only:
        return model
    rows, idle, rep = solver_selection(model)
    prow, pcol, blocks = block_structure(model, rows, idle)
    model = replace(model, solver_rows=rows, solver_idle=idle, solver_prow=prow, solver_pcol=pcol,
                    solver_blocks=blocks, topology=rep, **_drives(desc, act), **_body_groups(desc, order),
                    limits=dict(desc.limits), parameters=dict(desc.parameters),
                    parameter_bounds=dict(desc.parameter_bounds), reactions=desc.reactions)
    return replace(model, legs=explicit_legs(model))


def load_mechanism(source: str | Path | dict[str, Any], limits: dict[str, Any] | None = None) -> MechanismModel:
    """Read, validate and compile a description (a TOML path or a dict); ``limits`` lay over its
    ``[limits]`` for the plausibility of its numbers (:func:`~.description.load_description`)."""
    return compile_model(load_description(source, limits))


def _drives(desc: Description, act: list[int]) -> dict:
    """The model's ``drive_*`` arrays (:class:`MechanismModel`) for the actuated joints ``act``."""
    by_joint = {a.joint: a for a in desc.actuators}
    specs = [by_joint.get(desc.joints[k].name) for k in act]
    inf = float("inf")

    def arr(attr: str, default: float) -> Array:
        return np.array([default if a is None else float(getattr(a, attr)) for a in specs], dtype=float)

    return {"drive_name": tuple(None if a is None else a.name for a in specs),
            "drive_kind": tuple("" if a is None else a.kind for a in specs),
            "drive_ratio": arr("ratio", 1.0), "drive_rotor": arr("rotor", 0.0), "drive_coulomb": arr("coulomb", 0.0),
            "drive_viscous": arr("viscous", 0.0), "drive_max_effort": arr("max_effort", inf),
            "drive_max_speed": arr("max_speed", inf), "drive_max_acceleration": arr("max_acceleration", inf),
            "drive_encoder": arr("encoder_resolution", 0.0), "drive_specs": tuple(specs)}


def _body_groups(desc: Description, order: list[str]) -> dict:
    """``group_names`` and ``body_group`` (nb,) of the model's body order."""
    names = tuple(g for g, _ in desc.groups)
    of = {b: i for i, (_, bodies) in enumerate(desc.groups) for b in bodies}
    if not names:  # a description made without groups: one group of every body
        return {"group_names": ("bodies",), "body_group": np.zeros(len(order), dtype=np.int64)}
    return {"group_names": names, "body_group": np.array([of[b] for b in order], dtype=np.int64)}


def _ancestor_list(anc: NDArray[np.bool_]) -> IntArray:
    """(nb, 1 + max count): per body the number of coordinates moving it, then their indices."""
    counts = anc.sum(axis=1)
    out = np.full((anc.shape[0], 1 + int(counts.max(initial=0))), -1, dtype=np.int64)
    for b in range(anc.shape[0]):
        idx = np.flatnonzero(anc[b])
        out[b, 0] = idx.size
        out[b, 1:1 + idx.size] = idx
    return out


def _loop_path(desc: Description, tree: list[int], child_of_joint: dict, parent_name: dict, a: str, b: str) -> tuple[str, ...]:
    """Tree joints on the path between bodies ``a`` and ``b``."""
    joint_of = {child_of_joint[k]: desc.joints[k].name for k in tree}

    def up(x: str) -> list[str]:
        out = [x]
        while x != GROUND:
            x = parent_name[x]
            out.append(x)
        return out

    ua, ub = up(a), up(b)
    common = next(x for x in ua if x in ub)
    path = [joint_of[x] for x in ua[:ua.index(common)]] + [joint_of[x] for x in reversed(ub[:ub.index(common)])]
    return tuple(path)
