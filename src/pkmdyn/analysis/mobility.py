"""Mobility and over-constraint analysis of any mechanism given as a joint list.

Two independent answers:

* the count of Eq. 1 of the PDM paper, ``t = 3S + 4U + 5R + 5P + A - 6n`` (``A`` the degrees
  of freedom, ``n`` the moving links), i.e. the constraints the joints impose plus the
  mobility minus the 6 n that the moving links can lose -- :func:`overconstraint_count`;
* screw theory at a configuration (section 5.2, Eq. 70): every joint contributes its unit
  twists; a body-twist formulation ``V_b - V_a = sum_k q_dot_k $_k`` for every joint gives
  the mobility ``M = 6 n + f - rank`` (idle freedoms included) and the over-constraints
  ``t = 6 J - rank`` (the redundant equations) without choosing loops -- :func:`analyse`.
  For each loop of a short cycle basis the wrenches reciprocal to the loop's twists (zero
  power ``f . v + m . omega`` against every joint twist) are its over-constrained directions:
  for a planar loop in the x-y plane, a force along z and couples about x and y (Eq. 70).

Screw conventions: twists ``(omega; v)`` and wrenches ``(f; m)`` as (6,) arrays in the base
frame, moments and velocities taken at the base origin.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..errors import ParameterError

__all__ = [
    "FREEDOMS",
    "Joint",
    "LoopConstraints",
    "MobilityReport",
    "joint_counts",
    "overconstraint_count",
    "kutzbach_mobility",
    "joint_twists",
    "reciprocal_wrenches",
    "cycle_basis",
    "analyse",
]

Array = NDArray[np.float64]

#: Freedoms of each joint type; a joint of type k removes ``6 - FREEDOMS[k]`` freedoms.
FREEDOMS: dict[str, int] = {"R": 1, "P": 1, "C": 2, "U": 2, "S": 3}
_AXES_NEEDED = {"R": 1, "P": 1, "C": 1, "U": 2, "S": 0}
WRENCH_NAMES = ("force_x", "force_y", "force_z", "couple_x", "couple_y", "couple_z")


@dataclass(frozen=True)
class Joint:
    """One joint between ``body_a`` and ``body_b``: ``kind`` in ``FREEDOMS``; ``point`` (3,)
    [m] its centre (on its axis); ``axes``: unit axes in the base frame -- one for R, P, C,
    two for U (first, second), none for S."""

    name: str
    kind: str
    body_a: str
    body_b: str
    point: tuple[float, float, float] = (0.0, 0.0, 0.0)
    axes: tuple[tuple[float, float, float], ...] = ()

    def __post_init__(self) -> None:
        if self.kind not in FREEDOMS:
            raise ParameterError(f"joint {self.name}: unknown kind {self.kind!r} (known: {', '.join(FREEDOMS)})")
        if len(self.axes) != _AXES_NEEDED[self.kind]:
            raise ParameterError(f"joint {self.name}: a {self.kind} joint needs {_AXES_NEEDED[self.kind]} axes")
        if self.body_a == self.body_b:
            raise ParameterError(f"joint {self.name}: joins body {self.body_a!r} to itself")


def joint_counts(joints: Iterable[Joint]) -> dict[str, int]:
    """Number of joints of each kind, e.g. ``{"S": 2, "U": 2, "R": 11, "P": 4}``."""
    counts: dict[str, int] = {}
    for j in joints:
        counts[j.kind] = counts.get(j.kind, 0) + 1
    return counts


def overconstraint_count(counts: Mapping[str, int], moving_links: int, dof: int) -> int:
    """Eq. 1: ``t = sum_k (6 - f_k) N_k + A - 6 n`` (= 3S + 4U + 5R + 5P + A - 6n)."""
    unknown = set(counts) - set(FREEDOMS)
    if unknown:
        raise ParameterError(f"unknown joint kind {sorted(unknown)[0]!r}")
    return sum((6 - FREEDOMS[k]) * int(c) for k, c in counts.items()) + int(dof) - 6 * int(moving_links)


def kutzbach_mobility(counts: Mapping[str, int], moving_links: int) -> int:
    """Chebychev-Gruebler-Kutzbach count ``6 n - sum_k (6 - f_k) N_k`` (blind to over-constraints)."""
    return overconstraint_count(counts, moving_links, 0) * -1


def _unit(v: Sequence[float], name: str) -> Array:
    a = np.asarray(v, dtype=float)
    norm = float(np.linalg.norm(a))
    if a.shape != (3,) or norm < 1e-12:
        raise ParameterError(f"joint {name}: an axis must be a non-zero 3-vector")
    return a / norm


def joint_twists(joint: Joint) -> Array:
    """Unit twists ``(omega; v)`` (f, 6) of ``body_b`` relative to ``body_a`` at the origin.

    Revolute about unit ``s`` through ``r``: ``(s; r x s)``; prismatic along ``s``: ``(0; s)``;
    C = R + P on one axis; U = two revolutes through its centre; S = three revolutes.
    """
    r = np.asarray(joint.point, dtype=float)
    axes = [_unit(a, joint.name) for a in joint.axes]
    if joint.kind == "S":
        axes = list(np.eye(3))
    rows = []
    if joint.kind in ("R", "C", "U", "S"):
        rows += [np.concatenate([s, np.cross(r, s)]) for s in axes]
    if joint.kind in ("P", "C"):
        rows.append(np.concatenate([np.zeros(3), axes[0]]))
    return np.array(rows)


def _rref(a: Array, tol: float) -> Array:
    a = a.copy()
    rows, cols = a.shape
    r = 0
    for c in range(cols):
        if r == rows:
            break
        p = r + int(np.argmax(np.abs(a[r:, c])))
        if abs(a[p, c]) <= tol:
            continue
        a[[r, p]] = a[[p, r]]
        a[r] /= a[r, c]
        for k in range(rows):
            if k != r:
                a[k] -= a[k, c] * a[r]
        r += 1
    a[np.abs(a) < tol] = 0.0
    return a[:r]


def reciprocal_wrenches(twists: Array, tol: float = 1e-9) -> Array:
    """Basis (k, 6) of the wrenches ``(f; m)`` reciprocal to every twist row ``(omega; v)``.

    Solves ``f . v + m . omega = 0`` for all rows (the constraint screws of section 5.2); the
    basis is returned in reduced row-echelon form so that axis-aligned constraints read as
    unit rows, e.g. ``[0 0 1 0 0 0]``, ``[0 0 0 1 0 0]``, ``[0 0 0 0 1 0]`` for a planar chain
    in the x-y plane (Eq. 70).
    """
    twists = np.atleast_2d(np.asarray(twists, dtype=float))
    swapped = np.concatenate([twists[:, 3:], twists[:, :3]], axis=1)
    _, sv, vh = np.linalg.svd(swapped)
    rank = int(np.sum(sv > tol * max(1.0, sv.max(initial=0.0))))
    basis = vh[rank:]
    return _rref(basis, 1e-9) if basis.size else np.zeros((0, 6))


def describe_wrench(w: Array) -> str:
    """``"force_z"`` for a unit row along one axis, otherwise the row itself as text."""
    nz = np.flatnonzero(np.abs(w) > 1e-9)
    if nz.size == 1 and abs(abs(w[nz[0]]) - 1.0) < 1e-9:
        return WRENCH_NAMES[int(nz[0])]
    return "wrench(" + ", ".join(f"{x:.6g}" for x in w) + ")"


def cycle_basis(joints: Sequence[Joint]) -> list[list[int]]:
    """A short cycle basis of the joint graph (bodies = vertices, joints = edges).

    Horton's construction: for every body v and joint (x, y) the candidate cycle
    ``path(v, x) + (x, y) + path(y, v)`` along shortest paths; candidates sorted by length are
    kept while independent over GF(2). Returns the cycles as lists of joint indices in
    traversal order.
    """
    bodies = sorted({b for j in joints for b in (j.body_a, j.body_b)})
    adj: dict[str, list[tuple[str, int]]] = {b: [] for b in bodies}
    for k, j in enumerate(joints):
        adj[j.body_a].append((j.body_b, k))
        adj[j.body_b].append((j.body_a, k))
    n_loops = len(joints) - len(bodies) + 1
    candidates: set[frozenset[int]] = set()
    for v in bodies:
        parent: dict[str, tuple[str, int] | None] = {v: None}
        queue = deque([v])
        while queue:
            x = queue.popleft()
            for y, k in adj[x]:
                if y not in parent:
                    parent[y] = (x, k)
                    queue.append(y)

        def path(x: str) -> list[int]:
            out = []
            while parent[x] is not None:
                x, k = parent[x]  # type: ignore[misc]
                out.append(k)
            return out

        for k, j in enumerate(joints):
            pa, pb = path(j.body_a), path(j.body_b)
            if k in pa or k in pb or set(pa) & set(pb):
                continue
            candidates.add(frozenset([*pa, *pb, k]))
    basis: list[frozenset[int]] = []
    reduced: dict[int, int] = {}  # pivot (highest) bit -> row of the GF(2) elimination
    for cyc in sorted(candidates, key=lambda c: (len(c), sorted(c))):
        vec = sum(1 << k for k in cyc)
        for pivot in sorted(reduced, reverse=True):
            if vec >> pivot & 1:
                vec ^= reduced[pivot]
        if vec:
            reduced[vec.bit_length() - 1] = vec
            basis.append(cyc)
        if len(basis) == n_loops:
            break
    return [_order(joints, sorted(c)) for c in basis]


def _order(joints: Sequence[Joint], cyc: list[int]) -> list[int]:
    left = list(cyc)
    first = left.pop(0)
    order, at = [first], joints[first].body_b
    while left:
        k = next(k for k in left if at in (joints[k].body_a, joints[k].body_b))
        left.remove(k)
        order.append(k)
        at = joints[k].body_b if joints[k].body_a == at else joints[k].body_a
    return order


@dataclass(frozen=True)
class LoopConstraints:
    """One independent loop: its joints in order, the rank of their twists, its
    over-constraints ``6 - rank`` and their directions (reciprocal wrench basis (k, 6))."""

    joints: tuple[str, ...]
    twist_rank: int
    overconstraints: int
    wrenches: Array
    directions: tuple[str, ...]


@dataclass(frozen=True)
class MobilityReport:
    """Result of :func:`analyse`. ``mobility`` includes idle freedoms; ``output_dof`` is the
    number of independent twists of ``output_body`` (None when none was named)."""

    joint_counts: dict[str, int]
    moving_links: int
    loops_count: int
    mobility: int
    output_dof: int | None
    overconstraints: int
    kutzbach: int
    eq1_overconstraints: int
    loops: tuple[LoopConstraints, ...] = field(default_factory=tuple)


def analyse(joints: Sequence[Joint], ground: str, output_body: str | None = None, tol: float = 1e-9) -> MobilityReport:
    """Mobility and over-constraints of a mechanism at the configuration its joints describe.

    Unknowns: the twist of every moving body (6 n) and every joint rate (f in all). Each of
    the J joints gives six equations ``V_b - V_a - sum_k q_dot_k $_k = 0`` (ground twist 0).
    With ``rho`` the rank of this 6J x (6n + f) system: mobility ``M = 6 n + f - rho`` and
    over-constraints ``t = 6 J - rho``; then Eq. 1 evaluated with ``A = M`` must give the
    same t. Raises :class:`~pkmdyn.errors.ParameterError` if the bodies are not connected.
    """
    bodies = sorted({b for j in joints for b in (j.body_a, j.body_b)})
    if ground not in bodies:
        raise ParameterError(f"ground body {ground!r} is not joined to anything")
    moving = [b for b in bodies if b != ground]
    col = {b: 6 * k for k, b in enumerate(moving)}
    twists = [joint_twists(j) for j in joints]
    f_total = sum(t.shape[0] for t in twists)
    A = np.zeros((6 * len(joints), 6 * len(moving) + f_total))
    c = 6 * len(moving)
    for k, (j, tw) in enumerate(zip(joints, twists)):
        rows = slice(6 * k, 6 * k + 6)
        if j.body_b != ground:
            A[rows, col[j.body_b]:col[j.body_b] + 6] += np.eye(6)
        if j.body_a != ground:
            A[rows, col[j.body_a]:col[j.body_a] + 6] -= np.eye(6)
        A[rows, c:c + tw.shape[0]] = -tw.T
        c += tw.shape[0]
    sv = np.linalg.svd(A, compute_uv=False)
    rank = int(np.sum(sv > tol * sv.max()))
    mobility = A.shape[1] - rank
    loops = cycle_basis(joints)
    if len(loops) != len(joints) - len(bodies) + 1:
        raise ParameterError("the joint graph is not connected")
    output_dof = None
    if output_body is not None:
        if output_body not in col:
            raise ParameterError(f"output body {output_body!r} is not a moving body")
        _, s, vh = np.linalg.svd(A)
        null = vh[rank:].T
        block = null[col[output_body]:col[output_body] + 6]
        output_dof = int(np.linalg.matrix_rank(block, tol=1e-7)) if block.size else 0
    loop_reports = []
    for loop in loops:
        tw = np.concatenate([twists[k] for k in loop])
        w = reciprocal_wrenches(tw, tol)
        loop_reports.append(LoopConstraints(
            joints=tuple(joints[k].name for k in loop),
            twist_rank=6 - w.shape[0],
            overconstraints=w.shape[0],
            wrenches=w,
            directions=tuple(describe_wrench(row) for row in w),
        ))
    counts = joint_counts(joints)
    return MobilityReport(
        joint_counts=counts,
        moving_links=len(moving),
        loops_count=len(loops),
        mobility=mobility,
        output_dof=output_dof,
        overconstraints=6 * len(joints) - rank,
        kutzbach=kutzbach_mobility(counts, len(moving)),
        eq1_overconstraints=overconstraint_count(counts, len(moving), mobility),
        loops=tuple(loop_reports),
    )
