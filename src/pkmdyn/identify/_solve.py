"""Physically consistent least squares with standard errors; machine-independent.

Problem. With the stacked regressor ``W (m, p)`` and the measured efforts less the part that
does not depend on the parameters, ``y (m,)``, and the parameters written as ``theta = T s``
in coordinates ``s`` in which physical consistency is a box (non-negative friction,
positive masses, and the inertia triangle inequality, which is ``s >= 0`` for the second
moments of mass, e.g. a machine's principal inertias):

    minimise  |W T s - y|^2 + w^2 |C (T s - theta_0)|^2   subject to  lb <= s <= ub,

solved by bounded-variable least squares (``scipy.optimize.lsq_linear``, method ``bvls``)
on unit-norm columns. ``C = diag |W_k|`` and ``w = 1e-9``: the second term only fixes the
directions the data cannot see (a combination's split, an unexcited parameter) at the prior
``theta_0``; in every direction the data do see its pull is below ``(w / sigma_r)^2`` of the
estimate, 1e-6 or less for singular values above the rank tolerance.

Rows may carry weights (weighted least squares; :func:`._identify.fit_regressor` uses the
inverse residual level of each actuator from a first, unweighted pass, so that actuators with
different noise count fairly).

Uncertainty. ``sigma^2 = |y - W theta|^2 / (m - r)`` and the covariance of the base
parameters ``theta_b = theta_I + K theta_D`` is ``sigma^2 (W_I^T W_I)^-1`` (the reduced
normal matrix), the usual least-squares result for independent, equal-variance errors. Where
a bound is active the estimate is on that bound and the interval is one-sided in truth; such
parameters are listed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import lsq_linear

from ._base import BaseParameters

__all__ = ["Estimate", "constrained_least_squares", "PRIOR_WEIGHT"]

Array = NDArray[np.float64]

#: weight of the prior in column-scaled units (module docstring)
PRIOR_WEIGHT = 1e-9


@dataclass(frozen=True)
class Estimate:
    """A constrained fit. ``theta (p,)`` physical parameters; ``s (p,)`` solver coordinates;
    ``base_values, base_std (r,)`` the base parameters and their standard errors;
    ``residual (m,)`` [effort]; ``sigma`` the residual standard deviation [effort] with
    ``dof`` degrees of freedom; ``at_bound`` the solver coordinates on a bound."""

    theta: Array
    s: Array
    base_values: Array
    base_std: Array
    base_covariance: Array
    residual: Array
    sigma: float
    dof: int
    at_bound: tuple[int, ...]


def constrained_least_squares(
    W: Array,
    y: Array,
    base: BaseParameters,
    T: Array,
    lower: Array,
    upper: Array,
    theta_prior: Array,
    weights: Array | None = None,
) -> Estimate:
    """Solve the bounded problem of the module docstring and attach standard errors.

    ``weights (m,)``, when given, multiply the rows of ``W`` and ``y`` (weighted least squares,
    e.g. the inverse noise level of each actuator); ``residual`` stays unweighted and
    ``sigma`` is then the weighted residual's standard deviation.
    """
    W0 = np.asarray(W, dtype=float)
    w_rows = np.ones(W0.shape[0]) if weights is None else np.asarray(weights, dtype=float)
    W = W0 * w_rows[:, None]
    y = np.asarray(y, dtype=float) * w_rows
    m, p = W.shape
    r = base.rank
    if r == 0:
        raise ValueError("no base parameter: nothing to estimate")
    c = np.linalg.norm(W, axis=0)
    c = np.where(c > 0, c, 1.0)
    B = W @ T
    cs = np.linalg.norm(B, axis=0)
    cs = np.where(cs > 0, cs, np.linalg.norm(c[:, None] * T, axis=0))
    cs = np.where(cs > 0, cs, 1.0)
    M = np.vstack([B / cs, PRIOR_WEIGHT * (c[:, None] * T) / cs])
    rhs = np.concatenate([y, PRIOR_WEIGHT * c * np.asarray(theta_prior, dtype=float)])
    lb, ub = np.asarray(lower, dtype=float) * cs, np.asarray(upper, dtype=float) * cs
    z0 = np.clip(np.linalg.solve(T, np.asarray(theta_prior, dtype=float)) * cs, lb, ub)
    sol = lsq_linear(M, rhs, bounds=(lb, ub), method="bvls", tol=1e-13, max_iter=50 * p)
    # bvls keeps the bounds up to rounding; the clip removes only that rounding
    z = np.clip(sol.x, lb, ub) if sol.status >= 0 else z0
    s = z / cs
    theta = T @ s
    wres = y - W @ theta
    residual = wres / w_rows
    dof = m - r
    sigma = float(np.sqrt(wres @ wres / dof)) if dof > 0 else float("nan")
    ind = list(base.independent)
    A_I = W[:, ind] / c[ind]
    _, R = np.linalg.qr(A_I)
    Rinv = np.linalg.solve(R, np.eye(r))
    cov = sigma**2 * (Rinv @ Rinv.T) / np.outer(c[ind], c[ind])
    near = 1e-10 * max(float(np.max(np.abs(z))), 1e-300)
    at_bound = tuple(int(k) for k in range(p) if z[k] - lb[k] <= near or ub[k] - z[k] <= near)
    return Estimate(
        theta=theta,
        s=s,
        base_values=base.values(theta),
        base_std=np.sqrt(np.diag(cov)),
        base_covariance=cov,
        residual=residual,
        sigma=sigma,
        dof=dof,
        at_bound=at_bound,
    )
