"""The mechanism description: a TOML file validated into plain, immutable records.

Format (``docs/mechanism_format.md``): ``[mechanism]`` (name, source, gravity, optional cut
joints), ``[[bodies]]``, ``[[joints]]``, ``[task]``, optional ``[[loads]]``, ``[[legs]]``
(a leg template repeated at given angles) and ``[default_motion]``. Every body, joint and
point is given in the *reference configuration*, in the base frame: a joint's point and axes
are given once and fixed in both bodies at that configuration, so the reference configuration
is assembled by construction and every joint coordinate is zero there. SI units, angles in
radians, except the keys that say ``_deg``.

:func:`load_description` reads and validates a file (or a dict) and expands the legs;
every failure is one :class:`~pkmdyn.errors.ParameterError` line naming the file, the table
and the body, joint or key.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, ValidationError, field_validator

from ...errors import ParameterError
from ...params_util import Section, _rule, read_toml
from ...spatial import check_sequence, cross
from .expressions import parameter_bounds, resolve_parameters
from .joint_types import JOINT_TYPES, joint_type

__all__ = ["MAGNITUDES", "Description", "BodySpec", "JointSpec", "TaskSpec", "split_task_joint", "LoadSpec", "MotionSpec", "ActuatorSpec",
           "load_description", "GROUND", "inertia_matrix", "LIMIT_KEYS", "RESERVED_PARTS"]

Array = NDArray[np.float64]
GROUND = "ground"
#: the largest mechanism a description may hold (after the legs are expanded); the topology
#: takes singular value decompositions of matrices of up to 6 x joints rows
MAX_BODIES = 300
MAX_JOINTS = 600
_TYPES = tuple(t.name for t in JOINT_TYPES)
Vec3 = Annotated[list[float], Field(min_length=3, max_length=3)]
Pair = Annotated[list[float], Field(min_length=2, max_length=2)]
#: a name of the description (a body, a joint, ...): a letter or ``_``, then letters, digits, ``_ ' . -``
NAME_PATTERN = r"^[A-Za-z_][A-Za-z0-9_'.-]*$"
NAME = Field(min_length=1, max_length=64, pattern=NAME_PATTERN)


class _Section(Section):
    """Link cross-section for compliance (stored for the dynamics)."""

    outer_diameter_m: float = Field(gt=0)
    inner_diameter_m: float = Field(default=0.0, ge=0)
    #: the beam's axis: the line through the body's two joints farthest apart, or the body
    #: frame's x axis through the centre of mass (multibody.dynamics.compliance.reactions)
    beam_axis: Literal["joints", "body_x"] = "joints"


class _Material(Section):
    youngs_modulus_Pa: float = Field(gt=0)
    poisson_ratio: float = Field(default=0.3, gt=-1, lt=0.5)


class _Shape(Section):
    """Drawing hint: a rod or tube between points, a box, a sphere (base frame, reference)."""

    kind: Literal["rod", "box", "sphere", "disc"]
    points_m: list[Vec3] = Field(default_factory=list, max_length=16)
    radius_m: float = Field(default=0.01, gt=0)
    size_m: Vec3 | None = None


class _Body(Section):
    name: str = NAME
    mass_kg: float = Field(ge=0)
    com_m: Vec3
    inertia_kgm2: list[float] | list[list[float]]
    frame_origin_m: Vec3 = [0.0, 0.0, 0.0]
    frame_euler_deg: Vec3 = [0.0, 0.0, 0.0]
    section: _Section | None = None
    material: _Material | None = None
    shape: _Shape | None = None


class _ExternalFriction(Section):
    """Friction whose normal force is a named external load (``[[loads]]`` with a ``name``):
    ``coefficient * radius_m * |F + offset_N|`` added to the joint's Coulomb torque (a joint
    that rotates), ``coefficient * |F + offset_N|`` to its Coulomb force (one that only slides,
    no radius); ``F`` [N] the load's magnitude at the sample (the form of Eq. 16 of Chen, Cheng & Pang 2022)."""

    load: str = NAME
    coefficient: float = Field(ge=0)
    radius_m: float = Field(default=0.0, ge=0)
    offset_N: float = 0.0


class _Friction(Section):
    """Joint friction data, stored for the dynamics (units in every key)."""

    coulomb_force_N: float = Field(default=0.0, ge=0)
    coulomb_torque_Nm: float = Field(default=0.0, ge=0)
    viscous_N_s_m: float = Field(default=0.0, ge=0)
    viscous_Nm_s_rad: float = Field(default=0.0, ge=0)
    coefficient: float = Field(default=0.0, ge=0)
    pin_radius_m: float = Field(default=0.0, ge=0)
    ball_radius_m: float = Field(default=0.0, ge=0)
    mean_radius_m: float = Field(default=0.0, ge=0)
    external: list[_ExternalFriction] = Field(default_factory=list, max_length=16)


class _Stiffness(Section):
    """Joint and drive stiffness (``docs/stiffness.md``, "Compliance sources"): ``drive_N_m`` /
    ``drive_Nm_rad`` the drive's stiffness along an actuated joint's coordinate (joint side: a
    ball screw, its nut and bearings, a belt, a gearbox's torsion); ``force_N_m`` and
    ``moment_Nm_rad`` the joint's stiffness against its reaction force and moment (one number,
    or three along the axes of the joint's frame on its parent), e.g. a bearing's radial
    stiffness. Not given: rigid."""

    drive_N_m: float | None = Field(default=None, gt=0)
    drive_Nm_rad: float | None = Field(default=None, gt=0)
    force_N_m: float | Vec3 | None = None
    moment_Nm_rad: float | Vec3 | None = None

    @field_validator("force_N_m", "moment_Nm_rad")
    @classmethod
    def _positive(cls, v: float | list[float] | None) -> float | list[float] | None:
        if v is not None and not all(x > 0 for x in (v if isinstance(v, list) else [v])):
            raise ValueError("must be positive (leave the key out for a rigid direction)")
        return v


class _Spring(Section):
    """A joint spring along the joint's one coordinate (``docs/mechanism_format.md``): the
    generalised force ``-k (q - q_s)``; ``reference_*`` the coordinate where it is slack (default:
    the joint's position at the reference configuration)."""

    stiffness_Nm_rad: float | None = Field(default=None, gt=0)
    stiffness_N_m: float | None = Field(default=None, gt=0)
    reference_rad: float | None = None
    reference_m: float | None = None


class _Joint(Section):
    name: str = NAME
    type: str
    parent: str = NAME
    child: str = NAME
    point_m: Vec3
    axis: Vec3 | None = None
    axes: list[Vec3] | None = None
    x_axis: Vec3 | None = None
    actuated: bool = False
    position_at_reference_m: float | None = None
    angle_at_reference_rad: float | None = None
    limits_m: Pair | None = None
    limits_rad: Pair | None = None
    friction: _Friction | None = None
    stiffness: _Stiffness | None = None
    spring: _Spring | None = None
    bearing: str | None = Field(default=None, min_length=1, max_length=64)

    @field_validator("type")
    @classmethod
    def _known_type(cls, v: str) -> str:
        if v not in _TYPES:  # the joint-type table is the one list of types
            raise ValueError(f"unknown joint type {v[:40]!r} (one of {', '.join(_TYPES)})")
        return v


class _Load(Section):
    name: str | None = Field(default=None, min_length=3, max_length=64, pattern=r"^[A-Za-z][A-Za-z0-9_]*_N$")
    body: str = NAME
    force_N: Vec3 | None = None
    moment_Nm: Vec3 | None = None
    point_m: Vec3 | None = None
    direction: Vec3 | None = None
    magnitude_N: float | None = None


class _Task(Section):
    body: str | None = Field(default=None, min_length=1, max_length=64, pattern=NAME_PATTERN)
    point_m: Vec3 | None = None
    position: list[Literal["x", "y", "z"]] = Field(default_factory=list, max_length=3)
    euler_sequence: str = "XYZ"
    orientation: list[Literal[1, 2, 3]] = Field(default_factory=list, max_length=3)
    joints: list[str] = Field(default_factory=list, max_length=600)


class _Output(Section):
    name: str = Field(min_length=1, max_length=40, pattern=r"^[A-Za-z][A-Za-z0-9_]*$")
    body: str = NAME
    point_m: Vec3 | None = None


class _Motion(Section):
    period_s: float = Field(default=2.0, gt=0)
    samples: int = Field(default=201, ge=2, le=200_000)  # one cycle, held whole as a motion file is
    offset: dict[str, float] = Field(default_factory=dict)
    amplitude: dict[str, float] = Field(default_factory=dict)


class _Actuator(Section):
    """A drive on an actuated joint (``docs/mechanism_format.md``, ``[[actuators]]``): the
    transmission, the rotor and the motor-side friction, limits and encoder. The keys carry the
    motor coordinate's unit: a rotary motor (a revolute joint, or a prismatic joint driven by a
    screw) in rad, N m; a linear motor (a prismatic joint without a screw) in m, N."""

    name: str | None = Field(default=None, min_length=1, max_length=64, pattern=r"^[A-Za-z_][A-Za-z0-9_'.-]*$")
    joint: str = NAME
    gear_ratio: float | None = None
    screw_lead_m: float | None = None
    rotor_inertia_kgm2: float | None = None
    moving_mass_kg: float | None = None
    coulomb_torque_Nm: float | None = None
    viscous_Nm_s_rad: float | None = None
    coulomb_force_N: float | None = None
    viscous_N_s_m: float | None = None
    max_torque_Nm: float | None = None
    max_force_N: float | None = None
    max_speed_rad_s: float | None = None
    max_speed_m_s: float | None = None
    max_acceleration_rad_s2: float | None = None
    max_acceleration_m_s2: float | None = None
    encoder_counts_per_turn: int | None = Field(default=None, ge=1, le=10**12)
    encoder_counts_per_m: float | None = None
    winding_resistance_ohm: float | None = None
    torque_constant_Nm_A: float | None = None
    force_constant_N_A: float | None = None


class _Actuation(Section):
    """How a redundantly actuated mechanism's efforts are shared among its actuated joints
    (``[actuation]``, ``docs/mechanism_format.md``, "Redundant actuation"); the joints' values
    in their own unit (SI: N for a prismatic joint, N m for a revolute one)."""

    distribution: Literal["minimum_norm", "weighted", "minimax"] = "minimum_norm"
    weights: dict[str, float] = Field(default_factory=dict)
    max_effort_SI: dict[str, float] = Field(default_factory=dict)
    preload_min_effort_SI: float = 0.0
    preload_sign: dict[str, int] = Field(default_factory=dict)


class _Group(Section):
    """A named group of bodies whose share of the efforts is reported (``[[groups]]``)."""

    name: str = Field(min_length=1, max_length=40, pattern=r"^[A-Za-z][A-Za-z0-9_]*$")
    bodies: list[str] = Field(min_length=1, max_length=MAX_BODIES)


class _Limits(Section):
    """Plausibility limits of motions (``[limits]``); a user raises them here or with
    ``--limit KEY=VALUE``."""

    max_samples: int = Field(default=20_000_000, gt=0)
    max_body_samples: int = Field(default=200_000, gt=0)
    max_workspace_poses: int = Field(default=100_000, gt=0)
    max_wear_track_points: int = Field(default=5_000_000, gt=0)
    max_task_speed_m_s: float = Field(default=10.0, gt=0)
    max_task_acceleration_m_s2: float = Field(default=1000.0, gt=0)
    max_task_speed_rad_s: float = Field(default=100.0, gt=0)
    max_task_acceleration_rad_s2: float = Field(default=1e4, gt=0)
    max_joint_speed_m_s: float = Field(default=10.0, gt=0)
    max_joint_acceleration_m_s2: float = Field(default=1000.0, gt=0)
    max_joint_speed_rad_s: float = Field(default=100.0, gt=0)
    max_joint_acceleration_rad_s2: float = Field(default=1e4, gt=0)
    # magnitudes of the description's own numbers (:data:`MAGNITUDES`)
    max_length_m: float = Field(default=1e3, gt=0)
    max_mass_kg: float = Field(default=1e6, gt=0)
    max_inertia_kgm2: float = Field(default=1e9, gt=0)
    max_gravity_m_s2: float = Field(default=1e3, gt=0)
    max_force_N: float = Field(default=1e9, gt=0)
    max_torque_Nm: float = Field(default=1e9, gt=0)
    max_viscous_SI: float = Field(default=1e9, gt=0)
    max_modulus_Pa: float = Field(default=1e13, gt=0)
    max_angle_rad: float = Field(default=1e4, gt=0)
    max_time_s: float = Field(default=1e6, gt=0)
    max_friction_coefficient: float = Field(default=10.0, gt=0)
    max_factor: float = Field(default=1e6, gt=0)
    max_stiffness_SI: float = Field(default=1e13, gt=0)


#: the plausibility limits of a description's numbers by the unit of their key: a number whose
#: key ends with one of the suffixes may not exceed the limit in magnitude (``[limits]``; checked
#: in this order, so that ``viscous_N_s_m`` is a viscous coefficient and not a length). Every
#: other number (a gear ratio, a count) is bounded by ``max_factor``; directions (axes, load directions) by nothing.
MAGNITUDES: tuple[tuple[str, tuple[str, ...], float], ...] = (
    ("max_stiffness_SI", ("_N_m", "_Nm_rad"), 1.0),
    ("max_viscous_SI", ("_N_s_m", "_Nm_s_rad"), 1.0),
    ("max_gravity_m_s2", ("_m_s2",), 1.0),
    ("max_inertia_kgm2", ("_kgm2",), 1.0),
    ("max_torque_Nm", ("_Nm",), 1.0),
    ("max_force_N", ("_N",), 1.0),
    ("max_modulus_Pa", ("_Pa",), 1.0),
    ("max_mass_kg", ("_kg",), 1.0),
    ("max_angle_rad", ("_rad",), 1.0),
    ("max_angle_rad", ("_deg",), 180.0 / np.pi),
    ("max_time_s", ("_s",), 1.0),
    ("max_length_m", ("_m",), 1.0),
    ("max_friction_coefficient", ("coefficient",), 1.0),
)


#: the plausibility limits of motions and their types (``[limits]``, ``--limit KEY=VALUE``)
LIMIT_KEYS: dict[str, type] = {k: (int if k in ("max_samples", "max_body_samples", "max_workspace_poses",
                                                  "max_wear_track_points") else float)
                               for k in _Limits.model_fields}


class _Leg(Section):
    count: int | None = Field(default=None, ge=1, le=64)
    angles_deg: list[float] | None = Field(default=None, min_length=1, max_length=64)
    axis: Vec3 = [0.0, 0.0, 1.0]
    origin_m: Vec3 = [0.0, 0.0, 0.0]
    suffixes: list[str] | None = None
    bodies: list[_Body] = Field(default_factory=list, max_length=64)
    joints: list[_Joint] = Field(min_length=1, max_length=64)
    actuators: list[_Actuator] = Field(default_factory=list, max_length=64)


class _Mechanism(Section):
    name: str = NAME
    source: str = ""
    gravity_m_s2: Vec3 = [0.0, 0.0, -9.80665]
    cut_joints: list[str] | None = None
    #: an over-constrained mechanism without the compliance that makes its reactions unique:
    #: "unique" refuses its run (the default), "minimum-norm" writes the minimum-norm reactions
    #: (flagged, as pkmdyn run --minimum-norm-reactions)
    reactions: Literal["unique", "minimum-norm"] = "unique"


class _File(Section):
    mechanism: _Mechanism
    bodies: list[_Body] = Field(default_factory=list, max_length=MAX_BODIES)
    joints: list[_Joint] = Field(default_factory=list, max_length=MAX_JOINTS)
    legs: list[_Leg] = Field(default_factory=list, max_length=32)
    task: _Task
    loads: list[_Load] = Field(default_factory=list, max_length=2000)
    outputs: list[_Output] = Field(default_factory=list, max_length=64)
    default_motion: _Motion = _Motion()
    actuators: list[_Actuator] = Field(default_factory=list, max_length=MAX_JOINTS)
    groups: list[_Group] = Field(default_factory=list, max_length=MAX_BODIES)
    limits: _Limits = _Limits()
    actuation: _Actuation = _Actuation()


@dataclass(frozen=True)
class BodySpec:
    """A validated body. ``R0 (3, 3)``, ``p0 (3,)`` [m]: its frame in the base frame at the
    reference configuration; ``com (3,)`` [m] and ``inertia (3, 3)`` [kg m^2] (about the
    centre of mass) in the body frame."""

    name: str
    mass: float
    com: Array
    inertia: Array
    R0: Array
    p0: Array
    section: dict[str, float] | None = None
    material: dict[str, float] | None = None
    shape: dict[str, Any] | None = None


@dataclass(frozen=True)
class JointSpec:
    """A validated joint: ``frame (3, 3)`` the joint frame's axes (columns) and ``point (3,)``
    [m] its origin, base frame, reference configuration; ``offset``: the joint coordinate at
    the reference configuration (reported coordinate = internal + offset)."""

    name: str
    type: str
    parent: str
    child: str
    point: Array
    frame: Array
    actuated: bool
    offset: float
    limits: tuple[float, float] | None
    friction: dict[str, float] | None
    #: joint and drive stiffness (:class:`_Stiffness`; ``force_N_m``/``moment_Nm_rad`` as three
    #: numbers), None when rigid
    stiffness: dict[str, Any] | None = None
    #: a joint spring ``(k, q_s)`` along the joint's one coordinate (N m/rad and rad, or N/m and m),
    #: its generalised force ``-k (q - q_s)``; None without one
    spring: tuple[float, float] | None = None
    #: a sliding joint's ``bearing``: the body (its parent or child) whose point is the joint's
    #: node on both bodies' beams (a cylinder's mouth); None: each body its own point
    bearing: str | None = None


@dataclass(frozen=True)
class TaskSpec:
    """Task coordinates: base-frame components of a point of ``body`` and Euler angles of its
    frame, then the coordinates of ``joints`` (``"name"``, a joint of one coordinate, or
    ``"name:k"``, a joint's k-th coordinate; its value as the joint's own: an actuated joint's
    is its actuator coordinate). ``point (3,)`` [m] base frame,
    reference configuration (default: the body's centre of mass); ``position``: component
    indices 0-2; ``sequence``: the Euler sequence; ``orientation``: angle indices 0-2. A task
    of joints alone has for ``body`` (the body whose whole pose a run writes) the one given,
    else its last joint's child (its parent where the child is the ground)."""

    body: str
    point: Array
    position: tuple[int, ...]
    sequence: str
    orientation: tuple[int, ...]
    names: tuple[str, ...]
    units: tuple[str, ...]
    joints: tuple[str, ...] = ()


@dataclass(frozen=True)
class OutputSpec:
    """A body whose pose a run writes (``[[outputs]]``): the base-frame position of ``point``
    (base frame, reference configuration, fixed in the body; default: the body's centre of mass)
    and the Euler angles of the body's frame, as columns ``<name>_x_m`` ... ``<name>_euler3_rad``."""

    name: str
    body: str
    point: Array


@dataclass(frozen=True)
class LoadSpec:
    """An external load on ``body``: force [N] at ``point`` (base frame, reference
    configuration, fixed in the body) and moment [N m], both in the base frame. A named load
    (``name``, e.g. ``hydraulic_N``) is the force ``magnitude * direction`` (unit ``direction``,
    base frame) whose magnitude [N] a motion gives per sample (its column ``name``);
    ``force`` is then its force at the default ``magnitude``."""

    body: str
    force: Array
    moment: Array
    point: Array
    name: str | None = None
    direction: Array | None = None
    magnitude: float = 0.0


@dataclass(frozen=True)
class ActuatorSpec:
    """A validated drive of an actuated joint. ``kind``: ``"rotary"`` (motor coordinate [rad],
    effort [N m]) or ``"linear"`` ([m], [N]); ``ratio`` k: motor coordinate per joint coordinate
    (a revolute joint's gear ratio [rad/rad]; a screw's ``gear_ratio * 2 pi / lead`` [rad/m];
    1 for a linear motor), so that ``theta = k q`` and the joint's effort is ``k`` times the
    motor's net effort; ``rotor`` [kg m^2, or kg for a linear motor] the motor's moving
    inertia; ``coulomb``, ``viscous`` its friction [N m, N m s/rad or N, N s/m]; limits
    ``max_effort``, ``max_speed``, ``max_acceleration`` (motor side, ``inf`` when not given);
    ``encoder_resolution`` the motor displacement per encoder count (0: not given);
    ``resistance`` [ohm] the winding's resistance and ``constant`` [N m/A or N/A] the motor's
    torque or force constant (0: not given), whose copper losses are ``resistance / constant^2``
    times the squared motor effort [W]."""

    name: str
    joint: str
    kind: str
    ratio: float
    rotor: float
    coulomb: float
    viscous: float
    max_effort: float
    max_speed: float
    max_acceleration: float
    encoder_resolution: float
    lead: float | None = None
    gear_ratio: float = 1.0
    resistance: float = 0.0
    constant: float = 0.0


@dataclass(frozen=True)
class ActuationSpec:
    """The validated ``[actuation]``: ``distribution`` (``"minimum_norm"``, ``"weighted"``,
    ``"minimax"``), per actuated joint name its ``weights`` (> 0; 1 where not given) and
    ``max_effort`` bound (> 0; joint side, N or N m), ``preload_min_effort`` (>= 0, joint side)
    and ``preload_sign`` (+1 or -1 per joint given). ``given``: the section is in the file."""

    distribution: str = "minimum_norm"
    weights: tuple[tuple[str, float], ...] = ()
    max_effort: tuple[tuple[str, float], ...] = ()
    preload_min_effort: float = 0.0
    preload_sign: tuple[tuple[str, int], ...] = ()
    given: bool = False


@dataclass(frozen=True)
class MotionSpec:
    """The default motion: ``x(t) = x_ref + offset + amplitude sin(2 pi t / period)``,
    ``samples`` points over one period; offsets and amplitudes keyed by task column name."""

    period: float
    samples: int
    offset: dict[str, float]
    amplitude: dict[str, float]


@dataclass(frozen=True)
class Description:
    """A validated, leg-expanded mechanism description (see the module docstring)."""

    name: str
    source: str
    gravity: Array
    bodies: tuple[BodySpec, ...]
    joints: tuple[JointSpec, ...]
    task: TaskSpec
    loads: tuple[LoadSpec, ...]
    cut_joints: tuple[str, ...] | None
    motion: MotionSpec
    path: str = field(default="")
    #: the drives of actuated joints (``[[actuators]]``; a joint without one drives itself)
    actuators: tuple[ActuatorSpec, ...] = ()
    #: the effort split's body groups: ``(name, body names)`` covering every body
    groups: tuple[tuple[str, tuple[str, ...]], ...] = ()
    #: the plausibility limits of motions (``[limits]``, keys of :data:`LIMIT_KEYS`)
    limits: dict[str, float] = field(default_factory=dict)
    #: the named design parameters and their values (``[parameters]``, :mod:`pkmdyn.multibody.description.expressions`)
    parameters: dict[str, Any] = field(default_factory=dict)
    #: the bounded parameters' ``(min, max)`` (either None where absent)
    parameter_bounds: dict[str, tuple[float | None, float | None]] = field(default_factory=dict)
    #: ``[mechanism] reactions``: ``"unique"`` or ``"minimum-norm"`` (an over-constrained
    #: mechanism's run without compliance data)
    reactions: str = "unique"
    #: the bodies and points whose pose a run writes beside the task body's (``[[outputs]]``)
    outputs: tuple[OutputSpec, ...] = ()
    #: how a redundantly actuated mechanism's efforts are shared (``[actuation]``)
    actuation: ActuationSpec = ActuationSpec()


def _rot(axis: Array, angle: float) -> Array:
    """Rotation by ``angle`` [rad] about unit ``axis`` (Rodrigues)."""
    k = axis / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


#: results of :func:`_euler_xyz` and :func:`inertia_matrix` by their arguments' exact text
#: (:func:`_exact_key`), at most :data:`_MEMO_SIZE` each: a design sweep compiles the same
#: angles and inertias (those it does not vary, and every leg copy's turned frame) for every
#: design, and these are pure functions of the numbers, so a stored result is the same to the
#: last bit as a fresh one
_EULER_MEMO: dict[str, Array] = {}
_INERTIA_MEMO: dict[str, Array] = {}
_MEMO_SIZE = 1024


def _exact_key(values: Any) -> str | None:
    """A key that tells apart any two different lists of plain numbers (a list of ``float`` and
    ``int``, or of such lists): their ``repr``, which writes every float to its last bit and
    keeps the sign of a zero; None for anything else (not memoised)."""
    if type(values) is not list:
        return None
    for v in values:
        if type(v) is list:
            if not all(type(x) is float or type(x) is int for x in v):
                return None
        elif type(v) is not float and type(v) is not int:
            return None
    return repr(values)


def _memo(table: dict[str, Array], key: str | None, value: Array) -> Array:
    """``value`` stored under ``key`` (unless None or the table is full); returned as it is."""
    if key is not None and len(table) < _MEMO_SIZE:
        table[key] = value.copy()
    return value


def _euler_xyz(deg: Vec3) -> Array:
    """``Rx(a) Ry(b) Rz(c)`` of intrinsic XYZ angles ``deg`` [deg] (memoised by their exact
    values, :data:`_EULER_MEMO`)."""
    key = _exact_key(deg)
    hit = _EULER_MEMO.get(key) if key is not None else None
    if hit is not None:
        return hit.copy()
    a, b, c = np.radians(deg)
    R = _rot(np.array([1.0, 0, 0]), a) @ _rot(np.array([0, 1.0, 0]), b) @ _rot(np.array([0, 0, 1.0]), c)
    return _memo(_EULER_MEMO, key, R)


def inertia_matrix(values: list, where: str) -> Array:
    """``[Ixx, Iyy, Izz, Ixy, Ixz, Iyz]`` or a 3 x 3 list -> symmetric (3, 3) [kg m^2], checked:
    symmetric, positive definite, principal moments obeying the triangle inequality (a checked
    result memoised by the exact values, :data:`_INERTIA_MEMO`)."""
    key = _exact_key(values)
    hit = _INERTIA_MEMO.get(key) if key is not None else None
    if hit is not None:
        return hit.copy()
    return _memo(_INERTIA_MEMO, key, _checked_inertia(values, where))


def _checked_inertia(values: list, where: str) -> Array:
    """:func:`inertia_matrix` without the memo."""
    if len(values) == 6 and all(isinstance(v, (int, float)) for v in values):
        xx, yy, zz, xy, xz, yz = (float(v) for v in values)
        inertia = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    elif len(values) == 3 and all(isinstance(r, list) and len(r) == 3 for r in values):
        inertia = np.array(values, dtype=float)
    else:
        raise ParameterError(f"{where} inertia_kgm2: give 6 values [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] or a 3 x 3 table")
    if not np.all(np.isfinite(inertia)):
        raise ParameterError(f"{where} inertia_kgm2: must be finite")
    if not np.allclose(inertia, inertia.T, rtol=1e-9, atol=1e-15):
        raise ParameterError(f"{where} inertia_kgm2: not symmetric")
    ev = np.linalg.eigvalsh(inertia)
    scale = max(float(np.abs(ev).max()), 1e-300)
    if ev[0] <= 1e-12 * scale:
        raise ParameterError(f"{where} inertia_kgm2: not positive definite (principal moments {', '.join(f'{e:.4g}' for e in ev)} kg m^2)")
    if ev[0] + ev[1] < ev[2] * (1 - 1e-9):
        raise ParameterError(f"{where} inertia_kgm2: principal moments {', '.join(f'{e:.4g}' for e in ev)} kg m^2 violate "
                             "the triangle inequality (I1 + I2 >= I3)")
    return inertia


def _unit(v: Vec3 | None, where: str) -> Array:
    a = np.asarray(v, dtype=float)
    n = float(np.linalg.norm(a))
    if not n > 1e-12:
        raise ParameterError(f"{where}: axis of zero length")
    return a / n


def _perpendicular(z: Array) -> Array:
    """A unit vector normal to unit ``z``: the base axis least aligned with it, made normal."""
    e = np.eye(3)[int(np.argmin(np.abs(z)))]
    x = e - (e @ z) * z
    return x / np.linalg.norm(x)


def _joint_frame(j: _Joint, where: str) -> Array:
    """Joint frame axes (columns x, y, z) in the base frame at the reference configuration."""
    jt = joint_type(j.type)
    if jt.axes == 2:
        if j.axes is None or len(j.axes) != 2 or j.axis is not None:
            raise ParameterError(f"{where} a {j.type} joint needs axes = [[first], [second]] (and no axis)")
        x, y = _unit(j.axes[0], f"{where} axes[0]"), _unit(j.axes[1], f"{where} axes[1]")
        if abs(float(x @ y)) > 1e-6:
            raise ParameterError(f"{where} axes: the two axes of a {j.type} joint must be perpendicular "
                                 f"(cosine {float(x @ y):.3g})")
        return np.column_stack([x, y, cross(x, y)])
    if j.axes is not None:
        raise ParameterError(f"{where} a {j.type} joint takes no axes list (use axis)")
    if jt.axes == 1 and j.axis is None:
        raise ParameterError(f"{where} a {j.type} joint needs axis")
    if j.axis is None:  # a type that takes no axis: the joint frame's z is the base z
        z = np.array([0.0, 0.0, 1.0])
    else:
        z = _unit(j.axis, f"{where} axis")
    if j.x_axis is not None:
        x0 = _unit(j.x_axis, f"{where} x_axis")
        x = x0 - (x0 @ z) * z
        if np.linalg.norm(x) < 1e-6:
            raise ParameterError(f"{where} x_axis: parallel to axis")
        x /= np.linalg.norm(x)
    else:
        x = _perpendicular(z)
    return np.column_stack([x, cross(z, x), z])


def _body(b: _Body, where: str) -> BodySpec:
    return BodySpec(
        name=b.name, mass=float(b.mass_kg), com=np.array(b.com_m, dtype=float),
        inertia=inertia_matrix(b.inertia_kgm2, where), R0=_euler_xyz(b.frame_euler_deg),
        p0=np.array(b.frame_origin_m, dtype=float),
        section=b.section.model_dump() if b.section else None,
        material=b.material.model_dump() if b.material else None,
        shape=b.shape.model_dump() if b.shape else None,
    )


def _joint(j: _Joint, where: str) -> JointSpec:
    jt = joint_type(j.type)
    if j.parent == j.child:
        raise ParameterError(f"{where} joins body {j.parent!r} to itself")
    frame = _joint_frame(j, where)
    unit = jt.units[0] if jt.freedoms == 1 else None
    offset = 0.0
    limits = None
    for key, want in (("position_at_reference_m", "m"), ("limits_m", "m"),
                      ("angle_at_reference_rad", "rad"), ("limits_rad", "rad")):
        if getattr(j, key) is not None and unit != want:
            raise ParameterError(f"{where} {key}: only for a joint with one {'angular' if want == 'rad' else 'linear'} "
                                 f"coordinate, not a {j.type} joint")
    if j.position_at_reference_m is not None:
        offset = float(j.position_at_reference_m)
    if j.angle_at_reference_rad is not None:
        offset = float(j.angle_at_reference_rad)
    lim = j.limits_m if j.limits_m is not None else j.limits_rad
    if lim is not None:
        if not lim[0] < lim[1]:
            raise ParameterError(f"{where} limits: lower {lim[0]:g} must be below upper {lim[1]:g}")
        limits = (float(lim[0]), float(lim[1]))
    if j.actuated and jt.freedoms != 1:
        raise ParameterError(f"{where} actuated: only a joint with one coordinate (revolute, prismatic) can be "
                             f"actuated, not a {j.type} joint")
    if j.bearing is not None:
        if j.bearing not in (j.parent, j.child):
            raise ParameterError(f"{where} bearing: {j.bearing!r} is neither the joint's parent ({j.parent!r}) nor its "
                                 f"child ({j.child!r})")
        if not any(m.startswith("T") for m in jt.motions):
            raise ParameterError(f"{where} bearing: only for a joint that slides, not a {j.type} joint")
    spring = None
    if j.spring is not None:
        sp = j.spring
        if unit is None:
            raise ParameterError(f"{where} spring: only for a joint with one coordinate (revolute, prismatic), not a "
                                 f"{j.type} joint")
        k, ref = (sp.stiffness_Nm_rad, sp.reference_rad) if unit == "rad" else (sp.stiffness_N_m, sp.reference_m)
        wrong = [key for key in ("stiffness_Nm_rad", "reference_rad", "stiffness_N_m", "reference_m")
                 if getattr(sp, key) is not None and not key.endswith("_rad" if unit == "rad" else "_m")]
        if wrong or k is None:
            want = "stiffness_Nm_rad (and reference_rad)" if unit == "rad" else "stiffness_N_m (and reference_m)"
            raise ParameterError(f"{where} spring: a {j.type} joint's spring takes {want}")
        spring = (float(k), float(offset if ref is None else ref))
    return JointSpec(name=j.name, type=j.type, parent=j.parent, child=j.child,
                     point=np.array(j.point_m, dtype=float), frame=frame, actuated=bool(j.actuated),
                     offset=offset, limits=limits, friction=j.friction.model_dump() if j.friction else None,
                     stiffness=_stiffness(j, jt, where), bearing=j.bearing, spring=spring)


def _stiffness(j: _Joint, jt: Any, where: str) -> dict[str, Any] | None:
    """Joint j's stiffness as plain numbers (three per direction), or None; a drive stiffness
    only on an actuated joint and in its coordinate's unit."""
    st = j.stiffness
    if st is None:
        return None
    out: dict[str, Any] = {}
    for key, unit in (("drive_N_m", "m"), ("drive_Nm_rad", "rad")):
        v = getattr(st, key)
        if v is None:
            continue
        if not j.actuated:
            raise ParameterError(f"{where} stiffness.{key}: only an actuated joint has a drive")
        if jt.units[0] != unit:
            other = "drive_Nm_rad" if unit == "m" else "drive_N_m"
            raise ParameterError(f"{where} stiffness.{key}: a {j.type} joint's drive stiffness is {other}")
        out["drive"] = float(v)
    for key in ("force_N_m", "moment_Nm_rad"):
        v = getattr(st, key)
        if v is not None:
            out[key] = [float(x) for x in (v if isinstance(v, list) else [v] * 3)]
    return out or None


def _load(ld: _Load, where: str, body_specs: dict[str, BodySpec], task: TaskSpec) -> LoadSpec:
    """A validated load: constant (``force_N``, ``moment_Nm``) or named (``name``,
    ``direction``, ``magnitude_N``)."""
    if ld.body not in body_specs:
        raise ParameterError(f"{where} body: {ld.body!r} is not a body of the mechanism")
    b = body_specs[ld.body]
    pt = np.array(ld.point_m if ld.point_m is not None else b.p0 + b.R0 @ b.com, dtype=float)
    if ld.name is None:
        for key in ("direction", "magnitude_N"):
            if getattr(ld, key) is not None:
                raise ParameterError(f"{where} {key}: only for a named load (give it a name such as 'push_N'), "
                                     "or give force_N")
        return LoadSpec(ld.body, np.array(ld.force_N or [0.0] * 3, float), np.array(ld.moment_Nm or [0.0] * 3, float),
                        pt)
    for key in ("force_N", "moment_Nm"):
        if getattr(ld, key) is not None:
            raise ParameterError(f"{where} {key}: a named load ({ld.name!r}) is a force along direction with a "
                                 "magnitude per sample; give direction and magnitude_N instead")
    cols = {f"{n}_{u}" for n, u in zip(task.names, task.units)} | {"t_s"}
    if ld.name in cols or any(k in ld.name for k in ("_pos_", "_vel_", "_acc_", "_effort_")):
        raise ParameterError(f"{where} name: {ld.name!r} reads as a task or joint column of the results; "
                             "name the load otherwise")
    d = np.array(ld.direction if ld.direction is not None else [0.0] * 3, float)
    big = float(np.abs(d).max())
    if not (np.isfinite(big) and big > 0):
        raise ParameterError(f"{where} direction: a named load needs a finite nonzero direction")
    d = d / big
    d = d / np.linalg.norm(d)
    mag = float(ld.magnitude_N or 0.0)
    return LoadSpec(ld.body, d * mag, np.zeros(3), pt, name=ld.name, direction=d, magnitude=mag)


def _check_beams(label: str, body_specs: dict[str, BodySpec], joints: list[JointSpec]) -> None:
    """A body given a ``section`` and a ``material`` must be a beam: two joints at least, and
    (its axis through its joints) two of them apart at the reference configuration; else the
    section would be left rigid without a word."""
    span = max([float(np.linalg.norm(j.point)) for j in joints] + [1e-3])
    for name, b in body_specs.items():
        if not (b.section and b.material):
            continue
        pts = [j.point for j in joints if name in (j.parent, j.child)]
        where = f"{label}: [bodies] {name} section"
        if len(pts) < 2:
            raise ParameterError(f"{where}: the body has {len(pts)} joint{'' if len(pts) == 1 else 's'}, and a beam needs "
                                 "two; remove its section "
                                 "and material, or give it no compliance (docs/stiffness.md)")
        if (b.section.get("beam_axis", "joints") == "joints"
                and max(float(np.linalg.norm(p - q)) for p in pts for q in pts) <= 1e-9 * span):
            raise ParameterError(f"{where}: its joints meet at one point, so there is no beam between them to "
                                 "strain; remove its section and material, or move a joint to the beam's other end")


def _check_external_friction(label: str, joints: list[JointSpec], names: set[str]) -> None:
    """Each joint's ``friction.external`` names a named load; a radius exactly where the joint
    rotates."""
    for j in joints:
        for k, e in enumerate((j.friction or {}).get("external", [])):
            where = f"{label}: [joints] {j.name} friction external[{k}]"
            if e["load"] not in names:
                known = ", ".join(sorted(names)) or "none"
                raise ParameterError(f"{where} load: {e['load']!r} is not a named load (named loads: {known})")
            rotates = any(m.startswith("R") for m in joint_type(j.type).motions)
            if rotates and not e["radius_m"] > 0:
                raise ParameterError(f"{where} radius_m: a {j.type} joint rotates; give the radius at which the "
                                     "load's friction acts")
            if not rotates and e["radius_m"] > 0:
                raise ParameterError(f"{where} radius_m: a {j.type} joint only slides; its friction is "
                                     "coefficient x the load, without a radius")


@dataclass
class _Expanded:
    """The file's bodies, joints and actuators with every ``[[legs]]`` template repeated (each
    with the text that names it in messages), and per leg copy its bodies (``legs``: ``(leg
    table, suffix, body names)``) and per template body name its copies (``copies``)."""

    bodies: list[tuple[_Body, str]]
    joints: list[tuple[_Joint, str]]
    actuators: list[tuple[_Actuator, str]]
    legs: list[tuple[int, str, list[str]]]
    copies: dict[str, list[str]]


def _expand_legs(data: _File, source: str) -> _Expanded:
    """Bodies, joints and actuators of the file with every ``[[legs]]`` template repeated."""
    bodies = [(b, f"{source}: [bodies] {b.name}:") for b in data.bodies]
    joints = [(j, f"{source}: [joints] {j.name}:") for j in data.joints]
    actuators = [(a, f"{source}: [actuators] {a.name or a.joint}:") for a in data.actuators]
    legs: list[tuple[int, str, list[str]]] = []
    copies: dict[str, list[str]] = {}
    for li, leg in enumerate(data.legs):
        where = f"{source}: [legs][{li}]"
        if leg.angles_deg is None and leg.count is None:
            raise ParameterError(f"{where}: give count or angles_deg")
        angles = leg.angles_deg if leg.angles_deg is not None else [360.0 * k / leg.count for k in range(leg.count)]
        if leg.count is not None and leg.count != len(angles):
            raise ParameterError(f"{where} count: {leg.count} but angles_deg has {len(angles)} entries")
        suffixes = leg.suffixes if leg.suffixes is not None else [f"_{k + 1}" for k in range(len(angles))]
        if len(suffixes) != len(angles) or len(set(suffixes)) != len(suffixes):
            raise ParameterError(f"{where} suffixes: need {len(angles)} distinct suffixes")
        axis = _unit(leg.axis, f"{where} axis")
        origin = np.array(leg.origin_m)
        own = {b.name for b in leg.bodies}
        own_joints = {j.name for j in leg.joints}
        for ang, suf in zip(angles, suffixes):
            legs.append((li, suf, [b.name + suf for b in leg.bodies]))
            for b in leg.bodies:
                copies.setdefault(b.name, []).append(b.name + suf)
            Q = _rot(axis, math.radians(ang))

            def move(p: Vec3) -> Vec3:
                return list(float(v) for v in Q @ (np.array(p) - origin) + origin)

            def turn(v: Vec3) -> Vec3:
                return list(float(x) for x in Q @ np.array(v))

            for b in leg.bodies:
                R0 = Q @ _euler_xyz(b.frame_euler_deg)
                eul = _matrix_to_xyz_deg(R0)
                nb = b.model_copy(update={"name": b.name + suf, "frame_origin_m": move(b.frame_origin_m),
                                          "frame_euler_deg": eul})
                shape = b.shape
                if shape is not None:
                    nb = nb.model_copy(update={"shape": shape.model_copy(update={"points_m": [move(p) for p in shape.points_m]})})
                bodies.append((nb, f"{where} body {b.name + suf}:"))
            for j in leg.joints:
                upd: dict[str, Any] = {"name": j.name + suf, "point_m": move(j.point_m),
                                       "parent": j.parent + suf if j.parent in own else j.parent,
                                       "child": j.child + suf if j.child in own else j.child,
                                       "bearing": j.bearing + suf if j.bearing in own else j.bearing}
                if j.axis is not None:
                    upd["axis"] = turn(j.axis)
                if j.axes is not None:
                    upd["axes"] = [turn(a) for a in j.axes]
                if j.x_axis is not None:
                    upd["x_axis"] = turn(j.x_axis)
                joints.append((j.model_copy(update=upd), f"{where} joint {j.name + suf}:"))
            for a in leg.actuators:
                if a.joint not in own_joints:
                    raise ParameterError(f"{where} actuators: joint {a.joint!r} is not a joint of the leg template "
                                         f"({', '.join(sorted(own_joints))})")
                upd_a = {"joint": a.joint + suf, "name": None if a.name is None else a.name + suf}
                actuators.append((a.model_copy(update=upd_a), f"{where} actuator {(a.name or a.joint) + suf}:"))
    return _Expanded(bodies, joints, actuators, legs, copies)


def _matrix_to_xyz_deg(R: Array) -> Vec3:
    """Intrinsic XYZ angles [deg] of ``R = Rx(a) Ry(b) Rz(c)``."""
    b = math.asin(max(-1.0, min(1.0, R[0, 2])))
    a = math.atan2(-R[1, 2], R[2, 2])
    c = math.atan2(-R[0, 1], R[0, 0])
    return [math.degrees(a), math.degrees(b), math.degrees(c)]


_POS_NAMES = {"x": 0, "y": 1, "z": 2}


def split_task_joint(item: str) -> tuple[str, int]:
    """A ``[task] joints`` entry as ``(joint name, k)``: ``"name"`` (k = 0, a joint of one
    freedom) or ``"name:k"``, the joint's k-th coordinate (1-based, in the order of its type's
    motions)."""
    name, sep, k = item.rpartition(":")
    if sep and k.isdigit() and name and int(k) > 0:
        return name, int(k)
    return item, 0


def _task(t: _Task, where: str, bodies: dict[str, BodySpec], joints: list[JointSpec]) -> TaskSpec:
    by_name = {j.name: j for j in joints}
    seen = set()
    coords = []  # (name, k) of each entry, k 1-based
    for i, item in enumerate(t.joints):
        nm, k = split_task_joint(item)
        if nm not in by_name:
            raise ParameterError(f"{where} joints[{i}]: {nm!r} is not a joint of the mechanism")
        jt = joint_type(by_name[nm].type)
        n = len(jt.motions)
        if n == 0:
            raise ParameterError(f"{where} joints[{i}]: {nm!r} is a {jt.name} joint, which has no coordinate")
        if k == 0 and n != 1:
            raise ParameterError(f"{where} joints[{i}]: {nm!r} is a {jt.name} joint of {n} coordinates; name one of "
                                 f"them, {nm + ':1'!r} ... {nm + ':' + str(n)!r}")
        if k > n:
            raise ParameterError(f"{where} joints[{i}]: {item!r}: joint {nm!r} has {n} coordinate(s)")
        key = (nm, max(k, 1))
        if key in seen:
            raise ParameterError(f"{where} joints: a joint coordinate is named twice ({item!r})")
        seen.add(key)
        coords.append((nm, k))
    body = t.body
    if body is None:
        if not t.joints or t.position or t.orientation:
            raise ParameterError(f"{where} body: missing (the task body; a task of joints alone may leave it out)")
        last = by_name[coords[-1][0]]
        body = last.child if last.child != GROUND else last.parent
    if body not in bodies:
        raise ParameterError(f"{where} body: {body!r} is not a body of the mechanism")
    if not t.position and not t.orientation and not t.joints:
        raise ParameterError(f"{where}: no task coordinate (give position and/or orientation, or joints)")
    if len(set(t.position)) != len(t.position) or len(set(t.orientation)) != len(t.orientation):
        raise ParameterError(f"{where}: a task coordinate is named twice")
    try:
        seq = check_sequence(t.euler_sequence)
    except ParameterError as exc:
        raise ParameterError(f"{where} {exc}") from None
    b = bodies[body]
    point = np.array(t.point_m if t.point_m is not None else b.p0 + b.R0 @ b.com, dtype=float)
    names = (tuple(t.position) + tuple(f"euler{k}" for k in t.orientation)
             + tuple(f"{nm}_q{k}" if k else f"{nm}_q" for nm, k in coords))
    units = (("m",) * len(t.position) + ("rad",) * len(t.orientation)
             + tuple(joint_type(by_name[nm].type).units[max(k, 1) - 1] for nm, k in coords))
    return TaskSpec(body=body, point=point, position=tuple(_POS_NAMES[c] for c in t.position), sequence=seq,
                    orientation=tuple(int(k) - 1 for k in t.orientation), names=names, units=units,
                    joints=tuple(t.joints))


#: keys of directions (normalised where read: only their direction counts), bounded by nothing
_DIRECTIONS = ("axis", "axes", "direction")


def _bound(key: str, limits: dict[str, Any]) -> tuple[str, float]:
    """The limit key and the bound of a description number under ``key``."""
    if key in _DIRECTIONS:
        return "", np.inf
    for name, suffixes, scale in MAGNITUDES:
        if key.endswith(suffixes):
            return name, float(limits[name]) * scale
    return "max_factor", float(limits["max_factor"])


def _check_magnitudes(raw: dict[str, Any], label: str, limits: dict[str, Any]) -> None:
    """Every number of the description ``raw`` within the plausibility limit of its key's unit
    (:data:`MAGNITUDES`); the error names the table, the entry (by its name, else its number)
    and the key: ``[legs][0] joints U point_m[0]: 1e+300 is beyond ...``. Directions (axes,
    load directions) are left alone: they are normalised where read."""

    bounds: dict[str, tuple[str, float]] = {}  # (:func:`_bound` of each key, once)

    def walk(v: Any, where: str, key: str) -> None:
        if isinstance(v, dict):
            for k, x in v.items():
                if (not where and k == "limits") or k == "actuators":
                    continue  # the limits themselves; the drives' entries have bounds of their own (_actuators)
                w = f"{where} {k}" if where else f"[{k}]"
                if isinstance(x, dict):
                    walk(x, w, "")
                elif isinstance(x, list) and any(isinstance(e, dict) for e in x):
                    for i, e in enumerate(x):
                        nm = e.get("name") if isinstance(e, dict) else None
                        walk(e, f"{w} {nm}" if isinstance(nm, str) else f"{w}[{i}]", "")
                else:
                    walk(x, where, k)
        elif isinstance(v, list):
            for i, e in enumerate(v):
                walk(e, where, f"{key}[{i}]")
        elif isinstance(v, (int, float)) and not isinstance(v, bool):
            base = key.split("[")[0]
            found = bounds.get(base)
            if found is None:
                found = bounds[base] = _bound(base, limits)
            name, bound = found
            if not abs(v) <= bound:
                raise ParameterError(f"{label}: {where} {key}: {v:g} is beyond the plausibility limit {name} = "
                                     f"{limits[name]:g} (raise it in the description's [limits])")

    walk(raw, "", "")


def load_description(source: str | Path | dict[str, Any], limits: dict[str, Any] | None = None) -> Description:
    """Read (a path) or take (a dict) a description, validate it and expand its legs;
    ``limits`` (``--limit``) lay over its ``[limits]`` for the plausibility of its numbers.

    Raises :class:`~pkmdyn.errors.ParameterError` (one line naming the file, table, body,
    joint or key) on: unknown or missing keys, wrong types, duplicate names, a joint naming a
    missing body, a body joined to nothing or not connected to the ground, a zero-length axis,
    non-perpendicular universal axes, an inertia that is not positive definite or violates the
    triangle inequality, no actuated joint, an actuated joint with more than one coordinate.
    """
    if isinstance(source, dict):
        raw, label, path = source, "description", ""
    else:
        path = str(Path(source).absolute())
        raw, label = read_toml(source), str(source)
    bounds = parameter_bounds(raw) if isinstance(raw, dict) else {}
    raw, parameters = resolve_parameters(raw, label)
    data = _validate(raw, label)
    _check_magnitudes(raw, label, {**data.limits.model_dump(), **(limits or {})})
    body_specs: dict[str, BodySpec] = {}
    expanded = _expand_legs(data, label)
    expanded_bodies, expanded_joints = expanded.bodies, expanded.joints
    if len(expanded_bodies) > MAX_BODIES or len(expanded_joints) > MAX_JOINTS:
        raise ParameterError(f"{label}: {len(expanded_bodies)} bodies and {len(expanded_joints)} joints with the legs "
                             f"repeated; at most {MAX_BODIES} bodies and {MAX_JOINTS} joints")
    for b, where in expanded_bodies:
        if b.name == GROUND:
            raise ParameterError(f"{where} name: {GROUND!r} is reserved for the base")
        if b.name in body_specs:
            raise ParameterError(f"{where} name: body {b.name!r} is defined twice")
        body_specs[b.name] = _body(b, where)
    if not body_specs:
        raise ParameterError(f"{label}: [bodies]: the mechanism has no body")
    joints: list[JointSpec] = []
    seen: set[str] = set()
    for j, where in expanded_joints:
        if j.name in seen:
            raise ParameterError(f"{where} name: joint {j.name!r} is defined twice")
        seen.add(j.name)
        for key in ("parent", "child"):
            nm = getattr(j, key)
            if nm != GROUND and nm not in body_specs:
                raise ParameterError(f"{where} {key}: body {nm!r} is not defined")
        joints.append(_joint(j, where))
    _check_connected(label, body_specs, joints)
    _check_beams(label, body_specs, joints)
    if not any(j.actuated for j in joints):
        raise ParameterError(f"{label}: [joints]: no joint is actuated (set actuated = true on the driven joints)")
    task = _task(data.task, f"{label}: [task]", body_specs, joints)
    loads = [_load(ld, f"{label}: [loads][{k}]", body_specs, task) for k, ld in enumerate(data.loads)]
    first: dict[str, tuple[int, float]] = {}
    for k, ld in enumerate(loads):
        if ld.name is not None:
            k0, m0 = first.setdefault(ld.name, (k, ld.magnitude))
            if ld.magnitude != m0:
                raise ParameterError(f"{label}: [loads][{k}] magnitude_N: {ld.magnitude:g} differs from "
                                     f"{m0:g} of [loads][{k0}]; entries of one named load ({ld.name!r}) share "
                                     "one magnitude")
    _check_external_friction(label, joints, {ld.name for ld in loads if ld.name is not None})
    cuts = None
    if data.mechanism.cut_joints is not None:
        names = {j.name: j for j in joints}
        for c in data.mechanism.cut_joints:
            if c not in names:
                raise ParameterError(f"{label}: [mechanism] cut_joints: {c!r} is not a joint")
            if names[c].actuated:
                raise ParameterError(f"{label}: [mechanism] cut_joints: {c!r} is actuated; an actuated joint stays in the tree")
        cuts = tuple(data.mechanism.cut_joints)
    m = data.default_motion
    for key in (*m.offset, *m.amplitude):
        cols = [f"{n}_{u}" for n, u in zip(task.names, task.units)]
        if key not in cols:
            raise ParameterError(f"{label}: [default_motion] {key}: not a task coordinate (one of {', '.join(cols)})")
    motion = MotionSpec(float(m.period_s), int(m.samples), dict(m.offset), dict(m.amplitude))
    actuators = _actuators(label, expanded.actuators, joints, body_specs)
    groups = _groups(label, data, expanded, body_specs, task)
    return Description(name=data.mechanism.name, source=data.mechanism.source,
                       gravity=np.array(data.mechanism.gravity_m_s2, dtype=float),
                       bodies=tuple(body_specs.values()), joints=tuple(joints), task=task, loads=tuple(loads),
                       cut_joints=cuts, motion=motion, path=path, actuators=actuators, groups=groups,
                       limits=data.limits.model_dump(), parameters=parameters, parameter_bounds=bounds,
                       reactions=data.mechanism.reactions,
                       outputs=_outputs(label, data.outputs, body_specs),
                       actuation=_actuation(label, data, joints))


def _actuation(label: str, data: _File, joints: list[JointSpec]) -> ActuationSpec:
    """The validated ``[actuation]`` (:class:`ActuationSpec`): every name an actuated joint,
    every number finite and in its range."""
    a = data.actuation
    acts = [j.name for j in joints if j.actuated]
    where = f"{label}: [actuation]"

    def named(key: str, items: dict, check: Any, what: str) -> tuple:
        out = []
        for name, v in items.items():
            if name not in acts:
                raise ParameterError(f"{where} {key}: {name!r} is not an actuated joint (one of {', '.join(acts)})")
            if not check(v):
                raise ParameterError(f"{where} {key}: {name} = {v!r}: {what}")
            out.append((name, v))
        return tuple(out)

    def positive(v: Any) -> bool:
        return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and 0 < v <= 1e12

    weights = named("weights", a.weights, positive, "must be a finite number > 0")
    bounds = named("max_effort_SI", a.max_effort_SI, positive, "must be a finite number > 0 [N or N m]")
    signs = named("preload_sign", a.preload_sign, lambda v: v in (1, -1), "must be 1 or -1")
    pre = a.preload_min_effort_SI
    if not (math.isfinite(pre) and 0.0 <= pre <= 1e12):
        raise ParameterError(f"{where} preload_min_effort_SI: must be a finite number >= 0 [N or N m], got {pre!r}")
    if weights and a.distribution != "weighted":
        raise ParameterError(f"{where} weights: they weigh the \"weighted\" distribution only (distribution = "
                             f"{a.distribution!r})")
    if signs and not pre:
        raise ParameterError(f"{where} preload_sign: it orients a preload; give preload_min_effort_SI too")
    return ActuationSpec(a.distribution, weights, bounds, float(pre), signs, "actuation" in data.model_fields_set)


def _outputs(label: str, outputs: list[_Output], body_specs: dict[str, BodySpec]) -> tuple[OutputSpec, ...]:
    """The validated ``[[outputs]]``: a known body, a name used once, not ``task_body`` (the
    task body's own pose columns) and not reading as a joint's column."""
    out: list[OutputSpec] = []
    for k, o in enumerate(outputs):
        where = f"{label}: [outputs][{k}]"
        if o.body not in body_specs:
            raise ParameterError(f"{where} body: {o.body!r} is not a body of the mechanism")
        if o.name == "task_body" or any(o.name == p.name for p in out):
            raise ParameterError(f"{where} name: {o.name!r} is taken (the task body's columns, or an earlier output); "
                                 "name the output otherwise")
        if any(w in f"_{o.name}_" for w in ("_pos_", "_vel_", "_acc_", "_effort_", "_deflection_")):
            raise ParameterError(f"{where} name: {o.name!r} reads as a joint's column of the results; "
                                 "name the output otherwise")
        b = body_specs[o.body]
        pt = np.array(o.point_m if o.point_m is not None else b.p0 + b.R0 @ b.com, dtype=float)
        out.append(OutputSpec(o.name, o.body, pt))
    return tuple(out)


#: the keys of an actuator entry for each kind of motor (rotary, linear), by role
MOTOR_KEYS = {
    "rotary": {"rotor": "rotor_inertia_kgm2", "coulomb": "coulomb_torque_Nm", "viscous": "viscous_Nm_s_rad",
               "max_effort": "max_torque_Nm", "max_speed": "max_speed_rad_s",
               "max_acceleration": "max_acceleration_rad_s2", "encoder": "encoder_counts_per_turn",
               "constant": "torque_constant_Nm_A"},
    "linear": {"rotor": "moving_mass_kg", "coulomb": "coulomb_force_N", "viscous": "viscous_N_s_m",
               "max_effort": "max_force_N", "max_speed": "max_speed_m_s", "max_acceleration": "max_acceleration_m_s2",
               "encoder": "encoder_counts_per_m", "constant": "force_constant_N_A"},
}
#: plausible ranges of a drive's transmission keys: a gear ratio (motor turns per joint or screw
#: turn) and a screw's lead [m per turn]; the largest transmission ratio (motor coordinate per
#: joint coordinate) and rotor inertia taken
_TRANSMISSION_BOUNDS = {"gear_ratio": (1e-6, 1e6), "screw_lead_m": (1e-6, 10.0)}
_MAX_RATIO = 1e7
_MAX_ROTOR = 1e3
#: the largest motor friction, limit or encoder count taken (an entry beyond is a typing error)
_MAX_MOTOR_VALUE = 1e12


def _actuators(label: str, entries: list[tuple[_Actuator, str]], joints: list[JointSpec],
               bodies: dict[str, BodySpec]) -> tuple[ActuatorSpec, ...]:
    """Validated ``[[actuators]]`` entries (see :class:`ActuatorSpec`): one per actuated joint at
    most, the transmission that fits the joint, the motor's keys in its own units."""
    by_name = {j.name: j for j in joints}
    out: list[ActuatorSpec] = []
    seen_joint: dict[str, str] = {}
    seen_name: set[str] = set()
    for a, where in entries:
        if a.joint not in by_name:
            raise ParameterError(f"{where} joint: {a.joint!r} is not a joint of the mechanism")
        j = by_name[a.joint]
        if not j.actuated:
            raise ParameterError(f"{where} joint: {a.joint!r} is not actuated (set actuated = true on it, or drive "
                                 "another joint)")
        name = a.name if a.name is not None else f"{a.joint}_motor"
        if a.joint in seen_joint:
            raise ParameterError(f"{where} joint: {a.joint!r} is driven by {seen_joint[a.joint]!r} already")
        if name in seen_name:
            raise ParameterError(f"{where} name: actuator {name!r} is defined twice")
        if name in by_name or name in bodies:
            raise ParameterError(f"{where} name: {name!r} is the name of a joint or body; name the actuator "
                                 "otherwise (its columns would read as the joint's)")
        seen_joint[a.joint] = name
        seen_name.add(name)
        for key, (lo, hi) in _TRANSMISSION_BOUNDS.items():
            v = getattr(a, key)
            if v is not None and not (math.isfinite(v) and v > 0):
                raise ParameterError(f"{where} {key}: must be a finite number > 0, got {v!r}")
            if v is not None and not lo <= v <= hi:
                raise ParameterError(f"{where} {key}: {v:g} is outside the plausible range [{lo:g}, {hi:g}]")
        gear = 1.0 if a.gear_ratio is None else float(a.gear_ratio)
        if j.type == "revolute":
            if a.screw_lead_m is not None:
                raise ParameterError(f"{where} screw_lead_m: joint {a.joint!r} is revolute; a screw drives a "
                                     "prismatic joint (give gear_ratio)")
            kind, ratio = "rotary", gear
        elif a.screw_lead_m is not None:
            kind, ratio = "rotary", gear * 2.0 * math.pi / float(a.screw_lead_m)
        else:
            if a.gear_ratio is not None:
                raise ParameterError(f"{where} gear_ratio: joint {a.joint!r} is prismatic; give screw_lead_m for a "
                                     "rotary motor on a screw (gear_ratio then is motor turns per screw turn), or "
                                     "neither for a linear motor")
            kind, ratio = "linear", 1.0
        if not ratio <= _MAX_RATIO:
            raise ParameterError(f"{where} gear_ratio: with screw_lead_m the transmission ratio {ratio:.4g} (motor "
                                 f"radians per joint metre) exceeds {_MAX_RATIO:g}")
        keys = MOTOR_KEYS[kind]
        other = MOTOR_KEYS["linear" if kind == "rotary" else "rotary"]
        for key in other.values():
            if getattr(a, key) is not None and key not in keys.values():
                raise ParameterError(f"{where} {key}: the motor of joint {a.joint!r} is {kind}; give "
                                     f"{keys[next(r for r, k in other.items() if k == key)]} instead")
        vals: dict[str, float] = {}
        for role, key in keys.items():
            v = getattr(a, key)
            if v is None:
                vals[role] = 0.0 if role in ("rotor", "coulomb", "viscous", "encoder", "constant") else math.inf
                continue
            v = float(v)
            if not math.isfinite(v):
                raise ParameterError(f"{where} {key}: must be finite, got {v!r}")
            if role in ("rotor", "coulomb", "viscous") and v < 0:
                raise ParameterError(f"{where} {key}: must be >= 0, got {v:g}")
            if role.startswith("max_") or role in ("encoder", "constant"):
                if not v > 0:
                    raise ParameterError(f"{where} {key}: must be > 0, got {v:g}")
            bound = _MAX_ROTOR if role == "rotor" else _MAX_MOTOR_VALUE
            if v > bound:
                raise ParameterError(f"{where} {key}: {v:g} exceeds the plausibility bound {bound:g}")
            vals[role] = v
        ohm = 0.0 if a.winding_resistance_ohm is None else float(a.winding_resistance_ohm)
        if a.winding_resistance_ohm is not None and not (math.isfinite(ohm) and 0.0 < ohm <= _MAX_MOTOR_VALUE):
            raise ParameterError(f"{where} winding_resistance_ohm: must be a finite number > 0, got {ohm!r}")
        if (a.winding_resistance_ohm is None) != (not vals["constant"]):
            raise ParameterError(f"{where} {'winding_resistance_ohm' if a.winding_resistance_ohm is None else keys['constant']}: "
                                 f"give the winding's resistance and the motor's {keys['constant']} together (its "
                                 "copper losses need both)")
        res = 0.0
        if vals["encoder"]:
            res = (2.0 * math.pi if kind == "rotary" else 1.0) / vals["encoder"]
        out.append(ActuatorSpec(name=name, joint=a.joint, kind=kind, ratio=float(ratio), rotor=vals["rotor"],
                                coulomb=vals["coulomb"], viscous=vals["viscous"], max_effort=vals["max_effort"],
                                max_speed=vals["max_speed"], max_acceleration=vals["max_acceleration"],
                                encoder_resolution=res,
                                lead=None if a.screw_lead_m is None else float(a.screw_lead_m), gear_ratio=gear,
                                resistance=ohm, constant=vals["constant"]))
    return tuple(out)


#: part names of the effort split that a body group may not take
RESERVED_PARTS = ("rotor", "friction", "total", "internal")


def _groups(label: str, data: _File, expanded: _Expanded, bodies: dict[str, BodySpec],
            task: TaskSpec) -> tuple[tuple[str, tuple[str, ...]], ...]:
    """The effort split's body groups (``[[groups]]``; a leg template's body name stands for
    all its copies). Without ``[[groups]]``: one group per leg copy (``leg_1`` ... by its
    suffix; ``legs2_1`` ... by leg table and suffix when two copies share a suffix), one for
    the task body (its name), and ``other`` for the remaining bodies. Bodies no group names
    go to ``other``."""
    out: list[tuple[str, tuple[str, ...]]] = []
    owner: dict[str, str] = {}
    if data.groups:
        for g in data.groups:
            where = f"{label}: [groups] {g.name}:"
            if g.name in RESERVED_PARTS:
                raise ParameterError(f"{where} name: {g.name!r} is a part of the split of its own; name the group "
                                     "otherwise")
            if any(g.name == o for o, _ in out):
                raise ParameterError(f"{where} name: group {g.name!r} is defined twice")
            names: list[str] = []
            for b in g.bodies:
                members = [b] if b in bodies else expanded.copies.get(b, [])
                if not members:
                    raise ParameterError(f"{where} bodies: {b!r} is not a body of the mechanism")
                for m in members:
                    if m in owner:
                        raise ParameterError(f"{where} bodies: body {m!r} is in group {owner[m]!r} already")
                    owner[m] = g.name
                    names.append(m)
            out.append((g.name, tuple(names)))
    else:
        sufs = [suf for _, suf, _ in expanded.legs]
        distinct = len(set(sufs)) == len(sufs)
        for li, suf, names in expanded.legs:
            tag = suf.lstrip("_") or str(li + 1)
            gname = f"leg_{tag}" if distinct else f"legs{li + 1}_{tag}"
            gname = "".join(c if c.isalnum() or c == "_" else "_" for c in gname)
            members = [m for m in names if m not in owner and m != task.body]
            if members:
                for m in members:
                    owner[m] = gname
                out.append((gname, tuple(members)))
        if task.body not in owner:
            gname = "".join(c if c.isalnum() or c == "_" else "_" for c in task.body)
            gname = gname if gname[:1].isalpha() else "task_" + gname
            if gname in RESERVED_PARTS:
                gname = "task_" + gname
            owner[task.body] = gname
            out.append((gname, (task.body,)))
    rest = tuple(b for b in bodies if b not in owner)
    if rest:
        if any(n == "other" for n, _ in out):
            raise ParameterError(f"{label}: [groups] other: bodies {', '.join(rest[:4])} are in no group, and 'other' "
                                 "(their group) is a group of the file; name every body or rename the group")
        out.append(("other", rest))
    names = [n for n, _ in out]
    dup = next((n for n in names if names.count(n) > 1), None)
    if dup is not None:
        raise ParameterError(f"{label}: [groups]: group name {dup!r} is taken twice (a leg's and a body's); give "
                             "[[groups]]")
    return tuple(out)


def _item_name(raw: Any, loc: tuple) -> str | None:
    """The ``name`` of the table at ``loc`` (e.g. ``("legs", 0, "joints", 2)``) in the raw data."""
    node = raw
    try:
        for part in loc:
            node = node[part]
    except (KeyError, IndexError, TypeError):
        return None
    name = node.get("name") if isinstance(node, dict) else None
    return name if isinstance(name, str) and len(name) <= 64 else None


def _validate(raw: Any, label: str) -> _File:
    """Validate with one line per failing key; list items are named by their ``name`` when they
    have one: ``[joints] U1 axis: ...`` rather than ``[joints] 3[axis]``."""
    if not isinstance(raw, dict):
        raise ParameterError(f"{label}: expected a description (a dict of tables), got {type(raw).__name__}")
    try:
        return _File.model_validate(raw)
    except ValidationError as exc:
        parts = []
        for err in exc.errors():
            loc = tuple(err["loc"])
            rule = _rule(err)
            if not loc:
                parts.append(f"file: {rule}")
                continue
            words = [f"[{loc[0]}]"]
            k = 1
            while k < len(loc):
                p = loc[k]
                if isinstance(p, int):
                    nm = _item_name(raw, loc[:k + 1])
                    words.append(nm if nm is not None else f"#{p + 1}")
                else:
                    words.append(str(p))
                k += 1
            if len(loc) == 1:
                rule = rule.replace("key", "section")
                if err["type"] == "extra_forbidden":
                    rule = "unknown section"
            parts.append(" ".join(words) + f": {rule}")
        raise ParameterError(f"{label}: " + "; ".join(parts[:5]) + (f"; and {len(parts) - 5} more" if len(parts) > 5 else "")) from None


def _check_connected(label: str, bodies: dict[str, BodySpec], joints: list[JointSpec]) -> None:
    """Every body is joined to something, and reaches the ground through joints."""
    adj: dict[str, set[str]] = {b: set() for b in [GROUND, *bodies]}
    for j in joints:
        adj[j.parent].add(j.child)
        adj[j.child].add(j.parent)
    for b in bodies:
        if not adj[b]:
            raise ParameterError(f"{label}: [bodies] {b}: body is not joined to anything (unconnected body)")
    seen, stack = {GROUND}, [GROUND]
    while stack:
        for nb in adj[stack.pop()]:
            if nb not in seen:
                seen.add(nb)
                stack.append(nb)
    for b in bodies:
        if b not in seen:
            raise ParameterError(f"{label}: [bodies] {b}: body is not connected to the ground through any chain of joints")
