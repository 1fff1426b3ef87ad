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
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray

from ..errors import ParameterError
from .description import GROUND, Description
from .joint_types import JOINT_TYPES, MOTION_CODES, joint_type, type_code
from .legs import explicit_legs
from .topology import block_structure, solver_selection

__all__ = ["MechanismModel", "LoopRecord", "compile_model", "spanning_tree"]

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class LoopRecord:
    """One independent loop, closed by the cut joint ``joint``.

    ``body_a`` (the cut joint's parent) carries frame ``(R_a, p_a)``, ``body_b`` (its child)
    carries ``(R_b, p_b)``: rotation (3, 3) and origin (3,) [m] in that body's frame.
    ``constraints``: the residual rows of :mod:`.joint_types` (``("T", i)`` or
    ``("R", i, j)``); ``directions``: their names (``force_x`` ... ``couple_z`` in the joint
    frame of ``body_a``); ``path``: the tree joints of the loop."""

    name: str
    joint: str
    type: str
    body_a: str
    body_b: str
    R_a: Array
    p_a: Array
    R_b: Array
    p_b: Array
    constraints: tuple[tuple, ...]
    directions: tuple[str, ...]
    path: tuple[str, ...]


@dataclass(frozen=True)
class MechanismModel:
    """A compiled mechanism. Index conventions: bodies ``0..nb-1`` in tree order (a parent
    before its children), ``-1`` is the ground; joints in description order; tree
    coordinates ``0..nq-1`` in body order.

    Bodies: ``body_names`` (nb,); ``body_parent`` (nb,) parent body; ``body_joint`` (nb,) the
    tree joint whose child it is; ``mass`` (nb,) [kg]; ``com`` (nb, 3) [m] and ``inertia``
    (nb, 3, 3) [kg m^2] about the centre of mass, body frame; ``R0`` (nb, 3, 3), ``p0``
    (nb, 3) [m]: body frame in the base frame at the reference configuration.

    Joints: ``joint_names``, ``joint_type`` (nj,) codes into
    :data:`~.joint_types.JOINT_TYPES`; ``joint_parent``/``joint_child`` (nj,) body indices;
    ``joint_R_parent``/``joint_p_parent`` (nj, 3, 3)/(nj, 3) [m] the joint frame in the
    parent's frame, ``joint_R_child``/``joint_p_child`` in the child's; ``joint_cut`` (nj,)
    bool; ``joint_actuated`` (nj,) bool; ``joint_q0`` (nj,) first tree coordinate (-1 for a
    cut joint); ``joint_nq`` (nj,) its number of coordinates; ``joint_offset`` (nj,) the
    coordinate at the reference configuration (1-coordinate joints, [m] or [rad]).

    Tree coordinates: ``coord_joint`` (nq,), ``coord_motion`` (nq,) elementary-motion codes
    (:data:`~.joint_types.MOTION_CODES`), ``coord_offset`` (nq,), ``coord_sign`` (nq,);
    ``ancestors`` (nb, nq) bool: coordinate k moves body b; ``ancestor_list`` (nb, 1 + max)
    the same as a count followed by the coordinates (what the kernels read). A tree joint reached from its
    child's side (``joint_flipped``) moves its description parent by the inverse motion
    ``M_k(-q_k) ... M_1(-q_1)``: its coordinates are stored in reverse order with sign -1,
    and ``tree_R_parent``/``tree_p_parent``/``tree_R_child``/``tree_p_child`` (nj, ...) hold
    the frames in tree order (exchanged for a flipped joint). A one-coordinate joint's
    coordinate is the description's either way.

    Loops: ``loops`` (records); kernel rows ``row_loop``, ``row_kind`` (0 translation,
    1 rotation), ``row_i``, ``row_j`` (nr,).

    Task coordinates: ``task_body``; ``task_point`` (3,) [m] body frame; ``task_kind`` (nt,)
    0 position / 1 Euler angle; ``task_index`` (nt,) the base-frame component or the angle's
    place in ``euler_axes`` (3,) (the intrinsic axes; an extrinsic sequence is stored as the
    reversed intrinsic one, ``euler_perm`` mapping its angles); ``task_names``,
    ``task_units``.

    Actuators: ``act_joint`` (na,) joint indices, ``act_coord`` (na,) tree coordinates.

    Solver: ``solver_rows`` (m,) rows of the square Newton system (independent constraint
    rows, then every task row) and ``solver_idle`` (nq - m, nq) the directions of the idle
    freedoms, held (``solver_idle (q - q_ref) = 0``), chosen at the reference configuration;
    ``solver_prow``, ``solver_pcol`` (nq,) the row and column order that makes the Newton
    matrix block lower-triangular, ``solver_blocks`` the first row of each diagonal block
    (then nq) (:func:`~.topology.block_structure`)
    (:func:`~.topology.solver_selection`); ``topology``: the
    :class:`~.topology.TopologyReport` there; ``legs``: the blocks solved in closed form
    (:mod:`.legs`).
    """

    name: str
    source: str
    path: str
    gravity: Array
    body_names: tuple[str, ...]
    body_parent: IntArray
    body_joint: IntArray
    mass: Array
    com: Array
    inertia: Array
    R0: Array
    p0: Array
    body_extra: tuple[dict, ...]
    joint_names: tuple[str, ...]
    joint_type: IntArray
    joint_parent: IntArray
    joint_child: IntArray
    joint_R_parent: Array
    joint_p_parent: Array
    joint_R_child: Array
    joint_p_child: Array
    joint_cut: NDArray[np.bool_]
    joint_actuated: NDArray[np.bool_]
    joint_q0: IntArray
    joint_nq: IntArray
    joint_offset: Array
    joint_limits: tuple[tuple[float, float] | None, ...]
    joint_friction: tuple[dict | None, ...]
    #: joint and drive stiffness (``JointSpec.stiffness``), None for a rigid joint
    joint_stiffness: tuple[dict | None, ...]
    coord_joint: IntArray
    coord_motion: IntArray
    coord_offset: Array
    coord_sign: Array
    joint_flipped: NDArray[np.bool_]
    tree_R_parent: Array
    tree_p_parent: Array
    tree_R_child: Array
    tree_p_child: Array
    ancestors: NDArray[np.bool_]
    ancestor_list: IntArray
    loops: tuple[LoopRecord, ...]
    loop_joint: IntArray
    row_loop: IntArray
    row_kind: IntArray
    row_i: IntArray
    row_j: IntArray
    task_body: int
    task_point: Array
    task_kind: IntArray
    task_index: IntArray
    euler_sequence: str
    euler_axes: IntArray
    euler_perm: IntArray
    task_names: tuple[str, ...]
    task_units: tuple[str, ...]
    act_joint: IntArray
    act_coord: IntArray
    load_body: IntArray
    load_force: Array
    load_moment: Array
    load_point: Array
    length_scale: float
    motion: object
    #: per load: its name when it is a named load (magnitude per sample), else None; its unit
    #: direction (base frame; zero for a constant load); the distinct names in order
    load_name: tuple[str | None, ...] = ()
    load_direction: Array = field(default_factory=lambda: np.zeros((0, 3)))
    load_magnitude: Array = field(default_factory=lambda: np.zeros(0))
    named_loads: tuple[str, ...] = ()
    solver_rows: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    solver_idle: Array = field(default_factory=lambda: np.zeros((0, 0)))
    solver_prow: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    solver_pcol: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    solver_blocks: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    topology: object = None
    #: the explicit legs (:class:`~.legs.LegTable`): blocks of the Newton system solved in closed
    #: form; None only while the model is being compiled
    legs: object = None
    #: per actuator (order of ``act_joint``): its drive's name (``[[actuators]]``; None for a
    #: joint that drives itself), ``drive_kind`` (``"rotary"``, ``"linear"``, ``""``), the
    #: transmission ratio ``drive_ratio`` k (motor coordinate per joint coordinate, 1 without a
    #: drive), the rotor inertia ``drive_rotor`` [kg m^2 or kg], the motor's friction
    #: ``drive_coulomb``, ``drive_viscous``, its limits ``drive_max_effort``,
    #: ``drive_max_speed``, ``drive_max_acceleration`` (motor side, inf when not given) and the
    #: encoder's resolution ``drive_encoder`` (motor displacement per count; 0 when not given)
    drive_name: tuple[str | None, ...] = ()
    drive_kind: tuple[str, ...] = ()
    drive_ratio: Array = field(default_factory=lambda: np.zeros(0))
    drive_rotor: Array = field(default_factory=lambda: np.zeros(0))
    drive_coulomb: Array = field(default_factory=lambda: np.zeros(0))
    drive_viscous: Array = field(default_factory=lambda: np.zeros(0))
    drive_max_effort: Array = field(default_factory=lambda: np.zeros(0))
    drive_max_speed: Array = field(default_factory=lambda: np.zeros(0))
    drive_max_acceleration: Array = field(default_factory=lambda: np.zeros(0))
    drive_encoder: Array = field(default_factory=lambda: np.zeros(0))
    drive_specs: tuple = ()
    #: the effort split's body groups: names, and each body's group index (nb,)
    group_names: tuple[str, ...] = ()
    body_group: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    #: plausibility limits of motions (``[limits]``: ``description.LIMIT_KEYS``)
    limits: dict = field(default_factory=dict)
    #: the description's named design parameters and their values (``[parameters]``)
    parameters: dict = field(default_factory=dict)
    #: ``[mechanism] reactions``: ``"unique"`` (an over-constrained run without compliance data
    #: is refused) or ``"minimum-norm"``
    reactions: str = "unique"

    @property
    def nb(self) -> int:
        return len(self.body_names)

    @property
    def nq(self) -> int:
        return int(self.coord_joint.shape[0])

    @property
    def nt(self) -> int:
        return len(self.task_names)

    @property
    def na(self) -> int:
        return int(self.act_joint.shape[0])

    @property
    def actuator_names(self) -> tuple[str, ...]:
        return tuple(self.joint_names[j] for j in self.act_joint)

    @property
    def actuator_units(self) -> tuple[str, ...]:
        return tuple(JOINT_TYPES[self.joint_type[j]].units[0] for j in self.act_joint)

    @property
    def has_drives(self) -> bool:
        """Whether any actuated joint has a drive (an ``[[actuators]]`` entry)."""
        return any(d is not None for d in self.drive_name)

    @property
    def motor_units(self) -> tuple[str, ...]:
        """Unit of each actuator's motor coordinate: ``rad`` (a rotary motor) or ``m`` (a linear
        one; also a joint without a drive, in its own unit)."""
        return tuple("rad" if k == "rotary" else ("m" if k == "linear" else u)
                     for k, u in zip(self.drive_kind, self.actuator_units))

    def body_index(self, name: str) -> int:
        """Index of body ``name`` (-1 for the ground)."""
        if name == GROUND:
            return -1
        try:
            return self.body_names.index(name)
        except ValueError:
            raise ParameterError(f"{name!r} is not a body of mechanism {self.name!r}") from None

    def joint_index(self, name: str) -> int:
        try:
            return self.joint_names.index(name)
        except ValueError:
            raise ParameterError(f"{name!r} is not a joint of mechanism {self.name!r}") from None


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
                    limits=dict(desc.limits), parameters=dict(desc.parameters), reactions=desc.reactions)
    return replace(model, legs=explicit_legs(model))


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
