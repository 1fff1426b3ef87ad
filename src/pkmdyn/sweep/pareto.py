"""Pareto set and best design of a table of objective values."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

__all__ = ["pareto_mask", "minimised", "best_index"]

Array = NDArray[np.float64]


def minimised(values: Array, senses: Sequence[str]) -> Array:
    """Objective values ``(n, k)`` turned into quantities to minimise (``"max"`` columns negated)."""
    sign = np.array([-1.0 if s == "max" else 1.0 for s in senses])
    return np.asarray(values, dtype=float) * sign


def pareto_mask(F: Array, chunk: int = 256) -> NDArray[np.bool_]:
    """Non-dominated rows of ``F (n, k)`` (every column minimised).

    Row i is dominated when some row j is no worse in every objective and strictly better in
    one: ``all(F_j <= F_i) and any(F_j < F_i)``. Equal rows do not dominate each other, so
    duplicates of a Pareto point all belong to the set. ``O(n^2 k)`` comparisons, ``chunk``
    rows at a time.
    """
    F = np.asarray(F, dtype=float)
    if F.ndim != 2:
        raise ValueError(f"F must be (n, k), got shape {F.shape}")
    n = F.shape[0]
    keep = np.ones(n, dtype=bool)
    for s in range(0, n, chunk):
        blk = F[s:s + chunk]
        no_worse = np.all(F[None, :, :] <= blk[:, None, :], axis=-1)
        better = np.any(F[None, :, :] < blk[:, None, :], axis=-1)
        keep[s:s + chunk] = ~np.any(no_worse & better, axis=1)
    return keep


def best_index(F: Array) -> int:
    """The row best in the first column, ties broken by the next columns, then by position:
    always a member of the Pareto set."""
    F = np.asarray(F, dtype=float)
    order = np.lexsort(tuple(F[:, k] for k in range(F.shape[1] - 1, -1, -1)))
    return int(order[0])
