"""URDF files with loop closures, read by Pinocchio's URDF parser, as a
:class:`~pkmdyn.multibody.formats.graph.Graph`.

A URDF file holds a tree; its loops are closed by pairs of frames that must coincide:

* a **sidecar** YAML file in the Extended-URDF form of Gepetto's example-parallel-robots:
  ``closed_loop: [[frame_A, frame_B], ...]`` (joint or link frames), ``type: ['6d' | '3d', ...]``
  (the two frames coincide, or only their origins; default ``6d``), ``name_mot: [joint, ...]``
  (the actuated joints); optional ``joint_name`` / ``joint_type`` (``SPHERICAL`` replaces a
  revolute joint by a spherical joint at its origin, ``UJOINT_XY`` ... by a universal joint
  about two axes of its frame, ``FIXED`` locks it where it is); and pkmdyn's own optional ``task: {body, point, position,
  orientation, euler_sequence}``, ``actuators`` (drives, as ``[[actuators]]`` entries) and
  ``gravity_m_s2`` (URDF holds none: default ``[0, 0, -9.81]``, Pinocchio's and MuJoCo's);
* or, without a sidecar, **onshape-to-robot's** frames ``closing_<name>_1`` and
  ``closing_<name>_2`` (3D closures, as onshape-to-robot closes them in MuJoCo).

The reference configuration is the zero joint position (``pinocchio.neutral``). Joint
``<dynamics damping friction>`` becomes joint friction; ``<limit lower upper>`` the joint's
limits where ``lower < upper``. Mimic, floating and planar joints are
refused by name; a continuous joint is a revolute joint without limits.
"""

from __future__ import annotations

import contextlib
import math
import os
import re
import sys
import tempfile
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np

from pydantic import Field, field_validator

from ...errors import ParameterError
from ...params_util import Section, validate
from ..description.schema import GROUND
from .prescan import prescan_urdf
from .graph import (
    CLOSE_TOL,
    Actuator,
    Closure,
    Frame,
    Graph,
    Joint,
    Link,
    TaskChoice,
    safe_name,
)

#: URDF holds no gravity: Pinocchio's and MuJoCo's default, unless the sidecar gives gravity_m_s2
URDF_GRAVITY = (0.0, 0.0, -9.81)


def _pinocchio():
    try:
        import pinocchio
    except ImportError as exc:  # pragma: no cover - the extra is in the test dependencies
        raise ParameterError("reading URDF needs Pinocchio, in the import extra: pip install 'pkmdyn[import]' (from a "
                             "source checkout: pip install '.[import]')") from exc
    return pinocchio


@contextlib.contextmanager
def _stderr_captured():
    """What the C++ parser writes on the process's stderr meanwhile (``said()``: its lines)."""
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile(mode="w+b") as tmp:
        os.dup2(tmp.fileno(), 2)
        try:
            lines: list[str] = []
            yield lambda: lines
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            tmp.seek(0)
            lines += tmp.read().decode("utf-8", "replace").splitlines()


def _refuse_mimic(path: Path, src: str) -> None:
    """A ``<mimic>`` joint (Pinocchio's parser reads it as an independent joint by default); the
    file bounded first (:func:`~pkmdyn.multibody.formats.prescan.prescan_urdf`)."""
    root = prescan_urdf(path, src)
    for j in root.iter("joint"):
        if j.find("mimic") is not None:
            raise ParameterError(f"{src}: joint {j.get('name')}: a mimic joint has no equivalent in a description")


#: a sidecar's most bytes, and the deepest nesting of its lists and mappings
MAX_SIDECAR_BYTES = 1_000_000
MAX_SIDECAR_DEPTH = 8

_Frame = Annotated[str, Field(min_length=1, max_length=256)]


class _SidecarTask(Section):
    body: _Frame | None = None
    point: Any = None

    @field_validator("point")
    @classmethod
    def _frame_or_point(cls, v: Any) -> Any:
        if v is None or (isinstance(v, str) and 0 < len(v) <= 256):
            return v
        if isinstance(v, list) and len(v) == 3 and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                                       and math.isfinite(x) for x in v):
            return [float(x) for x in v]
        raise ValueError("expected a frame name or three finite numbers [x, y, z] in metres")

    position: list[Literal["x", "y", "z"]] = Field(default_factory=list, max_length=3)
    orientation: list[Literal[1, 2, 3]] = Field(default_factory=list, max_length=3)
    joints: list[_Frame] = Field(default_factory=list, max_length=600)
    euler_sequence: str = Field(default="XYZ", pattern=r"^([XYZ]{3}|[xyz]{3})$")

    @field_validator("euler_sequence")
    @classmethod
    def _sequence(cls, v: str) -> str:
        if v[0] == v[1] or v[1] == v[2]:
            raise ValueError(f"{v!r}: no axis twice in a row (e.g. XYZ, ZYX, ZXZ; upper case intrinsic)")
        return v


class _Sidecar(Section):
    """The sidecar's schema (module docstring): names are text, numbers finite, lists bounded."""

    closed_loop: list[Annotated[list[_Frame], Field(min_length=2, max_length=2)]] = Field(default_factory=list,
                                                                                         max_length=1000)
    type: list[Literal["3d", "6d", "3D", "6D"]] | None = Field(default=None, max_length=1000)
    name_mot: list[_Frame] = Field(default_factory=list, max_length=1000)
    joint_name: list[_Frame] = Field(default_factory=list, max_length=1000)
    joint_type: list[Annotated[str, Field(min_length=1, max_length=32)]] = Field(default_factory=list,
                                                                                  max_length=1000)
    task: _SidecarTask | None = None
    actuators: list[dict[str, Any]] = Field(default_factory=list, max_length=1000)
    gravity_m_s2: Annotated[list[float], Field(min_length=3, max_length=3)] = list(URDF_GRAVITY)
    drive_stiffness: dict[_Frame, Annotated[float, Field(gt=0)]] = Field(default_factory=dict, max_length=1000)
    #: a joint's coordinate at the URDF's zero position [rad or m] (pkmdyn's exports: its reference value)
    reference: dict[_Frame, Annotated[float, Field(allow_inf_nan=False)]] = Field(default_factory=dict,
                                                                                 max_length=1000)


def _plain_yaml(text: str, src: str) -> Any:
    """The YAML document ``text`` without anchors or aliases (which expand without bound) and
    nested at most :data:`MAX_SIDECAR_DEPTH` deep, checked on its events before anything is built."""
    import yaml

    depth = 0
    try:
        for ev in yaml.parse(text, Loader=yaml.SafeLoader):
            if isinstance(ev, yaml.AliasEvent) or getattr(ev, "anchor", None):
                raise ParameterError(f"{src}: YAML anchors and aliases (&, *) are not taken in a sidecar; write the "
                                     "values out")
            if isinstance(ev, (yaml.MappingStartEvent, yaml.SequenceStartEvent)):
                depth += 1
                if depth > MAX_SIDECAR_DEPTH:
                    raise ParameterError(f"{src}: nested more than {MAX_SIDECAR_DEPTH} deep")
            elif isinstance(ev, (yaml.MappingEndEvent, yaml.SequenceEndEvent)):
                depth -= 1
        return yaml.safe_load(text)
    except (yaml.YAMLError, ValueError, RecursionError) as exc:  # ValueError: an integer of thousands of digits
        raise ParameterError(f"{src}: cannot read it as YAML: {' '.join(str(exc).split())[:200]}") from None


def read_sidecar(path: str | Path) -> dict[str, Any]:
    """The sidecar YAML (module docstring), checked: a regular file of at most
    :data:`MAX_SIDECAR_BYTES`, plain YAML (:func:`_plain_yaml`), then the schema."""
    src = Path(path).name
    try:
        if not Path(path).is_file():
            raise ParameterError(f"{src}: not a regular file")
        with open(path, "rb") as fh:
            raw = fh.read(MAX_SIDECAR_BYTES + 1)
        if len(raw) > MAX_SIDECAR_BYTES:
            raise ParameterError(f"{src}: larger than {MAX_SIDECAR_BYTES:,} bytes; a sidecar names loops and joints")
        text = raw.decode("utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ParameterError(f"{src}: cannot read it as YAML: {' '.join(str(exc).split())[:200]}") from None
    data = _plain_yaml(text, src)
    if not isinstance(data, dict):
        raise ParameterError(f"{src}: a YAML mapping is expected (closed_loop, type, name_mot)")
    side = validate(_Sidecar, data, src)
    loops = [list(p) for p in side.closed_loop]
    types = [t.lower() for t in side.type] if side.type else ["6d"] * len(loops)  # none given: 6d each
    if len(types) != len(loops):
        raise ParameterError(f"{src}: type: one of '3d' or '6d' per closed_loop pair is expected "
                             f"({len(types)} for {len(loops)} pairs)")
    if len(side.joint_name) != len(side.joint_type):
        raise ParameterError(f"{src}: joint_name and joint_type: two lists of one length are expected")
    task = side.task.model_dump(exclude_unset=True) if side.task is not None else {}
    return {"gravity_m_s2": [float(x) for x in side.gravity_m_s2], "closed_loop": loops, "type": types,
            "name_mot": list(side.name_mot), "joint_name": list(side.joint_name),
            "joint_type": [t.upper() for t in side.joint_type], "task": task,
            "actuators": [dict(d) for d in side.actuators], "drive_stiffness": dict(side.drive_stiffness),
            "reference": dict(side.reference)}


def sidecar_task(side: dict[str, Any]) -> TaskChoice:
    """The sidecar's ``task`` as a :class:`TaskChoice`."""
    t = side.get("task") or {}
    point = t.get("point")
    if isinstance(point, list):
        point = tuple(float(x) for x in point)
    pos = tuple(t["position"]) if "position" in t else None
    ori = tuple(int(x) for x in t["orientation"]) if "orientation" in t else None
    joints = tuple(str(x) for x in t["joints"]) if "joints" in t else None
    return TaskChoice(body=t.get("body"), point=point, position=pos, orientation=ori, sequence=t.get("euler_sequence"),
                      joints=joints)


def _closure_pairs(model, src: str, sidecar: dict[str, Any] | None) -> list[tuple[str, str, str]]:
    """``(frame_A, frame_B, kind)`` of every loop closure (module docstring)."""
    pin = _pinocchio()
    frames = {f.name for f in model.frames}
    if sidecar is not None:
        pairs = [(a, b, kind) for (a, b), kind in zip(sidecar.get("closed_loop", []), sidecar.get("type", []))]
    else:  # onshape-to-robot's closing frames
        found: dict[str, dict[str, str]] = {}
        for f in model.frames:
            m = re.fullmatch(r"closing_(.+)_([12])", f.name)
            if m and f.type == pin.FrameType.BODY:
                found.setdefault(m[1], {})[m[2]] = f.name
        pairs = []
        for key, both in sorted(found.items()):
            if set(both) != {"1", "2"}:
                raise ParameterError(f"{src}: frame closing_{key}_{next(iter(both))}: its pair "
                                     f"closing_{key}_{'2' if '1' in both else '1'} is missing")
            pairs.append((both["1"], both["2"], "3d"))
    for a, b, _ in pairs:
        for nm in (a, b):
            if nm not in frames:
                raise ParameterError(f"{src}: closed_loop frame {nm!r}: no frame of that name in the URDF")
    return pairs


def _assemble(model, data, q0, pairs: list[tuple[str, str, str]], src: str):
    """A configuration near ``q0`` at which every closure holds (Levenberg-Marquardt from
    ``q0``); refused naming the pair and its gap where it does not converge."""
    pin = _pinocchio()
    ids = [(model.getFrameId(a), model.getFrameId(b), kind) for a, b, kind in pairs]
    q = q0.copy()
    pin.forwardKinematics(model, data, q)  # the joints' places at the start: the model's size
    size = max(float(np.abs(np.array([np.array(data.oMi[j].translation) for j in range(model.njoints)])).max()), 1e-3)

    def residual(q):
        pin.forwardKinematics(model, data, q)
        pin.updateFramePlacements(model, data)
        pin.computeJointJacobians(model, data, q)
        rs, Js = [], []
        for fa, fb, kind in ids:
            Ma, Mb = data.oMf[fa], data.oMf[fb]
            Ja = pin.getFrameJacobian(model, data, fa, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
            Jb = pin.getFrameJacobian(model, data, fb, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
            rs.append(np.array(Ma.translation - Mb.translation) / size)
            Js.append((Ja[:3] - Jb[:3]) / size)
            if kind == "6d":
                rs.append(np.array(pin.log3(Ma.rotation @ Mb.rotation.T)))  # world frame, as the rows
                Js.append(Ja[3:] - Jb[3:])
        return np.concatenate(rs), np.vstack(Js)

    # Levenberg-Marquardt (a Gauss-Newton step where it reduces the residual, damped where not)
    r, J = residual(q)
    mu = 1e-6
    for _ in range(500):
        if np.abs(r).max() < 1e-14:
            break
        A = J.T @ J
        step = -np.linalg.solve(A + mu * (np.trace(A) / len(A) + 1e-12) * np.eye(len(A)), J.T @ r)
        q_new = pin.integrate(model, q, step)
        r_new, J_new = residual(q_new)
        if r_new @ r_new < r @ r:
            q, r, J, mu = q_new, r_new, J_new, max(mu / 10, 1e-12)
        else:
            mu *= 10
            if mu > 1e8:
                break
    r, _ = residual(q)
    k = 0
    for fa, fb, kind in ids:
        n = 6 if kind == "6d" else 3
        gap = float(np.linalg.norm(r[k:k + 3])) * size
        turn = float(np.linalg.norm(r[k + 3:k + n]))  # a 6D pair's frames: the angle between them [rad]
        if gap > CLOSE_TOL * size or turn > 1e-6:
            angle = f" and {turn:.6g} rad" if n == 6 else ""
            raise ParameterError(f"{src}: loop closure {model.frames[fa].name}-{model.frames[fb].name}: the loops do "
                                 f"not close near the zero configuration (gap {gap:.6g} m{angle} after assembly)")
        k += n
    return q


def urdf_graph(path: str | Path, sidecar: dict[str, Any] | None = None,
               actuated: tuple[str, ...] = (), assemble: bool = False) -> Graph:
    """The mechanism of a URDF file and its loop closures (module docstring)."""
    pin = _pinocchio()
    src = Path(path).name
    _refuse_mimic(Path(path), src)
    with _stderr_captured() as said:
        try:
            model = pin.buildModelFromUrdf(str(path))
        except Exception as exc:  # the parser's message names the element
            raise ParameterError(f"{src}: cannot read it as URDF: {' '.join(str(exc).split())[:300]}") from None
    errors = [ln.strip() for ln in said() if ln.strip().startswith("Error")]
    if errors:  # urdfdom reports some errors on stderr and goes on without the element
        raise ParameterError(f"{src}: cannot read it as URDF: {' '.join(errors[:2])[:300]}")
    data = model.createData()
    q0 = pin.neutral(model)
    pairs = _closure_pairs(model, src, sidecar)
    notes = []
    if assemble and pairs:
        q0 = _assemble(model, data, q0, pairs, src)
        notes.append("reference configuration: the loops closed from the zero configuration (--assemble)")
    pin.forwardKinematics(model, data, q0)
    pin.updateFramePlacements(model, data)
    pin.computeJointJacobians(model, data, q0)
    side = sidecar or {}
    special = dict(zip(side.get("joint_name", []), side.get("joint_type", [])))
    for nm in special:
        if nm not in model.names:
            raise ParameterError(f"{src}: sidecar joint_name {nm!r}: no joint of that name")

    # the link carried by each joint: the BODY frame whose parent frame is the joint's frame
    link_of = {0: GROUND}
    for f in model.frames:
        if f.type == pin.FrameType.BODY and f.parentJoint > 0 and f.parentJoint not in link_of:
            nm = safe_name(f.name, f"link_{f.parentJoint}")
            link_of[int(f.parentJoint)] = nm if nm != GROUND else "ground_body"  # a moving link called ground
    links, joints = [], []
    stiff = dict(side.get("drive_stiffness", {}))
    refs = dict(side.get("reference", {}))
    for j in range(1, model.njoints):
        jm, name = model.joints[j], safe_name(model.names[j], f"joint_{j}")
        short = jm.shortname()
        M = data.oMi[j]
        R, p = np.array(M.rotation), np.array(M.translation)
        child = link_of.setdefault(j, safe_name(model.names[j] + "_link", f"link_{j}"))
        parent = link_of[int(model.parents[j])]
        Y = model.inertias[j]
        links.append(Link(child, float(Y.mass), p + R @ np.array(Y.lever), R @ np.array(Y.inertia) @ R.T))
        iq = model.idx_qs[j]
        value = float(q0[iq])
        revolute = re.fullmatch(r"JointModel(R[XYZ]|RUB[XYZ]|RevoluteUnaligned|RevoluteUnboundedUnaligned)", short)
        prismatic = re.fullmatch(r"JointModel(P[XYZ]|PrismaticUnaligned)", short)
        if revolute or prismatic:
            S = np.array(pin.getJointJacobian(model, data, j, pin.ReferenceFrame.LOCAL))[:, model.idx_vs[j]]
            kind, axis = ("hinge", R @ S[3:]) if revolute else ("slide", R @ S[:3])  # motion subspace [v; w]
            if model.nqs[j] == 2:  # continuous: (cos, sin) of the angle
                value = float(np.arctan2(q0[iq + 1], q0[iq]))
        else:
            what = {"JointModelFreeFlyer": "a floating joint", "JointModelPlanar": "a planar joint"}.get(
                short, f"a {short} joint")
            raise ParameterError(f"{src}: joint {name}: {what} has no equivalent in a description")
        lo, hi = float(model.lowerPositionLimit[iq]), float(model.upperPositionLimit[iq])
        lim = (lo, hi) if lo < hi and np.isfinite(lo) and np.isfinite(hi) and abs(hi - lo) < 1e6 \
            and "RUB" not in short and "Unbounded" not in short else None
        r = refs.pop(model.names[j], 0.0)  # the coordinate at the URDF's zero
        value += r
        lim = None if lim is None else (lim[0] + r, lim[1] + r)
        v = model.idx_vs[j]
        kw = dict(value=value, limits=lim, damping=float(model.damping[v]),
                  frictionloss=float(model.friction[v]))
        k_drive = stiff.pop(model.names[j], None)
        if k_drive is not None:
            kw["stiffness"] = {("drive_Nm_rad" if kind == "hinge" else "drive_N_m"): k_drive}
        sp = special.get(model.names[j])
        if sp is not None and (kw["damping"] or kw["frictionloss"]):
            raise ParameterError(f"{src}: joint {name}: friction on a joint the sidecar makes {sp} has no equivalent")
        if sp is None:
            joints.append(Joint(name, kind, parent, child, p, axis, **kw))
        elif sp == "FIXED":  # locked where it is (Gepetto's loader reduces the model there)
            joints.append(Joint(name, "fixed", parent, child, p, axis))
        elif sp == "SPHERICAL":
            joints.append(Joint(name, "ball", parent, child, p, axis))
        elif re.fullmatch(r"UJOINT_[XYZ]{2}", sp):
            a1, a2 = (R[:, "XYZ".index(c)] for c in sp[-2:])
            mid = f"{child}__u"
            links.append(Link(mid, 0.0, p.copy(), np.zeros((3, 3))))
            joints.append(Joint(f"{name}_{sp[-2]}", "hinge", parent, mid, p, a1))
            joints.append(Joint(f"{name}_{sp[-1]}", "hinge", mid, child, p, a2))
        else:
            raise ParameterError(f"{src}: sidecar joint_type {sp!r} of joint {name}: one of SPHERICAL, "
                                 "UJOINT_XY (two letters of XYZ), FIXED")

    frames = []
    frame_pose = {}
    for fid, f in enumerate(model.frames):
        M = data.oMf[fid]
        lk = link_of.get(int(f.parentJoint), GROUND)
        frame_pose[f.name] = (lk, np.array(M.translation), np.array(M.rotation))
        if f.type in (pin.FrameType.BODY, pin.FrameType.FIXED_JOINT, pin.FrameType.OP_FRAME):
            frames.append(Frame(safe_name(f.name, f"frame_{fid}"), lk, np.array(M.translation)))

    closures = []
    for a, b, kind in pairs:
        (l1, p1, R1), (l2, p2, R2) = frame_pose[a], frame_pose[b]
        both = re.fullmatch(r"(.+)_A", a)
        cname = both[1] if both and b == f"{both[1]}_B" else f"{a}_{b}"  # pkmdyn's own <joint>_A, <joint>_B
        closures.append(Closure(safe_name(cname, "closure"), kind, l1, l2, p1, p2, R1, R2))

    mot = list(side.get("name_mot", [])) + list(actuated)
    names = {model.names[j] for j in range(1, model.njoints)} | {safe_name(model.names[j], "") for j in range(1, model.njoints)}
    for nm in mot:
        if nm not in names:
            raise ParameterError(f"{src}: actuated joint {nm!r}: no joint of that name")
    actuators = [Actuator(safe_name(nm, "motor"), safe_name(nm, "motor")) for nm in dict.fromkeys(mot)]
    if stiff:
        raise ParameterError(f"{src}: sidecar drive_stiffness {next(iter(stiff))!r}: no hinge or slide joint of that "
                             "name")
    if refs:
        raise ParameterError(f"{src}: sidecar reference {next(iter(refs))!r}: no hinge or slide joint of that name")
    g = np.array(side.get("gravity_m_s2", URDF_GRAVITY), dtype=float)
    # a generic robot name (Gepetto's files say "robot", onshape-to-robot's "onshape"): the file's own name
    name = Path(path).stem if model.name in ("", "onshape", "robot") else model.name
    return Graph(name=name, source=src, gravity=g, links=links, joints=joints, closures=closures, actuators=actuators,
                 frames=frames, notes=notes, drives=list(side.get("actuators", [])))
