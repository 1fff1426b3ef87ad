"""Rotations, Euler-angle sequences and their rate maps, skew matrices.

Pure geometry: this module knows nothing about any machine. Every function takes a
leading sample axis ``n`` and broadcasts over it.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .errors import ParameterError

__all__ = [
    "skew",
    "cross",
    "dot",
    "axis_rotation",
    "check_sequence",
    "euler_to_matrix",
    "euler_kinematics",
]

Array = NDArray[np.float64]

_AXES = {"x": 0, "y": 1, "z": 2}


def skew(v: Array) -> Array:
    """Skew-symmetric matrix ``[v]x`` with ``[v]x @ w = v x w``; ``(..., 3) -> (..., 3, 3)``."""
    v = np.asarray(v, dtype=float)
    out = np.zeros(v.shape[:-1] + (3, 3))
    out[..., 0, 1] = -v[..., 2]
    out[..., 0, 2] = v[..., 1]
    out[..., 1, 0] = v[..., 2]
    out[..., 1, 2] = -v[..., 0]
    out[..., 2, 0] = -v[..., 1]
    out[..., 2, 1] = v[..., 0]
    return out


def cross(a: Array, b: Array) -> Array:
    """Cross product over the last axis, written out (faster than ``np.cross`` on batches and,
    by far, on two single vectors)."""
    if np.ndim(a) == 1 and np.ndim(b) == 1:
        a0, a1, a2 = (float(v) for v in a)
        b0, b1, b2 = (float(v) for v in b)
        return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack((a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0), axis=-1)


def dot(a: Array, b: Array) -> Array:
    """Dot product over the last axis: ``(..., 3), (..., 3) -> (...)``."""
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


def axis_rotation(axis: int, angle: Array) -> Array:
    """Rotation by ``angle`` [rad] about base axis 0, 1 or 2: ``(n,) -> (n, 3, 3)``."""
    angle = np.asarray(angle, dtype=float)
    c, s = np.cos(angle), np.sin(angle)
    out = np.zeros(angle.shape + (3, 3))
    i, j = (axis + 1) % 3, (axis + 2) % 3
    out[..., axis, axis] = 1.0
    out[..., i, i] = c
    out[..., j, j] = c
    out[..., i, j] = -s
    out[..., j, i] = s
    return out


def check_sequence(seq: str) -> str:
    """Validate a scipy-style Euler sequence: three of ``XYZ`` (intrinsic) or ``xyz`` (extrinsic).

    Consecutive axes must differ. Returns the sequence unchanged.
    """
    if (
        not isinstance(seq, str)
        or len(seq) != 3
        or not (seq.isupper() or seq.islower())
        or any(c.lower() not in _AXES for c in seq)
        or seq[0].lower() == seq[1].lower()
        or seq[1].lower() == seq[2].lower()
    ):
        raise ParameterError(
            f"euler_sequence: {seq!r} is not a valid Euler sequence "
            "(three axes from XYZ for intrinsic or xyz for extrinsic, no axis twice in a row)"
        )
    return seq


def _intrinsic(seq: str, angles: Array) -> tuple[list[int], Array]:
    """Express any sequence as intrinsic axes and the matching angle order.

    An extrinsic rotation ``xyz`` by (a, b, c) equals the intrinsic ``ZYX`` by (c, b, a).
    """
    if seq.isupper():
        return [_AXES[c.lower()] for c in seq], angles
    return [_AXES[c] for c in reversed(seq)], angles[..., ::-1]


def euler_to_matrix(seq: str, angles: Array) -> Array:
    """Rotation matrix of an Euler sequence: ``(n, 3)`` [rad] -> ``(n, 3, 3)``.

    Intrinsic ``"XYZ"`` gives ``R = Rx(a) @ Ry(b) @ Rz(c)`` (the spec's FE, AA, IER order).
    """
    axes, ang = _intrinsic(check_sequence(seq), np.asarray(angles, dtype=float))
    r = axis_rotation(axes[0], ang[..., 0])
    r = r @ axis_rotation(axes[1], ang[..., 1])
    return r @ axis_rotation(axes[2], ang[..., 2])


def euler_kinematics(
    seq: str, angles: Array, rates: Array, accels: Array
) -> tuple[Array, Array, Array]:
    """Rotation, angular velocity and angular acceleration from Euler angles and their rates.

    For an intrinsic sequence ``R = R1(q1) R2(q2) R3(q3)`` about base unit axes ``k1, k2, k3``
    the angular velocity in the base frame is

        omega = E(q) qdot,  E = [k1, R1 k2, R1 R2 k3]

    and its derivative ``omega_dot = E qddot + Edot qdot`` with
    ``d/dt (R1 k2) = (k1 q1dot) x (R1 k2)`` and
    ``d/dt (R1 R2 k3) = (k1 q1dot + R1 k2 q2dot) x (R1 R2 k3)``.

    Returns ``R (n, 3, 3)``, ``omega (n, 3)`` [rad/s] and ``omega_dot (n, 3)`` [rad/s^2], all in
    the base frame.
    """
    seq = check_sequence(seq)
    angles = np.asarray(angles, dtype=float)
    axes, q = _intrinsic(seq, angles)
    _, qd = _intrinsic(seq, np.asarray(rates, dtype=float))
    _, qdd = _intrinsic(seq, np.asarray(accels, dtype=float))
    r1 = axis_rotation(axes[0], q[..., 0])
    r12 = r1 @ axis_rotation(axes[1], q[..., 1])
    rot = r12 @ axis_rotation(axes[2], q[..., 2])
    e1 = np.zeros(q.shape)
    e1[..., axes[0]] = 1.0
    e2 = r1[..., :, axes[1]]
    e3 = r12[..., :, axes[2]]
    w1 = e1 * qd[..., 0:1]
    w12 = w1 + e2 * qd[..., 1:2]
    omega = w12 + e3 * qd[..., 2:3]
    omega_dot = (
        e1 * qdd[..., 0:1]
        + e2 * qdd[..., 1:2]
        + e3 * qdd[..., 2:3]
        + cross(w1, e2) * qd[..., 1:2]
        + cross(w12, e3) * qd[..., 2:3]
    )
    return rot, omega, omega_dot
