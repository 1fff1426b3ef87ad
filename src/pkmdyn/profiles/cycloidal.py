"""Cycloidal rest-to-rest motion, Eq. 84 of the PDM paper.

``s(t) = S (t/T - sin(2 pi t/T) / (2 pi))`` for ``t`` in ``[0, T]``: zero velocity and zero
acceleration at both ends, displacement ``S`` at ``t = T``. No machine knowledge here.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import MotionError

__all__ = ["cycloidal"]

Array = NDArray[np.float64]


def cycloidal(t: Array, stroke: Array, period: float) -> tuple[Array, Array, Array]:
    """Displacement, velocity and acceleration of Eq. 84.

    ``t`` (n,) [s] within ``[0, period]``; ``stroke`` (k,) amplitudes ``S`` in any unit u.
    Returns three (n, k) arrays [u, u/s, u/s^2]:
    ``s = S (tau - sin(2 pi tau) / (2 pi))``, ``s_dot = S (1 - cos(2 pi tau)) / T``,
    ``s_ddot = 2 pi S sin(2 pi tau) / T^2`` with ``tau = t / T``.
    """
    t = np.asarray(t, dtype=float).reshape(-1)
    stroke = np.atleast_1d(np.asarray(stroke, dtype=float))
    if not period > 0:
        raise MotionError(f"cycloidal motion: period_s must be > 0, got {period}")
    if t.size and (t.min() < -1e-12 * period or t.max() > period * (1 + 1e-12)):
        raise MotionError(f"cycloidal motion: time {t.min() if t.min() < 0 else t.max():g} s is outside [0, {period:g}] s")
    tau = (t / period)[:, None]
    w = 2.0 * np.pi * tau
    s = stroke * (tau - np.sin(w) / (2.0 * np.pi))
    sd = stroke * (1.0 - np.cos(w)) / period
    sdd = stroke * 2.0 * np.pi * np.sin(w) / period**2
    return s, sd, sdd
