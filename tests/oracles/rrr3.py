"""3-RRR planar parallel robot oracle (actuated base revolutes).

Closed-form inverse kinematics per leg (circle / circle intersection),
analytic actuated-joint rates and accelerations, passive angles and the
Jacobian pair.  References: Gosselin & Angeles, "Singularity analysis of
closed-loop kinematic chains", IEEE Trans. Robot. Autom. 6(3), 1990,
281-290; Merlet, *Parallel Robots*, 2nd ed., Springer 2006, ch. 3 (planar
3-RRR); Tsai, *Robot Analysis*, Wiley 1999.

Frame and conventions
---------------------
* Base frame {O} in the plane, angles counter-clockwise (CCW) positive
  from the +x axis, units m, rad, s.
* Leg i = 0,1,2: base pivot A_i (3,2) in {O}; actuated revolute at A_i.
  Proximal link (length l1) from A_i to the elbow
      B_i = A_i + l1 (cos theta_i, sin theta_i);
  distal link (length l2) from B_i to the platform joint
      C_i = p + R(phi) c_i,
  where c_i (3,2) are the platform joint points in the platform frame,
  p = (x, y) and phi the platform pose, R(phi) the planar rotation.
* theta_i: ABSOLUTE angle of the proximal link from +x (CCW).
  psi_i:   ABSOLUTE angle of the distal link (direction B_i -> C_i).
  Relative passive angles (wrapped to (-pi, pi]):
      elbow angle    beta_i  = psi_i - theta_i
      platform angle gamma_i = phi - psi_i   (platform x-axis relative to the distal link)
* Branch sigma_i = +1 ("left" elbow): the elbow lies to the LEFT of the
  directed line A_i -> C_i, i.e. cross(C_i - A_i, B_i - A_i) > 0;
  sigma_i = -1: to the right.
"""

from __future__ import annotations

import numpy as np

from ._batch import as_batch as _as_batch


def _wrap(a):
    return np.angle(np.exp(1j * a))


def _cross2(u, v):
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def _perp(u):
    """E u with E = [[0,-1],[1,0]] (rotate by +90 deg)."""
    return np.stack([-u[..., 1], u[..., 0]], axis=-1)


def platform_points(pose, c):
    """C (n,3,2) platform joint points in {O}; r (n,3,2) = R(phi) c_i."""
    pose = _as_batch(pose, 3)
    ph = pose[:, 2]
    cs, sn = np.cos(ph)[:, None], np.sin(ph)[:, None]
    c = np.asarray(c, float)[None]
    r = np.stack([cs * c[..., 0] - sn * c[..., 1], sn * c[..., 0] + cs * c[..., 1]], -1)
    return pose[:, None, :2] + r, r


def inverse_kinematics(pose, A, c, l1, l2, sigma=(1, 1, 1), pose_d=None, pose_dd=None):
    """Closed-form IK with rates and accelerations.

    Inputs
      pose, pose_d, pose_dd (n,3): (x, y, phi) and time derivatives
        [m, m, rad; /s; /s^2]; A (3,2), c (3,2) [m]; l1, l2 [m] (scalars or (3,));
      sigma (3,) elbow branch per leg, +1 or -1 (see module doc).
    Position: d_i = C_i - A_i,  k_i = (|d_i|^2 + l1^2 - l2^2) / (2 l1),
      theta_i = atan2(d_y, d_x) + sigma_i acos(k_i / |d_i|).
    Velocity (differentiate |C_i - B_i|^2 = l2^2), s_i = C_i - B_i, r_i = R c_i,
      u_i = (cos theta_i, sin theta_i):
      A_i = [s_x, s_y, r_i x s_i],   B_ii = l1 (u_i x s_i)   (2-D cross),
      A pose_d = B thetad.
    Acceleration: sd = Cd - Bd,
      thetadd_i = (|sd|^2 + s.a + phidd (r x s) - phid^2 (s.r) + l1 thd^2 (s.u))
                  / (l1 (u x s)).
    Returns dict:
      theta, thetad, thetadd (n,3)   actuated angles and derivatives
      psi, psid, psidd (n,3)         absolute distal-link angles and derivatives
                                     (psid = (s x sd)/l2^2, psidd = (s x sdd)/l2^2)
      beta (n,3), gamma (n,3)        relative passive angles (elbow, platform)
      A, B (n,3,3)                   Jacobian pair, J (n,3,3) = B^-1 A (thetad = J pose_d)
      Bpts (n,3,2) elbows, C (n,3,2) platform joints [m]
    Unreachable poses give NaN.
    """
    pose = _as_batch(pose, 3)
    n = pose.shape[0]
    pd = np.zeros((n, 3)) if pose_d is None else _as_batch(pose_d, 3)
    pdd = np.zeros((n, 3)) if pose_dd is None else _as_batch(pose_dd, 3)
    A = np.asarray(A, float)
    l1 = np.broadcast_to(np.asarray(l1, float), (3,))[None]
    l2 = np.broadcast_to(np.asarray(l2, float), (3,))[None]
    sig = np.asarray(sigma, float)[None]
    C, r = platform_points(pose, c)
    d = C - A[None]
    dn = np.linalg.norm(d, axis=-1)
    k = (dn**2 + l1**2 - l2**2) / (2.0 * l1)
    with np.errstate(invalid="ignore"):
        theta = _wrap(np.arctan2(d[..., 1], d[..., 0]) + sig * np.arccos(k / dn))
    u = np.stack([np.cos(theta), np.sin(theta)], -1)
    Bp = A[None] + l1[..., None] * u
    s = C - Bp
    psi = np.arctan2(s[..., 1], s[..., 0])
    # Jacobian pair
    rxs = _cross2(r, s)
    Bd = l1 * _cross2(u, s)
    Amat = np.concatenate([s, rxs[..., None]], axis=-1)
    Bmat = np.zeros((n, 3, 3))
    idx = np.arange(3)
    Bmat[:, idx, idx] = Bd
    thd = np.einsum("nki,ni->nk", Amat, pd) / Bd
    # velocities of points
    phid, phidd = pd[:, 2][:, None], pdd[:, 2][:, None]
    Cd = pd[:, None, :2] + phid[..., None] * _perp(r)
    Bvel = (l1 * thd)[..., None] * _perp(u)
    sd = Cd - Bvel
    acc = pdd[:, None, :2]
    thdd = (np.einsum("nki,nki->nk", sd, sd) + np.einsum("nki,nki->nk", s, acc)
            + phidd * rxs - phid**2 * np.einsum("nki,nki->nk", s, r)
            + l1 * thd**2 * np.einsum("nki,nki->nk", s, u)) / Bd
    Cdd = acc + phidd[..., None] * _perp(r) - (phid**2)[..., None] * r
    Bacc = (l1 * thdd)[..., None] * _perp(u) - (l1 * thd**2)[..., None] * u
    sdd = Cdd - Bacc
    psid = _cross2(s, sd) / l2**2
    psidd = _cross2(s, sdd) / l2**2
    return {
        "theta": theta, "thetad": thd, "thetadd": thdd,
        "psi": psi, "psid": psid, "psidd": psidd,
        "beta": _wrap(psi - theta), "gamma": _wrap(pose[:, 2][:, None] - psi),
        "A": Amat, "B": Bmat, "J": Amat / Bd[..., None], "Bpts": Bp, "C": C,
    }


def symmetric_geometry(base_radius=0.5, platform_radius=0.1, l1=0.3, l2=0.3):
    """Documented default symmetric 3-RRR (not a published design).

    Base pivots on a circle of radius R_A at 90, 210, 330 deg; platform joints
    on a circle of radius R_c at the same angles in the platform frame
    (equilateral base and platform, as in the symmetric designs studied by
    Gosselin & Angeles and by Merlet).  Defaults: R_A = 0.5 m, R_c = 0.1 m,
    l1 = l2 = 0.3 m; a representative pose is (0, 0, 0) with sigma = (+1,+1,+1).
    Returns dict A (3,2), c (3,2), l1, l2.
    """
    ang = np.radians([90.0, 210.0, 330.0])
    A = base_radius * np.stack([np.cos(ang), np.sin(ang)], -1)
    c = platform_radius * np.stack([np.cos(ang), np.sin(ang)], -1)
    return {"A": A, "c": c, "l1": l1, "l2": l2}
