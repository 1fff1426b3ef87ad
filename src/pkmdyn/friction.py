"""Friction laws of any machine: the regularised sign and Coulomb plus viscous friction.

All laws oppose the relative velocity they are given and return the force or torque that
the joint *resists with*, so the power they dissipate is ``velocity . friction >= 0``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["regularised_sign", "coulomb_viscous"]

Array = NDArray[np.float64]


def regularised_sign(w: Array, eps: float, vector: bool) -> Array:
    """``u(w) = w / sqrt(|w|^2 + eps^2)``: the sign (or unit direction) made smooth at rest.

    ``vector=True``: ``w (..., 3)`` is an angular velocity and the norm is taken over the last
    axis; otherwise ``w`` holds scalar velocities. ``|u| < 1`` always, and ``u(0) = 0``.
    """
    w = np.asarray(w, dtype=float)
    norm2 = np.sum(w * w, axis=-1, keepdims=True) if vector else w * w
    return w / np.sqrt(norm2 + eps * eps)


def coulomb_viscous(w: Array, coulomb: float, viscous: float, eps: float, vector: bool) -> Array:
    """Coulomb plus viscous friction ``coulomb * u(w) + viscous * w`` (spec, "Loads and friction").

    ``vector=True`` treats the last axis of ``w`` as a 3-vector (relative angular velocity of
    a joint); otherwise ``w`` holds scalar velocities.
    """
    w = np.asarray(w, dtype=float)
    return coulomb * regularised_sign(w, eps, vector) + viscous * w
