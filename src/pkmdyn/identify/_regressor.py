"""Regressors of efforts that are affine in a parameter vector; machine-independent.

A machine's inverse dynamics ``u = Y(q, qd, qdd, load) theta + u_0`` is affine in its
friction coefficients and inertial parameters ``theta (p,)`` once every other parameter is
held (geometry, gravity, the friction regularisation, and the products that make it
bilinear, written as products that are parameters of their own). An affine map is recovered exactly from ``p + 1``
evaluations: ``u_0 = u(0)`` and column ``k`` of ``Y`` is ``u(e_k) - u(0)``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["Regressor", "affine_regressor"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Regressor:
    """``u = Y theta + offset`` for every sample.

    ``Y (n, nu, p)`` [effort per parameter unit], ``offset (n, nu)`` [effort] the part that
    does not depend on ``theta``; ``names (p,)`` the parameters with their unit suffix.
    """

    Y: Array
    offset: Array
    names: tuple[str, ...]

    def efforts(self, theta: Array) -> Array:
        """``Y theta + offset (n, nu)``."""
        return np.einsum("nup,p->nu", self.Y, np.asarray(theta, dtype=float)) + self.offset

    def stacked(self) -> Array:
        """``Y`` with samples and actuators flattened, ``(n nu, p)`` (sample-major)."""
        n, nu, p = self.Y.shape
        return self.Y.reshape(n * nu, p)


def affine_regressor(efforts: Callable[[Array], Array], names: tuple[str, ...]) -> Regressor:
    """Columns of an affine effort map ``efforts(theta) -> (n, nu)`` by unit vectors.

    Exact up to rounding for any map that is affine in ``theta``; the caller is responsible
    for that (a map with a product of two entries of ``theta`` is not affine).
    """
    p = len(names)
    offset = np.asarray(efforts(np.zeros(p)), dtype=float)
    cols = []
    for k in range(p):
        e = np.zeros(p)
        e[k] = 1.0
        cols.append(np.asarray(efforts(e), dtype=float) - offset)
    return Regressor(np.stack(cols, axis=-1), offset, tuple(names))
