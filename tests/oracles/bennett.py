"""Bennett linkage closed-form input-output oracle.

The Bennett linkage is the spatial 4R loop with zero joint offsets, opposite
links equal (a, alpha, b, beta, a, alpha, b, beta) and the Bennett condition
a / sin(alpha) = b / sin(beta).  References: G. T. Bennett, "A new
mechanism", Engineering 76 (1903) 777-778; G. T. Bennett, "The skew isogram
mechanism", Proc. London Math. Soc. (2nd ser.) 13 (1914) 151-173;
J. M. McCarthy, *Geometric Design of Linkages*, Springer 2000, ch. 9 / 10;
J. E. Baker, "An analysis of the Bennett linkage", Mech. Mach. Theory 23
(1988).

DH convention (classical Denavit-Hartenberg, zero offsets)
----------------------------------------------------------
  T_k = Rz(theta_k) Tx(a_k) Rx(alpha_k),   k = 1..4,
  (a_1, alpha_1) = (a, alpha), (a_2, alpha_2) = (b, beta),
  (a_3, alpha_3) = (a, alpha), (a_4, alpha_4) = (b, beta),
  loop closure:  T_1 T_2 T_3 T_4 = I (4x4).
theta_k is the rotation about joint axis z_k from the common normal x_{k-1}
(link k-1, the previous link) to x_k (link k), right-hand rule about z_k.
Joint 1 joins link 4 (b, beta) to link 1 (a, alpha); joint 2 joins link 1 to
link 2 (b, beta).  Angles rad, lengths m.

Input-output relation (adjacent joints 1 and 2):
  tan(theta_1/2) tan(theta_2/2) = K,  K = sin((beta + alpha)/2) / sin((beta - alpha)/2),
and, in this convention, theta_3 = -theta_1, theta_4 = -theta_2 (mod 2 pi).
"""

from __future__ import annotations

import numpy as np


def _wrap(a):
    return np.angle(np.exp(1j * a))


def bennett_b(a, alpha, beta):
    """Length b satisfying the Bennett condition a/sin(alpha) = b/sin(beta)."""
    return a * np.sin(beta) / np.sin(alpha)


def ratio_K(alpha, beta):
    """K = sin((beta+alpha)/2) / sin((beta-alpha)/2); requires alpha != beta."""
    return np.sin(0.5 * (beta + alpha)) / np.sin(0.5 * (beta - alpha))


def input_output(theta1, alpha, beta, theta1_d=None, theta1_dd=None):
    """theta_2 and its derivatives from theta_1 (all (n,) arrays, rad, rad/s, rad/s^2).

    theta_2 = 2 atan2(K cos(theta_1/2), sin(theta_1/2)), wrapped to (-pi, pi].
    With h = theta_1/2 and D = sin^2 h + K^2 cos^2 h:
      dtheta_2/dtheta_1   = g1 = -K / D
      d2theta_2/dtheta_1^2 = g2 = K (1 - K^2) sin(theta_1) / (2 D^2)
      theta_2_d  = g1 theta_1_d
      theta_2_dd = g2 theta_1_d^2 + g1 theta_1_dd
    Returns dict theta2, theta2_d, theta2_dd, g1, g2, and the remaining loop
    angles theta3 = -theta1, theta4 = -theta2 (wrapped) with their rates.
    """
    th1 = np.atleast_1d(np.asarray(theta1, float))
    th1d = np.zeros_like(th1) if theta1_d is None else np.atleast_1d(np.asarray(theta1_d, float))
    th1dd = np.zeros_like(th1) if theta1_dd is None else np.atleast_1d(np.asarray(theta1_dd, float))
    K = ratio_K(alpha, beta)
    h = 0.5 * th1
    th2 = _wrap(2.0 * np.arctan2(K * np.cos(h), np.sin(h)))
    D = np.sin(h) ** 2 + K**2 * np.cos(h) ** 2
    g1 = -K / D
    g2 = K * (1.0 - K**2) * np.sin(th1) / (2.0 * D**2)
    th2d = g1 * th1d
    th2dd = g2 * th1d**2 + g1 * th1dd
    return {"theta2": th2, "theta2_d": th2d, "theta2_dd": th2dd, "g1": g1, "g2": g2,
            "theta3": _wrap(-th1), "theta3_d": -th1d, "theta3_dd": -th1dd,
            "theta4": _wrap(-th2), "theta4_d": -th2d, "theta4_dd": -th2dd}


def dh_transform(theta, a, alpha):
    """T = Rz(theta) Tx(a) Rx(alpha); theta (n,) -> (n,4,4)."""
    th = np.atleast_1d(np.asarray(theta, float))
    ct, st = np.cos(th), np.sin(th)
    ca, sa = np.cos(alpha), np.sin(alpha)
    T = np.zeros(th.shape + (4, 4))
    T[..., 0, 0] = ct
    T[..., 0, 1] = -st * ca
    T[..., 0, 2] = st * sa
    T[..., 0, 3] = a * ct
    T[..., 1, 0] = st
    T[..., 1, 1] = ct * ca
    T[..., 1, 2] = -ct * sa
    T[..., 1, 3] = a * st
    T[..., 2, 1] = sa
    T[..., 2, 2] = ca
    T[..., 3, 3] = 1.0
    return T


def loop_transform(thetas, a, alpha, b, beta):
    """Loop product T_1 T_2 T_3 T_4 (n,4,4) for joint angles thetas (n,4)."""
    th = np.atleast_2d(np.asarray(thetas, float))
    T = dh_transform(th[:, 0], a, alpha)
    T = T @ dh_transform(th[:, 1], b, beta)
    T = T @ dh_transform(th[:, 2], a, alpha)
    return T @ dh_transform(th[:, 3], b, beta)


def joint_frames(thetas, a, alpha, b, beta):
    """Frames of the four joints in the frame of joint 1 (n,4,4,4).

    Frame k (k = 0..3) = T_1 ... T_k (frame 0 = identity); its z axis is
    joint axis k+1 and its origin lies on that axis.
    """
    th = np.atleast_2d(np.asarray(thetas, float))
    n = th.shape[0]
    params = [(a, alpha), (b, beta), (a, alpha), (b, beta)]
    out = np.empty((n, 4, 4, 4))
    T = np.broadcast_to(np.eye(4), (n, 4, 4)).copy()
    for k in range(4):
        out[:, k] = T
        T = T @ dh_transform(th[:, k], *params[k])
    return out
