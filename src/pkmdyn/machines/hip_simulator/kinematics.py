"""Inverse kinematics of the 2(3PUS+S) hip simulator, Eq. (1)-(6) of the hip paper.

Vectorised over samples: every array has a leading sample axis ``n``; legs (modules)
``i = 1..3`` are axis ``-2`` of the per-leg arrays. Both platforms share the orientation
``R(t)`` and the two sliders on a screw are rigidly ``h1 - h2`` apart, so the two levers of
one module are parallel and move by the same velocity field: lever directions, angular
velocities and centre velocities/accelerations are the same for both platforms and are
stored once per module; positions are given per platform.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ...errors import MotionError, ParameterError, SingularityError, SingularityWarning, UnreachablePoseError
from ...errors import as_array, check_type
from ...profiles.orientation import OrientationMotion
from ...spatial import cross0, dot0, euler_kinematics
from .params import HipModel

__all__ = ["HipKinematics", "inverse_kinematics", "platform_kinematics", "DEFAULT_SINGULARITY_THRESHOLD"]

Array = NDArray[np.float64]

#: warn when 1 / cond(J_j) falls below this (the pose is near a J_a or J_b singularity)
DEFAULT_SINGULARITY_THRESHOLD = 1e-3


@dataclass(frozen=True)
class HipKinematics:
    """Kinematics of all bodies, per sample. Base frame O-XYZ, SI units.

    Platform and slider quantities
      ``t (n,)`` [s]; ``R (n, 3, 3)`` platform rotation; ``omega, omega_dot (n, 3)`` [rad/s,
      rad/s^2] platform angular velocity/acceleration; ``r (n, 3, 3)`` [m] vectors o_j a_ji
      [sample, leg, xyz]; ``L, Ld, Ldd (n, 2, 3)`` [m, m/s, m/s^2] slider positions,
      velocities, accelerations [sample, platform, leg] (Eq. 2, 3, 5).
    Jacobians (Eq. 3) -- identical for both platforms
      ``Ja (n, 3)`` diagonal of J_a (e_ji . e_z); ``Jb (n, 3, 3)`` rows (r_ji x e_ji);
      ``J (n, 3, 3)`` = J_a^-1 J_b, so ``Ld_j = J omega``; ``det_Ja, det_Jb, cond_J (n,)``.
    Levers (Eq. 4, 6) -- per module, both platforms alike
      ``d (n, 3, 3)`` [m] lever vector b -> a; ``d_dot, d_ddot`` its rates; ``e_lever`` unit
      vector; ``R_lever (n, 3, 3, 3)`` lever frame [sample, leg] (columns: x along the U
      joint's second axis, y = z x x, z from b to a); ``omega_lever, omega_lever_dot (n, 3,
      3)``; ``v_lever, a_lever (n, 3, 3)`` centre velocity/acceleration; ``c_lever (n, 2, 3,
      3)`` [m] centre positions [sample, platform, leg]; ``spin (n, 3)`` [rad/s] the lever's
      angular velocity about its own axis (zero for ``lever_spin = "perpendicular"``).
    """

    t: Array
    R: Array
    omega: Array
    omega_dot: Array
    r: Array
    L: Array
    Ld: Array
    Ldd: Array
    Ja: Array
    Jb: Array
    J: Array
    det_Ja: Array
    det_Jb: Array
    cond_J: Array
    d: Array
    d_dot: Array
    d_ddot: Array
    e_lever: Array
    R_lever: Array
    omega_lever: Array
    omega_lever_dot: Array
    v_lever: Array
    a_lever: Array
    c_lever: Array
    spin: Array


def _unreachable(model: HipModel, t: Array, reach2: Array) -> None:
    rows, legs = np.nonzero(~(reach2 > 0.0))
    k = int(np.argmin(rows))
    row, leg = int(rows[k]), int(legs[k])
    horiz = np.sqrt(max(model.geometry.l**2 - float(reach2[row, leg]), 0.0))
    raise UnreachablePoseError(
        f"t = {t[row]:.6g} s (sample {row + 1}): leg {leg + 1} cannot reach its platform: the horizontal "
        f"distance {horiz:.4f} m from the screw to the S joint is not less than the lever length "
        f"{model.geometry.l:.4f} m"
    )


def _last(x: Array) -> Array:
    """Internal ``(3, leg, n)`` -> the documented ``(n, leg, 3)`` (a view, no copy)."""
    return x.transpose(2, 1, 0)


def _check_platform_motion(model: object, t: object, R: object, omega: object, omega_dot: object,
                           singularity_threshold: object) -> tuple[Array, Array, Array, Array]:
    """Entry check of :func:`platform_kinematics`: types, shapes ``t (n,), R (n, 3, 3), omega,
    omega_dot (n, 3)``, finite values, ``R`` orthonormal with det +1 (to 1e-6)."""
    check_type(model, HipModel, "model", ParameterError)
    t = as_array(t, (None,), "t", MotionError)
    n = t.shape[0]
    R = as_array(R, (n, 3, 3), "R", MotionError)
    omega = as_array(omega, (n, 3), "omega", MotionError)
    omega_dot = as_array(omega_dot, (n, 3), "omega_dot", MotionError)
    for name, a in (("t", t), ("R", R), ("omega", omega), ("omega_dot", omega_dot)):
        bad = ~np.isfinite(a.reshape(n, -1)).all(axis=1)
        if bad.any():
            raise MotionError(f"{name}: sample {int(np.flatnonzero(bad)[0]) + 1} is not finite")
    err = np.abs(np.einsum("nki,nkj->nij", R, R) - np.eye(3)).max(axis=(1, 2)) if n else np.zeros(0)
    bad = ~(err <= 1e-6) | ~(np.linalg.det(R) > 0) if n else np.zeros(0, bool)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise MotionError(f"R: sample {k + 1} is not a rotation matrix (|R^T R - I| = {err[k]:.3g}, det = "
                          f"{np.linalg.det(R[k]):.6g}); expected orthonormal with det +1")
    _check_threshold(singularity_threshold)
    return t, R, omega, omega_dot


def _check_threshold(singularity_threshold: object) -> None:
    if isinstance(singularity_threshold, bool) or not isinstance(singularity_threshold, (int, float, np.floating)) \
            or not 0 <= singularity_threshold <= 1:
        raise ParameterError(f"singularity_threshold: expected a number in [0, 1], got {singularity_threshold!r}")


def platform_kinematics(
    model: HipModel,
    t: Array,
    R: Array,
    omega: Array,
    omega_dot: Array,
    singularity_threshold: float = DEFAULT_SINGULARITY_THRESHOLD,
    check_conditioning: bool = True,
) -> HipKinematics:
    """All body kinematics from the platform motion ``R (n,3,3), omega, omega_dot (n,3)``.

    Solves, for each leg i and platform j, the loop closure of Eq. (1),
    ``|o_j + R r_ai - (A_i + L_ji e_z)| = l``, on the branch with the slider below the S joint
    (Eq. 2), then differentiates it twice (Eq. 3, 5):

        Ld = d . (omega x r) / d_z,   Ldd = (d . a_a + |d_dot|^2) / d_z,

    with ``d = a - b`` the lever vector, ``a_a = omega_dot x r + omega x (omega x r)``. Lever
    angular velocity: the U joint's first axis t_i is fixed in the slider and its second axis is
    perpendicular to t_i and to the lever, so ``omega_l = omega_perp + s e`` with
    ``omega_perp = d x d_dot / l^2`` (the paper's Eq. 4) and the spin
    ``s = (omega_perp . t)(t . e) / (1 - (t . e)^2)`` that keeps ``omega_l`` in the plane of the
    two U axes; ``omega_l_dot`` is its exact derivative (Eq. 6 plus the spin rate).

    Internally every vector is held component-first with the sample axis innermost,
    ``(3, leg, n)``, so that each component of each leg is a contiguous run of samples; the
    returned fields are views in the documented layout.
    """
    t, R, omega, omega_dot = _check_platform_motion(model, t, R, omega, omega_dot, singularity_threshold)
    return _platform_kinematics(model, t, R, omega, omega_dot, singularity_threshold, check_conditioning)


def _platform_kinematics(model: HipModel, t: Array, R: Array, omega: Array, omega_dot: Array,
                         singularity_threshold: float = DEFAULT_SINGULARITY_THRESHOLD,
                         check_conditioning: bool = True) -> HipKinematics:
    """:func:`platform_kinematics` without its entry checks, for callers whose ``R`` comes from
    :func:`~pkmdyn.spatial.euler_kinematics` of validated angles (a rotation by construction):
    the checks cost about a third of the batched hot path."""
    g = model.geometry
    n = t.shape[0]
    l2 = g.l * g.l
    # r_ji = R r_ai, internal layout (3, leg, n)
    r = np.einsum("nxk,ik->xin", R, g.r_a, optimize=False)
    dx = r[0] - g.A[:, 0, None]
    dy = r[1] - g.A[:, 1, None]
    reach2 = l2 - dx * dx - dy * dy
    if not np.all(reach2 > 0.0):
        _unreachable(model, t, reach2.T)
    dz = np.sqrt(reach2)
    d = np.stack((dx, dy, dz))
    L2 = g.h[1] + r[2] - dz  # Eq. (2), lower platform
    w = np.ascontiguousarray(omega.T)[:, None, :]
    wd = np.ascontiguousarray(omega_dot.T)[:, None, :]
    v_a = cross0(w, r)
    Ld = dot0(d, v_a) / dz  # Eq. (3)
    d_dot = v_a
    d_dot[2] -= Ld
    a_a = cross0(wd, r)
    a_a += cross0(w, cross0(w, r))
    Ldd = (dot0(d, a_a) + dot0(d_dot, d_dot)) / dz  # Eq. (5)
    d_ddot = a_a
    d_ddot[2] -= Ldd
    e = d / g.l
    Ja = e[2]
    Jb = cross0(r, e)
    J = Jb / Ja
    w_perp = cross0(d, d_dot) / l2  # Eq. (4)
    wd_perp = cross0(d, d_ddot) / l2  # Eq. (6)
    tt = g.t.T[:, :, None]  # (3, leg, 1)
    if g.lever_spin == "u_joint":
        c = dot0(tt, e)
        one_c2 = 1.0 - c * c
        if np.any(one_c2 < 1e-12):
            row = int(np.flatnonzero((one_c2 < 1e-12).any(axis=0))[0])
            raise SingularityError(f"t = {t[row]:.6g} s: a lever is aligned with its U joint's first axis")
        wt = dot0(w_perp, tt)
        spin = wt * c / one_c2
        e_dot = d_dot / g.l
        c_dot = dot0(tt, e_dot)
        wt_dot = dot0(wd_perp, tt)
        spin_dot = (wt_dot * c + wt * c_dot) / one_c2 + 2.0 * wt * c * c * c_dot / (one_c2 * one_c2)
        omega_l = w_perp + spin * e
        omega_l_dot = wd_perp + spin_dot * e + spin * e_dot
    else:
        spin = np.zeros((3, n))
        omega_l = w_perp
        omega_l_dot = wd_perp
    v_lever = 0.5 * d_dot
    v_lever[2] += Ld
    a_lever = 0.5 * d_ddot
    a_lever[2] += Ldd
    x_axis = cross0(tt, e)
    x_axis /= np.sqrt(dot0(x_axis, x_axis))
    frame = np.stack((x_axis, cross0(e, x_axis), e))  # (column, row, leg, n)
    dh = g.h[0] - g.h[1]
    c2 = np.empty((3, 3, n))
    c2[0] = g.A[:, 0, None] + 0.5 * dx
    c2[1] = g.A[:, 1, None] + 0.5 * dy
    c2[2] = L2 + 0.5 * dz
    c1 = c2.copy()
    c1[2] += dh
    det_Ja = Ja[0] * Ja[1] * Ja[2]
    det_Jb = dot0(Jb[:, 0], cross0(Jb[:, 1], Jb[:, 2]))
    J_n = _last(J)  # (n, leg, 3): row i of J is leg i
    if check_conditioning:
        cond_J = np.linalg.cond(J_n)
        near = np.flatnonzero(~(1.0 / cond_J >= singularity_threshold))
        if near.size:
            k = int(near[np.argmax(cond_J[near])])
            warnings.warn(
                f"{near.size} sample(s) near a singularity (1/cond(J) < {singularity_threshold:g}); the "
                f"worst at t = {t[k]:.6g} s (sample {k + 1}): cond(J) = {cond_J[k]:.3g}, "
                f"det(J_a) = {det_Ja[k]:.3g}, det(J_b) = {det_Jb[k]:.3g} m^3",
                SingularityWarning,
                stacklevel=2,
            )
    else:
        cond_J = np.full(n, np.nan)
    return HipKinematics(
        t=t,
        R=R,
        omega=omega,
        omega_dot=omega_dot,
        r=_last(r),
        L=np.stack((L2 + dh, L2)).transpose(2, 0, 1),
        Ld=np.stack((Ld, Ld)).transpose(2, 0, 1),
        Ldd=np.stack((Ldd, Ldd)).transpose(2, 0, 1),
        Ja=Ja.T,
        Jb=_last(Jb),
        J=J_n,
        det_Ja=det_Ja,
        det_Jb=det_Jb,
        cond_J=cond_J,
        d=_last(d),
        d_dot=_last(d_dot),
        d_ddot=_last(d_ddot),
        e_lever=_last(e),
        R_lever=frame.transpose(3, 2, 1, 0),
        omega_lever=_last(omega_l),
        omega_lever_dot=_last(omega_l_dot),
        v_lever=_last(v_lever),
        a_lever=_last(a_lever),
        c_lever=np.stack((c1, c2)).transpose(3, 0, 2, 1),
        spin=spin.T,
    )


def inverse_kinematics(
    model: HipModel,
    motion: OrientationMotion,
    singularity_threshold: float = DEFAULT_SINGULARITY_THRESHOLD,
) -> HipKinematics:
    """Inverse kinematics along a motion (Euler angles and rates -> every body's motion)."""
    check_type(model, HipModel, "model", ParameterError)
    check_type(motion, OrientationMotion, "motion", MotionError)
    _check_threshold(singularity_threshold)
    R, omega, omega_dot = euler_kinematics(model.geometry.euler_sequence, motion.angles, motion.rates, motion.accels)
    return _platform_kinematics(model, motion.t, R, omega, omega_dot, singularity_threshold)
