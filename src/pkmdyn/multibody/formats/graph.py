"""A mechanism read from another format, as a description (``pkmdyn import``).

The readers (:mod:`pkmdyn.multibody.formats.mjcf_in`, :mod:`pkmdyn.multibody.formats.urdf_in`, :mod:`pkmdyn.multibody.formats.sdf_in`) turn a file into a
:class:`Graph`: every link's mass, centre of mass and inertia, every elementary joint (hinge,
slide, ball, fixed) and every loop closure, all in the base frame at the file's reference
configuration (MJCF: ``qpos0`` or a keyframe; URDF, SDFormat: zero joint positions).
:func:`description_from_graph` then writes the description (``docs/import.md``):

* a link joined to its parent by a fixed joint is merged into it (mass, centre of mass and
  inertia added by the parallel-axis theorem); its name stays usable for loop frames and the
  task;
* a chain of hinges (or a slide and a hinge) through links without mass becomes one joint
  where the description has one: two hinges through one point with perpendicular axes a
  universal joint, three whose axes are not in one plane a spherical joint, a slide and a
  hinge along one axis a cylindrical joint; any other massless link is refused by name (the
  description's bodies need a positive definite inertia);
* a 3D loop closure (MJCF ``connect``, a URDF frame pair of type ``3d``, an onshape-to-robot
  ``closing_*`` pair) becomes a spherical cut joint, a 6D one (``weld``, ``6d``) a fixed cut
  joint; ``[mechanism] cut_joints`` names them, so that the spanning tree is the file's tree;
  a closure whose two frames do not coincide at the reference configuration is refused
  with its gap;
* actuators give the actuated joints and, with a gear, armature or motor friction, a drive
  (``[[actuators]]``); joint damping and dry friction become the joint's viscous and Coulomb
  friction;
* the task: the body, point and coordinates given (options or sidecar), or else the first of
  these whose coordinates can determine the pose: the body of an end-effector frame or site
  (by name), then the moving bodies with the most joints, the deepest in the tree first;
  its coordinates are chosen among ``x y z`` first, then the ``XYZ`` Euler angles, as many
  as the mechanism's degrees of freedom, independent at the reference configuration
  (pivoted QR of the task rows on the loops' null space); where no body's coordinates can (a
  mechanism of two legs, whose freedoms no single body carries), joint coordinates: the
  actuated joints', then the sprung ones', then the others' in the file's order, then the
  first candidate body's, then single coordinates of joints of several freedoms, each taken
  where it is independent of those before it on the loops' null space less the idle freedoms
  (a task of joints, said in a note).

Anything without an equivalent is refused with one line naming the element
(:class:`~pkmdyn.errors.ParameterError`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

from ...errors import ParameterError
from ..description.joint_types import joint_type
from ..description.schema import GROUND, MOTOR_KEYS, load_description, split_task_joint
from ..model.compiler import compile_model
from ..model.topology import _null, _point_jacobian, analyse_topology, column_scale, constraint_jacobian, row_scale

Array = NDArray[np.float64]

#: a link lighter than this [kg] with no inertia is massless (a frame or an intermediate link)
MASSLESS_KG = 1e-9
#: a loop closure closes where its frames' points differ by at most this fraction of the size
CLOSE_TOL = 1e-6
#: axes within this (cosine, or 1 - |cosine|) are perpendicular or parallel: files written with six decimals
AXIS_TOL = 1e-6
#: task bodies tried, in order, until one has independent coordinates enough
MAX_CANDIDATES = 12
#: names taken for the end-effector body or point, in this order of preference
EFFECTOR_WORDS = ("end_effector", "effector", "tcp", "tool", "platform", "ee")


@dataclass
class Link:
    """A rigid link at the reference configuration: ``mass`` [kg], ``com (3,)`` [m] and
    ``inertia (3, 3)`` [kg m^2] about the centre of mass, base frame."""

    name: str
    mass: float
    com: Array
    inertia: Array


@dataclass
class Joint:
    """An elementary joint: ``kind`` hinge, slide, ball or fixed, from ``parent`` to ``child``
    (link names, ``ground`` the base) at ``point`` along ``axis`` (base frame, reference
    configuration); ``value`` the joint coordinate there; ``limits`` its range or ``None``;
    ``damping`` [N m s/rad or N s/m], ``frictionloss`` [N m or N], ``armature`` [kg m^2 or kg]."""

    name: str
    kind: str
    parent: str
    child: str
    point: Array
    axis: Array
    value: float = 0.0
    limits: tuple[float, float] | None = None
    damping: float = 0.0
    frictionloss: float = 0.0
    armature: float = 0.0
    #: the joint's ``stiffness`` table where the file gives one (pkmdyn's own exports: a drive's)
    stiffness: dict | None = None
    #: a joint spring ``(k, q_s)`` along the joint's coordinate (MJCF's ``stiffness`` and ``springref``)
    spring: tuple[float, float] | None = None


@dataclass
class Closure:
    """A loop closure between a frame on ``link1`` and one on ``link2``: ``kind`` ``3d`` (the
    two points coincide) or ``6d`` (the two frames coincide); ``point1``, ``point2`` and
    ``R1``, ``R2`` the frames at the reference configuration (base frame)."""

    name: str
    kind: str
    link1: str
    link2: str
    point1: Array
    point2: Array
    R1: Array = field(default_factory=lambda: np.eye(3))
    R2: Array = field(default_factory=lambda: np.eye(3))
    #: the residual a reader measured itself (MuJoCo's own constraint residual): [m], [rad]
    gap: tuple[float, float] | None = None
    #: ``kind == "joint"``: a joint of the file that closes a loop (SDFormat: a link's second
    #: parent), as a description joint's ``type`` and ``axis``/``axes``, at ``point1``
    joint: dict | None = None


@dataclass
class Actuator:
    """A drive of joint ``joint``: joint effort = ``gear`` x its control."""

    name: str
    joint: str
    gear: float = 1.0


@dataclass
class Frame:
    """A named point of a link (an MJCF site, a URDF frame): ``point`` base frame."""

    name: str
    link: str
    point: Array


@dataclass
class Graph:
    """What a reader found (module docstring). ``source`` names the file, ``notes`` are lines
    written at the top of the description (what was merged or renamed)."""

    name: str
    source: str
    gravity: Array
    links: list[Link]
    joints: list[Joint]
    closures: list[Closure]
    actuators: list[Actuator]
    frames: list[Frame]
    notes: list[str] = field(default_factory=list)
    #: drives given whole (``[[actuators]]`` entries, e.g. from a URDF sidecar written by pkmdyn)
    drives: list[dict] = field(default_factory=list)
    #: the task the file names (pkmdyn's own MJCF exports carry it), None where it names none
    task: TaskChoice | None = None


@dataclass(frozen=True)
class TaskChoice:
    """The task asked for: ``body`` (a link or frame name), ``point`` (a frame name or three
    numbers, base frame), ``position`` (``x y z`` letters), ``orientation`` (1-3); ``None``:
    chosen as the module docstring says."""

    body: str | None = None
    point: str | tuple[float, float, float] | None = None
    position: tuple[str, ...] | None = None
    orientation: tuple[int, ...] | None = None
    sequence: str | None = None
    #: joints whose coordinates are task coordinates (after the body's, if any)
    joints: tuple[str, ...] | None = None


def safe_name(name: str, fallback: str) -> str:
    """A description name (a letter or ``_`` first, then letters, digits, ``_ ' . -``)."""
    s = re.sub(r"[^A-Za-z0-9_'.-]", "_", name or "")[:64]
    if not s:
        s = fallback
    if not re.match(r"[A-Za-z_]", s[0]):
        s = "_" + s[:63]
    return s


def _unit(v: Array) -> Array:
    return np.asarray(v, dtype=float) / np.linalg.norm(v)


def _lump(a: Link, b: Link) -> Link:
    """Link ``a`` with ``b`` rigidly added (parallel-axis theorem, Eq. of Steiner)."""
    m = a.mass + b.mass
    if m <= 0.0:
        return Link(a.name, 0.0, a.com.copy(), np.zeros((3, 3)))
    c = (a.mass * a.com + b.mass * b.com) / m

    def shifted(lk: Link) -> Array:
        d = lk.com - c
        return lk.inertia + lk.mass * (float(d @ d) * np.eye(3) - np.outer(d, d))

    return Link(a.name, m, c, shifted(a) + shifted(b))


def _massless(lk: Link) -> bool:
    return lk.mass <= MASSLESS_KG and float(np.abs(lk.inertia).max(initial=0.0)) <= MASSLESS_KG


class _Builder:
    def __init__(self, g: Graph):
        self.g = g
        self.links = {lk.name: lk for lk in g.links}
        if len(self.links) != len(g.links):
            dup = next(lk.name for k, lk in enumerate(g.links) if any(o.name == lk.name for o in g.links[:k]))
            raise ParameterError(f"{g.source}: two links are named {dup!r} (after replacing the characters a "
                                 "description name cannot hold by _)")
        names = [j.name for j in g.joints] + [c.name for c in g.closures]
        if len(set(names)) != len(names):
            dup = next(n for k, n in enumerate(names) if n in names[:k])
            raise ParameterError(f"{g.source}: two joints or closures are named {dup!r} (after replacing the "
                                 "characters a description name cannot hold by _)")
        self.alias: dict[str, str] = {}  # a merged link -> the link it went into
        self.notes = list(g.notes)
        scale = [np.linalg.norm(j.point) for j in g.joints] + [np.linalg.norm(c.point1) for c in g.closures]
        spread = np.ptp(np.array([j.point for j in g.joints] or [np.zeros(3)]), axis=0)
        self.size = max(float(np.max(spread, initial=0.0)), 1e-3 * max(scale, default=0.0), 1e-3)

    def owner(self, name: str) -> str:
        while name in self.alias:
            name = self.alias[name]
        return name

    # -- fixed joints: merge the child into the parent ------------------------------------
    def merge_fixed(self) -> list[Joint]:
        kept = []
        for j in self.g.joints:
            if j.kind != "fixed":
                kept.append(j)
                continue
            par, ch = self.owner(j.parent), self.owner(j.child)
            if ch == GROUND:
                raise ParameterError(f"{self.g.source}: joint {j.name}: a fixed joint whose child is the base "
                                     f"(from link {j.parent})")
            if par == GROUND:
                self.links.pop(ch, None)
                self.alias[ch] = GROUND
                self.notes.append(f"link {ch} is fixed to the base (joint {j.name})")
            else:
                self.links[par] = _lump(self.links[par], self.links.pop(ch))
                self.alias[ch] = par
                self.notes.append(f"link {ch} merged into {par} (fixed joint {j.name})")
        for j in kept:
            j.parent, j.child = self.owner(j.parent), self.owner(j.child)
        return kept

    # -- massless intermediate links: universal, spherical, cylindrical joints ---------------
    def combine(self, joints: list[Joint]) -> list[dict]:
        by_child = {j.child: j for j in joints}
        if len(by_child) != len(joints):
            dup = next(j for j in joints if sum(k.child == j.child for k in joints) > 1)
            raise ParameterError(f"{self.g.source}: link {dup.child} is the child of two tree joints")
        children: dict[str, list[Joint]] = {}
        for j in joints:
            children.setdefault(j.parent, []).append(j)
        out = []
        consumed: set[str] = set()
        for j in joints:
            if j.name in consumed:
                continue
            if j.parent != GROUND and j.parent in self.links and _massless(self.links[j.parent]) \
                    and j.parent in by_child:
                continue  # handled from the chain's first joint
            chain = [j]
            while (chain[-1].child in self.links and _massless(self.links[chain[-1].child])
                   and len(children.get(chain[-1].child, [])) == 1 and len(chain) < 3):
                chain.append(children[chain[-1].child][0])
            last = chain[-1].child
            if last in self.links and _massless(self.links[last]):
                why = "" if len(chain) == 1 else (f", and its joints ({', '.join(k.name for k in chain)}) are not a "
                                                  "universal, spherical or cylindrical joint")
                raise ParameterError(f"{self.g.source}: link {last}: no mass and no inertia{why} (a moving body needs "
                                     "an inertia; give it one, or fix it to a neighbour)")
            consumed.update(k.name for k in chain)
            for k in chain[:-1]:
                self.alias[k.child] = last
                self.links.pop(k.child, None)
            if len(chain) > 1:
                self.notes.append(f"joints {', '.join(k.name for k in chain)} through massless links form one joint")
            out.append(self.joint_entry(chain))
        return out

    def joint_entry(self, chain: list[Joint]) -> dict:
        j0 = chain[0]
        kinds = [k.kind for k in chain]
        name = j0.name if len(chain) == 1 else "_".join(k.name for k in chain)[:64]
        base = re.fullmatch(r"(.+)_1", j0.name)
        if len(chain) > 1 and base and all(k.name == f"{base[1]}_{i + 1}" for i, k in enumerate(chain)):
            name = base[1]  # <joint>_1, <joint>_2, ...: how pkmdyn's exports split one joint
        entry: dict = {"name": name, "parent": j0.parent, "child": chain[-1].child, "point_m": list(map(float, j0.point))}
        same_point = all(np.linalg.norm(k.point - j0.point) <= CLOSE_TOL * self.size for k in chain)
        axes = [_unit(k.axis) for k in chain]
        perp = all(abs(float(axes[a] @ axes[b])) <= AXIS_TOL for a in range(len(axes)) for b in range(a + 1, len(axes)))
        where = f"{self.g.source}: joints {', '.join(k.name for k in chain)}"
        if kinds == ["hinge"] or kinds == ["slide"]:
            entry["type"] = "revolute" if kinds[0] == "hinge" else "prismatic"
            entry["axis"] = list(map(float, axes[0]))
            key = "angle_at_reference_rad" if kinds[0] == "hinge" else "position_at_reference_m"
            if j0.value:
                entry[key] = float(j0.value)
            if j0.limits is not None:
                entry["limits_rad" if kinds[0] == "hinge" else "limits_m"] = [float(j0.limits[0]), float(j0.limits[1])]
            fr = {}
            if j0.damping:
                fr["viscous_Nm_s_rad" if kinds[0] == "hinge" else "viscous_N_s_m"] = float(j0.damping)
            if j0.frictionloss:
                fr["coulomb_torque_Nm" if kinds[0] == "hinge" else "coulomb_force_N"] = float(j0.frictionloss)
            if fr:
                entry["friction"] = fr
            if j0.stiffness:
                entry["stiffness"] = dict(j0.stiffness)
            if j0.spring is not None:
                entry["spring"] = ({"stiffness_Nm_rad": j0.spring[0], "reference_rad": j0.spring[1]} if kinds[0] == "hinge"
                                   else {"stiffness_N_m": j0.spring[0], "reference_m": j0.spring[1]})
            return entry
        if kinds == ["ball"]:
            entry["type"] = "spherical"
            fr = {}
            if j0.damping:  # the same viscous coefficient about every axis, as MuJoCo's ball damping
                fr["viscous_Nm_s_rad"] = float(j0.damping)
            if j0.frictionloss:
                fr["coulomb_torque_Nm"] = float(j0.frictionloss)
            if fr:
                entry["friction"] = fr
            return entry
        for k in chain:
            if k.damping or k.frictionloss or k.armature:
                raise ParameterError(f"{where}: friction or armature on a joint inside a combined "
                                     f"{'/'.join(kinds)} joint has no equivalent (joint {k.name})")
        kept_out = [k.name for k in chain if k.limits is not None]
        if kept_out:
            self.notes.append(f"joints {', '.join(kept_out)}: their limits are not kept (a combined joint has none)")
        if any(k.value for k in chain):
            self.notes.append(f"joints {', '.join(k.name for k in chain)}: the combined joint's coordinates are "
                              "zero at the reference configuration, not the file's joint positions")
        if kinds == ["hinge", "hinge"] and same_point and perp:
            entry["type"] = "universal"
            entry["axes"] = [list(map(float, axes[0])), list(map(float, axes[1]))]
            return entry
        if kinds == ["hinge", "hinge", "hinge"] and same_point and abs(float(np.linalg.det(np.column_stack(axes)))) >= 1e-3:
            # three hinges through one point with axes not in one plane: a spherical joint (its
            # coordinates are pkmdyn's XYZ angles in the frame x = first axis, z = last axis,
            # not the hinges' angles; the axes need not be perpendicular away from the zero pose)
            entry["type"] = "spherical"
            entry["axis"] = list(map(float, axes[2]))
            entry["x_axis"] = list(map(float, axes[0]))
            return entry
        if sorted(kinds) == ["hinge", "slide"] and abs(abs(float(axes[0] @ axes[1])) - 1.0) <= AXIS_TOL:
            d = chain[1].point - j0.point
            if np.linalg.norm(d - (d @ axes[0]) * axes[0]) <= CLOSE_TOL * self.size:
                entry["type"] = "cylindrical"
                entry["axis"] = list(map(float, axes[kinds.index("slide")]))
                return entry
        raise ParameterError(f"{where}: a chain of {'-'.join(kinds)} joints through massless links "
                             "that is not a universal, spherical or cylindrical joint (give the links between them "
                             "a mass and an inertia)")

    # -- loop closures ------------------------------------------------------------------------
    def closures(self) -> list[dict]:
        out = []
        pairs: dict[frozenset, dict] = {}
        for c in self.g.closures:
            a, b = self.owner(c.link1), self.owner(c.link2)
            where = f"{self.g.source}: loop closure {c.name}"
            if a == b:
                raise ParameterError(f"{where}: both frames are on link {a}")
            if c.kind == "joint":  # assembled by construction; pkmdyn chooses where to cut
                out.append({"name": c.name, "parent": a, "child": b, "point_m": list(map(float, c.point1)), **c.joint})
                continue
            gap, ang = c.gap if c.gap is not None else (float(np.linalg.norm(c.point1 - c.point2)), None)
            if gap > CLOSE_TOL * self.size:
                raise ParameterError(f"{where}: its frames are {gap:.6g} m apart at the reference configuration "
                                     "(the loop does not close there; --assemble closes it for MJCF and URDF)")
            if c.kind == "6d":
                if ang is None:
                    ang = float(np.linalg.norm(_rotvec(c.R1.T @ c.R2)))
                if ang > 1e-6:
                    raise ParameterError(f"{where}: its frames are turned {ang:.6g} rad apart at the reference "
                                         "configuration (the loop does not close there)")
            if a == GROUND:
                a, b = b, a
            key = frozenset((a, b))
            first = pairs.get(key)
            if c.kind == "3d" and first is not None and first["type"] == "spherical":
                # two point closures between one pair of links: a revolute joint about the line through them
                # (how pkmdyn export writes a revolute cut joint)
                axis = c.point1 - np.asarray(first["point_m"])
                if np.linalg.norm(axis) > CLOSE_TOL * self.size:
                    first["type"] = "revolute"
                    first["axis"] = list(map(float, _unit(axis)))
                    self.notes.append(f"loop closures {first['name']} and {c.name} (two points between {a} and {b}) "
                                      "form one revolute cut joint")
                    continue
            if first is not None:
                raise ParameterError(f"{where}: a second loop closure between links {a} and {b} that does not "
                                     "form a revolute joint with the first")
            entry = {"name": c.name, "type": "spherical" if c.kind == "3d" else "fixed", "parent": a, "child": b,
                     "point_m": list(map(float, c.point1))}
            pairs[key] = entry
            if c.kind == "6d":
                entry["axis"] = list(map(float, c.R1[:, 2]))
                entry["x_axis"] = list(map(float, c.R1[:, 0]))
            out.append(entry)
        return out


def _rotvec(R: Array) -> Array:
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(R).as_rotvec()


def _actuators(b: _Builder, joints: list[dict]) -> list[dict]:
    """Mark the actuated joints; a drive where a gear, armature or motor friction says so."""
    by_name = {j["name"]: j for j in joints}
    elementary = {j.name: j for j in b.g.joints}
    drives = []
    seen: set[str] = set()
    given = {d.get("joint") for d in b.g.drives}
    for a in b.g.actuators:
        where = f"{b.g.source}: actuator {a.name}"
        if a.joint not in by_name:
            inside = next((j["name"] for j in joints if a.joint in j["name"].split("_")), None)
            raise ParameterError(f"{where}: joint {a.joint} is not a hinge or slide joint of its own"
                                 + (f" (it is part of joint {inside})" if inside else ""))
        if a.joint in seen:
            raise ParameterError(f"{where}: a second actuator on joint {a.joint}")
        seen.add(a.joint)
        j, e = by_name[a.joint], elementary.get(a.joint)  # None: a joint of the file that closes a loop
        if j["type"] not in ("revolute", "prismatic"):
            raise ParameterError(f"{where}: joint {a.joint} is {j['type']}; only hinge and slide joints are driven")
        if not np.isfinite(a.gear) or a.gear <= 0:
            raise ParameterError(f"{where}: gear {a.gear:g}; a drive needs a positive gear (reverse the joint's axis)")
        j["actuated"] = True
        if a.joint in given:  # a drive given whole: the joint's own friction stays the joint's
            continue
        j.pop("friction", None)  # an actuated joint's damping and dry friction are its drive's
        arm, damp, fric = (e.armature, e.damping, e.frictionloss) if e is not None else (0.0, 0.0, 0.0)
        if a.gear == 1.0 and not (arm or damp or fric):
            continue
        k = a.gear
        taken = set(by_name) | set(b.links)
        d: dict = {"joint": a.joint, "name": a.name if a.name not in taken else f"{a.joint}_motor"}
        if j["type"] == "revolute":
            d["gear_ratio"] = k
        elif k != 1.0:
            d["screw_lead_m"] = 2 * np.pi / k  # transmission ratio 2 pi / lead = gear (motor turns per screw turn 1)
        keys = MOTOR_KEYS["rotary" if j["type"] == "revolute" or k != 1.0 else "linear"]
        for role, v in (("rotor", arm / (k * k)), ("viscous", damp / (k * k)), ("coulomb", fric / k)):
            if v:
                d[keys[role]] = v
        drives.append(d)
    for j in b.g.joints:
        if j.armature and j.name not in seen:
            raise ParameterError(f"{b.g.source}: joint {j.name}: armature (a rotor's inertia) on a joint without an "
                                 "actuator has no equivalent in a description")
    return drives


def _task_candidates(b: _Builder, joints: list[dict], choice: TaskChoice) -> list[tuple[str, Array]]:
    """The task body and point asked for, or the candidates in the order the module docstring
    gives (an end-effector frame's body; the bodies with the most joints, the deepest first)."""
    frames = {f.name: f for f in b.g.frames}
    point: Array | None = None
    body = safe_name(choice.body, "") if choice.body else None
    if isinstance(choice.point, str):
        f = frames.get(safe_name(choice.point, ""))
        if f is None:
            raise ParameterError(f"{b.g.source}: task point {choice.point!r}: no site or frame of that name")
        point = f.point
        body = body or b.owner(f.link)
    elif choice.point is not None:
        point = np.asarray(choice.point, dtype=float)
    if body is not None:
        body = b.owner(body) if body not in b.links else body
        if body not in b.links:
            raise ParameterError(f"{b.g.source}: task body {body!r}: no moving link of that name")
        return [(body, np.asarray(point if point is not None else b.links[body].com, dtype=float))]
    out: list[tuple[str, Array]] = []
    def named(nm: str, word: str) -> bool:  # a long word anywhere, a short one as a whole token (not "knee")
        low = nm.lower()
        return word in low if len(word) > 4 else word in re.split(r"[^a-z0-9]+", low)

    for word in EFFECTOR_WORDS:
        out += [(b.owner(f.link), f.point) for f in b.g.frames if named(f.name, word) and b.owner(f.link) in b.links]
        out += [(nm, b.links[nm].com) for nm in b.links if named(nm, word)]
    count: dict[str, int] = {}
    parent: dict[str, str] = {}
    for j in joints:
        parent.setdefault(j["child"], j["parent"])
        for side in (j["parent"], j["child"]):
            count[side] = count.get(side, 0) + 1

    def depth(nm: str) -> int:
        d = 0
        while nm in parent and d < len(parent):
            nm, d = parent[nm], d + 1
        return d

    ranked = sorted(b.links, key=lambda nm: (-count.get(nm, 0), -depth(nm), -b.links[nm].mass))
    out += [(nm, b.links[nm].com) for nm in ranked]
    seen, unique = set(), []
    for nm, p in out:
        if nm not in seen:
            seen.add(nm)
            unique.append((nm, np.asarray(p if point is None else point, dtype=float)))
    return unique


def _choose_coordinates(desc: dict, choice: TaskChoice, source: str) -> None:
    """Set ``[task] position`` and ``orientation`` (module docstring)."""
    if choice.position is not None or choice.orientation is not None or choice.joints is not None:
        desc["task"]["position"] = list(choice.position or [])
        desc["task"]["orientation"] = list(choice.orientation or [])
        if choice.joints:
            desc["task"]["joints"] = list(choice.joints)
        return
    desc["task"]["position"] = ["x", "y", "z"]
    desc["task"]["orientation"] = [1, 2, 3]
    model = compile_model(load_description(desc), topology_only=True)
    rep = analyse_topology(model)
    _, J = constraint_jacobian(model, model.coord_offset)
    Js = J[0] * row_scale(model)[:, None] * column_scale(model)[None, :]
    nr = model.row_loop.shape[0]
    phi, task = Js[:nr], Js[nr:]
    T = task @ _null(phi, model.nq)
    if rep.dof <= 0:
        raise ParameterError(f"{source}: the mechanism does not move (mobility {rep.mobility}, {rep.idle} idle)")
    if rep.dof < model.na:  # motions that leave this body still are idle for it: another body is needed
        raise ParameterError(f"{source}: task body {desc['task']['body']} sees {rep.dof} of the mechanism's "
                             f"freedoms, fewer than its {model.na} actuators (choose another with --task-body)")
    chosen: list[int] = []
    for group in ([0, 1, 2], [3, 4, 5]):
        if len(chosen) == rep.dof:
            break
        rest = T[group]
        if chosen:  # what the chosen rows leave
            Q, _ = np.linalg.qr(T[chosen].T)
            rest = rest - (rest @ Q) @ Q.T
        _, R, piv = scipy.linalg.qr(rest.T, pivoting=True, mode="economic")
        d = np.abs(np.diag(R)) if R.size else np.zeros(0)
        for k in range(len(d)):
            if len(chosen) == rep.dof or d[k] <= 1e-6 * max(float(np.abs(T).max()), 1e-300):
                break
            chosen.append(group[int(piv[k])])
    if len(chosen) != rep.dof:
        raise ParameterError(f"{source}: no {rep.dof} independent coordinates of task body {desc['task']['body']} "
                             "(choose another with --task-body)")
    chosen.sort()
    desc["task"]["position"] = ["xyz"[i] for i in chosen if i < 3]
    desc["task"]["orientation"] = [i - 2 for i in chosen if i >= 3]


def _choose_joints(desc: dict, source: str) -> None:
    """Set ``[task] joints`` (module docstring), and the task body's coordinates where the
    joints' do not suffice: the coordinates of one-freedom tree joints, the actuated first,
    then the sprung, then the others, then the task body's ``x y z`` and ``XYZ`` angles, then
    the coordinates of joints of several freedoms (``"name:k"``), each
    kept where its row on the loops' null space less the idle freedoms (the motions that move
    no joint centre) is independent of the rows kept before it (scaled residual above 1e-6),
    until there are as many as the mechanism's degrees of freedom."""
    task = desc["task"]
    task.update(position=["x", "y", "z"], orientation=[1, 2, 3], joints=[])
    model = compile_model(load_description(desc), topology_only=True)
    _, J = constraint_jacobian(model, model.coord_offset)
    nr = model.row_loop.shape[0]
    Js = J[0] * row_scale(model)[:, None] * column_scale(model)[None, :]
    N = _null(Js[:nr], model.nq)
    # the freedoms that move a joint centre: the idle ones (a rod's spin) are no task's
    P = _point_jacobian(model, model.coord_offset) / model.length_scale * column_scale(model)[None, :]
    moving = _null(_null(P @ N, N.shape[1]).T, N.shape[1]) if N.shape[1] else np.zeros((0, 0))
    Nm = N @ moving
    dof = Nm.shape[1]
    if dof <= 0:
        raise ParameterError(f"{source}: the mechanism does not move")
    spec = {j["name"]: j for j in desc["joints"]}
    order = sorted(
        (k for k in range(len(model.joint_names)) if not model.joint_cut[k] and model.joint_nq[k] == 1),
        key=lambda k: (0 if model.joint_actuated[k] else 1 if spec[model.joint_names[k]].get("spring") else 2, k))
    rows = [(("joint", model.joint_names[k]), Nm[int(model.joint_q0[k])]) for k in order]
    rows += [(("body", r), Js[nr + r] @ Nm) for r in range(6)]
    for k in range(len(model.joint_names)):  # last, a coordinate of a joint of several (a ball's angle)
        n = int(model.joint_nq[k])
        if model.joint_cut[k] or n < 2:
            continue
        for i in range(n):
            c = int(model.joint_q0[k]) + (n - 1 - i if model.joint_flipped[k] else i)
            rows.append((("joint", f"{model.joint_names[k]}:{i + 1}"), Nm[c]))
    chosen: list[tuple[str, Any]] = []
    basis = np.zeros((0, dof))
    for what, row in rows:
        row = row - (row @ basis.T) @ basis if basis.size else row.copy()
        size = float(np.linalg.norm(row))
        if size > 1e-6:
            chosen.append(what)
            basis = np.vstack([basis, row / size])
        if len(chosen) == dof:
            break
    if len(chosen) != dof:
        raise ParameterError(f"{source}: no {dof} independent coordinates of joints and of body {task['body']} "
                             "either (choose the task with --task-body or --task-joints)")
    task["joints"] = [nm for kind, nm in chosen if kind == "joint"]
    body = sorted(r for kind, r in chosen if kind == "body")
    task["position"] = ["xyz"[r] for r in body if r < 3]
    task["orientation"] = [r - 2 for r in body if r >= 3]


def description_from_graph(g: Graph, choice: TaskChoice = TaskChoice()) -> tuple[dict, list[str]]:
    """The description (a dict, as :func:`~pkmdyn.multibody.load_mechanism` takes) of ``g``,
    and the notes (module docstring)."""
    b = _Builder(g)
    tree = b.merge_fixed()
    joints = b.combine(tree)
    for j in joints:
        j["parent"], j["child"] = b.owner(j["parent"]), b.owner(j["child"])
    cuts = b.closures()
    drives = _actuators(b, joints + cuts)
    if not any(j.get("actuated") for j in joints + cuts):
        raise ParameterError(f"{g.source}: no actuated joint (an MJCF <actuator>, the sidecar's name_mot, or --actuated)")
    candidates = _task_candidates(b, joints + cuts, choice)
    body, point = candidates[0]
    bodies = [{"name": lk.name, "mass_kg": float(lk.mass), "com_m": list(map(float, lk.com)),
               "inertia_kgm2": [[float(x) for x in row] for row in 0.5 * (lk.inertia + lk.inertia.T)]}
              for lk in b.links.values()]
    desc: dict = {
        "mechanism": {"name": safe_name(g.name, "imported"), "source": f"imported from {g.source}",
                      "gravity_m_s2": list(map(float, g.gravity))},
        "bodies": bodies,
        "joints": joints + cuts,
        "task": {"body": body, "point_m": list(map(float, point)), "euler_sequence": choice.sequence or "XYZ"},
    }
    if cuts and not any(c.kind == "joint" for c in g.closures):
        desc["mechanism"]["cut_joints"] = [c["name"] for c in cuts]  # the file's tree is the spanning tree
    given = {d.get("joint") for d in g.drives}
    drives = [d for d in drives if d["joint"] not in given] + [dict(d) for d in g.drives]
    if drives:
        desc["actuators"] = drives
    chose_body = choice.body is not None or choice.point is not None
    if choice.joints is not None:  # the joints asked for, by their names in the description
        known = {j["name"] for j in joints + cuts}
        named = []
        for given in choice.joints:
            base, kc = split_task_joint(given)
            nm = safe_name(base, "")
            if nm not in known:
                raise ParameterError(f"{g.source}: task joint {given!r}: no joint of that name (the joints: "
                                     f"{', '.join(sorted(known)[:12])}{' ...' if len(known) > 12 else ''})")
            named.append(f"{nm}:{kc}" if kc else nm)
        choice = TaskChoice(body=choice.body, point=choice.point, position=choice.position,
                            orientation=choice.orientation, sequence=choice.sequence, joints=tuple(named))
        chose_body = True  # the task asked for is the task: no other is tried
    for k, (body, point) in enumerate(candidates[:MAX_CANDIDATES]):
        desc["task"].update(body=body, point_m=list(map(float, point)))
        try:
            _choose_coordinates(desc, choice, g.source)
            break
        except ParameterError as exc:
            if k == min(len(candidates), MAX_CANDIDATES) - 1:
                if chose_body:
                    raise
                # no body carries every freedom (two legs): a task of joint coordinates
                desc["task"].update(body=candidates[0][0], point_m=list(map(float, candidates[0][1])))
                _choose_joints(desc, g.source)
                t = desc["task"]
                also = [*t["position"], *(f"euler{a}" for a in t["orientation"])]
                b.notes.append(f"task: no body's coordinates determine the mechanism's freedoms (the last tried: "
                               f"{str(exc).split(': ', 1)[-1]}); the task is the coordinates of joints "
                               f"{', '.join(t['joints'])}" + (f" and {', '.join(also)} of body {t['body']}" if also
                                                               else "") + " (--task-joints to choose others)")
    types = {j["name"]: j["type"] for j in desc["joints"]}
    amp = {f"{c}_m": 0.01 * b.size for c in desc["task"]["position"]}
    amp.update({f"euler{k}_rad": 0.02 for k in desc["task"]["orientation"]})
    for item in desc["task"].get("joints", []):
        nm, kc = split_task_joint(item)
        unit = joint_type(types[nm]).units[max(kc, 1) - 1]
        amp[f"{nm}_q{kc or ''}_{unit}"] = 0.01 * b.size if unit == "m" else 0.02
    desc["default_motion"] = {"period_s": 2.0, "samples": 201, "amplitude": amp}
    return desc, b.notes
