"""A mechanism's topology for the ``view`` page: bodies, joints, actuated and cut joints, loops."""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass

from ..errors import ParameterError

__all__ = ["Topology", "topology_from_model", "fundamental_loops", "layered_layout"]


@dataclass(frozen=True)
class Topology:
    """``joints``: ``(name, type, body_a, body_b)``; ``ground`` the fixed body; ``actuated`` the
    driven joints; ``cuts`` the joints that, opened, leave a spanning tree (one per loop)."""

    joints: tuple[tuple[str, str, str, str], ...]
    ground: str = "ground"
    actuated: tuple[str, ...] = ()
    cuts: tuple[str, ...] = ()

    @property
    def bodies(self) -> tuple[str, ...]:
        """Every body, ground first, then in order of first appearance."""
        seen = {self.ground: None}
        for _, _, a, b in self.joints:
            seen.setdefault(a, None)
            seen.setdefault(b, None)
        return tuple(seen)


def topology_from_model(doc: dict, ground: str = "ground") -> Topology:
    """The topology of a ``model.json`` document: ``joints`` with ``name``, ``type`` (a letter
    R, P, C, U, S, or the joint's ``letter`` key), ``body_a``, ``body_b``, and optional
    ``actuated`` / ``cut`` flags."""
    try:
        joints = tuple((j["name"], str(j.get("letter", j["type"])), j["body_a"], j["body_b"]) for j in doc["joints"])
    except (KeyError, TypeError) as exc:
        raise ParameterError(f"model: a joint lacks {exc} (expected name, type, body_a, body_b)") from None
    actuated = tuple(j["name"] for j in doc["joints"] if j.get("actuated"))
    cuts = tuple(j["name"] for j in doc["joints"] if j.get("cut"))
    return Topology(joints, ground, actuated, cuts)


def _tree_paths(bodies: Sequence[str], edges: Sequence[tuple[str, str, str]], root: str) -> dict[str, list[str]]:
    """Joint path from ``root`` to each body over the tree ``edges (joint, a, b)``."""
    adj: dict[str, list[tuple[str, str]]] = {b: [] for b in bodies}
    for name, a, b in edges:
        adj[a].append((name, b))
        adj[b].append((name, a))
    path = {root: []}
    queue = deque([root])
    while queue:
        u = queue.popleft()
        for name, v in adj[u]:
            if v not in path:
                path[v] = path[u] + [name]
                queue.append(v)
    return path


def fundamental_loops(top: Topology) -> list[list[str]]:
    """The loop each cut joint closes: the cut joint, then the tree path from its second body back
    to its first (the joints in the order of a walk round the loop).

    Without ``cuts`` the chords of a breadth-first spanning tree from ground are used. Raises
    :class:`~pkmdyn.errors.ParameterError` when the joints without the cuts are not a tree
    spanning every body.
    """
    bodies = top.bodies
    cuts = list(top.cuts)
    if not cuts:
        reached = {top.ground}
        queue = deque([top.ground])
        tree: set[str] = set()
        while queue:
            u = queue.popleft()
            for name, _, a, b in top.joints:
                if u in (a, b):
                    v = b if u == a else a
                    if v not in reached:
                        reached.add(v)
                        tree.add(name)
                        queue.append(v)
        cuts = [j[0] for j in top.joints if j[0] not in tree]
    edges = [(n, a, b) for n, _, a, b in top.joints if n not in cuts]
    path = _tree_paths(bodies, edges, top.ground)
    if len(path) != len(bodies) or len(edges) != len(bodies) - 1:
        raise ParameterError("topology: the joints without the cut joints are not a spanning tree of the bodies")
    by_name = {j[0]: j for j in top.joints}
    loops = []
    for c in cuts:
        _, _, a, b = by_name[c]
        pa, pb = path[a], path[b]
        k = 0
        while k < min(len(pa), len(pb)) and pa[k] == pb[k]:
            k += 1
        loops.append([c, *reversed(pb[k:]), *pa[k:]])  # a walk: cut a -> b, then b back round to a
    return loops


def layered_layout(top: Topology) -> dict[str, tuple[float, float]]:
    """Node positions for a topology graph: ground on top, each body one row below its nearest
    neighbour towards ground (breadth-first depth); within a row, bodies ordered by the mean
    position of their neighbours in the row above, spread evenly over ``[0, 1]``."""
    adj: dict[str, set[str]] = {b: set() for b in top.bodies}
    for _, _, a, b in top.joints:
        adj[a].add(b)
        adj[b].add(a)
    depth = {top.ground: 0}
    queue = deque([top.ground])
    while queue:
        u = queue.popleft()
        for v in sorted(adj[u], key=top.bodies.index):
            if v not in depth:
                depth[v] = depth[u] + 1
                queue.append(v)
    for b in top.bodies:  # a body not connected to ground: its own row at the bottom
        depth.setdefault(b, max(depth.values()) + 1)
    rows: dict[int, list[str]] = {}
    for b in top.bodies:
        rows.setdefault(depth[b], []).append(b)
    pos: dict[str, tuple[float, float]] = {}
    for d in sorted(rows):
        members = rows[d]
        if d > 0:
            def key(b: str) -> float:
                up = [pos[v][0] for v in adj[b] if v in pos]
                return sum(up) / len(up) if up else 0.5
            members = sorted(members, key=key)
        for k, b in enumerate(members):
            pos[b] = ((k + 0.5) / len(members), -float(d))
    if len(pos) != len(top.bodies):  # pragma: no cover - every body has a depth
        raise ParameterError("topology: a body has no position")
    return pos
