"""Explicit leg closure: the legs of a parallel mechanism whose joint coordinates follow in
closed form from the pose of the body they meet.

A parallel robot's leg is solved by its own inverse kinematics once the platform is placed
(ParRob's leg-wise inverse kinematics; Merlet, *Parallel Robots*, 2006, ch. 4). The
kinematics solver (:mod:`pkmdyn.multibody.kinematics.inverse`) orders the Newton system block lower-triangular
(:func:`~pkmdyn.multibody.model.topology.block_structure`): for a Stewart platform, the task rows with the leg that
carries the platform, then each other leg's closure rows with that leg's coordinates. This
module recognises, from the compiled model's topology and geometry alone, the diagonal blocks
that are such a leg and can be solved in closed form, and records each as a row of a table
(:class:`LegTable`) that the kernels read (:func:`pkmdyn.multibody.model._tree_kernels._explicit_leg`).

A block is an **explicit leg** when

* its rows are the translation rows of one cut joint (a spherical joint, or a revolute joint
  whose rotation rows are not among the solved rows: a planar mechanism) and it has no task
  or idle row;
* its coordinates are those of a serial chain of whole tree joints, from a base body (the
  ground or a body placed by earlier blocks) to the body that carries the cut joint's point
  ``e`` on the leg's side, but for coordinates that an idle row of their own holds at their
  reference values (an S-S rod's spin about the rod where the first ball's frame has an axis
  along it; :func:`pkmdyn.multibody.model.topology.sparse_basis`): an R-S-S leg is then A2 with the spin held;
  the cut joint's other body (the one the leg meets, holding the point ``c``) is placed by
  earlier blocks (or by an explicit leg solved before this one);
* the chain, written as the product of exponentials about the reference configuration
  (``e(th) = exp(xi_1 th_1) ... exp(xi_k th_k) e0``, ``th = q - q_ref``; Murray, Li &
  Sastry 1994, ch. 3) has one of four patterns, each solved by the subproblems of Paden and
  Kahan (ibid., ch. 3):

  ====  ===================================  ====================================  ==============
  code  chain (base to end)                  closed form                           leg types
  ====  ===================================  ====================================  ==============
  A1    turn or slide, then a turn           distance to the turn's axis point     R-R-R, P-R-R
        (planar: a turn parallel, a slide    (subproblem 3 or a quadratic), then   planar, P-R-S
        normal to the second turn)           subproblem 1                          planar
  A2    turn or slide, then two turns about  subproblem 3 or a quadratic for the   R-U-S, P-U-S
        one point ``m0`` (a universal        first joint, subproblem 2 for the     (3-PUS
        joint, or a ball with its spin held) two turns                             legs),
                                                                                   R-S-S, P-S-S
  B1    a turn, then a slide normal to it    quadratic in the plane, then          R-P-R planar
                                             subproblem 1
  B2    two turns about one point ``m0``,    quadratic ``|e0 + s a - m0| = |c -    U-P-S
        then a slide                         m0|``, then subproblem 2
  ====  ===================================  ====================================  ==============

Each has two assembly branches (the sign of a square root); the kernels take the one nearest
the coordinates they start from (the previous sample's solution, or the reference
configuration for the first), so a leg stays on the branch it starts on (an elbow-up leg
stays elbow-up), as Newton from the same start does. Where the point is out of the leg's
reach, the leg's coordinates are left to Newton, which reports the sample.

The leg that carries the task body (the block of the task rows) is explicit where the task
fixes that body's pose (three Euler angles, and three positions unless the body sits on a
spherical joint on the ground): its chain ends with a spherical joint into the task body
(pattern T), placed by one of the four patterns above (T+A1 ... T+B2) or fixed to the ground;
the ball's angles are Euler angles of the relative rotation (:func:`pkmdyn.multibody.model._tree_kernels._task_leg`).

The explicit legs set their coordinates at each evaluation of the positions; Newton then
solves the remaining blocks (coupled sub-chains such as a Delta robot's parallelograms or the
a second platform of a 3-PUS pair, a Bennett linkage) and checks every row, the explicit legs' included,
so the two routes give the same solution to the solver's tolerance (:func:`newton_only`
builds a model without explicit legs; the tests compare the two). Where every block is an
explicit leg, the first evaluation is exact and Newton's simplified step is left out.
Recognition is documented in ``docs/mechanism_format.md`` and printed by ``pkmdyn describe``.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray

from ...spatial import cross
from ..model._tree_kernels import forward_positions, place_legs
from .poses import body_poses, positions_args

__all__ = ["LegTable", "explicit_legs", "newton_only", "place", "held_coordinates", "LEG_PATTERNS"]

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: pattern code -> name (:mod:`pkmdyn.multibody.model._tree_kernels`: LEG_A1, LEG_A2, LEG_B1, LEG_B2)
LEG_PATTERNS = {1: "A1 (first joint, then one turn; planar)", 2: "A2 (first joint, then a universal joint)",
                3: "B1 (turn, then a slide; planar)", 4: "B2 (universal joint, then a slide)",
                10: "T (the task body on a ball joint)"}
LEG_PATTERNS.update({10 + k: f"T+{v.split(' ')[0]} (the task body on a ball joint placed by {v.split(' ', 1)[1][1:-1]})"
                     for k, v in list(LEG_PATTERNS.items()) if k < 10})


def held_coordinates(model) -> set[int]:
    """The tree coordinates held at their reference values by an idle row of their own (a rod's
    spin about its axis, where a ball's frame has an axis along the rod:
    :func:`pkmdyn.multibody.model.topology.sparse_basis`)."""
    return {int(np.flatnonzero(r)[0]) for r in np.asarray(model.solver_idle) if np.count_nonzero(r) == 1}


def _empty_int(*shape: int) -> IntArray:
    return np.zeros(shape, dtype=np.int64)


@dataclass(frozen=True)
class LegTable:
    """The explicit legs of a model (module docstring), as the kernels read them.

    ``late (nb,)``: the leg whose chain moves body b (its chain's bodies and their
    descendants, placed after the leg is solved), else -1; per leg L (nL of them):
    ``kind`` the pattern code; ``coord (nL, 3)`` its tree coordinates from the base (unused
    entries 0); ``base`` the body the chain starts from and ``placed`` the body it meets (-1:
    the ground); ``cpt (nL, 3)`` the cut joint's point on ``placed``, in that body's frame
    [m]; in the base body's frame at the reference configuration: ``axis (nL, 3, 3)`` each
    coordinate's unit direction (sign included), ``point (nL, 3, 3)`` a point on each turning
    axis [m] (NaN for a slide), ``m0`` the point the ball turns about [m], ``e0`` the cut
    joint's point on the leg [m]; ``q0 (nL, 3)`` the coordinates' reference values;
    ``redo (nL, 1 + max)`` the count and the bodies the leg moves, in tree order. The leg that
    carries the task body (``kind >= 10``): ``ball (nL, 4)`` its spherical joint and that
    joint's three coordinates (-1 for another leg), ``ball_axes`` their turning axes (0-2 of
    the joint frame), ``ball_offset``, ``ball_sign`` their reference values and signs,
    ``R_end0 (nL, 3, 3)`` the reference rotation of the body before the ball.
    ``fixed (nL,)``: 1 for a leg placed from the task coordinates alone (it starts from and
    meets the ground or bodies that only such legs move: the task leg, a Stewart platform's or
    a 3-PUS platform's legs), whose closed form the solver evaluates once per sample, and
    ``fixed_coord (nq,)``: 1 for the coordinates such legs set (both empty without legs).
    ``names``: per leg, its cut joint's name, the chain's joint names and the pattern."""

    late: IntArray
    kind: IntArray = field(default_factory=lambda: _empty_int(0))
    coord: IntArray = field(default_factory=lambda: _empty_int(0, 3))
    base: IntArray = field(default_factory=lambda: _empty_int(0))
    placed: IntArray = field(default_factory=lambda: _empty_int(0))
    cpt: Array = field(default_factory=lambda: np.zeros((0, 3)))
    axis: Array = field(default_factory=lambda: np.zeros((0, 3, 3)))
    point: Array = field(default_factory=lambda: np.zeros((0, 3, 3)))
    m0: Array = field(default_factory=lambda: np.zeros((0, 3)))
    e0: Array = field(default_factory=lambda: np.zeros((0, 3)))
    q0: Array = field(default_factory=lambda: np.zeros((0, 3)))
    redo: IntArray = field(default_factory=lambda: _empty_int(0, 1))
    ball: IntArray = field(default_factory=lambda: _empty_int(0, 4))
    ball_axes: IntArray = field(default_factory=lambda: _empty_int(0, 3))
    ball_offset: Array = field(default_factory=lambda: np.zeros((0, 3)))
    ball_sign: Array = field(default_factory=lambda: np.zeros((0, 3)))
    R_end0: Array = field(default_factory=lambda: np.zeros((0, 3, 3)))
    fixed: IntArray = field(default_factory=lambda: _empty_int(0))
    fixed_coord: IntArray = field(default_factory=lambda: _empty_int(0))
    names: tuple[tuple[str, tuple[str, ...], int], ...] = ()

    @property
    def count(self) -> int:
        return int(self.kind.shape[0])

    def arrays(self) -> tuple:
        """The tuple the kernels take (:func:`pkmdyn.multibody.model._tree_kernels.forward_positions`)."""
        return (self.late, self.kind, self.coord, self.base, self.placed, self.cpt, self.axis, self.point,
                self.m0, self.e0, self.q0, self.redo, self.ball, self.ball_axes, self.ball_offset, self.ball_sign,
                self.R_end0, self.fixed, self.fixed_coord)


def no_legs(nb: int) -> LegTable:
    """A table without explicit legs (every block by Newton)."""
    return LegTable(late=np.full(nb, -1, dtype=np.int64))


def newton_only(model):
    """``model`` with every block solved by Newton (no explicit legs): the second route the
    tests compare the explicit legs with."""
    return replace(model, legs=no_legs(model.nb))


def place(model, q: Array, x: Array) -> Array:
    """Tree coordinates ``q (nq,)`` with every explicit leg's set in closed form for the task
    coordinates ``x (nt,)`` (one pass of the positions, as the solver makes it before each of its
    evaluations; the other coordinates as given). A leg out of reach keeps its coordinates."""
    q = np.array(q, dtype=float)
    args = positions_args(model, np.empty((model.nb, 3, 3)), np.empty((model.nb, 3)), np.empty((model.nq, 6)))
    forward_positions(q, *args, model.legs.late, True)
    task = (int(model.task_body), model.task_point, model.task_kind, model.task_index, model.euler_axes)
    place_legs(q, *args, model.legs.arrays(), np.ascontiguousarray(x, dtype=float), task, False)
    return q


def _unit(v: Array) -> Array:
    return v / np.linalg.norm(v)


def _intersection(p1: Array, w1: Array, p2: Array, w2: Array, tol: float) -> Array | None:
    """The common point of two non-parallel lines ``p_i + t w_i`` (unit ``w_i``), or None when
    they are parallel or pass more than ``tol`` apart."""
    n = cross(w1, w2)
    nn = float(n @ n)
    if nn < 1e-12:
        return None
    d = p2 - p1
    if abs(float(d @ n)) / np.sqrt(nn) > tol:
        return None
    t1 = float(cross(d, w2) @ n) / nn
    t2 = float(cross(d, w1) @ n) / nn
    return 0.5 * (p1 + t1 * w1 + p2 + t2 * w2)


def _foot(p: Array, w: Array, x: Array) -> Array:
    """The foot of ``x`` on the line ``p + t w`` (unit ``w``)."""
    return p + float((x - p) @ w) * w


def explicit_legs(model) -> LegTable:
    """Recognise the explicit legs of ``model`` (module docstring) at its reference
    configuration; a table without legs where none is found."""
    nb, nr = model.nb, model.row_loop.shape[0]
    blocks, prow, pcol, rows = model.solver_blocks, model.solver_prow, model.solver_pcol, model.solver_rows
    m = rows.shape[0]
    if blocks.shape[0] < 2 or model.nq == 0:
        return no_legs(nb)
    R, p, S = body_poses(model, model.coord_offset)
    tol = 1e-9 * max(model.length_scale, 1e-300)
    coord_body = np.full(model.nq, -1, dtype=np.int64)  # the body each coordinate's joint carries
    for b in range(nb):
        k = model.body_joint[b]
        coord_body[model.joint_q0[k]:model.joint_q0[k] + model.joint_nq[k]] = b
    held = held_coordinates(model)  # a leg's chain may hold such a coordinate
    found: list[dict] = []
    for bk in range(blocks.shape[0] - 1):
        r_idx = prow[blocks[bk]:blocks[bk + 1]]
        cols = np.sort(pcol[blocks[bk]:blocks[bk + 1]])
        if np.any(r_idx >= m):
            continue
        rr = rows[r_idx]
        if np.all(rr >= nr):  # the task rows: the leg that carries the task body
            leg = _task_chain(model, cols, coord_body, R, p, S, tol, held)
        elif np.any(rr >= nr) or cols.size not in (2, 3):
            continue
        else:
            loops = set(int(model.row_loop[i]) for i in rr)
            if len(loops) != 1 or np.any(model.row_kind[rr] != 0):
                continue
            leg = _chain(model, cols, coord_body, int(model.loop_joint[loops.pop()]), R, p, S, tol, held)
        if leg is not None:
            found.append(leg)
    # each leg's bodies: its chain's and their descendants', placed once the leg is solved (in
    # block order); a leg whose bodies meet another leg's, or carry a body that an earlier leg
    # starts from or meets, or that starts from or meets a body a later leg moves, is left to
    # Newton
    moved = [[b for b in range(nb) if _descends(model.body_parent, b, leg["first"])] for leg in found]
    keep: list[int] = []
    for i in range(len(found)):
        others = set().union(*(moved[j] for j in range(len(found)) if j != i), ())
        ends = {found[j][key] for j in range(i + 1) for key in ("base", "placed")}
        earlier = set().union(*(moved[j] for j in keep), ())
        needs = {found[i][key] for key in ("base", "placed")} - {-1}
        if not (set(moved[i]) & others) and not (set(moved[i]) & ends) and \
                all(b in earlier or not _moved_by_any(b, moved) for b in needs):
            keep.append(i)
    found, moved = [found[i] for i in keep], [moved[i] for i in keep]
    if not found:
        return no_legs(nb)
    late = np.full(nb, -1, dtype=np.int64)
    redo = np.zeros((len(found), 1 + max(len(mv) for mv in moved)), dtype=np.int64)
    for i, mv in enumerate(moved):
        late[mv] = i
        redo[i, 0] = len(mv)
        redo[i, 1:1 + len(mv)] = mv
    fixed, fixed_coord = _fixed(model, found, held)
    pad = lambda c: list(c) + [0] * (3 - len(c))  # noqa: E731
    nan3 = np.full((3, 3), np.nan)
    return LegTable(
        fixed=fixed, fixed_coord=fixed_coord,
        late=late, redo=redo,
        kind=np.array([g["kind"] for g in found], dtype=np.int64),
        coord=np.array([pad(g["coords"]) for g in found], dtype=np.int64),
        base=np.array([g["base"] for g in found], dtype=np.int64),
        placed=np.array([g["placed"] for g in found], dtype=np.int64),
        cpt=np.array([g.get("cpt", np.zeros(3)) for g in found]),
        axis=np.array([g.get("axis", np.zeros((3, 3))) for g in found]),
        point=np.array([g.get("point", nan3) for g in found]),
        m0=np.array([g["m0"] if g.get("m0") is not None else np.zeros(3) for g in found]),
        e0=np.array([g.get("e0", np.zeros(3)) for g in found]),
        q0=np.array([pad(model.coord_offset[g["coords"]]) for g in found], dtype=float),
        ball=np.array([g.get("ball", [-1, 0, 0, 0]) for g in found], dtype=np.int64),
        ball_axes=np.array([g.get("ball_axes", [0, 1, 2]) for g in found], dtype=np.int64),
        ball_offset=np.array([g.get("ball_offset", np.zeros(3)) for g in found], dtype=float),
        ball_sign=np.array([g.get("ball_sign", np.ones(3)) for g in found], dtype=float),
        R_end0=np.array([g.get("R_end0", np.eye(3)) for g in found], dtype=float),
        names=tuple((g["cut"], g["joints"], g["kind"]) for g in found),
    )


def _leg_coords(leg: dict) -> list[int]:
    """The coordinates a leg's closed form sets: its chain's, and the ball's of the task leg."""
    return [int(c) for c in leg["coords"]] + [int(c) for c in leg.get("ball", [-1])[1:]]


def _fixed(model, found: list[dict], held: set[int] = frozenset()) -> tuple[IntArray, IntArray]:
    """Which legs are placed from the task coordinates alone (:class:`LegTable`'s ``fixed``) and
    the coordinates they set: in block order, a leg whose base and met bodies are the ground or
    bodies whose every tree coordinate from the ground is set by such a leg (or ``held`` at
    its reference value)."""
    fixed = np.zeros(len(found), dtype=np.int64)
    fixed_coord = np.zeros(model.nq, dtype=np.int64)

    def placed_by_fixed(b: int) -> bool:
        while b >= 0:
            k = model.body_joint[b]
            coords = range(model.joint_q0[k], model.joint_q0[k] + model.joint_nq[k])
            if not all(fixed_coord[c] or c in held for c in coords):
                return False
            b = int(model.body_parent[b])
        return True

    for i, leg in enumerate(found):
        if placed_by_fixed(int(leg["base"])) and placed_by_fixed(int(leg["placed"])):
            fixed[i] = 1
            fixed_coord[_leg_coords(leg)] = 1
    return fixed, fixed_coord


def _moved_by_any(b: int, moved: list[list[int]]) -> bool:
    return any(b in mv for mv in moved)


def _geometry(model, cols: IntArray, R: Array, p: Array, S: Array, base: int, e_world: Array,
              tol: float) -> dict | None:
    """The reference geometry of the chain with coordinates ``cols`` from body ``base`` whose end
    point is ``e_world`` (the base body's frame): its unit axes, a point on each turning axis, and
    its pattern (module docstring) with the ball's point ``m0``; None where no pattern fits."""
    Rb = np.eye(3) if base < 0 else R[base]
    pb = np.zeros(3) if base < 0 else p[base]
    e0 = Rb.T @ (e_world - pb)
    turns = [bool(model.coord_motion[c] < 3) for c in cols]
    axis, point = np.zeros((3, 3)), np.full((3, 3), np.nan)
    for i, c in enumerate(cols):
        w, v = S[c, :3], S[c, 3:]
        if turns[i]:
            axis[i] = _unit(Rb.T @ w)
            r_world = cross(w, v) / float(w @ w)  # the point of the axis nearest the origin
            point[i] = Rb.T @ (r_world - pb)
        else:
            axis[i] = _unit(Rb.T @ v)
    n = len(cols)
    kind, m0 = 0, None
    if n == 2 and turns[1]:  # A1: planar, the first joint in the plane of the turn
        if (turns[0] and np.linalg.norm(cross(axis[0], axis[1])) < 1e-9) or \
                (not turns[0] and abs(float(axis[0] @ axis[1])) < 1e-9):
            kind, m0 = 1, _foot(point[1], axis[1], e0)
    elif n == 2 and turns[0] and not turns[1]:  # B1: a turn, then a slide normal to it
        if abs(float(axis[0] @ axis[1])) < 1e-9:
            kind, m0 = 3, _foot(point[0], axis[0], e0)
    elif n == 3 and turns[1] and turns[2]:  # A2: a first joint, then two turns about one point
        m0 = _intersection(point[1], axis[1], point[2], axis[2], tol)
        if m0 is not None and _ball_ok(e0 - m0, axis[1], axis[2]):
            kind = 2
            if turns[0] and np.linalg.norm(cross(axis[0], m0 - point[0])) < tol:
                kind = 0  # the ball's centre on the first axis: its distance to c does not change
    elif n == 3 and turns[0] and turns[1] and not turns[2]:  # B2: two turns about one point, a slide
        m0 = _intersection(point[0], axis[0], point[1], axis[1], tol)
        if m0 is not None and _ball_ok(e0 - m0, axis[0], axis[1]):
            kind = 4
    if kind == 0:
        return None
    return {"kind": kind, "axis": axis, "point": point, "m0": m0, "e0": e0}


def _path(model, cols: IntArray, coord_body: IntArray, held: set[int] = frozenset()) -> list[int] | None:
    """The bodies of a chain of whole tree joints with coordinates ``cols``, base first, or None;
    a joint's coordinates in ``held`` (held at their reference values by idle rows of their
    own) need not be among ``cols``."""
    bodies: list[int] = []
    for c in cols:
        b = int(coord_body[c])
        if not bodies or bodies[-1] != b:
            bodies.append(b)
    have = set(int(c) for c in cols)
    for b in bodies:
        j = model.body_joint[b]
        if not set(range(model.joint_q0[j], model.joint_q0[j] + model.joint_nq[j])) <= have | held:
            return None
    for a, b in zip(bodies, bodies[1:]):
        if model.body_parent[b] != a:
            return None
    return bodies


def _chain(model, cols: IntArray, coord_body: IntArray, k: int, R: Array, p: Array, S: Array,
           tol: float, held: set[int] = frozenset()) -> dict | None:
    """The explicit leg of the block with coordinates ``cols`` closed by cut joint ``k``, or
    None (module docstring)."""
    bodies = _path(model, cols, coord_body, held)
    if bodies is None:
        return None
    end, first = bodies[-1], bodies[0]
    base = int(model.body_parent[first])
    pa, ch = int(model.joint_parent[k]), int(model.joint_child[k])
    if end == ch:
        placed, e_loc, c_loc = pa, model.joint_p_child[k], model.joint_p_parent[k]
    elif end == pa:
        placed, e_loc, c_loc = ch, model.joint_p_parent[k], model.joint_p_child[k]
    else:
        return None
    if placed >= 0 and np.any(model.ancestors[placed][cols]):
        return None
    geo = _geometry(model, cols, R, p, S, base, p[end] + R[end] @ e_loc, tol)
    if geo is None:
        return None
    joints = tuple(model.joint_names[model.body_joint[b]] for b in bodies)
    return {**geo, "coords": [int(c) for c in cols], "base": base, "placed": placed, "first": first,
            "cpt": np.asarray(c_loc, dtype=float), "cut": model.joint_names[k], "joints": joints}


def _task_chain(model, cols: IntArray, coord_body: IntArray, R: Array, p: Array, S: Array,
                tol: float, held: set[int] = frozenset()) -> dict | None:
    """The leg that carries the task body (the block of the task rows), or None: the task gives
    the body's three Euler angles and, where the chain places its ball, its position too; the
    chain ends with a spherical joint (three turns about its centre) into the task body, from
    the ground or from a chain of one of the patterns that reaches the ball's centre."""
    tb = int(model.task_body)
    n_ang = int(np.sum(model.task_kind == 1))
    n_pos = int(np.sum(model.task_kind == 0))
    bodies = _path(model, cols, coord_body, held)
    if bodies is None or bodies[-1] != tb or n_ang != 3 or n_pos not in (0, 3) or cols.size != model.nt:
        return None
    if int(model.body_parent[bodies[0]]) >= 0:
        return None  # block 0 starts from the ground
    k = int(model.body_joint[tb])
    bc = list(range(model.joint_q0[k], model.joint_q0[k] + model.joint_nq[k]))
    motions = [int(model.coord_motion[c]) for c in bc]
    if not set(bc) <= set(int(c) for c in cols):
        return None  # (a ball coordinate held by an idle row: the task cannot set it)
    if len(bc) != 3 or any(mo >= 3 for mo in motions) or motions[0] == motions[1] or motions[1] == motions[2]:
        return None
    front = [int(c) for c in cols if c not in bc]
    ball = {"ball": [k, *bc], "ball_axes": motions, "ball_offset": model.coord_offset[bc],
            "ball_sign": model.coord_sign[bc], "coords": front or [0], "base": -1, "placed": -1,
            "cut": "the task body", "joints": tuple(model.joint_names[model.body_joint[b]] for b in bodies)}
    if n_pos == 0:
        if front:
            return None
        return {**ball, "kind": 10, "first": tb, "coords": []}
    if len(front) not in (2, 3) or len(bodies) < 2:
        return None
    end = bodies[-2]
    geo = _geometry(model, np.array(front), R, p, S, -1, p[end] + R[end] @ model.tree_p_parent[k], tol)
    if geo is None:
        return None
    return {**ball, **geo, "kind": 10 + geo["kind"], "first": bodies[0], "coords": front, "R_end0": R[end]}


def _descends(parent: IntArray, b: int, a: int) -> bool:
    """Whether body ``b`` is ``a`` or one of its descendants."""
    while b >= 0:
        if b == a:
            return True
        b = int(parent[b])
    return False


def _ball_ok(u: Array, w1: Array, w2: Array) -> bool:
    """Whether the point ``m0 + u`` is off both axes of a ball (subproblem 2 then has a unique
    angle for each axis)."""
    nu = float(np.linalg.norm(u))
    return nu > 0 and np.linalg.norm(cross(u, w1)) > 1e-6 * nu and np.linalg.norm(cross(u, w2)) > 1e-6 * nu
