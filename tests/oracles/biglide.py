"""Planar biglide (2 DOF, two parallel prismatic joints on the base, each slider driven by a
rotary motor through a ball screw): closed-form kinematics, joint forces and motor torques
for a prescribed motion of the end point.

References: J.-P. Merlet, *Parallel Robots*, 2nd ed., Springer 2006 (2-DOF planar
robots, the biglide); L.-W. Tsai, *Robot Analysis*, Wiley 1999; H. Goldstein,
*Classical Mechanics*, 3rd ed. (virtual work); for the drive: the ball-screw relations
``theta = 2 pi N s / p``, ``F = (2 pi N / p) tau`` of an ideal (lossless) screw.

Plane and conventions
---------------------
* The mechanism moves in a vertical plane ``y = y0`` of the base frame. Planar vectors are
  ``(x, z)`` pairs of base-frame components; angles are measured from +x toward +z.
  ``e(a) = (cos a, sin a)``, ``n(a) = (-sin a, cos a)``.
* The two rails are parallel, along the unit vector ``d = e(rail_angle)``. Slider i sits at
  ``S_i = O_i + s_i d`` (``O_i`` the rail's origin, ``s_i`` its travel). Link i of length
  ``L_i`` goes from ``S_i`` (revolute joint) at absolute angle ``psi_i`` to the end point
  ``P = S_i + L_i e(psi_i)`` (the revolute joint between the two links).
* Branch ``sigma_i = +1``: the slider lies beyond the foot of ``P`` on its rail along +d:
  with ``w = P - O_i``, ``h = w.n(rail_angle)``,
  ``s_i = w.d + sigma_i sqrt(L_i^2 - h^2)``.
* Joint coordinate of the driven prismatic joint: ``q_i = joint_sign_i * s_i``
  (``joint_sign = +1``: the joint axis along ``+d``).
* Slider i translates only: its centre of mass is ``S_i + slider_com_i`` (a fixed offset;
  it does not enter the dynamics). Each link's centre of mass is given in its own frame,
  ``(along, across)``, from ``S_i`` along ``e(psi_i)`` and ``n(psi_i)``; ``inertia`` is
  the centroidal moment about the plane normal (the base frame's ``I_yy``).
* Drive i: screw lead ``p_i`` [m per screw turn] and gear ratio ``N_i`` (motor turns per
  screw turn), ``k_i = 2 pi N_i / p_i`` [rad/m], motor angle ``theta_i = k_i q_i``;
  motor torque ``tau_i = u_i / k_i + I_r,i theta_dd_i + C_i sgn_eps(theta_d_i)
  + b_i theta_d_i``, ``u_i`` the joint force along ``q_i`` (mechanism side),
  ``sgn_eps(x) = x / sqrt(x^2 + eps^2)``, ``eps = 1e-3 rad/s``.

Dynamics route: virtual work with the bodies' velocity Jacobians per unit end-point rate
(as in ``five_bar``): ``H^T u = sum_b Jc_b^T m_b (a_b - g) + Jw_b^T I_b alpha_b``,
``H = dq/dP``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ._batch import as_batch as _as_batch
from ._planar import G0, dot as _dot, e as _e, n as _n, perp as _perp  # noqa: F401
from ._planar import regularised_sign, sine_motion  # noqa: F401  (re-exported)
from . import _planar


@dataclass
class Biglide:
    """Geometry, inertia and drives of a planar biglide (arrays per leg, (2, ...))."""

    rail_origin: np.ndarray             # (2, 2) O_i, (x, z) [m]
    rail_angle: float                   # direction of both rails, from +x toward +z [rad]
    length: np.ndarray                  # (2,) link lengths L_i [m]
    sigma: np.ndarray                   # (2,) branch, +1 / -1
    mass_slider: np.ndarray             # (2,) [kg]
    mass_link: np.ndarray               # (2,) [kg]
    slider_com: np.ndarray              # (2, 2) offset of the slider's centre of mass [m]
    com_link: np.ndarray                # (2, 2) (along, across) [m]
    inertia_link: np.ndarray            # (2,) centroidal, about the plane normal [kg m^2]
    screw_lead: np.ndarray = field(default_factory=lambda: np.full(2, 0.01))  # p [m/turn]
    gear_ratio: np.ndarray = field(default_factory=lambda: np.ones(2))        # N
    rotor_inertia: np.ndarray = field(default_factory=lambda: np.zeros(2))    # I_r [kg m^2]
    coulomb: np.ndarray = field(default_factory=lambda: np.zeros(2))          # C [N m]
    viscous: np.ndarray = field(default_factory=lambda: np.zeros(2))          # b [N m s/rad]
    joint_sign: np.ndarray = field(default_factory=lambda: np.ones(2))        # q = sign * s
    gravity: np.ndarray = field(default_factory=lambda: np.array([0.0, -G0]))  # (gx, gz)

    def __post_init__(self):
        for name in self.__dataclass_fields__:
            setattr(self, name, np.asarray(getattr(self, name), float))

    @property
    def ratio(self):
        """``k = 2 pi N / p`` [rad/m]: motor angle per unit joint travel."""
        return 2.0 * np.pi * self.gear_ratio / self.screw_lead


def inverse_kinematics(par: Biglide, P, Pd=None, Pdd=None):
    """Closed-form inverse kinematics with rates and accelerations.

    From ``Pd = sd d + L psid n(psi)``: ``sd = Pd.e(psi) / (d.e(psi))``,
    ``psid = (Pd - sd d).n(psi) / L``; and from
    ``Pdd = sdd d + L psidd n(psi) - L psid^2 e(psi)``:
    ``sdd = (Pdd.e(psi) + L psid^2) / (d.e(psi))``, ``psidd = (Pdd - sdd d).n(psi) / L``.
    Returns ``s, sd, sdd, psi, psid, psidd (n, 2)``, ``S (n, 2, 2)`` slider points,
    ``K (n, 2, 2)`` (``sd = K Pd``), ``q, qd, qdd (n, 2)``, ``leg_cosine = d.e(psi)``
    and ``link_sine (n,) = sin(psi_1 - psi_0)`` (zero at the singularities).
    """
    P = _as_batch(P, 2)
    n = P.shape[0]
    Pd = np.zeros((n, 2)) if Pd is None else _as_batch(Pd, 2)
    Pdd = np.zeros((n, 2)) if Pdd is None else _as_batch(Pdd, 2)
    d = _e(np.asarray(par.rail_angle))
    nd = _n(np.asarray(par.rail_angle))
    L = par.length[None]
    w = P[:, None, :] - par.rail_origin[None]
    h = _dot(w, nd)
    with np.errstate(invalid="ignore"):
        s = _dot(w, d) + par.sigma[None] * np.sqrt(L**2 - h**2)
    S = par.rail_origin[None] + s[..., None] * d
    ev = (P[:, None, :] - S) / L[..., None]
    psi = np.arctan2(ev[..., 1], ev[..., 0])
    epsi, npsi = _e(psi), _n(psi)
    de = _dot(epsi, d)
    K = epsi / de[..., None]
    sd = _dot(Pd[:, None, :], epsi) / de
    psid = _dot(Pd[:, None, :] - sd[..., None] * d, npsi) / L
    sdd = (_dot(Pdd[:, None, :], epsi) + L * psid**2) / de
    psidd = _dot(Pdd[:, None, :] - sdd[..., None] * d, npsi) / L
    sg = par.joint_sign[None]
    return {
        "s": s, "sd": sd, "sdd": sdd, "psi": psi, "psid": psid, "psidd": psidd,
        "S": S, "K": K, "q": sg * s, "qd": sg * sd, "qdd": sg * sdd,
        "leg_cosine": de, "link_sine": np.sin(psi[:, 1] - psi[:, 0]),
    }


def body_motion(par: Biglide, P, Pd=None, Pdd=None):
    """Centres of mass, their velocities and accelerations, and angular motion.

    Bodies in the order ``slider_0, slider_1, link_0, link_1``. Returns ``c, v, a
    (n, 4, 2)``, ``angle, w, alpha (n, 4)``, ``mass, inertia (4,)`` and ``ik``.
    """
    ik = inverse_kinematics(par, P, Pd, Pdd)
    n = ik["s"].shape[0]
    d = _e(np.asarray(par.rail_angle))
    cs = ik["S"] + par.slider_com[None]
    vs = ik["sd"][..., None] * d
    as_ = ik["sdd"][..., None] * d
    psi, w, al = ik["psi"], ik["psid"], ik["psidd"]
    r = par.com_link[None, :, 0, None] * _e(psi) + par.com_link[None, :, 1, None] * _n(psi)
    cl = ik["S"] + r
    vl = vs + w[..., None] * _perp(r)
    al_ = as_ + al[..., None] * _perp(r) - (w**2)[..., None] * r
    cat = lambda a, b: np.concatenate([a, b], axis=1)
    zero = np.zeros((n, 2))
    return {
        "c": cat(cs, cl), "v": cat(vs, vl), "a": cat(as_, al_),
        "angle": cat(zero, psi), "w": cat(zero, w), "alpha": cat(zero, al),
        "mass": np.concatenate([par.mass_slider, par.mass_link]),
        "inertia": np.concatenate([np.zeros(2), par.inertia_link]),
        "ik": ik,
    }


def effort_shares(par: Biglide, P, Pd, Pdd):
    """Each body's share of the joint efforts, ``(n, 4, 2)`` (:func:`._planar.effort_shares`)."""
    return _planar.effort_shares(body_motion, par, P, Pd, Pdd)


def joint_efforts(par: Biglide, P, Pd, Pdd):
    """Joint efforts ``u (n, 2)`` along ``q_i`` (mechanism side, no drive terms), by virtual
    work (:func:`._planar.joint_efforts`)."""
    return _planar.joint_efforts(body_motion, par, P, Pd, Pdd)


def motor_torques(par: Biglide, P, Pd, Pdd):
    """Motor torques (motor side) for a prescribed end-point motion and their parts
    (:func:`._planar.motor_torques`)."""
    return _planar.motor_torques(inverse_kinematics(par, P, Pd, Pdd), joint_efforts(par, P, Pd, Pdd), par, par.ratio)


def energies(par: Biglide, P, Pd):
    """``T``, ``V``, ``T_rotor`` and the motors' friction power ``loss`` (:func:`._planar.energies`)."""
    return _planar.energies(body_motion, par, P, Pd, par.ratio)


def default_biglide(**drives) -> Biglide:
    """A documented default (not a published design): vertical rails (``rail_angle = pi/2``)
    through ``O = (-0.2, 0), (0.21, 0)`` m, links ``L = (0.30, 0.32)`` m, sliders above the
    end point (``sigma = (+1, +1)``); a regular pose is ``P = (0.01, -0.12)`` m. 10 mm
    screws."""
    par = dict(
        rail_origin=[[-0.20, 0.0], [0.21, 0.0]], rail_angle=np.pi / 2, length=[0.30, 0.32],
        sigma=[1, 1], mass_slider=[1.2, 1.1], mass_link=[0.40, 0.45],
        slider_com=[[0.01, 0.02], [-0.015, 0.01]], com_link=[[0.14, 0.01], [0.15, -0.012]],
        inertia_link=[3.1e-3, 3.6e-3],
    )
    par.update(drives)
    return Biglide(**par)


DEFAULT_POSE = np.array([0.01, -0.12])
