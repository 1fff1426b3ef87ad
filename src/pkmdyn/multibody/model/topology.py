"""Topology and mobility of a compiled mechanism.

Two counts, as in :mod:`pkmdyn.analysis.mobility` but from the model's own loop records:

* the Grübler-Kutzbach count ``M_GK = 6 n - sum_j (6 - f_j)`` (n moving bodies, f_j the
  freedoms of joint j), blind to special geometry;
* the mobility by rank at an assembled configuration: with ``Phi_q`` (nr, nq) the Jacobian
  of the cut joints' constraint rows over the tree coordinates, ``M = nq - rank(Phi_q)``
  and the number of over-constraints ``t = nr - rank(Phi_q)`` (so that ``M = M_GK + t``).
  The over-constrained directions are the rows left out of a maximal independent set chosen
  by pivoted QR of ``Phi_q^T`` (cut joint and direction, e.g. ``R4: couple_x``).

Idle freedoms: motions allowed by the loops that move no joint centre and no task
coordinate (a leg spinning about the line through its two spherical joints):
``idle = M - rank(P N)``, ``N`` a basis of the null space of ``Phi_q``, ``P`` the velocities
of every joint centre and the task rows. The degrees of freedom are ``dof = M - idle``.

Ranks are taken on the dimensionless Jacobian (translation rows divided, translation columns
multiplied, by the model's length scale) with the threshold ``1e-9 sigma_max``.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ..._lazy import lazy_module
from ...errors import ParameterError
from . import _tree_kernels as K
from ..description.joint_types import JOINT_TYPES
from .poses import body_poses
from .records import MechanismModel

if TYPE_CHECKING:
    import scipy.linalg as linalg
    import scipy.sparse as sparse
    from scipy.sparse import csgraph
else:  # imported by the first model compiled
    linalg, sparse = lazy_module("scipy.linalg"), lazy_module("scipy.sparse")
    csgraph = lazy_module("scipy.sparse.csgraph")

__all__ = ["TopologyReport", "analyse_topology", "kutzbach_count", "constraint_jacobian", "solver_selection",
           "row_scale", "column_scale", "row_labels", "sparse_basis", "block_structure", "block_pattern",
           "blocks_of_pattern"]

Array = NDArray[np.float64]
RANK_TOL = 1e-9


@dataclass(frozen=True)
class TopologyReport:
    """Topology and mobility at one configuration (see the module docstring).

    ``joint_counts``: joints of each type letter; ``tree_joints``/``cut_joints``: names;
    ``loops``: number of independent loops (= cut joints); ``kutzbach``: Grübler-Kutzbach
    count; ``mobility``: by rank; ``overconstraints``: t; ``overconstrained``: the
    ``(cut joint, direction)`` of each redundant constraint; ``idle``: idle freedoms;
    ``dof``: mobility less idle freedoms; ``actuators``, ``task_coordinates``: counts."""

    name: str
    bodies: int
    joint_counts: dict[str, int]
    tree_joints: tuple[str, ...]
    cut_joints: tuple[str, ...]
    loops: int
    kutzbach: int
    mobility: int
    overconstraints: int
    overconstrained: tuple[tuple[str, str], ...]
    idle: int
    dof: int
    actuators: int
    task_coordinates: int

    def as_dict(self) -> dict:
        return {
            "mechanism": self.name, "moving_bodies": self.bodies, "joint_counts": self.joint_counts,
            "tree_joints": list(self.tree_joints), "cut_joints": list(self.cut_joints),
            "independent_loops": self.loops, "kutzbach_mobility": self.kutzbach, "mobility": self.mobility,
            "overconstraints": self.overconstraints,
            "overconstrained_directions": [f"{j}: {d}" for j, d in self.overconstrained],
            "idle_freedoms": self.idle, "dof": self.dof, "actuators": self.actuators,
            "task_coordinates": self.task_coordinates,
        }


def kutzbach_count(model: MechanismModel) -> int:
    """``6 n - sum_j (6 - f_j)`` over every joint of the model."""
    return 6 * model.nb - sum(6 - JOINT_TYPES[t].freedoms for t in model.joint_type)


def row_scale(model: MechanismModel) -> Array:
    """(nr + nt,) factors making every row dimensionless: 1/L for lengths, 1 for angles."""
    L = model.length_scale
    cut = np.where(model.row_kind == 0, 1.0 / L, 1.0)
    task = np.where(model.task_length, 1.0 / L, 1.0)
    return np.concatenate([cut, task])


def column_scale(model: MechanismModel) -> Array:
    """(nq,) factors making every coordinate dimensionless: L for translations, 1 for angles."""
    return np.where(model.coord_motion >= 3, model.length_scale, 1.0)


def row_labels(model: MechanismModel) -> list[str]:
    """A name for every row: ``"loop 2 (cut S3): force_x"`` or ``"task coordinate z"``."""
    out = []
    r = 0
    for loop in model.loops:
        for d in loop.directions:
            out.append(f"{loop.name}: {d}")
            r += 1
    out += [f"task coordinate {n}" for n in model.task_names]
    return out


def _args(model: MechanismModel) -> tuple:
    return (model.body_parent, model.body_joint, model.joint_q0, model.joint_nq, model.coord_motion,
            model.coord_offset, model.coord_sign, model.tree_R_parent, model.tree_p_parent, model.tree_R_child,
            model.tree_p_child, model.joint_R_parent, model.joint_p_parent, model.joint_R_child,
            model.joint_p_child, model.ancestor_list, model.row_loop, model.row_kind, model.row_i, model.row_j,
            model.loop_joint, model.joint_parent, model.joint_child, model.task_body, model.task_point,
            model.task_kind, model.task_index, model.euler_axes)


def constraint_jacobian(model: MechanismModel, q: Array, out: tuple[Array, Array] | None = None
                        ) -> tuple[Array, Array]:
    """Row values (n, nr + nt) and Jacobians (n, nr + nt, nq) at tree coordinates ``q (n, nq)``.

    Rows: the cut joints' constraint residuals (loop order, the directions of each loop
    record) then the task coordinates' values (not residuals); columns: tree coordinates.
    ``out``: the two arrays to write (zeroed here), e.g. a caller's buffers reused from call to
    call (a fresh array of some megabytes costs its first touch of every page, about as much as
    the Jacobians themselves).
    """
    q = np.ascontiguousarray(np.atleast_2d(q), dtype=float)
    n, nrow = q.shape[0], model.row_loop.shape[0] + model.nt
    if out is None:
        val, J = np.zeros((n, nrow)), np.zeros((n, nrow, model.nq))
    else:
        val, J = out
        val.fill(0.0)
        J.fill(0.0)
    K.jacobians_batch(q, *_args(model), val, J)
    return val, J


def _rank(a: Array) -> int:
    if a.size == 0:
        return 0
    sv = np.linalg.svd(a, compute_uv=False)
    return int(np.sum(sv > RANK_TOL * max(sv.max(), 1e-300)))


def sparse_basis(B: Array) -> Array:
    """The rows of ``B (k, n)`` (independent) replaced by the reduced row echelon basis of the
    same row space (Gauss-Jordan with the largest remaining entry as pivot), each row scaled to
    unit length, entries below ``1e-12`` of their row's largest set to zero: rows with as few
    nonzero entries as the space allows (a unit row where the space holds one coordinate's
    direction). Holding ``B (q - q_ref) = 0`` is the same set of equations in either basis."""
    A = np.array(B, dtype=float)
    k, n = A.shape
    free = list(range(n))
    for r in range(k):
        sub = np.abs(A[r:, free])
        i, j = np.unravel_index(int(np.argmax(sub)), sub.shape)
        c = free.pop(int(j))
        A[[r, r + int(i)]] = A[[r + int(i), r]]
        A[r] /= A[r, c]
        for o in range(k):
            if o != r:
                A[o] -= A[o, c] * A[r]
        A[:, c] = 0.0
        A[r, c] = 1.0
    for r in range(k):
        big = float(np.abs(A[r]).max(initial=0.0))
        A[r, np.abs(A[r]) < 1e-12 * big] = 0.0
        A[r] /= max(float(np.linalg.norm(A[r])), 1e-300)
    return A


def _null(a: Array, ncols: int) -> Array:
    if a.shape[0] == 0:
        return np.eye(ncols)
    _, sv, vh = np.linalg.svd(a)
    r = int(np.sum(sv > RANK_TOL * max(sv.max(initial=0.0), 1e-300)))
    return vh[r:].T


def _point_jacobian(model: MechanismModel, q: Array) -> Array:
    """(3 nj, nq): velocity of every joint centre (the child frame's origin) per tree rate:
    ``S_c[3:] + S_c[:3] x x_k`` for every coordinate c that moves joint k's child, written out
    for every such pair at once (the same products and sums, entry by entry, as one joint at a
    time with :func:`~pkmdyn.spatial.cross`)."""
    R, p, S = body_poses(model, q)
    nj = len(model.joint_names)
    out = np.zeros((nj, 3, model.nq))
    x = np.zeros((nj, 3))
    for k in range(nj):
        b = int(model.joint_child[k])
        x[k] = p[b] + R[b] @ model.joint_p_child[k] if b >= 0 else model.joint_p_child[k]
    child = model.joint_child
    moved = np.zeros((nj, model.nq), dtype=bool)
    moved[child >= 0] = model.ancestors[child[child >= 0]]
    k, c = np.nonzero(moved)
    a, b = S[c, :3], x[k]
    a0, a1, a2 = a[:, 0], a[:, 1], a[:, 2]
    b0, b1, b2 = b[:, 0], b[:, 1], b[:, 2]
    w = S[c, 3:] + np.stack((a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0), axis=-1)
    out[k, :, c] = w
    return out.reshape(3 * nj, model.nq)


def _scaled_jacobian(model: MechanismModel, q: Array) -> Array:
    """The dimensionless Jacobian (nr + nt, nq) of the cut joints' constraint rows and the task
    rows at ``q`` (:func:`constraint_jacobian`, :func:`row_scale`, :func:`column_scale`)."""
    _, J = constraint_jacobian(model, q)
    return J[0] * row_scale(model)[:, None] * column_scale(model)[None, :]


def analyse_topology(model: MechanismModel, q: Array | None = None) -> TopologyReport:
    """Topology and mobility of ``model`` at tree coordinates ``q (nq,)`` (default: the
    reference configuration, which is assembled by construction)."""
    q = model.coord_offset.copy() if q is None else np.asarray(q, dtype=float)
    return _analyse(model, q, _scaled_jacobian(model, q))[0]


def _analyse(model: MechanismModel, q: Array, Js: Array) -> tuple[TopologyReport, Array | None]:
    """:func:`analyse_topology` at ``q`` of the scaled Jacobian ``Js`` there, and the column
    pivots of the pivoted QR of the constraint rows' ``Js^T`` where it was taken (an
    over-constrained mechanism; else None), which :func:`solver_selection` takes again."""
    nr = model.row_loop.shape[0]
    phi = Js[:nr]
    rank_c = _rank(phi)
    mobility = model.nq - rank_c
    labels = []
    piv = None
    if nr > rank_c:
        _, _, piv = linalg.qr(phi.T, pivoting=True, mode="economic")
        redundant = sorted(piv[rank_c:])
        for rr in redundant:
            loop = model.loops[model.row_loop[rr]]
            first = int(np.flatnonzero(model.row_loop == model.row_loop[rr])[0])
            labels.append((loop.joint, loop.directions[rr - first]))
    N = _null(phi, model.nq)
    P = np.concatenate([_point_jacobian(model, q) / model.length_scale * column_scale(model)[None, :], Js[nr:]])
    idle = mobility - _rank(P @ N) if N.shape[1] else 0
    counts: dict[str, int] = {}
    for t in model.joint_type:
        counts[JOINT_TYPES[t].letter] = counts.get(JOINT_TYPES[t].letter, 0) + 1
    return TopologyReport(
        name=model.name, bodies=model.nb, joint_counts=counts,
        tree_joints=tuple(n for n, c in zip(model.joint_names, model.joint_cut) if not c),
        cut_joints=tuple(model.joint_names[k] for k in model.loop_joint), loops=len(model.loops),
        kutzbach=kutzbach_count(model), mobility=mobility, overconstraints=nr - rank_c,
        overconstrained=tuple(labels), idle=idle, dof=mobility - idle, actuators=model.na,
        task_coordinates=model.nt,
    ), piv


def block_structure(model: MechanismModel, rows: Array, idle: Array) -> tuple[Array, Array, Array]:
    """Row and column orders making the Newton matrix ``[J[rows]; idle]`` block lower-triangular.

    From the structural pattern (:func:`block_pattern`: a loop row depends on the coordinates
    that move either of its bodies, a task row on those that move the task body (a joint's
    coordinate on that coordinate), an idle row on its nonzero entries): a perfect matching of rows to columns (``maximum_bipartite_matching``),
    the strongly connected components of the row graph ``i -> j`` where row i uses the column
    matched to row j (``connected_components``), put in an order where every block uses only
    the columns of itself and of the blocks before it (the block triangular form of
    Duff & Reid). For a Stewart platform: the six task rows with the six coordinates of the
    leg that carries the platform, then each other leg's three closure rows with its three
    coordinates. Returns ``(prow, pcol, blocks)``; a single block when no structure is found.
    """
    return blocks_of_pattern(block_pattern(model, rows, idle))


def block_pattern(model: MechanismModel, rows: Array, idle: Array) -> NDArray[np.bool_]:
    """The structural pattern ``(m + ni, nq)`` of the Newton matrix ``[J[rows]; idle]`` (see
    :func:`block_structure`): which coordinates each row may depend on. The block order is a
    function of this pattern alone (:func:`blocks_of_pattern`)."""
    nq, m = model.nq, rows.size
    n = m + idle.shape[0]
    P = np.zeros((n, nq), dtype=bool)
    nr = model.row_loop.shape[0]
    for i, r in enumerate(rows):
        if r < nr:
            k = model.loop_joint[model.row_loop[r]]
            for b in (model.joint_parent[k], model.joint_child[k]):
                if b >= 0:
                    P[i] |= model.ancestors[b]
        elif model.task_kind[r - nr] == 2:  # a joint's coordinate: that coordinate alone
            P[i, int(model.task_index[r - nr])] = True
        else:
            P[i] = model.ancestors[model.task_body]
    P[m:] = np.abs(idle) > 1e-14 * max(float(np.abs(idle).max(initial=0.0)), 1e-300)
    return P


def blocks_of_pattern(P: NDArray[np.bool_]) -> tuple[Array, Array, Array]:
    """:func:`block_structure`'s ``(prow, pcol, blocks)`` of the pattern ``P (n, nq)``
    (:func:`block_pattern`), remembered by the pattern (:func:`_blocks_of`): the designs of a
    sweep (:func:`pkmdyn.multibody.model.compiler.compile_with`) have one pattern, or a few (the idle rows of a
    symmetric mechanism come in another order where rounding picks another pivot), and the
    order is a function of the pattern alone, so it is found once for each."""
    P = np.ascontiguousarray(P, dtype=bool)
    return tuple(a.copy() for a in _blocks_of(P.shape, P.tobytes()))  # type: ignore[return-value]


@functools.lru_cache(maxsize=64)
def _blocks_of(shape: tuple[int, int], pattern: bytes) -> tuple[Array, Array, Array]:
    """:func:`blocks_of_pattern` of the pattern of ``shape`` whose entries are the bytes
    ``pattern`` (the cached computation)."""
    P = np.frombuffer(pattern, dtype=bool).reshape(shape)
    n, nq = P.shape
    single = (np.arange(n, dtype=np.int64), np.arange(n, dtype=np.int64), np.array([0, n], dtype=np.int64))
    if n != nq or n == 0:
        return single
    match = csgraph.maximum_bipartite_matching(sparse.csr_matrix(P.astype(np.int8)), perm_type="column")
    if np.any(match < 0):
        return single
    dep = P[:, match]  # dep[i, j]: row i uses the column matched to row j
    ncomp, label = csgraph.connected_components(sparse.csr_matrix(dep.astype(np.int8)), directed=True,
                                                connection="strong")
    # order the components so that each comes after every component it depends on
    needs = [set() for _ in range(ncomp)]
    for i, j in zip(*np.nonzero(dep)):
        if label[i] != label[j]:
            needs[label[i]].add(label[j])
    order, done = [], set()
    while len(order) < ncomp:
        ready = [c for c in range(ncomp) if c not in done and needs[c] <= done]
        if not ready:  # pragma: no cover - the condensation of a graph is acyclic
            return single
        for c in ready:
            order.append(c)
            done.add(c)
    prow = np.concatenate([np.flatnonzero(label == c) for c in order]).astype(np.int64)
    pcol = match[prow].astype(np.int64)
    sizes = [int(np.sum(label == c)) for c in order]
    blocks = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    return prow, pcol, blocks


def solver_selection(model: MechanismModel, q: Array | None = None) -> tuple[Array, Array, TopologyReport]:
    """Rows of the square Newton system and its idle rows, chosen at ``q`` (default: reference).

    Rows: a maximal independent set of the constraint rows (pivoted QR; the redundant
    directions of an over-constrained mechanism are left out and only checked) followed by
    every task row. Idle rows ``(ni, nq)``: a basis ``n_k`` of the null space of those rows
    (the idle freedoms), each held by the linear equation ``n_k . (q - q_ref) = 0``; a
    smooth choice, so that the coordinates stay differentiable functions of the task. The
    basis is the sparse one of :func:`sparse_basis` (the same equations as any other basis of
    that space): a rod's spin about the line through its two spherical joints is its own row,
    the rod's own coordinate where one of its joint's axes lies along that line, which leaves
    the leg to its closed form (:mod:`pkmdyn.multibody.model.legs`). Raises :class:`~pkmdyn.errors.ParameterError`
    when the task coordinates do not determine the mechanism (fewer or more than its degrees
    of freedom, or dependent).
    """
    q = model.coord_offset.copy() if q is None else np.asarray(q, dtype=float)
    Js = _scaled_jacobian(model, q)  # (one Jacobian and one pivoted QR for the report and the rows)
    rep, piv = _analyse(model, q, Js)
    nr = model.row_loop.shape[0]
    src = model.path or model.name
    if model.nt != rep.dof:
        raise ParameterError(
            f"{src}: [task] gives {model.nt} coordinate(s) but the mechanism has {rep.dof} degree(s) of freedom "
            f"(mobility {rep.mobility}, {rep.idle} idle); the task coordinates must determine its pose")
    rank_c = model.nq - rep.mobility
    if nr and rank_c:
        if piv is None:
            _, _, piv = linalg.qr(Js[:nr].T, pivoting=True, mode="economic")
        cut_rows = np.sort(piv[:rank_c])
    else:
        cut_rows = np.zeros(0, dtype=np.int64)
    sel = np.concatenate([cut_rows, nr + np.arange(model.nt)]).astype(np.int64)
    Ks = Js[sel]
    if _rank(Ks) != sel.size:
        raise ParameterError(f"{src}: [task]: the task coordinates {', '.join(model.task_names)} are not independent "
                             "at the reference configuration (they do not determine the mechanism's pose)")
    N = sparse_basis(_null(Ks, model.nq).T).T  # scaled coordinates; dq = D dq_s with D = column_scale
    idle = (N / column_scale(model)[:, None]).T.copy()
    Kfull = np.concatenate([Ks, N.T])
    if _rank(Kfull) != model.nq:  # pragma: no cover - N completes the rank by construction
        raise ParameterError(f"{src}: the loop-closure and task equations are singular at the reference "
                             "configuration; describe the mechanism at a regular pose")
    Phi = np.concatenate([Js[:nr][cut_rows], N.T])
    Ea = np.zeros((model.na, model.nq))
    Ea[np.arange(model.na), model.act_coord] = 1.0
    # the actuated joints move independently (at most as many as the freedoms) or, redundantly
    # actuated, together determine the pose
    if _rank(np.concatenate([Phi, Ea])) < min(Phi.shape[0] + model.na, model.nq):
        raise ParameterError(f"{src}: [joints]: the actuated joints {', '.join(model.actuator_names)} cannot "
                             f"{'move independently' if model.na <= rep.dof else 'determine the pose'} at the "
                             "reference configuration")
    return sel, np.ascontiguousarray(idle), rep
