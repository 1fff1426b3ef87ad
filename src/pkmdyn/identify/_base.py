"""Base parameters: the combinations of parameters that a regressor can separate.

Given a stacked regressor ``W (m, p)`` (rows: samples x actuators), the efforts depend on
``theta`` only through ``W theta``. Columns are first scaled to unit norm (``A = W C^-1``,
``C = diag |W_k|``) so that the rank test does not depend on the parameters' units. The
numerical rank ``r`` is the number of singular values of ``A`` above ``tol * sigma_1``; a
column-pivoted QR of ``A`` (LAPACK ``geqp3``) picks ``r`` independent columns ``I``, and the
remaining columns ``D`` are expressed in them, ``W_D = W_I K`` (least squares, exact when the
dependence is exact), so that

    W theta = W_I theta_b,    theta_b = theta_I + K theta_D,

and ``theta_b (r,)`` are the base parameters. A parameter whose column is zero (the motion does
not excite it) appears in no base parameter. A parameter ``k`` in ``I`` whose row of ``K`` is
zero is *separable*: its own value is a base parameter. Every other parameter enters the
torques only through a combination, and has no estimate of its own.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

from ..errors import ParameterError

__all__ = ["BaseParameters", "base_parameters", "DEFAULT_RANK_TOL"]

Array = NDArray[np.float64]

#: singular values of the column-scaled regressor below this fraction of the largest are zero
DEFAULT_RANK_TOL = 1e-6
#: entries of K (in column-scaled units) below this are rounding, not a dependence
_K_TOL = 1e-8


@dataclass(frozen=True)
class BaseParameters:
    """The identifiable structure of a regressor (see the module docstring).

    ``independent (r,)`` and ``dependent (d,)`` index the parameters; ``unexcited`` lists
    those whose column is zero. ``K (r, d)`` maps dependent parameters into the base
    parameters ``theta_b = theta[independent] + K theta[dependent]``. ``singular_values``
    are those of the column-scaled regressor and ``condition_number`` is the 2-norm
    condition number of its independent columns ``A_I``.
    """

    names: tuple[str, ...]
    independent: tuple[int, ...]
    dependent: tuple[int, ...]
    unexcited: tuple[int, ...]
    K: Array
    column_norms: Array
    singular_values: Array
    condition_number: float
    rank_tol: float

    @property
    def rank(self) -> int:
        return len(self.independent)

    def separable(self) -> tuple[int, ...]:
        """Parameters whose own value is a base parameter."""
        return tuple(j for i, j in enumerate(self.independent) if not np.any(self.K[i]))

    def terms(self, i: int) -> dict[str, float]:
        """Base parameter ``i`` as ``{name: coefficient}`` (the first term has coefficient 1)."""
        out = {self.names[self.independent[i]]: 1.0}
        for c, d in zip(self.K[i], self.dependent):
            if c != 0.0:
                out[self.names[d]] = float(c)
        return out

    def describe(self, i: int) -> str:
        """Base parameter ``i`` written out, e.g. ``"slider_viscous_Ns_m + 0.000253 * screw_viscous_Nms_rad"``."""
        parts = []
        for k, (name, c) in enumerate(self.terms(i).items()):
            if k == 0:
                parts.append(name)
            else:
                parts.append(f"{'+' if c > 0 else '-'} {abs(c):.6g} * {name}")
        return " ".join(parts)

    def values(self, theta: Array) -> Array:
        """Base parameters ``theta_b (r,)`` of a full parameter vector ``theta (p,)``."""
        theta = np.asarray(theta, dtype=float)
        return theta[list(self.independent)] + self.K @ theta[list(self.dependent)]

    def jacobian(self) -> Array:
        """``d theta_b / d theta (r, p)``."""
        G = np.zeros((self.rank, len(self.names)))
        G[np.arange(self.rank), list(self.independent)] = 1.0
        if self.dependent:
            G[:, list(self.dependent)] = self.K
        return G


def base_parameters(W: Array, names: tuple[str, ...], tol: float = DEFAULT_RANK_TOL) -> BaseParameters:
    """Rank-revealing decomposition of a stacked regressor ``W (m, p)`` (module docstring).
    ``tol`` must lie in (0, 1): at 1 no singular value counts, and the rank would be 0."""
    if not (np.isfinite(tol) and 0.0 < tol < 1.0):
        raise ParameterError(f"rank tolerance: {tol:g} must be a finite number in (0, 1)")
    W = np.asarray(W, dtype=float)
    p = W.shape[1]
    if len(names) != p:
        raise ValueError(f"{len(names)} names for {p} columns")
    norms = np.linalg.norm(W, axis=0)
    excited = np.flatnonzero(norms > 0.0)
    unexcited = tuple(int(k) for k in np.flatnonzero(~(norms > 0.0)))
    if excited.size == 0:
        return BaseParameters(tuple(names), (), (), unexcited, np.zeros((0, 0)), norms, np.zeros(0), np.inf, tol)
    A = W[:, excited] / norms[excited]
    sv = np.linalg.svd(A, compute_uv=False)
    r = int(np.sum(sv > tol * sv[0]))
    _, _, piv = scipy.linalg.qr(A, mode="economic", pivoting=True)
    ind_local = np.sort(piv[:r])
    dep_local = np.sort(piv[r:])
    A_I = A[:, ind_local]
    if dep_local.size:
        K_s = np.linalg.lstsq(A_I, A[:, dep_local], rcond=None)[0]
        K_s[np.abs(K_s) < _K_TOL] = 0.0
    else:
        K_s = np.zeros((r, 0))
    ind = excited[ind_local]
    dep = excited[dep_local]
    K = K_s / norms[ind][:, None] * norms[dep][None, :]
    s_I = np.linalg.svd(A_I, compute_uv=False)
    return BaseParameters(
        names=tuple(names),
        independent=tuple(int(k) for k in ind),
        dependent=tuple(int(k) for k in dep),
        unexcited=unexcited,
        K=K,
        column_norms=norms,
        singular_values=sv,
        condition_number=float(s_I[0] / s_I[-1]),
        rank_tol=tol,
    )
