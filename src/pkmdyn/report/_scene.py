"""The generic 3D scene of a mechanism: joint points per sample and which points each body joins.

A scene knows no machine. A machine (or a mechanism described in a file) gives the positions
of its joint points along the motion and, for every body, the points it connects; the page
draws each body as a polyline through its points (a filled face where the body is a plate),
the actuated bodies in a colour that follows their effort. :func:`scene_from_joints` builds a
scene from the joint list and joint points of ``model.json`` and ``bodies.npz`` (the outputs
of ``pdm run``), so any mechanism that writes those files plugs in unchanged.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..errors import ParameterError, PkmdynError

__all__ = ["Scene", "SceneBody", "SceneActuator", "FramePicker", "frame_indices", "scene_from_joints",
           "scene_from_files", "MAX_FRAMES"]

Array = NDArray[np.float64]

#: most animation frames of a report: a longer motion is shown at evenly spaced samples
MAX_FRAMES = 300


@dataclass(frozen=True)
class SceneBody:
    """One body drawn as a polyline through ``points`` (indices into :attr:`Scene.points`);
    ``closed`` joins the last point to the first; ``filled`` also draws the polygon's face (a
    platform or a plate); ``ground`` bodies do not move; ``line`` False draws the points only
    (the ground's joints)."""

    name: str
    points: tuple[int, ...]
    closed: bool = False
    filled: bool = False
    ground: bool = False
    line: bool = True


@dataclass(frozen=True)
class SceneActuator:
    """An actuated chain drawn through ``points`` in the colour of its effort ``effort (n,)``
    (``unit`` e.g. ``"N m"``, ``"N"``); ``label`` names it on the page ("motor 1 torque")."""

    name: str
    points: tuple[int, ...]
    effort: Array
    label: str
    unit: str


@dataclass(frozen=True)
class Scene:
    """A mechanism along a motion: ``t (n,)`` [s]; ``points (n, p, 3)`` [m], base frame, named by
    ``point_names (p,)``; the bodies and actuators that join them; ``path_point``: the index of a
    point whose path is drawn (the tool or platform point), or None. ``frame_label`` and
    ``frame_unit`` name what ``t`` counts on the page's slider (``"t"``, ``"s"``; a scene of
    configurations that are not a motion, such as assembly modes, names its own: ``"mode"``,
    ``""``)."""

    t: Array
    points: Array
    point_names: tuple[str, ...]
    bodies: tuple[SceneBody, ...]
    actuators: tuple[SceneActuator, ...] = ()
    path_point: int | None = None
    joint_points: tuple[int, ...] = field(default=())  #: points drawn as joint markers (all when empty)
    frame_label: str = "t"
    frame_unit: str = "s"

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=float)
        pts = np.asarray(self.points, dtype=float)
        n = t.shape[0]
        if t.ndim != 1 or n < 1:
            raise ParameterError(f"scene: t must be (n,) with n >= 1, got shape {t.shape}")
        if pts.ndim != 3 or pts.shape[0] != n or pts.shape[2] != 3:
            raise ParameterError(f"scene: points must be ({n}, p, 3), got shape {pts.shape}")
        if len(self.point_names) != pts.shape[1]:
            raise ParameterError(f"scene: {len(self.point_names)} point names for {pts.shape[1]} points")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(pts))):
            raise PkmdynError("scene: a time or a point position is not finite")
        p = pts.shape[1]
        for b in (*self.bodies, *self.actuators):
            if not b.points or min(b.points) < 0 or max(b.points) >= p:
                raise ParameterError(f"scene: body {b.name!r} names a point outside 0..{p - 1}")
        for a in self.actuators:
            e = np.asarray(a.effort, dtype=float)
            if e.shape != (n,) or not np.all(np.isfinite(e)):
                raise ParameterError(f"scene: actuator {a.name!r} effort must be ({n},) and finite")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "points", pts)

    def at(self, idx: Array) -> "Scene":
        """The scene at samples ``idx`` (an index array), e.g. the frames of an animation."""
        idx = np.asarray(idx, dtype=int)
        acts = tuple(SceneActuator(a.name, a.points, np.asarray(a.effort)[idx], a.label, a.unit) for a in self.actuators)
        return replace(self, t=self.t[idx], points=self.points[idx], actuators=acts)


def frame_indices(n: int, max_frames: int = MAX_FRAMES) -> Array:
    """At most ``max_frames`` evenly spaced sample indices of ``0 .. n - 1``, first and last included."""
    if n <= max_frames:
        return np.arange(n)
    return np.unique(np.round(np.linspace(0, n - 1, max_frames)).astype(int))


class FramePicker:
    """The animation's samples of a run that streams block by block: at most ``max_frames`` evenly
    spaced samples of ``0 .. n - 1`` (:func:`frame_indices`), picked from each block as it passes,
    so memory does not grow with the run. ``add(start, t=..., q=...)`` takes one block's arrays
    (leading sample axis, block starting at sample ``start``); ``arrays()`` the picked rows."""

    def __init__(self, n: int, max_frames: int = MAX_FRAMES) -> None:
        self.idx = frame_indices(n, max_frames)
        self.parts: dict[str, list[Array]] = {}

    def add(self, start: int, **arrays: Array) -> None:
        k = next(iter(arrays.values())).shape[0]
        pick = self.idx[(self.idx >= start) & (self.idx < start + k)] - start
        for key, v in arrays.items():
            self.parts.setdefault(key, []).append(np.asarray(v)[pick])

    def arrays(self) -> dict[str, Array]:
        return {k: np.concatenate(v) for k, v in self.parts.items()}


def _plate(pts: Array) -> bool:
    """True when the polygon ``pts (k, 3)`` has an area worth filling (not a line or a sliver)."""
    if pts.shape[0] < 3:
        return False
    c = pts.mean(axis=0)
    area = 0.5 * np.linalg.norm(sum(np.cross(pts[i] - c, pts[(i + 1) % len(pts)] - c) for i in range(len(pts))))
    perimeter = sum(np.linalg.norm(pts[(i + 1) % len(pts)] - pts[i]) for i in range(len(pts)))
    return bool(perimeter > 0 and area > 0.02 * perimeter**2)


def scene_from_joints(t: Array, joint_point: Array, joints: Sequence[tuple[str, str, str, str]],
                      actuated: Mapping[str, tuple[Array, str, str]] | None = None, ground: str = "ground",
                      extra_points: Mapping[str, Array] | None = None, path_point: str | None = None) -> Scene:
    """A scene from a joint list and the joint centres along a motion.

    ``t (n,)`` [s]; ``joint_point (n, J, 3)`` [m] the joint centres, base frame, in the order of
    ``joints``: ``(name, type, body_a, body_b)`` as in ``model.json``. Every moving body is drawn
    through the joints it takes part in (in the list's order, closed when there are three or
    more; filled when they span a plate). ``actuated``: ``{joint: (effort (n,), label, unit)}``;
    the two bodies of an actuated joint are drawn as one chain, from body_a's other joints through
    the actuated joint to body_b's other joints, in the effort's colour. ``extra_points``:
    further named points ``(n, 3)`` (e.g. the tool point, drawn with its path when named by
    ``path_point``).
    """
    jp = np.asarray(joint_point, dtype=float)
    names = [j[0] for j in joints]
    if jp.ndim != 3 or jp.shape[1] != len(joints):
        raise ParameterError(f"scene: joint_point has shape {jp.shape}, expected (n, {len(joints)}, 3)")
    actuated = dict(actuated or {})
    for name in actuated:
        if name not in names:
            raise ParameterError(f"scene: actuated joint {name!r} is not in the joint list")
    of_body: dict[str, list[int]] = {}
    for k, (_, _, a, b) in enumerate(joints):
        of_body.setdefault(a, []).append(k)
        of_body.setdefault(b, []).append(k)
    in_actuator: set[str] = set()
    actuators = []
    for name, (effort, label, unit) in actuated.items():
        k = names.index(name)
        _, _, a, b = joints[k]
        chain = [i for i in of_body[a] if i != k] + [k] + [i for i in of_body[b] if i != k]
        if a != ground:
            in_actuator.add(a)
        if b != ground:
            in_actuator.add(b)
        actuators.append(SceneActuator(name, tuple(chain), np.asarray(effort, dtype=float), label, unit))
    bodies = []
    for body, idx in of_body.items():
        if body == ground or body in in_actuator:
            continue
        closed = len(idx) >= 3
        bodies.append(SceneBody(body, tuple(idx), closed=closed, filled=closed and _plate(jp[0, idx])))
    ground_idx = of_body.get(ground, [])
    if ground_idx:
        bodies.append(SceneBody(ground, tuple(ground_idx), ground=True, line=False))
    point_names = list(names)
    points = [jp]
    path = None
    for pname, p in (extra_points or {}).items():
        if pname == path_point:
            path = len(point_names)
        point_names.append(pname)
        points.append(np.asarray(p, dtype=float).reshape(jp.shape[0], 1, 3))
    return Scene(np.asarray(t, dtype=float), np.concatenate(points, axis=1), tuple(point_names), tuple(bodies),
                 tuple(actuators), path, tuple(range(len(names))))


def scene_from_files(model_json: str | Path, bodies_npz: str | Path,
                     actuated: Mapping[str, tuple[Array, str, str]] | None = None) -> Scene:
    """The scene of a run from its ``model.json`` (``joints``: name, type, body_a, body_b) and
    ``bodies.npz`` (``t (n,)``, ``joint_point (n, J, 3)``), the files every multibody run writes.

    ``actuated``: ``{joint: (effort (n,), label, unit)}``; without it, joints marked
    ``"actuated": true`` in ``model.json`` are drawn as actuated chains in one colour (no effort
    known from a kinematics-only run)."""
    try:
        doc = json.loads(Path(model_json).read_text(encoding="utf-8"))
        with np.load(bodies_npz) as z:
            t, jp = np.asarray(z["t"]), np.asarray(z["joint_point"])
    except (OSError, ValueError, KeyError) as exc:
        raise PkmdynError(f"{model_json}, {bodies_npz}: cannot read the run's bodies ({exc})") from None
    try:
        joints = [(j["name"], j["type"], j["body_a"], j["body_b"]) for j in doc["joints"]]
    except (KeyError, TypeError) as exc:
        raise PkmdynError(f"{model_json}: a joint lacks {exc} (expected name, type, body_a, body_b)") from None
    if actuated is None:
        zero = np.zeros(np.asarray(t).shape[0])
        actuated = {j["name"]: (zero, f"{j['name']} (actuated)", "-") for j in doc["joints"] if j.get("actuated")}
    return scene_from_joints(t, jp, joints, actuated)
