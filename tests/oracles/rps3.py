"""Symmetric 3-RPS parallel manipulator: the parasitic motions in closed form.

References: K.-M. Lee & D. K. Shah, "Kinematic analysis of a three-degrees-of-freedom
in-parallel actuated manipulator", IEEE J. Robotics and Automation 4(3) (1988) 354-360;
J.-P. Merlet, *Parallel Robots*, 2nd ed., Springer 2006, §3.

Conventions
-----------
* Leg ``i`` at the angle ``th_i`` (0, 120, 240 deg): the revolute joint at the base point
  ``B_i = a (cos th_i, sin th_i, 0)``, its axis tangent to the base circle,
  ``t_i = (-sin th_i, cos th_i, 0)``; the spherical joint at the platform point
  ``C_i = p + R s_i``, ``s_i = b (cos th_i, sin th_i, 0)``; ``p`` the platform centre (base frame),
  the platform frame parallel to the base at the home pose.
* Each leg stays in the plane through ``B_i`` normal to ``t_i``: ``(C_i - B_i) . t_i = 0``, and
  as ``B_i . t_i = 0``: ``(p + R s_i) . t_i = 0``. The leg at 0 deg gives ``p_y = -b R21``; the sum
  and difference of the other two give ``R12 = R21`` and ``p_x = b (R11 - R22) / 2``.
* With the intrinsic XYZ angles ``R = Rx(alpha) Ry(beta) Rz(gamma)``:
  ``R11 = cb cg``, ``R12 = -cb sg``, ``R21 = sa sb cg + ca sg``, ``R22 = ca cg - sa sb sg``, so
  ``R12 = R21`` is ``tan gamma = -sa sb / (ca + cb)``.
"""

from __future__ import annotations

import numpy as np


def parasitic(alpha, beta, b):
    """The parasitic motions ``(x, y, gamma)`` (each (n,)) of the platform centre for the tilt
    angles ``alpha``, ``beta`` [rad] (intrinsic XYZ) and the platform radius ``b`` [m]."""
    alpha, beta = np.atleast_1d(np.asarray(alpha, float)), np.atleast_1d(np.asarray(beta, float))
    sa, ca, sb, cb = np.sin(alpha), np.cos(alpha), np.sin(beta), np.cos(beta)
    gamma = np.arctan2(-sa * sb, ca + cb)
    sg, cg = np.sin(gamma), np.cos(gamma)
    R11, R21, R22 = cb * cg, sa * sb * cg + ca * sg, ca * cg - sa * sb * sg
    return b * (R11 - R22) / 2.0, -b * R21, gamma


def rotation(alpha, beta, gamma):
    """``Rx(alpha) Ry(beta) Rz(gamma)`` (n, 3, 3)."""
    def rot(axis, q):
        c, s = np.cos(q), np.sin(q)
        out = np.zeros((len(q), 3, 3))
        i, j = [(1, 2), (2, 0), (0, 1)][axis]
        out[:, axis, axis] = 1.0
        out[:, i, i], out[:, j, j], out[:, i, j], out[:, j, i] = c, c, -s, s
        return out
    a, b, g = (np.atleast_1d(np.asarray(v, float)) for v in (alpha, beta, gamma))
    return rot(0, a) @ rot(1, b) @ rot(2, g)


def leg_tilt(p, R, a, b, h, th=0.0):
    """The platform point ``C`` (n, 3) of the leg at ``th`` and the leg's rotation about its
    revolute axis from the home pose (platform centre at height ``h``) [rad] (n,), positive by
    the right hand about ``t``."""
    e = np.array([np.cos(th), np.sin(th), 0.0])
    t = np.array([-np.sin(th), np.cos(th), 0.0])
    C = p + R @ (b * e)
    w0 = b * e + np.array([0.0, 0.0, h]) - a * e
    w = C - a * e
    # the angle from w0 to w about t, both normal to t: atan2((w0 x w) . t, w0 . w)
    return C, np.arctan2(np.cross(w0, w) @ t, w @ w0)
