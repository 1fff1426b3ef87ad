"""The singularity measures of a mechanism's poses: each the ratio of the least to the largest
singular value of a dimensionless matrix (:class:`SingularityMeasures`), per sample by singular
value decompositions (:func:`singularity_measures`), and cheaper where only bounds or the least
over a motion are wanted: proven level bounds (:func:`least_measure_bounds`, a workspace's) and
the least of each over a motion, decided by the decompositions of the few samples that proven
brackets leave open (:func:`least_measures`, a run's and a sweep's). The bounds and brackets
are compiled (:mod:`._kernels`)."""

from __future__ import annotations

import threading
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ...model.compiler import MechanismModel
from ...model.topology import column_scale, constraint_jacobian, row_scale
from ._kernels import WIDEN_ABS, WIDEN_REL, measure_bounds, measure_brackets

__all__ = ["SingularityMeasures", "singularity_measures", "least_measure_bounds", "least_measures", "SCREEN_STRIDE"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class SingularityMeasures:
    """Per-sample distance to the two kinds of singularity, each the ratio of the smallest
    to the largest singular value (1 isotropic, 0 singular) of a dimensionless matrix:

    ``inverse`` (n,): of ``[Phi_q; tau_q]`` (with the idle rows): zero where the task
    coordinates no longer determine the joint coordinates (a leg stretched or folded, the
    Gosselin-Angeles type I / serial singularity); ``direct`` (n,): of ``[Phi_q; E_a]``
    (``E_a`` selecting the actuator coordinates): zero where the mechanism moves with its
    actuators locked (type II / parallel singularity; for at least as many actuators as
    degrees of freedom, the ``nq`` singular values of the tall matrix of a redundantly
    actuated mechanism; NaN for fewer); ``constraint`` (n,): of ``Phi_q`` (with the idle
    rows) alone, the smallest of its ``nq - dof`` singular values: zero where the loops gain a
    freedom (constraint singularity)."""

    inverse: Array
    direct: Array
    constraint: Array


def _ratio(M: Array) -> Array:
    sv = np.linalg.svd(M, compute_uv=False)
    return sv[..., -1] / np.maximum(sv[..., 0], 1e-300)


def singularity_measures(model: MechanismModel, q: Array, only: str | None = None) -> SingularityMeasures:
    """:class:`SingularityMeasures` at tree coordinates ``q (n, nq)`` (``kin.q``); ``only`` one of
    the fields' names: that measure alone computed (one singular value decomposition a sample
    instead of three), the others NaN."""
    if only not in (None, "inverse", "direct", "constraint"):
        raise ValueError(f"only: {only!r} is not a singularity measure (inverse, direct, constraint)")
    q = np.atleast_2d(np.asarray(q, dtype=float))
    _, J = constraint_jacobian(model, q)
    Js = J * row_scale(model)[None, :, None] * column_scale(model)[None, None, :]
    rows = model.solver_rows
    nr = model.row_loop.shape[0]
    n = q.shape[0]
    idle = np.broadcast_to(model.solver_idle * column_scale(model)[None, :], (n, *model.solver_idle.shape))
    none = np.full(n, np.nan)
    inverse = _ratio(np.concatenate([Js[:, rows], idle], axis=1)) if only in (None, "inverse") else none
    cut = rows[rows < nr]
    Phi = np.concatenate([Js[:, cut], idle], axis=1)
    constraint = (_ratio(Phi) if Phi.shape[1] else np.ones(n)) if only in (None, "constraint") else none
    if model.na >= model.nt and only in (None, "direct"):  # (redundant actuation: the tall matrix's nq values)
        Ea = np.zeros((n, model.na, model.nq))
        for i, c in enumerate(model.act_coord):
            Ea[:, i, c] = 1.0
        direct = _ratio(np.concatenate([Phi, Ea], axis=1))
    else:
        direct = none
    return SingularityMeasures(inverse=inverse, direct=direct, constraint=constraint)


#: each thread's buffers of :func:`_measure_arguments`' Jacobians, reused up to this many values
#: (a run's chunk of the Stewart platform's takes some 0.45 million, of the Delta robot's 0.44 million)
_SCRATCH_VALUES = 2_000_000
_scratch = threading.local()


def _measure_arguments(model: MechanismModel, q: Array) -> tuple:
    """The model's arrays of :func:`pkmdyn.multibody.kinematics.singularity._kernels.measure_bounds`
    and ``measure_brackets`` at ``q (n, nq)``, ``n >= 1``: the Jacobian, the row and column
    factors, the cut, task and idle rows, the actuated coordinates and whether the direct
    measure applies. The Jacobian is written into this thread's buffer (valid until its next
    call) where it fits :data:`_SCRATCH_VALUES`."""
    n, nrow = q.shape[0], model.row_loop.shape[0] + model.nt
    size = n * nrow * model.nq
    out = None
    if size <= _SCRATCH_VALUES:
        flat = getattr(_scratch, "J", None)
        if flat is None or flat.size < size or _scratch.val.size < n * nrow:
            _scratch.J, _scratch.val = np.empty(max(size, 1)), np.empty(max(n * nrow, 1))
        out = (_scratch.val[: n * nrow].reshape(n, nrow), _scratch.J[:size].reshape(n, nrow, model.nq))
    _, J = constraint_jacobian(model, q, out=out)
    cs = column_scale(model)
    rows = model.solver_rows
    nr = model.row_loop.shape[0]
    return (J, np.ascontiguousarray(row_scale(model)), np.ascontiguousarray(cs),
            np.ascontiguousarray(rows[rows < nr]), np.ascontiguousarray(rows[rows >= nr]),
            np.ascontiguousarray(model.solver_idle * cs[None, :]),
            np.ascontiguousarray(model.act_coord, dtype=np.int64), model.na == model.nt)


def least_measure_bounds(model: MechanismModel, q: Array, level: float, tight: bool = False
                         ) -> tuple[NDArray[np.bool_], Array]:
    """Cheap bounds on the least of the :class:`SingularityMeasures` at ``q (n, nq)`` (the
    direct one only for as many actuators as degrees of freedom), from a Cholesky factorisation
    of each matrix's Gram matrix (:mod:`pkmdyn.multibody.kinematics.singularity._kernels`): ``passed (n,)`` where every measure
    is proven above ``level`` (by more than the rounding of its singular value decomposition),
    and ``upper (n,)`` an upper bound of the least measure (to rounding). Where ``passed`` is
    False, nothing is proven either way. ``tight``: each largest singular value bounded within
    0.5 % to 12 % (power iterations, then a proof by Cholesky; some twice the cost), so that a
    pose is proven above a level it exceeds by more than that, where the cheaper bound may need
    its measure to exceed the level by up to the square root of the matrix's rows."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    n = q.shape[0]
    passed = np.ones((n, 3), dtype=np.bool_)  # per measure (True for the direct one where it does not apply)
    upper = np.ones((n, 3))
    if n:
        measure_bounds(*_measure_arguments(model, q), np.full(3, float(level)), bool(tight), passed, upper)
    return passed.all(axis=1), upper.min(axis=1)


#: every this many samples one is bracketed by :func:`least_measures` whatever its neighbours
#: (an anchor); the others, first screened by Weyl's inequality from their nearest anchor
#: (:func:`pkmdyn.multibody.kinematics.singularity._kernels.measure_brackets`)
SCREEN_STRIDE = 8
#: the :class:`SingularityMeasures` fields in the order of :func:`pkmdyn.multibody.kinematics.singularity._kernels.measure_bounds`
_MEASURES = ("constraint", "inverse", "direct")


def least_measures(model: MechanismModel, q: Array, below: dict[str, float] | None = None) -> dict[str, float]:
    """The least of each of the :class:`SingularityMeasures` over the samples ``q (n, nq)``,
    ``n >= 1`` (``direct`` NaN where it does not apply): the least of
    :func:`singularity_measures` ``(model, q)``'s fields, the same singular value decompositions
    deciding, at a fraction of the cost. With ``below`` (a least found elsewhere, e.g. over the
    earlier chunks of one motion; NaN or infinite entries for none), the least of it and of
    these samples, each measure's samples proven above its entry left out.

    Each measure of every sample is first bracketed, ``lo <= measure <= hi``, by proven bounds
    on its matrix's largest and least singular values (:func:`pkmdyn.multibody.kinematics.singularity._kernels._bracket`:
    iterations warm-started from the sample before, certified by Cholesky factorisations), the
    bracket widened by the rounding of a decomposition (relative 1e-8, absolute 1e-12); every
    :data:`SCREEN_STRIDE`-th sample is bracketed so, and the others only where Weyl's
    inequality from their nearest such sample does not already place them above the least
    (:func:`pkmdyn.multibody.kinematics.singularity._kernels.measure_brackets`). Only where ``lo``
    is at most the least ``hi`` of all samples (and ``below``) can a sample hold the least
    measure: the decompositions run there alone (a few samples along a smooth motion; every
    sample whose bracket was not found)."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    known = np.array([(below or {}).get(key, np.inf) for key in _MEASURES], dtype=float)
    known[~np.isfinite(known)] = np.inf
    lohi = np.ones((q.shape[0], 3, 2))
    measure_brackets(*_measure_arguments(model, q), SCREEN_STRIDE, known, lohi)
    lo = lohi[:, :, 0] * (1.0 - WIDEN_REL) - WIDEN_ABS
    hi = lohi[:, :, 1] * (1.0 + WIDEN_REL) + WIDEN_ABS
    direct = model.na == model.nt
    applies = [not np.all(lohi[:, k] == 1.0) for k in range(3)]  # (1, 1): no rows, or the direct one not applying
    least = np.ones(3)
    for k, key in enumerate(_MEASURES):
        if not applies[k]:  # no rows: the measure is 1 (the direct one not applying: NaN below)
            least[k] = min(1.0, known[k])
            continue
        # a sample whose bracket is not a number (a pose of non-finite coordinates) is decided by
        # its decomposition too: the least is then NaN, as the least of every decomposition is
        bad = ~(np.isfinite(lo[:, k]) & np.isfinite(hi[:, k]))
        top = min(np.min(hi[~bad, k]) if np.any(~bad) else np.inf, known[k])
        rows = np.flatnonzero((lo[:, k] <= top) | bad)
        found = getattr(singularity_measures(model, q[rows], only=key), key) if rows.size else np.empty(0)
        least[k] = float(np.min(np.append(found, known[k])))  # (each measure's own decompositions, on its own candidates; NaN kept)
    return {key: (float(least[k]) if (k < 2 or direct) else float("nan")) for k, key in enumerate(_MEASURES)}
