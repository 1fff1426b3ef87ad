"""Friction laws: regularised sign, Coulomb plus viscous, load-dependent hip-joint friction.

All laws oppose the relative velocity they are given and return the force or torque that
the joint *resists with*, so the power they dissipate is ``velocity . friction >= 0``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["regularised_sign", "coulomb_viscous", "hip_bearing_friction"]

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


def hip_bearing_friction(
    omega: Array,
    load: Array,
    platform_weight: float,
    hip_radius: float,
    hip_coefficient: float,
    thrust_radius: float,
    thrust_coefficient: float,
    eps: float,
) -> Array:
    """Hip-joint plus thrust-bearing friction torque on a platform, Eq. (16) of the hip paper.

        tau_mf = u(omega) (r_h mu_h F + r_t mu_t |F + m_m g|)

    ``omega (n, 3)`` [rad/s] platform angular velocity, ``load (n,)`` [N] hydraulic force,
    ``platform_weight`` = m_m g [N]. Returns ``(n, 3)`` [N m] in the base frame.
    """
    magnitude = hip_radius * hip_coefficient * np.abs(load) + thrust_radius * thrust_coefficient * np.abs(
        load + platform_weight
    )
    return regularised_sign(omega, eps, vector=True) * magnitude[..., None]
