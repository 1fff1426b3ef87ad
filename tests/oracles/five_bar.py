"""Planar five-bar linkage (2 DOF, base revolutes driven by geared motors): closed-form
kinematics (inverse, and direct with both end-point solutions), joint efforts and motor
torques for a prescribed motion of the end point.

References: L.-W. Tsai, *Robot Analysis*, Wiley 1999 (planar five-bar, ch. 2 and 8);
J.-P. Merlet, *Parallel Robots*, 2nd ed., Springer 2006 (ch. 3 and 9); H. Goldstein,
*Classical Mechanics*, 3rd ed. (Lagrange's equations, virtual work); for the drive:
any text on geared servo drives (reflected inertia ``N^2 I_r``, ideal transmission).

Plane and conventions
---------------------
* The mechanism moves in a vertical plane ``y = y0`` of the base frame. Planar vectors
  are ``(x, z)`` pairs of base-frame components. Angles are measured from +x toward +z
  (counter-clockwise as seen with x to the right and z up, i.e. rotations about -y).
* Leg i = 0, 1: base pivot ``A_i``; proximal link of length ``l1_i`` at absolute angle
  ``phi_i`` to the elbow ``B_i = A_i + l1_i e(phi_i)``; distal link of length ``l2_i``
  at absolute angle ``psi_i`` from ``B_i`` to the end point ``P = B_i + l2_i e(psi_i)``.
  ``e(a) = (cos a, sin a)``, ``n(a) = (-sin a, cos a)``.
* Branch ``sigma_i = +1``: the elbow lies to the left of the directed line
  ``A_i -> P`` (``cross(P - A_i, B_i - A_i) > 0``, ``cross(a, b) = a_x b_z - a_z b_x``),
  ``-1`` to the right:
  ``phi_i = atan2(d_z, d_x) + sigma_i acos((|d|^2 + l1^2 - l2^2) / (2 l1 |d|))``,
  ``d = P - A_i``.
* Joint coordinate of the driven base joint: ``q_i = joint_sign_i * phi_i``.
  ``joint_sign = +1`` is a revolute axis along -y (the angle grows counter-clockwise),
  ``-1`` an axis along +y.
* Each link's centre of mass is given in its own frame: ``com = (along, across)``, along
  the link (from its proximal end toward its distal end) and along ``n`` of the link
  angle. ``inertia`` is the centroidal moment about the plane normal (the base frame's
  ``I_yy`` of the body's tensor; the other components do no work in a planar motion).
* Drive i: motor angle ``theta_i = N_i q_i``; motor torque (motor side)
  ``tau_i = u_i / N_i + I_r,i theta_dd_i + C_i sgn_eps(theta_d_i) + b_i theta_d_i``,
  with ``u_i`` the joint effort (mechanism side, along ``q_i``) and
  ``sgn_eps(x) = x / sqrt(x^2 + eps^2)``, ``eps = 1e-3 rad/s``.

Dynamics route: virtual work. Every body's centre-of-mass velocity and angular velocity is
linear in the end point's rate ``Pd``; with those Jacobians ``Jc_b``, ``Jw_b`` the
generalised force in the task coordinates is
``Q = sum_b Jc_b^T m_b (a_b - g) + Jw_b^T I_b alpha_b`` and the joint efforts solve
``H^T u = Q``, ``H = dq/dP`` (``qd = H Pd``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ._batch import as_batch as _as_batch

from ._planar import G0, cross as _cross, dot as _dot, e as _e, n as _n, perp as _perp  # noqa: F401
from ._planar import EPS_ROT, regularised_sign, sine_motion  # noqa: F401  (re-exported)
from . import _planar


@dataclass
class FiveBar:
    """Geometry, inertia and drives of a planar five-bar (every array is per leg, (2,...))."""

    base: np.ndarray                    # (2, 2) A_i, (x, z) [m]
    l1: np.ndarray                      # (2,) proximal lengths [m]
    l2: np.ndarray                      # (2,) distal lengths [m]
    sigma: np.ndarray                   # (2,) elbow branch, +1 / -1
    mass_proximal: np.ndarray           # (2,) [kg]
    mass_distal: np.ndarray             # (2,) [kg]
    com_proximal: np.ndarray            # (2, 2) (along, across) [m]
    com_distal: np.ndarray              # (2, 2) (along, across) [m]
    inertia_proximal: np.ndarray        # (2,) centroidal, about the plane normal [kg m^2]
    inertia_distal: np.ndarray          # (2,)
    gear_ratio: np.ndarray = field(default_factory=lambda: np.ones(2))      # N [rad/rad]
    rotor_inertia: np.ndarray = field(default_factory=lambda: np.zeros(2))  # I_r [kg m^2]
    coulomb: np.ndarray = field(default_factory=lambda: np.zeros(2))        # C [N m]
    viscous: np.ndarray = field(default_factory=lambda: np.zeros(2))        # b [N m s/rad]
    joint_sign: np.ndarray = field(default_factory=lambda: np.ones(2))      # q = sign * phi
    gravity: np.ndarray = field(default_factory=lambda: np.array([0.0, -G0]))  # (gx, gz)

    def __post_init__(self):
        for name in self.__dataclass_fields__:
            setattr(self, name, np.asarray(getattr(self, name), float))


def inverse_kinematics(par: FiveBar, P, Pd=None, Pdd=None):
    """Closed-form inverse kinematics with rates and accelerations.

    ``P, Pd, Pdd (n, 2)``: end point ``(x, z)`` and its time derivatives.
    Rates (from ``Pd = l1 phid n(phi) + l2 psid n(psi)``, dotted with ``e(psi)``, ``e(phi)``):
    ``phid = Pd.e(psi) / (l1 sin(psi - phi))``, ``psid = -Pd.e(phi) / (l2 sin(psi - phi))``.
    Accelerations: the same with ``r = Pdd + l1 phid^2 e(phi) + l2 psid^2 e(psi)``.
    Returns ``phi, phid, phidd, psi, psid, psidd (n, 2)``, ``B (n, 2, 2)`` elbows,
    ``K (n, 2, 2)`` (``phid = K Pd``), ``q, qd, qdd (n, 2)`` joint coordinates,
    ``leg_sine (n, 2) = sin(psi - phi)`` and ``distal_sine (n,) = sin(psi_1 - psi_0)``
    (zero at the two kinds of singularity). Unreachable points give NaN.
    """
    P = _as_batch(P, 2)
    n = P.shape[0]
    Pd = np.zeros((n, 2)) if Pd is None else _as_batch(Pd, 2)
    Pdd = np.zeros((n, 2)) if Pdd is None else _as_batch(Pdd, 2)
    A, l1, l2 = par.base[None], par.l1[None], par.l2[None]
    d = P[:, None, :] - A
    dn = np.linalg.norm(d, axis=-1)
    with np.errstate(invalid="ignore"):
        gam = np.arccos((dn**2 + l1**2 - l2**2) / (2.0 * l1 * dn))
    phi = np.arctan2(d[..., 1], d[..., 0]) + par.sigma[None] * gam
    B = A + l1[..., None] * _e(phi)
    s = P[:, None, :] - B
    psi = np.arctan2(s[..., 1], s[..., 0])
    sn = np.sin(psi - phi)
    ephi, epsi = _e(phi), _e(psi)
    K = epsi / (l1 * sn)[..., None]
    phid = _dot(Pd[:, None, :], epsi) / (l1 * sn)
    psid = -_dot(Pd[:, None, :], ephi) / (l2 * sn)
    r = Pdd[:, None, :] + (l1 * phid**2)[..., None] * ephi + (l2 * psid**2)[..., None] * epsi
    phidd = _dot(r, epsi) / (l1 * sn)
    psidd = -_dot(r, ephi) / (l2 * sn)
    sg = par.joint_sign[None]
    return {
        "phi": phi, "phid": phid, "phidd": phidd,
        "psi": psi, "psid": psid, "psidd": psidd,
        "B": B, "K": K,
        "q": sg * phi, "qd": sg * phid, "qdd": sg * phidd,
        "leg_sine": sn, "distal_sine": np.sin(psi[:, 1] - psi[:, 0]),
    }


def forward_kinematics(par: FiveBar, phi):
    """Direct kinematics: both end-point solutions for given proximal link angles.

    ``phi (n, 2)``: absolute proximal link angles ``phi_i`` (the convention of
    :func:`inverse_kinematics`; the driven joint's coordinate is ``q_i = joint_sign_i phi_i``,
    so pass ``phi = joint_sign * q``).

    The elbows ``B_i = A_i + l1_i e(phi_i)`` are fixed by ``phi``; the end point is an
    intersection of the circles of radius ``l2_0`` about ``B_0`` and ``l2_1`` about ``B_1``
    (Tsai 1999, sec. 2 (planar five-bar); Merlet 2006, ch. 4 (direct kinematics of planar
    2-DOF mechanisms)). With ``d = B_1 - B_0``, ``D = |d|``, ``u = d / D``:

    * ``a = (D^2 + l2_0^2 - l2_1^2) / (2 D)``: distance from ``B_0`` to the foot of the
      common chord along ``u`` (law of cosines),
    * ``h = sqrt(l2_0^2 - a^2)``: half the chord,
    * ``P = B_0 + a u +/- h perp(u)``, ``perp(u) = (-u_z, u_x)`` (``u`` turned +90 degrees).

    Solution 0 takes ``+h``: the end point lies to the LEFT of the directed line
    ``B_0 -> B_1`` (``cross(B_1 - B_0, P - B_0) = D h > 0``); solution 1 takes ``-h`` (right).

    Returns a dict: ``P (n, 2, 2)`` indexed ``[sample, solution, (x, z)]`` and ``B (n, 2, 2)``
    the elbows ``[sample, leg, (x, z)]``. Where the circles do not meet (``h^2 < 0``, or
    ``D = 0``) ``P`` is NaN; where they touch (``h = 0``, a singularity) both solutions coincide.
    """
    phi = _as_batch(phi, 2)
    A, l1, l2 = par.base[None], par.l1[None], par.l2[None]
    B = A + l1[..., None] * _e(phi)
    d = B[:, 1] - B[:, 0]
    D = np.linalg.norm(d, axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        u = d / D[:, None]
        a = (D**2 + l2[:, 0] ** 2 - l2[:, 1] ** 2) / (2.0 * D)
        h = np.sqrt(l2[:, 0] ** 2 - a**2)
    foot = B[:, 0] + a[:, None] * u
    off = h[:, None] * _perp(u)
    P = np.stack([foot + off, foot - off], axis=1)
    return {"P": P, "B": B}


def _link_com(origin, v_origin, a_origin, ang, w, al, com):
    """Centre of mass of a link at angle ``ang`` about its proximal end ``origin``."""
    r = com[None, :, 0, None] * _e(ang) + com[None, :, 1, None] * _n(ang)
    c = origin + r
    v = v_origin + w[..., None] * _perp(r)
    a = a_origin + al[..., None] * _perp(r) - (w**2)[..., None] * r
    return c, v, a


def body_motion(par: FiveBar, P, Pd=None, Pdd=None):
    """Every link's centre of mass, its velocity and acceleration, and angular motion.

    Bodies in the order ``proximal_0, proximal_1, distal_0, distal_1``.
    Returns ``c, v, a (n, 4, 2)``, ``angle, w, alpha (n, 4)``, ``mass, inertia (4,)``
    and the kinematics dict ``ik``.
    """
    ik = inverse_kinematics(par, P, Pd, Pdd)
    n = ik["phi"].shape[0]
    A = np.broadcast_to(par.base[None], (n, 2, 2))
    zero = np.zeros((n, 2, 2))
    l1 = par.l1[None, :, None]
    cp, vp, ap = _link_com(A, zero, zero, ik["phi"], ik["phid"], ik["phidd"], par.com_proximal)
    ephi, nphi = _e(ik["phi"]), _n(ik["phi"])
    vB = l1 * ik["phid"][..., None] * nphi
    aB = l1 * (ik["phidd"][..., None] * nphi - (ik["phid"] ** 2)[..., None] * ephi)
    cd, vd, ad = _link_com(ik["B"], vB, aB, ik["psi"], ik["psid"], ik["psidd"], par.com_distal)
    cat = lambda a, b: np.concatenate([a, b], axis=1)
    return {
        "c": cat(cp, cd), "v": cat(vp, vd), "a": cat(ap, ad),
        "angle": cat(ik["phi"], ik["psi"]), "w": cat(ik["phid"], ik["psid"]),
        "alpha": cat(ik["phidd"], ik["psidd"]),
        "mass": np.concatenate([par.mass_proximal, par.mass_distal]),
        "inertia": np.concatenate([par.inertia_proximal, par.inertia_distal]),
        "ik": ik,
    }


def effort_shares(par: FiveBar, P, Pd, Pdd):
    """Each body's share of the joint efforts, ``(n, 4, 2)`` (:func:`._planar.effort_shares`)."""
    return _planar.effort_shares(body_motion, par, P, Pd, Pdd)


def joint_efforts(par: FiveBar, P, Pd, Pdd):
    """Joint efforts ``u (n, 2)`` along ``q_i`` (mechanism side, no drive terms), by virtual
    work (:func:`._planar.joint_efforts`)."""
    return _planar.joint_efforts(body_motion, par, P, Pd, Pdd)


def motor_torques(par: FiveBar, P, Pd, Pdd):
    """Motor torques (motor side) for a prescribed end-point motion and their parts
    (:func:`._planar.motor_torques`)."""
    return _planar.motor_torques(inverse_kinematics(par, P, Pd, Pdd), joint_efforts(par, P, Pd, Pdd), par, par.gear_ratio)


def energies(par: FiveBar, P, Pd):
    """``T``, ``V``, ``T_rotor`` and the motors' friction power ``loss`` (:func:`._planar.energies`)."""
    return _planar.energies(body_motion, par, P, Pd, par.gear_ratio)


def default_five_bar(**drives) -> FiveBar:
    """A documented default (not a published design): pivots ``A = (-0.12, 0), (0.13, 0.02)``,
    ``l1 = (0.20, 0.22)``, ``l2 = (0.28, 0.26)`` m, elbows out (``sigma = (+1, -1)``);
    a regular pose is ``P = (0.01, 0.33)`` m. Light aluminium-like links."""
    par = dict(
        base=[[-0.12, 0.0], [0.13, 0.02]], l1=[0.20, 0.22], l2=[0.28, 0.26], sigma=[1, -1],
        mass_proximal=[0.60, 0.70], mass_distal=[0.50, 0.45],
        com_proximal=[[0.09, 0.01], [0.11, -0.015]], com_distal=[[0.13, -0.01], [0.12, 0.02]],
        inertia_proximal=[2.4e-3, 3.0e-3], inertia_distal=[3.5e-3, 2.8e-3],
    )
    par.update(drives)
    return FiveBar(**par)


DEFAULT_POSE = np.array([0.01, 0.33])
