"""Excitation trajectories: bounded finite Fourier series and their optimisation; machine-independent.

Each coordinate follows

    x(t) = c + h tanh f(t),   f(t) = a_0 + sum_{l=1..L} (a_l sin(l w t) + b_l cos(l w t)),

with ``w = 2 pi / T``, centre ``c = (x_max + x_min) / 2`` and half-range ``h = (x_max - x_min) / 2``.
The series is periodic with period ``T`` and stays strictly inside ``(x_min, x_max)`` for every
coefficient vector, so range limits need no penalty; its derivatives are exact:

    x' = h s f',   x'' = h s (f'' - 2 tanh(f) f'^2),   s = 1 - tanh(f)^2.

Optimisation: ``minimize_excitation`` minimises a scalar cost of the coefficient vector
(typically ``log10`` of the regressor's condition number plus penalties for the limits that
are not boxes) by L-BFGS-B with finite-difference gradients from a few random starts.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import minimize

__all__ = ["bounded_fourier", "minimize_excitation", "max_evaluations"]

Array = NDArray[np.float64]


def bounded_fourier(t: Array, period: float, coeffs: Array, low: float, high: float) -> tuple[Array, Array, Array]:
    """``x, x', x'' (n,)`` of the bounded series at ``t (n,)``; ``coeffs = (a_0, a_1, b_1, ..., a_L, b_L)``."""
    coeffs = np.asarray(coeffs, dtype=float)
    L = (coeffs.shape[0] - 1) // 2
    w = 2 * np.pi / period
    l = np.arange(1, L + 1)
    arg = w * np.asarray(t, dtype=float)[:, None] * l
    s, c = np.sin(arg), np.cos(arg)
    a, b = coeffs[1::2], coeffs[2::2]
    f = coeffs[0] + s @ a + c @ b
    fd = (c * (l * w)) @ a - (s * (l * w)) @ b
    fdd = -(s * (l * w) ** 2) @ a - (c * (l * w) ** 2) @ b
    th = np.tanh(f)
    sech2 = 1.0 - th * th
    half, mid = 0.5 * (high - low), 0.5 * (high + low)
    return mid + half * th, half * sech2 * fd, half * sech2 * (fdd - 2.0 * th * fd * fd)


def max_evaluations(n_vars: int, starts: int, iterations: int) -> int:
    """The most cost evaluations :func:`minimize_excitation` makes: ``4 starts`` draws plus, per
    refined start, ``2 iterations (n_vars + 1)`` (each iteration a finite-difference gradient of
    ``n_vars + 1`` evaluations and, typically, one line-search step)."""
    return 4 * starts + starts * 2 * iterations * (n_vars + 1)


def minimize_excitation(
    cost: Callable[[Array], float], n_vars: int, rng: np.random.Generator, starts: int = 3, iterations: int = 40,
    scale: float = 0.8,
) -> tuple[Array, float]:
    """The coefficient vector with the lowest cost found: the best of ``4 starts`` random draws
    (normal, standard deviation ``scale``) refines ``starts`` of them by L-BFGS-B, each limited
    to ``iterations`` iterations and ``2 iterations (n_vars + 1)`` cost evaluations, so the work
    is bounded by :func:`max_evaluations` (L-BFGS-B checks its own ``maxfun`` only between
    iterations; here the cost refuses the evaluation after the last, and the start ends with the
    best point it saw)."""
    draws = [rng.normal(0.0, scale, n_vars) for _ in range(4 * starts)]
    costs = [cost(z) for z in draws]
    best_z, best_c = draws[int(np.argmin(costs))], float(np.min(costs))
    if iterations < 1:
        return best_z, best_c
    maxfun = 2 * iterations * (n_vars + 1)
    for k in np.argsort(costs)[:starts]:
        seen: list[tuple[float, Array]] = []

        def counted(z: Array) -> float:
            if len(seen) >= maxfun:
                raise _BudgetSpent
            c = float(cost(z))
            seen.append((c, np.array(z, dtype=float)))
            return c

        try:
            res = minimize(counted, draws[k], method="L-BFGS-B",
                           options={"maxiter": iterations, "maxfun": maxfun, "eps": 1e-5})
            z_k, c_k = res.x, float(res.fun)
        except _BudgetSpent:
            c_k, z_k = min(seen, key=lambda p: p[0])
        if c_k < best_c:
            best_z, best_c = z_k, c_k
    return best_z, best_c


class _BudgetSpent(Exception):
    """The cost evaluations of one start are spent."""
