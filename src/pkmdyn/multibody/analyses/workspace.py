"""The workspace of any described mechanism on a grid of task poses (``docs/workspace.md``).

**Method.** A regular grid over one to three task coordinates (the others held at a given
pose, e.g. a constant orientation), solved by continuation over the grid
(:func:`pkmdyn.multibody.kinematics.inverse.solve_grid`): the grid pose nearest the held pose is reached from the
reference configuration along the straight task path (as the first sample of a motion; where
it is not, the next nearest, up to 16), and every other pose from a solved neighbour along a
grid axis, breadth first, so every pose on the description's assembly branch. A grid pose
is *reached* where it is solved with every joint within its limits (``limits_rad``/``limits_m``,
actuated joints included). It is *in the workspace* where

1. it is reached and every singularity measure (:func:`pkmdyn.multibody.kinematics.singularity.measures.singularity_measures`:
   inverse, direct, constraint) at it is at least ``threshold``, and
2. it is connected to the start through such poses (neighbours along the grid's axes): the
   part of the grid the mechanism moves through from its reference without crossing a
   singularity or a joint limit. A region reached only across a singularity, or on another
   assembly branch, reads outside (conservative).

**Size.** Each grid pose stands for its cell (the product of the grid steps); the workspace's
size (volume [m^3] for three position coordinates, area for two, length for one; angles count
in rad; the unit written ``m3``, ``m2``, ``m2_rad``, ...) is the number of inside poses times the cell. Its error estimate is half the cells on
the boundary (inside poses with an outside neighbour along a grid axis, and the reverse),
times the cell: the boundary's cells are the ones the grid cannot tell in or out.

**Refined size** (``refine = N``, ``pkmdyn workspace --refine``): the count above moves in
whole cells as a design changes, which leaves an optimiser of the workspace's size a staircase.
Where each boundary edge (an inside pose ``a`` and an outside neighbour ``b`` along a grid axis)
is stepped from ``a`` to ``b`` in ``N`` equal steps, each solved from the step before and
screened as a grid pose (reached within the limits, every measure at least the threshold), the
boundary crosses the edge within the first step that ends outside, after ``k`` good steps: at
``t = (k + f) / N`` of the edge, ``f`` where the margin of the condition the step's end fails
(each joint's distance to the limit it is beyond there, or the least singularity measure less
the threshold) reaches zero, linear between the step's ends, and ``f = 1/2``
where the step's end is out of reach (``t = 1`` when every step is good). Along grid axis
``d`` the size is the line integral over the grid's lines along ``d`` (the cross-section of a
cell times each line's inside length), ``V_d = cell (inside poses + sum over the edges along d
of (t - 1/2))``, and the size is the mean of ``V_d`` over the axes. A pose that joins the
workspace adds its cell and takes its edges' half cells away at once, so the size moves
continuously with a boundary of joint limits or singularity thresholds, and in steps of
``cell / (N D)`` (``D`` grid axes) with a boundary of reach; it still jumps where separate
parts of the workspace join or split. Its error estimate (:func:`refined_size`): the midpoint
rule's across the lines, an eighth of the second difference of the lines' inside lengths (its
bound where those lengths are concave or convex between lines, from the chords), plus half a
step an edge over the axes for the crossings. The steps cost up to ``N`` solves an edge, and
every inside pose is solved once more: with ``N = 4`` a Delta robot's 13 x 13 x 9 grid took
about three times the count's time (90-95 ms against 31-36 ms, every measure computed). Not
over an orientation range.

**Inscribed shapes about a centre** ``c`` (default: the reference pose): the largest cube
(the same half-width ``a`` along every grid axis) and the largest cylinder (axis along the last
grid axis, height equal to its diameter; a disc for two axes) centred at ``c`` holding no
outside grid pose: ``a`` = the least Chebyshev distance from ``c`` to an outside pose, less one
grid step (so that the shape is inside to within the grid's resolution); 0 where ``c`` itself
is outside; not given (None) for a grid of lengths and angles together.

**Dexterity** over the inside poses: the statistics of the smallest of the singularity
measures (1 isotropic, 0 singular; the inverse of a condition number of the scaled Jacobians).
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from ...errors import ParameterError
from ..kinematics.inverse import (
    beyond_limits,
    joint_coordinates,
    limit_bounds,
    limited_joints,
    neighbour_pairs,
    reference_task,
    solve_graph,
    solve_grid,
)
from ..kinematics.singularity.measures import least_measure_bounds, singularity_measures
from ..model.compiler import MechanismModel
from .task_grid import grid_poses

__all__ = ["Workspace", "workspace", "refined_size", "MAX_RANGE_POSES", "MAX_REFINE"]

Array = NDArray[np.float64]

#: the most poses a workspace over an orientation range solves (grid poses times held poses)
MAX_RANGE_POSES = 1_000_000
#: the most steps of a boundary edge (``refine``)
MAX_REFINE = 64


@dataclass(frozen=True)
class Workspace:
    """A workspace on a grid (module docstring): ``axes`` the grid's (task coordinate, values);
    ``x (N, nt)`` every grid pose (first axis slowest); ``reached (N,)`` reached within the
    joint limits; ``inside (N,)`` reached, away from every singularity and connected to the
    start (module docstring); ``q (N, nq)`` the tree coordinates (zeros where not reached;
    None over ``ranges``, the held coordinates taken over ranges, :func:`workspace`); ``measure (N,)`` the
    smallest singularity measure (0 where not reached; None where not every measure was asked
    for, :func:`workspace`); ``least_measure`` the least of it over the inside poses (None where
    no pose is inside); ``size``, ``size_error`` in the unit of
    the grid's cells (``unit``, :func:`size_unit`); ``cube_half_width``, ``cylinder_radius``
    about ``centre`` (None for a grid of lengths and angles together)."""

    axes: list
    x: Array
    reached: NDArray[np.bool_]
    inside: NDArray[np.bool_]
    q: Array | None
    ranges: list
    measure: Array | None
    least_measure: float | None
    cell: float
    size: float
    size_error: float
    unit: str
    centre: Array
    cube_half_width: float | None
    cylinder_radius: float | None
    threshold: float
    #: steps of each boundary edge behind ``size`` (0: inside poses times the cell; :func:`refined_size`)
    refine: int = 0
    #: the names of ``x``'s columns, each task coordinate with its unit (``x_m``, ``euler1_rad``, ...)
    x_columns: tuple[str, ...] = ()

    def columns(self) -> dict[str, Array]:
        """``workspace.csv``'s columns by name (``docs/workspace.md``): every grid pose's task
        coordinates (:attr:`x_columns`), ``reached`` and ``inside`` (1 or 0) and, where every
        measure was asked for, ``singularity_measure`` (0 where not reached)."""
        cols = {name: self.x[:, i] for i, name in enumerate(self.x_columns)}
        cols.update(reached=self.reached.astype(float), inside=self.inside.astype(float))
        if self.measure is not None:
            cols["singularity_measure"] = self.measure
        return cols


def check_centre(centre: object, n: int) -> Array:
    """``--centre``: one finite value per grid coordinate."""
    c = np.asarray(centre, dtype=float)
    if c.shape != (n,) or not np.all(np.isfinite(c)):
        raise ParameterError(f"--centre: expected {n} finite values (one per grid coordinate)")
    return c


def _roots(axes: list[tuple[int, Array]], base: Array) -> NDArray[np.int64]:
    """The grid's poses in order of distance from the held pose ``base`` (in grid steps)."""
    where = [(base[i] - v[0]) / (v[1] - v[0]) for i, v in axes]
    mesh = np.meshgrid(*[np.arange(len(v)) for _, v in axes], indexing="ij")
    d = sum((m.reshape(-1) - w) ** 2 for m, w in zip(mesh, where))
    return np.argsort(d, kind="stable")


def _boundary(inside: NDArray[np.bool_], shape: tuple[int, ...]) -> int:
    """Cells whose state differs from a neighbour's along a grid axis."""
    edge = np.zeros(inside.size, dtype=bool)
    for i, j in neighbour_pairs(shape):
        differ = inside[i] != inside[j]
        edge[i[differ]] = edge[j[differ]] = True
    return int(edge.sum())


def _least(model: MechanismModel, q: Array) -> Array:
    """The least singularity measure (inverse, constraint, and direct where as many actuators
    as degrees of freedom) at ``q (n, nq)``, from the singular values."""
    sm = singularity_measures(model, q)
    m = np.minimum(sm.inverse, sm.constraint)
    return np.minimum(m, sm.direct) if model.na == model.nt else m


def _screen(model: MechanismModel, kin, reached: NDArray[np.bool_], threshold: float, all_measures: bool,
            coords: Array | None = None) -> tuple[NDArray[np.bool_], NDArray[np.bool_], Array, Array]:
    """Of solved poses (``kin``, ``reached``): reached within the joint limits, and good (also
    every singularity measure at least ``threshold``); the least measure (0 where not reached;
    NaN where ``all_measures`` is False and its bounds prove it at least ``threshold``) and an
    upper bound of it (:func:`_held`). ``coords``: the limited joints' coordinates of every
    pose of ``kin`` (:func:`_limited_coordinates`), where already at hand."""
    n = len(reached)
    joints = limited_joints(model)
    if joints and reached.any():
        if coords is None:
            coords = _limited_coordinates(model, kin)
        reached = reached & ~beyond_limits(model, coords, joints).any(axis=1)
    measure = np.zeros(n)
    upper = np.zeros(n)
    proven = np.zeros(n, dtype=bool)
    if reached.any() and all_measures:
        measure[reached] = _least(model, kin.q[reached])
        upper = measure
    elif reached.any():
        at = np.flatnonzero(reached)
        passed, upper[at] = least_measure_bounds(model, kin.q[at], threshold)
        proven[at[passed]] = True
        rest = at[~passed]
        measure[at[passed]] = np.nan
        if rest.size:
            measure[rest] = upper[rest] = _least(model, kin.q[rest])
    return reached, reached & (proven | (measure >= threshold)), measure, upper


def _limited_coordinates(model: MechanismModel, kin) -> Array | None:
    """The coordinates of the limited joints (:func:`pkmdyn.multibody.kinematics.inverse.limited_joints`) at every pose
    of ``kin``; None without such joints."""
    joints = limited_joints(model)
    return joint_coordinates(model, kin, joints, along=False) if joints else None


def _edges(inside: NDArray[np.bool_], shape: tuple[int, ...]) -> tuple[NDArray[np.int64], NDArray[np.int64],
                                                                        NDArray[np.int64]]:
    """The boundary's edges: pairs of neighbours along a grid axis, ``a`` inside and ``b``
    outside, and the axis of each."""
    a, b, axis = [], [], []
    for ax, (i, j) in enumerate(neighbour_pairs(shape)):
        up, down = inside[i] & ~inside[j], ~inside[i] & inside[j]
        a += [i[up], j[down]]
        b += [j[up], i[down]]
        axis.append(np.full(int(up.sum() + down.sum()), ax))
    return np.concatenate(a), np.concatenate(b), np.concatenate(axis)


def _crossings(model: MechanismModel, x: Array, shape: tuple[int, ...], inside: NDArray[np.bool_], q: Array,
               root: int, threshold: float, steps: int, all_measures: bool
               ) -> tuple[NDArray[np.int64], NDArray[np.int64], Array]:
    """Where the workspace's boundary crosses each boundary edge (:func:`_edges`): the edge from
    inside pose ``a`` to outside pose ``b`` stepped in ``steps`` equal steps, each step's pose
    solved from the one before (continuation from ``a``'s solution ``q[a]``; every inside
    pose solved again from ``root`` over the inside poses, :func:`pkmdyn.multibody.kinematics.inverse.solve_graph`)
    and screened as a grid pose (:func:`_screen`). After ``k`` good steps the crossing lies in
    step ``k + 1``: where its end is solved, where the margin of the condition it fails
    (:func:`_between`) falls to zero, linear between the step's two ends; where it is not
    solved (out of reach), the step's middle. The fraction is 1 where every step is good.
    Returns each edge's inside pose, axis and fraction."""
    a, b, axis = _edges(inside, shape)
    ins = np.flatnonzero(inside)
    m, e, d = len(ins), len(a), len(shape)
    pos = np.full(inside.size, -1, dtype=np.int64)
    pos[ins] = np.arange(m)
    nbr = np.full((m + e * steps, 4 * d), -1, dtype=np.int64)
    for ax, (i, j) in enumerate(neighbour_pairs(shape)):  # inside poses lead to their inside neighbours
        both = inside[i] & inside[j]
        nbr[pos[i[both]], 2 * ax] = pos[j[both]]
        nbr[pos[j[both]], 2 * ax + 1] = pos[i[both]]
    first = m + np.arange(e) * steps  # each edge's first step's node; pose a leads to it
    slot = np.zeros(inside.size, dtype=np.int64)
    for k in range(e):
        nbr[pos[a[k]], 2 * d + slot[a[k]]] = first[k]
        slot[a[k]] += 1
    chain = (first[:, None] + np.arange(steps - 1)[None, :]).reshape(-1)
    nbr[chain, 0] = chain + 1
    s = np.arange(1, steps + 1) / steps
    xs = x[a][:, None, :] + s[None, :, None] * (x[b] - x[a])[:, None, :]
    kin, ok = solve_graph(model, np.concatenate([x[ins], xs.reshape(-1, x.shape[1])]), nbr, int(pos[root]), q[root])
    steps_ok = ok.copy()
    steps_ok[:m] = False  # the inside poses are screened already
    coords = _limited_coordinates(model, kin)  # for the screen and the crossings' margins alike
    _, good, _, _ = _screen(model, kin, steps_ok, threshold, all_measures, coords)
    g = good[m:].reshape(e, steps)
    k = np.where(g.all(axis=1), steps, np.argmin(g, axis=1))
    frac = np.full(e, 0.5)
    # where the first step outside is solved, the crossing between it and the last good pose
    # from the margin of the condition it fails (linear in between); else the step's middle
    part = np.flatnonzero((k < steps) & ok[m:].reshape(e, steps)[np.arange(e), np.minimum(k, steps - 1)])
    if part.size:
        bad = m + part * steps + k[part]
        last = np.where(k[part] == 0, pos[a[part]], bad - 1)
        frac[part] = _between(model, kin, last, bad, threshold, coords)
    t = np.where(k == steps, 1.0, (k + frac) / steps)
    # an inside pose that its second solve did not reach again (or reached elsewhere, another
    # branch) leaves its edges as the count has them: half a step
    again = ok[:m] & (np.abs(kin.q[:m] - q[ins]).max(axis=1, initial=0.0) <= 1e-6 * (1.0 + np.abs(q[ins]).max()))
    return a, axis, np.where(again[pos[a]], t, 0.5)


def _between(model: MechanismModel, kin, good: NDArray[np.int64], bad: NDArray[np.int64], threshold: float,
             coords: Array | None) -> Array:
    """Where between the poses ``good`` and ``bad`` of ``kin`` (pairs, the latter outside) the
    condition the latter fails is crossed, as a fraction of the way, linear between their
    margins: for each joint beyond its limit at ``bad``, its distance to that limit; where no
    joint is, the least singularity measure less ``threshold``; the first crossing over the
    joints. 1/2 where the margins do not bracket a crossing. ``coords``: the limited joints'
    coordinates at every pose of ``kin`` (:func:`_limited_coordinates`; None without them)."""
    f = np.full(len(good), np.inf)
    by_measure = np.ones(len(good), dtype=bool)
    joints = limited_joints(model)
    if joints:
        lo, hi = limit_bounds(model, joints)
        beyond = beyond_limits(model, coords[bad], joints)
        by_measure = ~beyond.any(axis=1)
        over = coords[bad] > hi  # the limit each joint beyond one is beyond
        m1 = np.where(over, hi - coords[good], coords[good] - lo)
        m2 = np.where(over, hi - coords[bad], coords[bad] - lo)
        f = np.where(beyond, _fraction(m1, m2), np.inf).min(axis=1)
    if by_measure.any():
        both = _least(model, kin.q[np.concatenate([good[by_measure], bad[by_measure]])]) - threshold
        f[by_measure] = _fraction(*np.split(both, 2))
    return np.where(np.isfinite(f), f, 0.5)


def _fraction(g1: Array, g2: Array) -> Array:
    """Where a margin linear from ``g1`` to ``g2`` falls to zero, as a fraction of the way in
    [0, 1]; 1/2 where ``g2`` is not below zero or not below ``g1``."""
    with np.errstate(all="ignore"):
        return np.where((g2 < 0.0) & (g1 > g2), np.clip(g1 / (g1 - g2), 0.0, 1.0), 0.5)


def _held(model: MechanismModel, axes: list[tuple[int, Array]], base: Array, threshold: float,
          all_measures: bool = True) -> tuple[NDArray[np.bool_], NDArray[np.bool_], Array, Array, Array]:
    """The workspace on the grid at one held pose ``base`` (module docstring): reached, inside,
    the smallest singularity measure (0 where not reached), the tree coordinates, and an upper
    bound of the measure (the measure itself where computed). Without ``all_measures`` the
    measure is computed only where its bounds (:func:`pkmdyn.multibody.kinematics.singularity.measures.least_measure_bounds`) do not
    prove it at least ``threshold``, and is NaN elsewhere."""
    x = grid_poses(model, axes, base)
    shape = tuple(len(v) for _, v in axes)
    roots = _roots(axes, base)
    kin, reached = solve_grid(model, x, shape, roots)
    reached, good, measure, upper = _screen(model, kin, reached, threshold, all_measures)
    inside = np.zeros(len(x), dtype=bool)
    if good.any():
        labels, _ = ndimage.label(good.reshape(shape))
        labels = labels.reshape(-1)
        inside = labels == labels[roots[good[roots]][0]]  # the part about the start
    return reached, inside, measure, np.where(reached[:, None], kin.q, 0.0), upper


def _least_inside(model: MechanismModel, q: Array, inside: NDArray[np.bool_], measure: Array, upper: Array,
                  candidates: int = 16) -> float:
    """The least singularity measure over the inside poses where only some measures are known
    (``measure`` NaN elsewhere, ``upper`` their upper bounds): the measures of the
    ``candidates`` unknown poses of least upper bound are computed, ``U`` the least known
    measure; every other inside pose is proven above ``U``
    (:func:`pkmdyn.multibody.kinematics.singularity.measures.least_measure_bounds`, ``tight``: where its measure exceeds ``U`` by
    more than a few per cent) or its measure is computed. ``U`` is a pose's measure, so the
    least is among the computed ones."""
    ins = np.flatnonzero(inside)
    vals = measure[ins]
    unknown = ins[np.isnan(vals)]
    known = [vals[~np.isnan(vals)]]
    order = np.argsort(upper[unknown], kind="stable")
    first, unknown = unknown[order[:candidates]], unknown[order[candidates:]]
    if first.size:
        known.append(_least(model, q[first]))
    level = float(np.concatenate(known).min())
    if unknown.size:
        passed, _ = least_measure_bounds(model, q[unknown], level, tight=True)
        rest = unknown[~passed]
        if rest.size:
            known.append(_least(model, q[rest]))
    return float(np.concatenate(known).min())


def workspace(model: MechanismModel, axes: list[tuple[int, Array]], base: Array | None = None,
              threshold: float = 1e-3, centre: Array | None = None,
              ranges: list[tuple[int, Array]] | None = None, measures: str = "all", refine: int = 0) -> Workspace:
    """The workspace on the grid ``axes`` (:func:`pkmdyn.multibody.analyses.task_grid.parse_grid`) about the pose
    ``base`` (default: the reference pose), with the singularity ``threshold`` and the inscribed
    shapes about ``centre`` (the grid coordinates' values; default: ``base``'s).

    ``ranges``: held coordinates (not on the grid) taken over ranges of values (the same
    syntax), e.g. the three Euler angles: a pose is reached (inside) where it is reached
    (inside) at every combination of their values, the *total orientation workspace* of
    Merlet (Parallel Robots, 2006, §6.2) for a range of orientations; its measure is the
    least over the combinations.

    ``measures``: ``"all"`` every reached pose's singularity measures (``measure``);
    ``"least"`` (a sweep's workspace, where the size and the least measure count) a pose's
    measures only where their cheap bounds do not prove them at least ``threshold``
    (:func:`pkmdyn.multibody.kinematics.singularity.measures.least_measure_bounds`, some ten times cheaper than the singular
    values), and the least over the inside poses as :func:`_least_inside` finds it: the same
    ``reached``, ``inside``, size and ``least_measure`` as ``"all"`` (to rounding), no
    ``measure`` per pose; ``"none"`` as ``"least"`` without ``least_measure`` (None). Over
    ``ranges`` every measure is computed.

    ``refine``: the size from where the boundary crosses the grid's edges, each boundary edge
    stepped in ``refine`` steps (:func:`refined_size`; 0: the count of inside poses, module
    docstring); not over ``ranges``."""
    if not (math.isfinite(threshold) and 0.0 <= threshold < 1.0):
        raise ParameterError(f"--threshold: {threshold!r} is not in [0, 1)")
    base = reference_task(model) if base is None else np.asarray(base, dtype=float)
    ranges = list(ranges or [])
    if {i for i, _ in ranges} & {i for i, _ in axes}:
        raise ParameterError("--orientation-range: a coordinate is on the grid too")
    x = grid_poses(model, axes, base)
    held = grid_poses(model, ranges, base) if ranges else base[None]
    if len(x) * len(held) > MAX_RANGE_POSES:
        raise ParameterError(f"--orientation-range: {len(held):,} held poses times {len(x):,} grid poses is more than "
                             f"{MAX_RANGE_POSES:,} poses")
    reached = np.ones(len(x), dtype=bool)
    inside = np.ones(len(x), dtype=bool)
    measure = np.full(len(x), np.inf)
    if measures not in ("all", "least", "none"):
        raise ParameterError(f"measures: {measures!r} is not one of all, least, none")
    if isinstance(refine, bool) or not isinstance(refine, (int, np.integer)) or not 0 <= refine <= MAX_REFINE:
        raise ParameterError(f"--refine: {refine!r} is not an integer from 0 to {MAX_REFINE}")
    if refine and ranges:
        raise ParameterError("--refine: not with --orientation-range (the size is the count of inside poses there)")
    every = measures == "all" or bool(ranges)
    for b in held:
        r, i, m, q, upper = _held(model, axes, b, threshold, every)
        reached &= r
        inside &= i
        measure = np.minimum(measure, m) if every else m
    if not inside.any() or measures == "none":
        least = None
    elif every:
        least = float(np.where(reached, measure, 0.0)[inside].min())
    else:
        least = _least_inside(model, q, inside, measure, upper)
    measure = np.where(reached, measure, 0.0) if every else None
    shape = tuple(len(v) for _, v in axes)
    steps = np.array([float(v[1] - v[0]) for _, v in axes])
    cell = float(np.prod(steps))
    size, size_error = float(inside.sum()) * cell, 0.5 * _boundary(inside, shape) * cell
    if refine and inside.any() and not inside.all():
        root = int(next(r for r in _roots(axes, base) if inside[r]))
        a, axis, frac = _crossings(model, x, shape, inside, q, root, threshold, int(refine), every)
        size, size_error = refined_size(inside, shape, a, axis, frac, cell, int(refine))
    units = [model.task_units[i] for i, _ in axes]
    unit = size_unit(units)
    c = np.array([base[i] for i, _ in axes]) if centre is None else check_centre(centre, len(axes))
    pts = x[:, [i for i, _ in axes]]
    out = ~inside
    step = float(steps.max())
    if len(set(units)) > 1:  # lengths and angles together: no distance to measure the shapes by
        cube = cylinder = None
    elif out.any():
        d = np.abs(pts[out] - c)
        cube = float(d.max(axis=1).min()) - step
        if len(axes) >= 2:
            rho = np.linalg.norm(d[:, :2], axis=1) if len(axes) == 3 else np.linalg.norm(d, axis=1)
            cyl = rho if len(axes) == 2 else np.maximum(rho, d[:, 2])
            cylinder = float(cyl.min()) - step
        else:
            cylinder = cube
    else:  # the whole grid is inside: bounded by the grid itself
        cube = float(np.minimum(pts.max(axis=0) - c, c - pts.min(axis=0)).min())
        cylinder = cube
    return Workspace(axes=axes, x=x, reached=reached, inside=inside, q=q if not ranges else None,
                     ranges=ranges, measure=measure, least_measure=least, cell=cell,
                     size=size, size_error=size_error, unit=unit,
                     centre=c, cube_half_width=None if cube is None else max(cube, 0.0),
                     cylinder_radius=None if cylinder is None else max(cylinder, 0.0), threshold=float(threshold),
                     refine=int(refine),
                     x_columns=tuple(f"{n}_{u}" for n, u in zip(model.task_names, model.task_units)))


def refined_size(inside: NDArray[np.bool_], shape: tuple[int, ...], a: NDArray[np.int64], axis: NDArray[np.int64],
                 frac: Array, cell: float, steps: int) -> tuple[float, float]:
    """The workspace's size from its boundary's crossings of the grid's edges (module
    docstring, "Refined size"): along each grid axis ``d``, each grid line along ``d`` is
    inside over ``c`` cells, its inside poses' less a half for each boundary edge on it plus
    the crossing's fraction ``t`` of that edge (``a`` each edge's inside pose, ``axis`` its
    axis, ``frac`` its ``t``: :func:`_crossings`); ``V_d`` is the cell times the sum of ``c``
    over the lines, and the size the mean of ``V_d`` over the axes.

    Error estimate: ``V_d`` takes each line for the band of lines about it (the midpoint rule
    across the lines), which errs by at most an eighth of the second difference of ``c``
    across the lines where ``c`` is concave or convex between them (the chords through the
    neighbouring lines bound it), summed over the transverse axes (the grid's outer lines
    repeated beyond it); the mean over ``d``, plus ``cell / (2 steps)`` an edge over the axes
    for the crossings (half a step: exact where the crossing is a step's middle, generous
    where it is interpolated between margins). An estimate, not a bound."""
    dims = len(shape)
    g = inside.reshape(shape).astype(float)
    idx = np.array(np.unravel_index(a, shape))
    sizes, errors = [], []
    for d in range(dims):
        on = axis == d
        c = g.sum(axis=d)  # each line along d: its inside poses
        if dims == 1:
            c = c + float(np.sum(frac[on] - 0.5))
        else:
            np.add.at(c, tuple(np.delete(idx, d, axis=0)[:, on]), frac[on] - 0.5)
        sizes.append(float(np.sum(c)) * cell)
        quad = 0.0
        for e in range(c.ndim):
            padded = np.concatenate([np.take(c, [0], axis=e), c, np.take(c, [-1], axis=e)], axis=e)
            quad += float(np.abs(np.diff(padded, n=2, axis=e)).sum()) / 8.0
        errors.append(quad * cell)
    return float(np.mean(sizes)), float(np.mean(errors)) + cell * len(frac) / (2.0 * steps * dims)


def size_unit(units: list[str]) -> str:
    """The unit of a grid cell's size from its coordinates' units: ``m3``, ``m2``, ``m2_rad``, ``rad``."""
    counts = Counter(units)
    return "_".join(u + (str(k) if k > 1 else "") for u, k in sorted(counts.items()))


def edges_reached(model: MechanismModel, ws: Workspace) -> list[str]:
    """The grid coordinates (``<name>_<unit>``) at whose first or last value an inside pose lies:
    there the workspace may go on beyond the grid, and its size is a lower bound."""
    shape = tuple(len(v) for _, v in ws.axes)
    inside = np.asarray(ws.inside, dtype=bool).reshape(shape)
    out = []
    for k, (i, v) in enumerate(ws.axes):
        if len(v) > 1 and (np.take(inside, 0, axis=k).any() or np.take(inside, -1, axis=k).any()):
            out.append(f"{model.task_names[i]}_{model.task_units[i]}")
    return out


def workspace_document(model: MechanismModel, ws: Workspace) -> dict:
    """``workspace.json`` (``docs/workspace.md``)."""
    names = [f"{model.task_names[i]}_{model.task_units[i]}" for i, _ in ws.axes]
    ins = ws.measure[ws.inside]
    edges = edges_reached(model, ws)
    return {
        "mechanism": model.name,
        "method": "grid of task poses solved by continuation from the reference configuration; inside: reached "
                  "within the joint limits, every singularity measure at least the threshold, and connected to the "
                  "start through such poses" + ("; at every combination of the orientation range's values"
                                                if ws.ranges else "") + " (docs/workspace.md)",
        "grid": {n: {"low": float(v[0]), "high": float(v[-1]), "count": int(len(v))} for n, (_, v) in zip(names, ws.axes)},
        "fixed": {f"{n}_{u}": float(ws.x[0, i]) for i, (n, u) in enumerate(zip(model.task_names, model.task_units))
                  if i not in [a for a, _ in ws.axes + ws.ranges]},
        "orientation_range": {f"{model.task_names[i]}_{model.task_units[i]}":
                              {"low": float(v[0]), "high": float(v[-1]), "count": int(len(v))} for i, v in ws.ranges},
        "singularity_threshold": ws.threshold,
        "poses": int(len(ws.x)), "reached": int(ws.reached.sum()), "inside": int(ws.inside.sum()),
        f"size_{ws.unit}": ws.size, f"size_error_{ws.unit}": ws.size_error, f"cell_{ws.unit}": ws.cell,
        # inside poses on the grid's edge: the workspace may go on beyond it
        "size_is_lower_bound": bool(edges), "inside_at_grid_edge": edges,
        "size_method": (f"boundary crossings of the grid's edges, {ws.refine} steps an edge" if ws.refine
                        else "inside poses times the cell"),
        "centre": dict(zip(names, (float(v) for v in ws.centre))),
        "inscribed_cube_half_width": ws.cube_half_width,
        "inscribed_cylinder_radius": ws.cylinder_radius,
        "dexterity": ({"min": float(ins.min()), "mean": float(ins.mean()), "median": float(np.median(ins)),
                       "max": float(ins.max())} if ins.size else None),
    }
