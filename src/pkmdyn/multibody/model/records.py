"""The compiled mechanism's record: :class:`MechanismModel`, the flat arrays of a spanning tree
plus loop records that the kernels read, and :class:`LoopRecord`, one closed loop. Built by
:func:`pkmdyn.multibody.model.compiler.compile_model`; kept apart from it so that the modules the compilation uses
(:mod:`pkmdyn.multibody.model.topology`) can name the record without importing the compiler."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ...errors import ParameterError
from ..description.schema import GROUND
from ..description.joint_types import JOINT_TYPES

__all__ = ["MechanismModel", "LoopRecord"]

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class LoopRecord:
    """One independent loop, closed by the cut joint ``joint``.

    ``body_a`` (the cut joint's parent) carries frame ``(R_a, p_a)``, ``body_b`` (its child)
    carries ``(R_b, p_b)``: rotation (3, 3) and origin (3,) [m] in that body's frame.
    ``constraints``: the residual rows of :mod:`pkmdyn.multibody.description.joint_types` (``("T", i)`` or
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
    :data:`~pkmdyn.multibody.description.joint_types.JOINT_TYPES`; ``joint_parent``/``joint_child`` (nj,) body indices;
    ``joint_R_parent``/``joint_p_parent`` (nj, 3, 3)/(nj, 3) [m] the joint frame in the
    parent's frame, ``joint_R_child``/``joint_p_child`` in the child's; ``joint_cut`` (nj,)
    bool; ``joint_actuated`` (nj,) bool; ``joint_q0`` (nj,) first tree coordinate (-1 for a
    cut joint); ``joint_nq`` (nj,) its number of coordinates; ``joint_offset`` (nj,) the
    coordinate at the reference configuration (1-coordinate joints, [m] or [rad]).

    Tree coordinates: ``coord_joint`` (nq,), ``coord_motion`` (nq,) elementary-motion codes
    (:data:`~pkmdyn.multibody.description.joint_types.MOTION_CODES`), ``coord_offset`` (nq,), ``coord_sign`` (nq,);
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
    0 position / 1 Euler angle / 2 a joint's coordinate; ``task_index`` (nt,) the base-frame
    component, the angle's place in ``euler_axes`` (3,) (the intrinsic axes; an extrinsic
    sequence is stored as the reversed intrinsic one, ``euler_perm`` mapping its angles) or the
    tree coordinate; ``task_length`` (nt,) whether the coordinate is a length [m] (else an
    angle [rad]); ``task_names``, ``task_units``.

    Actuators: ``act_joint`` (na,) joint indices, ``act_coord`` (na,) tree coordinates.

    Solver: ``solver_rows`` (m,) rows of the square Newton system (independent constraint
    rows, then every task row) and ``solver_idle`` (nq - m, nq) the directions of the idle
    freedoms, held (``solver_idle (q - q_ref) = 0``), chosen at the reference configuration;
    ``solver_prow``, ``solver_pcol`` (nq,) the row and column order that makes the Newton
    matrix block lower-triangular, ``solver_blocks`` the first row of each diagonal block
    (then nq) (:func:`~pkmdyn.multibody.model.topology.block_structure`)
    (:func:`~pkmdyn.multibody.model.topology.solver_selection`); ``topology``: the
    :class:`~pkmdyn.multibody.model.topology.TopologyReport` there; ``legs``: the blocks solved in closed form
    (:mod:`pkmdyn.multibody.model.legs`).
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
    task_length: NDArray[np.bool_]
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
    #: the task's ``[task] joints`` entries (``"name"`` or ``"name:k"``), in the order of its joint rows
    task_joints: tuple[str, ...] = ()
    load_direction: Array = field(default_factory=lambda: np.zeros((0, 3)))
    load_magnitude: Array = field(default_factory=lambda: np.zeros(0))
    named_loads: tuple[str, ...] = ()
    solver_rows: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    solver_idle: Array = field(default_factory=lambda: np.zeros((0, 0)))
    solver_prow: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    solver_pcol: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    solver_blocks: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    topology: object = None
    #: the explicit legs (:class:`~pkmdyn.multibody.model.legs.LegTable`): blocks of the Newton system solved in closed
    #: form; None only while the model is being compiled
    legs: object = None
    #: per actuator (order of ``act_joint``): its drive's name (``[[actuators]]``; None for a
    #: joint that drives itself), ``drive_kind`` (``"rotary"``, ``"linear"``, ``""``), the
    #: transmission ratio ``drive_ratio`` k (motor coordinate per joint coordinate, 1 without a
    #: drive), the rotor inertia ``drive_rotor`` [kg m^2 or kg], the motor's friction
    #: ``drive_coulomb``, ``drive_viscous``, its limits ``drive_max_effort``,
    #: ``drive_max_speed``, ``drive_max_acceleration`` (motor side, inf when not given) and the
    #: encoder's resolution ``drive_encoder`` (motor displacement per count; 0 when not given);
    #: ``drive_copper`` the copper losses per squared motor effort, ``R / k_t^2`` [W/(N m)^2 or
    #: W/N^2] (NaN where the drive gives no winding resistance and motor constant)
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
    drive_copper: Array = field(default_factory=lambda: np.zeros(0))
    #: a redundantly actuated mechanism's distribution of its efforts (``[actuation]``):
    #: ``"minimum_norm"``, ``"weighted"`` or ``"minimax"``; per actuator its weight, its effort
    #: bound (joint side [N or N m]: ``max_effort_SI``, or the drive's rated effort times its
    #: ratio, the smaller; inf where none) and its preload sign (0 where not given); the least
    #: preloaded effort ``act_preload`` (0: no preload)
    act_distribution: str = "minimum_norm"
    act_weight: Array = field(default_factory=lambda: np.zeros(0))
    act_bound: Array = field(default_factory=lambda: np.zeros(0))
    act_preload_sign: Array = field(default_factory=lambda: np.zeros(0))
    act_preload: float = 0.0
    #: the effort split's body groups: names, and each body's group index (nb,)
    group_names: tuple[str, ...] = ()
    body_group: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    #: plausibility limits of motions (``[limits]``: ``description.LIMIT_KEYS``)
    limits: dict = field(default_factory=dict)
    #: the description's named design parameters and their values (``[parameters]``)
    parameters: dict = field(default_factory=dict)
    #: the bounded parameters' ``(min, max)`` (either None where absent)
    parameter_bounds: dict = field(default_factory=dict)
    #: ``[mechanism] reactions``: ``"unique"`` (an over-constrained run without compliance data
    #: is refused) or ``"minimum-norm"``
    reactions: str = "unique"
    #: per joint: its spring ``(k, q_s)`` or None (:func:`pkmdyn.multibody.dynamics.newton_euler.spring_wrenches`)
    joint_spring: tuple = ()
    #: per joint: its ``bearing`` as 0 (the parent) or 1 (the child), -1 where none is named
    #: (:func:`pkmdyn.multibody.dynamics.compliance.reactions.beam_terms`)
    joint_bearing: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    #: ``[[outputs]]``: the names, bodies and points (body frame) whose pose a run writes
    output_names: tuple[str, ...] = ()
    output_body: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    output_point: Array = field(default_factory=lambda: np.zeros((0, 3)))

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
