"""The compiled mechanism model: flat arrays of a spanning tree plus loop records.

``compile_model(description)`` turns a validated :class:`~pkmdyn.multibody.description.schema.Description` into a
:class:`MechanismModel`, a frozen record of plain arrays in the spirit of Featherstone's
``model`` (``parent``, ``jtype``, ``Xtree``, ``I``) and MuJoCo's ``mjModel``: the kernels
loop over these arrays and know nothing else, so they are compiled once for every mechanism.

Spanning tree and cut joints (automatic unless ``[mechanism] cut_joints`` names them): the
tree is grown from the ground one joint at a time (Prim's order), always taking the frontier
joint that is actuated or carries a spring first, then one reached from its parent's side (a joint described
child-to-parent is traversed backwards only when needed), then the one with the fewest
freedoms, then the first in the file. Every joint left over closes a loop and is *cut*: it becomes a :class:`LoopRecord` (the
two bodies, a frame on each, the constrained relative directions of its type). Preferring
few freedoms in the tree cuts the joints with many (spherical first), which gives the fewest
constraint equations and unknowns; actuated joints are always tree joints, so every actuator
coordinate is a tree coordinate.

Frames: every body frame, joint frame and point is stored in the body's own frame; at the
reference configuration (all tree coordinates zero) each joint's two frames coincide.

Structure and numbers: the compilation is split where a design sweep can reuse it
(:func:`compile_with`). :func:`structure_key` reads the description's structure (body and
joint names, joint types, which bodies they join, which are actuated, the cut joints named,
the task's body and coordinates, the loads' bodies and names); :func:`model_structure` makes
from that key alone, and nothing else, everything of the model that it decides
(:class:`ModelStructure`: spanning tree, body order, coordinates, loop rows, task rows,
actuators). The numbers (frames, masses, inertias, offsets, the length scale, loads, drives)
are computed from the description for every model, and so is everything the numbers may change:
the solver's rows and idle freedoms and the topology report (ranks at the reference
configuration, :func:`~pkmdyn.multibody.model.topology.solver_selection`) and the explicit legs (recognised from the
reference geometry, :func:`~pkmdyn.multibody.model.legs.explicit_legs`); the block order of the Newton system
(:func:`~pkmdyn.multibody.model.topology.block_structure`) is a function of the rows' structural pattern alone and is
remembered by that pattern.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from ...errors import ParameterError
from ..description.joint_types import MOTION_CODES, joint_type, type_code
from ..description.schema import GROUND, Description, load_description, split_task_joint
from .legs import explicit_legs
from .records import LoopRecord, MechanismModel
from .topology import block_structure, solver_selection

__all__ = ["MechanismModel", "LoopRecord", "compile_model", "load_mechanism", "spanning_tree", "structure_key",
           "tree_task_joints",
           "ModelStructure", "model_structure", "compile_with"]

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]


class JointKey(NamedTuple):
    """What of a joint decides the model's structure (:func:`structure_key`)."""

    name: str
    type: str
    parent: str
    child: str
    actuated: bool
    #: a joint spring: kept in the tree like an actuated joint (a cut joint has no coordinate)
    sprung: bool = False


class TaskKey(NamedTuple):
    """What of the task decides the model's structure (:func:`structure_key`)."""

    body: str
    position: tuple[int, ...]
    sequence: str
    orientation: tuple[int, ...]
    names: tuple[str, ...]
    units: tuple[str, ...]
    joints: tuple[str, ...] = ()


class StructureKey(NamedTuple):
    """A description's structure (:func:`structure_key`): everything :func:`model_structure`
    reads. Plain strings, integers and booleans: equal keys are equal structures, and the key
    pickles with a sweep's context."""

    bodies: tuple[str, ...]
    joints: tuple[JointKey, ...]
    cut_joints: tuple[str, ...] | None
    task: TaskKey
    loads: tuple[tuple[str, str | None], ...]


def structure_key(desc: Description) -> StructureKey:
    """The structure of a validated description: its bodies' names, its joints' names, types,
    parent and child bodies and whether each is actuated, the cut joints it names, the task's
    body, coordinates and Euler sequence, and each load's body and name. No number of the
    description is part of it (the module docstring: the split of :func:`compile_model`)."""
    t = desc.task
    return StructureKey(
        bodies=tuple(b.name for b in desc.bodies),
        joints=tuple(JointKey(j.name, j.type, j.parent, j.child, bool(j.actuated), j.spring is not None)
                     for j in desc.joints),
        cut_joints=None if desc.cut_joints is None else tuple(desc.cut_joints),
        task=TaskKey(t.body, tuple(t.position), t.sequence, tuple(t.orientation), tuple(t.names), tuple(t.units),
                     tuple(t.joints)),
        loads=tuple((ld.body, ld.name) for ld in desc.loads))


def spanning_tree(desc: Description) -> tuple[list[int], list[int]]:
    """Tree joints (in the order they were added, i.e. parents first) and cut joints (indices
    into ``desc.joints``); see the module docstring for the rule."""
    key = structure_key(desc)
    return _spanning_tree(key.bodies, key.joints, key.cut_joints, key.task.joints)


def _spanning_tree(bodies: Sequence[str], joints: Sequence[JointKey], cut_joints: Sequence[str] | None,
                   task_joints: Sequence[str] = ()) -> tuple[list[int], list[int]]:
    """:func:`spanning_tree` of the bodies' names and the joints' structure (:class:`JointKey`);
    the task's joints (``task_joints``) are taken into the tree first, as the actuated and
    sprung ones are (a task coordinate is a tree coordinate)."""
    forced_cut = set(cut_joints or ())
    first = {split_task_joint(item)[0] for item in task_joints}
    adj: dict[str, list[int]] = {GROUND: [], **{b: [] for b in bodies}}
    for k, j in enumerate(joints):
        adj[j.parent].append(k)
        adj[j.child].append(k)
    reached = {GROUND}
    tree: list[int] = []
    heap: list[tuple[int, int, int, int]] = []

    def push(body: str) -> None:
        for k in adj[body]:
            j = joints[k]
            if j.name not in forced_cut:
                backwards = 1 if j.child == body else 0  # reaching the parent through the child
                heapq.heappush(heap, (0 if j.actuated or j.sprung or j.name in first else 1, backwards, joint_type(j.type).freedoms, k))

    push(GROUND)
    while heap:
        _, _, _, k = heapq.heappop(heap)
        j = joints[k]
        new = [b for b in (j.parent, j.child) if b not in reached]
        if not new:
            continue
        tree.append(k)
        reached.add(new[0])
        push(new[0])
    missing = [b for b in bodies if b not in reached]
    if missing:
        raise ParameterError(f"[mechanism] cut_joints: cutting {', '.join(sorted(forced_cut))} disconnects body "
                             f"{missing[0]!r} from the ground")
    tset = set(tree)
    cuts = [k for k in range(len(joints)) if k not in tset]
    for k in cuts:
        if joints[k].actuated:
            raise ParameterError(f"[joints] {joints[k].name}: the actuated joints form a loop; "
                                 "one of them would have to be cut")
    return tree, cuts


def _frame_in(R0: Array, p0: Array, frame: Array, point: Array) -> tuple[Array, Array]:
    """A base-frame joint frame (axes ``frame``, origin ``point``) in a body frame (R0, p0)."""
    return R0.T @ frame, R0.T @ (point - p0)


@dataclass(frozen=True, eq=False)
class ModelStructure:
    """What of a compiled model the description's structure alone decides: made by
    :func:`model_structure` from a :class:`StructureKey` and nothing else, so that every
    description with an equal key compiles to these same fields (the module docstring).

    ``tree``, ``cuts``: the tree and cut joints (indices into the description's joints, tree
    order); ``order``: the body names in tree order; ``flipped``: the tree joints traversed from
    their child's side; ``coord_joint_one`` (nq,): per tree coordinate, its joint where that
    joint has one coordinate (whose ``offset`` is the coordinate's), else -1; ``act``: the
    actuated joints (sorted); ``loops``: per cut joint, its :class:`~pkmdyn.multibody.model.records.LoopRecord` but the
    frames (name, joint, type, body_a, body_b, constraints, directions, path); ``fields``: the
    :class:`~pkmdyn.multibody.model.records.MechanismModel` fields it decides (names, index arrays, coordinates,
    ancestors, loop and task rows, actuators; arrays copied into every model compiled)."""

    key: StructureKey
    tree: tuple[int, ...]
    cuts: tuple[int, ...]
    order: tuple[str, ...]
    flipped: frozenset[int]
    coord_joint_one: tuple[int, ...]
    act: tuple[int, ...]
    loops: tuple[tuple[Any, ...], ...]
    fields: dict[str, Any]


def model_structure(key: StructureKey) -> ModelStructure:
    """The structure of every description whose :func:`structure_key` is ``key`` (spanning tree,
    body order, coordinates, loop rows, task rows, actuators: the module docstring). It reads
    the key alone, so that a design sweep may make it once for all designs of one structure.

    Raises :class:`~pkmdyn.errors.ParameterError` when the cut joints named in the file
    disconnect a body or an actuated joint would have to be cut."""
    joints = key.joints
    tree, cuts = _spanning_tree(key.bodies, joints, key.cut_joints, key.task.joints)
    # body order: the order in which the tree reached them
    order: list[str] = []
    child_of_joint = {}
    for k in tree:
        j = joints[k]
        reached_before = {GROUND, *order}
        child = j.child if j.child not in reached_before else j.parent
        order.append(child)
        child_of_joint[k] = child
    bidx = {name: i for i, name in enumerate(order)}
    bidx[GROUND] = -1
    nb, nj = len(order), len(joints)
    # a tree joint reached from its child side is traversed backwards ("flipped"): its motion is
    # the inverse, X_J(q)^-1 = M_k(-q_k) ... M_1(-q_1), with the two frames exchanged
    flipped = {k for k in tree if child_of_joint[k] == joints[k].parent}
    parent_name = {}
    for k in tree:
        j = joints[k]
        parent_name[child_of_joint[k]] = j.child if k in flipped else j.parent
    jt = np.array([type_code(j.type) for j in joints], dtype=np.int64)
    jp = np.array([bidx[j.parent] for j in joints], dtype=np.int64)
    jc = np.array([bidx[j.child] for j in joints], dtype=np.int64)
    body_joint = np.array([next(k for k in tree if child_of_joint[k] == n) for n in order], dtype=np.int64)
    body_parent = np.array([bidx[parent_name[n]] for n in order], dtype=np.int64)
    q0 = np.full(nj, -1, dtype=np.int64)
    nqj = np.array([joint_type(j.type).freedoms for j in joints], dtype=np.int64)
    coord_joint, coord_motion, coord_one, coord_sign = [], [], [], []
    for b in range(nb):
        k = int(body_joint[b])
        q0[k] = len(coord_joint)
        motions = joint_type(joints[k].type).motions
        for m in (motions[::-1] if k in flipped else motions):
            coord_joint.append(k)
            coord_motion.append(MOTION_CODES[m])
            coord_one.append(k if nqj[k] == 1 else -1)
            coord_sign.append(-1.0 if k in flipped else 1.0)
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
        j = joints[k]
        t = joint_type(j.type)
        for c in t.constraints:
            row_loop.append(li)
            row_kind.append(0 if c[0] == "T" else 1)
            row_i.append(c[1])
            row_j.append(c[2] if c[0] == "R" else 0)
        loops.append((f"loop {li + 1} (cut {j.name})", j.name, j.type, j.parent, j.child, t.constraints, t.directions,
                      _loop_path(joints, tree, child_of_joint, parent_name, j.parent, j.child)))
    task = key.task
    seq = task.sequence
    if seq.isupper():
        axes = [{"X": 0, "Y": 1, "Z": 2}[c] for c in seq]
        perm = [0, 1, 2]
    else:
        axes = [{"x": 0, "y": 1, "z": 2}[c] for c in reversed(seq)]
        perm = [2, 1, 0]  # user angle k is intrinsic angle perm[k]
    jnames = {j.name: k for k, j in enumerate(joints)}
    joint_coords = []  # the tree coordinate of each task joint entry
    for item in task.joints:
        nm, kc = split_task_joint(item)
        kj = jnames[nm]
        if kj in cuts:
            raise ParameterError(f"[task] joints: {nm!r} is a loop's cut joint, so its coordinates are not the "
                                 "tree's; name another joint of that loop in [mechanism] cut_joints, or choose "
                                 "another task joint")
        i = max(kc, 1) - 1  # the joint's i-th motion: a joint traversed backwards has them reversed
        joint_coords.append(q0[kj] + (nqj[kj] - 1 - i if kj in flipped else i))
    task_kind = [0] * len(task.position) + [1] * len(task.orientation) + [2] * len(task.joints)
    task_index = list(task.position) + [perm[k] for k in task.orientation] + joint_coords
    act = sorted(k for k in tree if joints[k].actuated)
    fields = dict(
        body_names=tuple(order), body_parent=body_parent, body_joint=body_joint,
        joint_names=tuple(j.name for j in joints), joint_type=jt, joint_parent=jp, joint_child=jc,
        joint_cut=np.isin(np.arange(nj), cuts), joint_actuated=np.array([j.actuated for j in joints]),
        joint_q0=q0, joint_nq=nqj,
        coord_joint=np.array(coord_joint, dtype=np.int64), coord_motion=np.array(coord_motion, dtype=np.int64),
        coord_sign=np.array(coord_sign, dtype=float),
        joint_flipped=np.isin(np.arange(nj), sorted(flipped)), ancestors=anc, ancestor_list=_ancestor_list(anc),
        loop_joint=np.array(cuts, dtype=np.int64),
        row_loop=np.array(row_loop, dtype=np.int64), row_kind=np.array(row_kind, dtype=np.int64),
        row_i=np.array(row_i, dtype=np.int64), row_j=np.array(row_j, dtype=np.int64),
        task_body=bidx[task.body], task_kind=np.array(task_kind, dtype=np.int64),
        task_index=np.array(task_index, dtype=np.int64), task_length=np.array([u == "m" for u in task.units]),
        euler_sequence=seq, euler_axes=np.array(axes, dtype=np.int64),
        euler_perm=np.array(perm, dtype=np.int64), task_names=task.names, task_units=task.units,
        task_joints=tuple(task.joints),
        act_joint=np.array(act, dtype=np.int64), act_coord=np.array([q0[k] for k in act], dtype=np.int64),
        load_body=np.array([bidx[b] for b, _ in key.loads], dtype=np.int64),
        load_name=tuple(name for _, name in key.loads),
        named_loads=tuple(dict.fromkeys(name for _, name in key.loads if name is not None)),
    )
    return ModelStructure(key=key, tree=tuple(tree), cuts=tuple(cuts), order=tuple(order), flipped=frozenset(flipped),
                          coord_joint_one=tuple(coord_one), act=tuple(act), loops=tuple(loops), fields=fields)


def _length_scale(desc: Description) -> float:
    """The model's length scale [m]: the largest of 1 mm, the distance of every joint point and
    body origin from the base origin and of every joint point from each of the first 50 joints'
    points (reference configuration). Each distance is ``np.linalg.norm`` of the difference, as
    it always was; the vectorised norms only pick the candidates for the largest (those within
    1e-9 of it, relative: a vectorised and a BLAS norm of three numbers differ by a few units in
    the last place), so the scale is the same number to the last bit, without 50 x joints calls."""
    points = np.array([j.point for j in desc.joints], dtype=float).reshape(-1, 3)
    origins = np.array([b.p0 for b in desc.bodies], dtype=float).reshape(-1, 3)
    pairs = (points[:, None, :] - points[None, :50, :]).reshape(-1, 3)
    every = np.concatenate([points, origins, pairs])
    approx = np.sqrt(np.einsum("ij,ij->i", every, every))
    if not np.all(np.isfinite(approx)):  # (validated descriptions are finite) the distances one by one
        lengths = [np.linalg.norm(j.point) for j in desc.joints] + [np.linalg.norm(b.p0) for b in desc.bodies]
        for j in desc.joints:
            lengths += [np.linalg.norm(j.point - o.point) for o in desc.joints[:50]]
        return float(max(max(lengths), 1e-3))
    nj, nbd, first = len(desc.joints), len(desc.bodies), min(len(desc.joints), 50)
    exact = []
    for i in np.flatnonzero(approx >= approx.max() * (1.0 - 1e-9)):
        i = int(i)
        if i < nj:
            exact.append(np.linalg.norm(desc.joints[i].point))
        elif i < nj + nbd:
            exact.append(np.linalg.norm(desc.bodies[i - nj].p0))
        else:
            a, b = divmod(i - nj - nbd, first)
            exact.append(np.linalg.norm(desc.joints[a].point - desc.joints[b].point))
    return float(max(max(exact), 1e-3))


def _number_fields(desc: Description, st: ModelStructure) -> dict[str, Any]:
    """The :class:`~pkmdyn.multibody.model.records.MechanismModel` fields that the description's numbers decide, in
    the body order and frames of the structure ``st``: mass properties, reference frames, joint
    frames and offsets, loop frames, the task point, the length scale, loads, the default
    motion (the module docstring)."""
    bspec = {b.name: b for b in desc.bodies}
    order = st.order
    R0 = np.stack([bspec[n].R0 for n in order])
    p0 = np.stack([bspec[n].p0 for n in order])

    def pose(name: str) -> tuple[Array, Array]:
        if name == GROUND:
            return np.eye(3), np.zeros(3)
        return bspec[name].R0, bspec[name].p0

    nj = len(desc.joints)
    RP, pP, RC, pC = (np.zeros((nj, 3, 3)), np.zeros((nj, 3)), np.zeros((nj, 3, 3)), np.zeros((nj, 3)))
    for k, j in enumerate(desc.joints):
        RP[k], pP[k] = _frame_in(*pose(j.parent), j.frame, j.point)
        RC[k], pC[k] = _frame_in(*pose(j.child), j.frame, j.point)
    tRP, tpP, tRC, tpC = RP.copy(), pP.copy(), RC.copy(), pC.copy()
    for k in st.flipped:
        tRP[k], tpP[k], tRC[k], tpC[k] = RC[k], pC[k], RP[k], pP[k]
    loops = tuple(LoopRecord(name=name, joint=joint, type=type_, body_a=a, body_b=b, R_a=RP[k], p_a=pP[k], R_b=RC[k],
                             p_b=pC[k], constraints=constraints, directions=directions, path=path)
                  for k, (name, joint, type_, a, b, constraints, directions, path) in zip(st.cuts, st.loops))
    task = desc.task
    return dict(
        name=desc.name, source=desc.source, path=desc.path, gravity=desc.gravity.copy(),
        mass=np.array([bspec[n].mass for n in order]), com=np.stack([bspec[n].com for n in order]),
        inertia=np.stack([bspec[n].inertia for n in order]), R0=R0, p0=p0,
        body_extra=tuple({"section": bspec[n].section, "material": bspec[n].material, "shape": bspec[n].shape}
                         for n in order),
        joint_R_parent=RP, joint_p_parent=pP, joint_R_child=RC, joint_p_child=pC,
        joint_offset=np.array([j.offset for j in desc.joints]),
        joint_limits=tuple(j.limits for j in desc.joints), joint_friction=tuple(j.friction for j in desc.joints),
        joint_stiffness=tuple(j.stiffness for j in desc.joints),
        joint_bearing=np.array([-1 if j.bearing is None else int(j.bearing == j.child) for j in desc.joints],
                               dtype=np.int64),
        joint_spring=tuple(j.spring for j in desc.joints),
        coord_offset=np.array([desc.joints[k].offset if k >= 0 else 0.0 for k in st.coord_joint_one], dtype=float),
        tree_R_parent=tRP, tree_p_parent=tpP, tree_R_child=tRC, tree_p_child=tpC, loops=loops,
        task_point=bspec[task.body].R0.T @ (task.point - bspec[task.body].p0),
        load_force=np.array([ld.force for ld in desc.loads]).reshape(-1, 3),
        load_moment=np.array([ld.moment for ld in desc.loads]).reshape(-1, 3),
        load_point=np.array([bspec[ld.body].R0.T @ (ld.point - bspec[ld.body].p0) for ld in desc.loads]).reshape(-1, 3),
        length_scale=_length_scale(desc), motion=desc.motion,
        load_direction=np.array([ld.direction if ld.direction is not None else np.zeros(3)
                                 for ld in desc.loads]).reshape(-1, 3),
        load_magnitude=np.array([ld.magnitude for ld in desc.loads], dtype=float),
        output_names=tuple(o.name for o in desc.outputs),
        output_body=np.array([order.index(o.body) for o in desc.outputs], dtype=np.int64),
        output_point=np.array([bspec[o.body].R0.T @ (o.point - bspec[o.body].p0) for o in desc.outputs]).reshape(-1, 3),
    )


def compile_model(desc: Description, *, topology_only: bool = False) -> MechanismModel:
    """Compile a description into the arrays of :class:`MechanismModel` (see there).
    ``topology_only``: the tree, loops and task rows alone, before the solver's equations are
    chosen (for :func:`~pkmdyn.multibody.model.topology.analyse_topology` of a task that does not match yet).

    Raises :class:`~pkmdyn.errors.ParameterError` when the cut joints named in the file
    disconnect a body or an actuated joint would have to be cut.
    """
    return _compile(desc, model_structure(structure_key(desc)), topology_only=topology_only)


def compile_with(structure: ModelStructure | None, desc: Description) -> MechanismModel:
    """:func:`compile_model` of ``desc``, the same model to the last bit, with ``structure`` (made
    once, :func:`model_structure`) where ``desc`` has that structure (:func:`structure_key`):
    the numbers, the solver's rows, idle freedoms and topology report and the explicit legs are
    computed for ``desc`` as always (the module docstring). A description of another structure
    (a swept count of legs; or no ``structure``) is compiled in full."""
    if structure is None or structure_key(desc) != structure.key:
        return compile_model(desc)
    return _compile(desc, structure)


def _compile(desc: Description, st: ModelStructure, topology_only: bool = False) -> MechanismModel:
    """The model of ``desc`` with the structure ``st`` (which must be
    ``model_structure(structure_key(desc))``): the structure's fields (arrays copied), the
    numbers', then, unless ``topology_only``, the solver's selection at the reference
    configuration, the block order, the drives, groups and the explicit legs."""
    # the structure/number split (module docstring): what the key decides from ``st``, the
    # numbers from ``desc``, then everything the numbers may change computed for ``desc``
    fields = {k: (v.copy() if isinstance(v, np.ndarray) else v) for k, v in st.fields.items()}
    model = MechanismModel(**fields, **_number_fields(desc, st))
    for k, sp in enumerate(model.joint_spring):
        if sp is not None and model.joint_cut[k]:
            raise ParameterError(f"{model.path or model.name}: [joints] {model.joint_names[k]} spring: the joint is cut to "
                                 "close a loop and has no coordinate of its own; cut another joint of the loop "
                                 "([mechanism] cut_joints)")
    if topology_only:
        return model
    rows, idle, rep = solver_selection(model)  # ranks at the reference: numbers
    prow, pcol, blocks = block_structure(model, rows, idle)
    model = replace(model, solver_rows=rows, solver_idle=idle, solver_prow=prow, solver_pcol=pcol,
                    solver_blocks=blocks, topology=rep, **_drives(desc, list(st.act)), **_body_groups(desc, list(st.order)),
                    limits=dict(desc.limits), parameters=dict(desc.parameters),
                    parameter_bounds=dict(desc.parameter_bounds), reactions=desc.reactions)
    model = replace(model, **_actuation(desc, model, rep.dof))
    return replace(model, legs=explicit_legs(model))  # recognised from the reference geometry: numbers


def _actuation(desc: Description, model: MechanismModel, dof: int) -> dict:
    """The model's ``act_*`` fields of ``[actuation]`` (:class:`MechanismModel`); the section is
    refused, naming it, on a mechanism with no more actuators than degrees of freedom."""
    a = desc.actuation
    if a.given and model.na <= dof:
        raise ParameterError(f"{model.path or model.name}: [actuation]: {model.na} actuated joint(s) for {dof} degree(s) "
                             "of freedom: the efforts are determined, there is nothing to distribute (the section "
                             "is for a redundantly actuated mechanism, more actuated joints than freedoms)")
    if a.preload_min_effort and model.na - dof > 1 and not a.preload_sign:
        raise ParameterError(f"{model.path or model.name}: [actuation] preload_sign: {model.na - dof} internal-force "
                             "directions; give each preloaded joint's sign (the preload's pattern is not one "
                             "direction's)")
    names = list(model.actuator_names)

    def per(items: tuple, default: float) -> Array:
        out = np.full(len(names), default, dtype=float)
        for name, v in items:
            out[names.index(name)] = float(v)
        return out

    rated = np.where(np.isfinite(model.drive_max_effort), model.drive_max_effort * model.drive_ratio, np.inf)
    return {"act_distribution": a.distribution, "act_weight": per(a.weights, 1.0),
            "act_bound": np.minimum(per(a.max_effort, math.inf), rated), "act_preload": float(a.preload_min_effort),
            "act_preload_sign": per(a.preload_sign, 0.0)}


def load_mechanism(source: str | Path | dict[str, Any], limits: dict[str, Any] | None = None) -> MechanismModel:
    """Read, validate and compile a description (a TOML path or a dict); ``limits`` lay over its
    ``[limits]`` for the plausibility of its numbers (:func:`~pkmdyn.multibody.description.schema.load_description`)."""
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
            "drive_encoder": arr("encoder_resolution", 0.0), "drive_specs": tuple(specs),
            "drive_copper": np.array([math.nan if a is None or not a.constant else a.resistance / a.constant ** 2
                                      for a in specs], dtype=float)}


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


def _loop_path(joints: Sequence[JointKey], tree: list[int], child_of_joint: dict, parent_name: dict, a: str,
               b: str) -> tuple[str, ...]:
    """Tree joints on the path between bodies ``a`` and ``b``."""
    joint_of = {child_of_joint[k]: joints[k].name for k in tree}

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


def tree_task_joints(model: MechanismModel) -> tuple[str, ...]:
    """The task's ``[task] joints`` entries as the spanning tree holds the joints (what an export
    writes): a joint of several coordinates that the tree reaches from its child has them in
    reverse order, so its k-th coordinate is the tree's ``n + 1 - k``-th (the same value)."""
    out = []
    for item in model.task_joints:
        nm, k = split_task_joint(item)
        j = model.joint_names.index(nm)
        n = int(model.joint_nq[j])
        out.append(f"{nm}:{n + 1 - k}" if k and n > 1 and model.joint_flipped[j] else item)
    return tuple(out)
