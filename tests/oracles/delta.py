"""Clavel Delta robot (3-RUU / 3-R(SS)2, parallelogram forearms) oracle.

Closed-form inverse kinematics (per-leg tangent-half-angle solution),
velocity / acceleration by differentiating the leg constraint, the Jacobian
pair A pd = B thetad, and forward kinematics by three-sphere intersection.
References: R. Clavel, "DELTA, a fast robot with parallel geometry",
Proc. 18th Int. Symp. on Industrial Robots, Lausanne, 1988, pp. 91-100;
R. Clavel, US Patent 4,976,582 (1990); R. L. Williams II, "The Delta
Parallel Robot: Kinematics Solutions", Ohio University, 2015/2016;
Tsai, *Robot Analysis*, Wiley 1999 (Delta-type position/Jacobian analysis).

Frame and conventions
---------------------
* Base frame {O}: origin at the centre of the base joint circle, z axis
  vertical pointing UP, base plane z = 0.  The platform works below the
  base (p_z < 0).  The platform stays parallel to the base (pure translation);
  ``p`` is the platform centre.
* Leg i = 0,1,2 lies in the vertical plane of azimuth phi_i = 0, 120, 240 deg
  (plus an optional common offset); e_i = (cos phi_i, sin phi_i, 0) is the
  outward radial unit vector, z = (0,0,1).
* Actuated revolute of leg i: axis through A_i = R_b e_i, direction
  z x e_i (horizontal, tangent to the base circle).
* theta_i: angle of the upper arm from the horizontal plane, POSITIVE
  DOWNWARDS.  theta_i = 0: arm horizontal pointing radially outward.
  Elbow:            C_i = (R_b + L_A cos theta_i) e_i - L_A sin theta_i z
  Platform joint:   P_i = p + R_p e_i   (centre of the forearm parallelogram's
                    platform-side edge)
  Leg constraint:   |P_i - C_i|^2 = L_B^2.
* Branch ("elbow-out"): of the two IK roots, the one with the elbow C_i on the
  outer side of the line A_i -> P_i in the leg plane; equivalently
  B_ii = s_i . dC_i/dtheta_i > 0 with s_i = P_i - C_i, i.e. the root
  theta_i = atan2(F, E) + acos(-G / sqrt(E^2 + F^2)) of the per-leg equation
  E cos theta + F sin theta + G = 0 (see ``inverse_kinematics``).
Units: m, rad, s.
"""

from __future__ import annotations

import numpy as np

from ._batch import as_batch as _as_batch

Z_UP = np.array([0.0, 0.0, 1.0])


def leg_directions(offset=0.0):
    """Outward radial unit vectors e_i (3,3) at azimuth offset + (0,120,240) deg."""
    phi = offset + np.radians([0.0, 120.0, 240.0])
    return np.stack([np.cos(phi), np.sin(phi), np.zeros(3)], axis=-1)


def elbow_points(theta, R_b, L_A, offset=0.0):
    """Elbow centres C (n,3,3) [m] for actuated angles theta (n,3) [rad]."""
    theta = _as_batch(theta, 3)
    e = leg_directions(offset)[None]
    return (R_b + L_A * np.cos(theta))[..., None] * e - (L_A * np.sin(theta))[..., None] * Z_UP


def _coefficients(p, R_b, R_p, L_A, L_B, offset):
    """``E, F, G (n, 3)`` of each leg's equation ``E cos theta + F sin theta + G = 0``
    (:func:`inverse_kinematics`), from the platform centre ``p`` in each leg's plane."""
    p = _as_batch(p, 3)
    e = leg_directions(offset)
    t_dir = np.cross(Z_UP, e)
    q = p[:, None, :] + (R_p - R_b) * e[None]
    x = np.einsum("nki,ki->nk", q, e)
    y = np.einsum("nki,ki->nk", q, t_dir)
    z = q[..., 2]
    return -2.0 * L_A * x, 2.0 * L_A * z, x**2 + y**2 + z**2 + L_A**2 - L_B**2


def inverse_kinematics(p, R_b, R_p, L_A, L_B, offset=0.0):
    """Closed-form IK, elbow-out branch.  p (n,3) [m] -> theta (n,3) [rad].

    Per leg, with q = p + (R_p - R_b) e_i, x = q.e_i, y = q.(z x e_i), z = q_z:
      E cos theta + F sin theta + G = 0,
      E = -2 L_A x,  F = 2 L_A z,  G = x^2 + y^2 + z^2 + L_A^2 - L_B^2.
    Tangent half angle t = tan(theta/2):  (G - E) t^2 + 2 F t + (G + E) = 0,
    elbow-out root t = (-F - sqrt(E^2 + F^2 - G^2)) / (G - E)
                     = (G + E) / (-F + sqrt(E^2 + F^2 - G^2)),
    theta = 2 atan(t) in (-pi, pi).  Points out of reach (negative
    discriminant) give NaN.
    """
    E, F, G = _coefficients(p, R_b, R_p, L_A, L_B, offset)
    disc = E**2 + F**2 - G**2
    with np.errstate(invalid="ignore", divide="ignore"):
        sq = np.sqrt(disc)
        # numerically stable choice between the two equivalent expressions
        den1 = G - E
        den2 = -F + sq
        t = np.where(np.abs(den1) >= np.abs(den2), (-F - sq) / den1, (G + E) / den2)
    return 2.0 * np.arctan(t)


def inverse_kinematics_atan2(p, R_b, R_p, L_A, L_B, offset=0.0):
    """Second closed form of the same elbow-out root (phase form).

    theta = atan2(F, E) + acos(-G / sqrt(E^2 + F^2)), wrapped to (-pi, pi].
    """
    E, F, G = _coefficients(p, R_b, R_p, L_A, L_B, offset)
    with np.errstate(invalid="ignore"):
        th = np.arctan2(F, E) + np.arccos(-G / np.hypot(E, F))
    return np.angle(np.exp(1j * th))


def jacobian(p, theta, R_b, R_p, L_A, offset=0.0):
    """Jacobian pair of the Delta: A pd = B thetad.

    s_i = P_i - C_i = p + (R_p - R_b - L_A cos theta_i) e_i + L_A sin theta_i z
    A (n,3,3): row i = s_i^T
    B (n,3,3): diagonal, B_ii = s_i . dC_i/dtheta_i
               = -L_A s_i . (sin theta_i e_i + cos theta_i z)
    (elbow-out branch <=> B_ii > 0).  Returns (A, B, s) with s (n,3,3).
    """
    p = _as_batch(p, 3)
    theta = _as_batch(theta, 3)
    e = leg_directions(offset)[None]
    C = elbow_points(theta, R_b, L_A, offset)
    s = p[:, None, :] + R_p * e - C
    dC = -L_A * (np.sin(theta)[..., None] * e + np.cos(theta)[..., None] * Z_UP)
    Bd = np.einsum("nki,nki->nk", s, dC)
    A = s
    B = np.zeros(theta.shape + (3,))
    idx = np.arange(3)
    B[:, idx, idx] = Bd
    return A, B, s


def kinematics(p, R_b, R_p, L_A, L_B, pd=None, pdd=None, offset=0.0):
    """IK with rates and accelerations.

    p, pd, pdd (n,3) [m, m/s, m/s^2].  Returns dict:
      theta, thetad, thetadd (n,3)  [rad, rad/s, rad/s^2]
      A, B (n,3,3)                  Jacobian pair (A pd = B thetad)
      J (n,3,3)                     inverse Jacobian B^-1 A  (thetad = J pd)
      C (n,3,3)                     elbow centres [m];  P (n,3,3) platform joints [m]
    Derivation (differentiate s.s = L_B^2 twice):
      w1 = sin th e + cos th z,  w2 = cos th e - sin th z,
      sd = pd + L_A thd w1,
      thd  = s.pd / B_ii,
      thdd = (s.pdd + L_A thd^2 s.w2 + |sd|^2) / B_ii.
    """
    p = _as_batch(p, 3)
    n = p.shape[0]
    v = np.zeros((n, 3)) if pd is None else _as_batch(pd, 3)
    acc = np.zeros((n, 3)) if pdd is None else _as_batch(pdd, 3)
    theta = inverse_kinematics(p, R_b, R_p, L_A, L_B, offset)
    A, B, s = jacobian(p, theta, R_b, R_p, L_A, offset)
    e = leg_directions(offset)[None]
    Bd = np.diagonal(B, axis1=1, axis2=2)
    thd = np.einsum("nki,ni->nk", s, v) / Bd
    w1 = np.sin(theta)[..., None] * e + np.cos(theta)[..., None] * Z_UP
    w2 = np.cos(theta)[..., None] * e - np.sin(theta)[..., None] * Z_UP
    sd = v[:, None, :] + L_A * thd[..., None] * w1
    thdd = (np.einsum("nki,ni->nk", s, acc)
            + L_A * thd**2 * np.einsum("nki,nki->nk", s, w2)
            + np.einsum("nki,nki->nk", sd, sd)) / Bd
    J = A / Bd[..., None]
    C = elbow_points(theta, R_b, L_A, offset)
    return {"theta": theta, "thetad": thd, "thetadd": thdd, "A": A, "B": B,
            "J": J, "C": C, "P": p[:, None, :] + R_p * e}


def forward_kinematics(theta, R_b, R_p, L_A, L_B, offset=0.0):
    """Forward kinematics by three-sphere intersection.

    The platform centre lies on the three spheres of radius L_B centred at
    c_i = C_i - R_p e_i.  Trilateration in the frame (ex, ey, ez) built on
    c_0, c_1, c_2; of the two mirror solutions the one with the LOWER z
    (platform below the elbows) is returned.  theta (n,3) -> p (n,3) [m];
    NaN where the spheres do not meet.
    """
    theta = _as_batch(theta, 3)
    e = leg_directions(offset)[None]
    c = elbow_points(theta, R_b, L_A, offset) - R_p * e
    c0, c1, c2 = c[:, 0], c[:, 1], c[:, 2]
    d01 = c1 - c0
    d = np.linalg.norm(d01, axis=-1)
    ex = d01 / d[:, None]
    d02 = c2 - c0
    i = np.einsum("ni,ni->n", ex, d02)
    eyv = d02 - i[:, None] * ex
    j = np.linalg.norm(eyv, axis=-1)
    ey = eyv / j[:, None]
    ez = np.cross(ex, ey)
    # equal radii: r^2 terms cancel in the differences
    X = d / 2.0
    Y = (i**2 + j**2) / (2.0 * j) - i * X / j
    with np.errstate(invalid="ignore"):
        Zc = np.sqrt(L_B**2 - X**2 - Y**2)
    base = c0 + X[:, None] * ex + Y[:, None] * ey
    s1 = base + Zc[:, None] * ez
    s2 = base - Zc[:, None] * ez
    return np.where((s1[:, 2] <= s2[:, 2])[:, None], s1, s2)


def williams_irb360_geometry():
    """Delta geometry of the ABB FlexPicker IRB 360 as tabulated by Williams.

    Source: R. L. Williams II, "The Delta Parallel Robot: Kinematics
    Solutions", Ohio University (2015/2016), section "Practical revolute-input
    Delta robots": base equilateral-triangle side s_B = 0.567 m, platform
    triangle side s_P = 0.076 m, upper arm L = 0.524 m, forearm l = 1.244 m
    (h = 0.131 m is the parallelogram width, not needed here).  Williams puts
    the actuated-joint axes on the sides of the base triangle and the forearm
    parallelogram centres on the sides of the platform triangle, so the
    radial distances used here are the in-radii w_B = s_B sqrt(3)/6 and
    w_P = s_P sqrt(3)/6.
    Returns dict R_b, R_p, L_A, L_B [m].
    """
    sB, sP = 0.567, 0.076
    return {"R_b": sB * np.sqrt(3.0) / 6.0, "R_p": sP * np.sqrt(3.0) / 6.0,
            "L_A": 0.524, "L_B": 1.244}
