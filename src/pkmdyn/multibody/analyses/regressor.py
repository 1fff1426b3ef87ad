"""The dynamics of a described mechanism as a regressor: efforts linear in its inertial and
friction parameters, for identification.

Per body b, the ten barycentric parameters in its own frame (about its frame origin O_b):

    theta_b = [m, m c_x, m c_y, m c_z, J_xx, J_yy, J_zz, J_xy, J_xz, J_yz]

with ``h = m c`` the first moment and ``J = I_c + m (|c|^2 1 - c c^T)`` the inertia about
O_b (tensor entries, ``J_xy = -∫ x y dm``). The required body wrench (Eq. 1 of
:mod:`pkmdyn.multibody.dynamics.newton_euler`) is linear in them: with ``R`` the body's rotation, ``o`` its origin, ``a_o``
its origin's acceleration and ``g`` gravity, ``h_w = R h``, ``J_w = R J R^T``,

    f   = m (a_o - g) + wd x h_w + w x (w x h_w)
    n_O = o x f + J_w wd + w x J_w w + h_w x (a_o - g).

Per joint with friction data, two parameters: its Coulomb and its viscous coefficient
(``coulomb_torque_Nm``/``viscous_Nm_s_rad`` for rotations, ``coulomb_force_N``/
``viscous_N_s_m`` for translations): the friction of law F1-F2 without the load-dependent part,
``u(w)`` and ``w`` per unit coefficient; per term of the friction a named load drives
(``friction.external``, Eq. 16 of Chen, Cheng & Pang 2022: ``mu_k r_k |F_k + o_k| u(w)``) its
coefficient ``mu_k`` (``<joint>_external<k>_<load>_coefficient``, the magnitudes ``named``).
The efforts are ``u = Y theta + u_0`` (``u_0`` the description's ``[[loads]]``), every column
of ``Y`` the projection (Eq. 2-3) of the wrenches or friction of one unit parameter. With
drives (``[[actuators]]``) the efforts are the motor efforts of :mod:`pkmdyn.multibody.dynamics.actuators` (Eq. A1):
every column divided by the transmission ratio ``k``, and per drive three more parameters,
its rotor inertia (column ``theta_ddot``), its motor's Coulomb (``u(theta_dot)``) and viscous
(``theta_dot``) coefficients. Idle freedoms are held (the kinematics' accelerations).
Friction that depends on the joints' own reactions (``coefficient`` with a radius or a guide)
is not linear in the parameters: such a description is refused, naming the joint.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from ...errors import ParameterError
from ..dynamics.actuators import motor_coordinates, motor_eps
from ..dynamics.distribution import least_norm_map
from ..dynamics.friction import (
    EPS_ROTATION,
    EPS_TRANSLATION,
    JointFriction,
    regularised_sign,
)
from ..dynamics.newton_euler import (
    actuator_efforts,
    body_wrenches,
    coordinate_twists,
    free_blocks,
    generalised_forces,
    named_magnitudes,
)
from ..kinematics.inverse import MechanismKinematics
from ..model.compiler import MechanismModel

__all__ = ["Regressor", "regressor", "inertial_parameters", "BODY_PARAMETERS"]

Array = NDArray[np.float64]

BODY_PARAMETERS = ("m_kg", "mcx_kgm", "mcy_kgm", "mcz_kgm", "Jxx_kgm2", "Jyy_kgm2", "Jzz_kgm2", "Jxy_kgm2",
                   "Jxz_kgm2", "Jyz_kgm2")


@dataclass(frozen=True)
class Regressor:
    """``Y`` (n, na, p) and ``u0`` (n, na): efforts ``u = Y theta + u0``; ``names`` (p,)
    ``<body>_<parameter>`` or ``<joint>_coulomb`` / ``<joint>_viscous``; ``theta`` (p,) the
    description's values."""

    Y: Array
    u0: Array
    names: tuple[str, ...]
    theta: Array


def inertial_parameters(model: MechanismModel) -> Array:
    """The description's barycentric parameters (nb, 10) in the order of :data:`BODY_PARAMETERS`."""
    out = np.zeros((model.nb, 10))
    for b in range(model.nb):
        m, c, Ic = model.mass[b], model.com[b], model.inertia[b]
        J = Ic + m * (np.dot(c, c) * np.eye(3) - np.outer(c, c))
        out[b] = [m, *(m * c), J[0, 0], J[1, 1], J[2, 2], J[0, 1], J[0, 2], J[1, 2]]
    return out


def _unit_wrenches(model: MechanismModel, kin: MechanismKinematics, b: int) -> Array:
    """Required wrench of body b per unit barycentric parameter (n, 10, 6)."""
    n = len(kin)
    R, o, w, wd = kin.R[:, b], kin.origin[:, b], kin.w[:, b], kin.wd[:, b]
    ag = kin.origin_a[:, b] - model.gravity
    out = np.zeros((n, 10, 6))
    # mass
    out[:, 0, 3:] = ag
    out[:, 0, :3] = np.cross(o, ag)
    # first moments (body frame axis k)
    for k in range(3):
        hw = R[:, :, k]
        f = np.cross(wd, hw) + np.cross(w, np.cross(w, hw))
        out[:, 1 + k, 3:] = f
        out[:, 1 + k, :3] = np.cross(o, f) + np.cross(hw, ag)
    # inertia about the origin
    pairs = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))
    for i, (p, q) in enumerate(pairs):
        E = np.zeros((3, 3))
        E[p, q] = E[q, p] = 1.0
        Jw = R @ E @ np.swapaxes(R, 1, 2)
        out[:, 4 + i, :3] = (Jw @ wd[..., None])[..., 0] + np.cross(w, (Jw @ w[..., None])[..., 0])
    return out


def linear_distribution(model: MechanismModel) -> MechanismModel:
    """``model``, a redundantly actuated one with its (weighted) least-norm distribution alone
    (no least peak, bounds or preload): the efforts' map that is linear in the parameters.
    Efforts of another distribution differ from it by an internal force alone, which no
    parameter determines (:func:`least_norm_projector`)."""
    if model.na <= model.nt:
        return model
    return replace(model, act_distribution="weighted" if model.act_distribution == "weighted" else "minimum_norm",
                   act_preload=0.0, act_bound=np.full(model.na, np.inf))


def least_norm_projector(model: MechanismModel, kin: MechanismKinematics) -> Array | None:
    """``P (n, na, na)`` that takes an actuator's efforts as :func:`regressor` counts them (a
    drive's motor effort, else the joint's) to their (weighted) least-norm part: ``K^-1 C^-1
    A^T (A C^-1 A^T)^-1 A K`` (``A = J_ax^T``, ``K`` the transmission ratios, ``C`` the
    weights). It removes an internal force ``K^-1 N lambda``, which no parameter determines,
    and keeps ``A K u`` (the task-space balance); None for a mechanism without redundancy."""
    if model.na <= model.nt:
        return None
    k = model.drive_ratio
    A = np.swapaxes(kin.J_ax, 1, 2)
    P = least_norm_map(model, A) @ A  # (n, na, na)
    return P * k[None, None, :] / k[None, :, None]


def regressor(model: MechanismModel, kin: MechanismKinematics, named: dict | None = None) -> Regressor:
    """The regressor of the efforts along a solved motion (module docstring)."""

    n = len(kin)
    model = linear_distribution(model)
    S = coordinate_twists(model, kin.q)
    cols, names, theta = [], [], []
    theta_b = inertial_parameters(model)
    for b in range(model.nb):
        U = _unit_wrenches(model, kin, b)
        for k in range(10):
            W = np.zeros((n, model.nb, 6))
            W[:, b] = U[:, k]
            cols.append(actuator_efforts(model, kin, generalised_forces(model, S, W)))
            names.append(f"{model.body_names[b]}_{BODY_PARAMETERS[k]}")
            theta.append(theta_b[b, k])
    for j, d in enumerate(model.joint_friction):
        if d and d.get("coefficient", 0.0):
            raise ParameterError(f"joint {model.joint_names[j]}: its friction depends on its own reaction "
                                 "(coefficient), which is not linear in the parameters; set it to 0 to identify")
    fr = JointFriction(model, kin, S, free_blocks(model, kin, S), named)
    mags = named_magnitudes(model, n, named) if model.named_loads else {}
    for jd in fr.joints:
        d = jd["d"]
        # the friction a named load drives (friction.external, Chen, Cheng & Pang 2022, Eq. 16): one column
        # per term, its coefficient mu_k the parameter (radius and offset known)
        for k_, term in enumerate(d.get("external", [])):
            mag = (term["radius_m"] or 1.0) * np.abs(mags[term["load"]] + term["offset_N"])
            tau = mag[:, None] * regularised_sign(jd["w"], EPS_ROTATION, True) if jd["has_rot"] else np.zeros((n, 3))
            phi = (mag[:, None] * regularised_sign(jd["v"], EPS_TRANSLATION, True)
                   if jd["has_slide"] and not jd["has_rot"] else np.zeros((n, 3)))
            Wf = np.concatenate([tau + np.cross(jd["pt"], phi), phi], axis=1)
            Qf = np.zeros((n, model.nq))
            fr.add_generalised(Qf, jd, np.einsum("nfk,nk->nf", jd["T"], Wf))
            cols.append(actuator_efforts(model, kin, Qf))
            names.append(f"{model.joint_names[jd['j']]}_external{k_ + 1}_{term['load']}_coefficient")
            theta.append(float(term["coefficient"]))
        for law in ("coulomb", "viscous"):
            tau = np.zeros((n, 3))
            phi = np.zeros((n, 3))
            if jd["has_rot"]:
                tau = regularised_sign(jd["w"], EPS_ROTATION, True) if law == "coulomb" else jd["w"]
            if jd["has_slide"]:
                phi = regularised_sign(jd["v"], EPS_TRANSLATION, True) if law == "coulomb" else jd["v"]
            Wf = np.concatenate([tau + np.cross(jd["pt"], phi), phi], axis=1)
            F = np.einsum("nfk,nk->nf", jd["T"], Wf)
            Qf = np.zeros((n, model.nq))
            fr.add_generalised(Qf, jd, F)
            cols.append(actuator_efforts(model, kin, Qf))
            name = model.joint_names[jd["j"]]
            names.append(f"{name}_{law}")
            rot = d.get("coulomb_torque_Nm" if law == "coulomb" else "viscous_Nm_s_rad", 0.0)
            tr = d.get("coulomb_force_N" if law == "coulomb" else "viscous_N_s_m", 0.0)
            if jd["has_rot"] and jd["has_slide"] and rot != tr:
                # one parameter per law: a joint that turns and slides needs the two equal to be linear in it
                raise ParameterError(f"joint {name}: rotation and translation {law} coefficients differ; "
                                 "the regressor takes one coefficient per law and joint")
            theta.append(rot if jd["has_rot"] else tr)
    Y = np.stack(cols, axis=2)
    unloaded = replace(model, load_body=model.load_body[:0], load_force=model.load_force[:0],
                       load_moment=model.load_moment[:0], load_point=model.load_point[:0], load_name=(),
                       load_direction=model.load_direction[:0], load_magnitude=model.load_magnitude[:0],
                       named_loads=(), joint_spring=())
    W0 = body_wrenches(model, kin, named=named) - body_wrenches(unloaded, kin)  # the [[loads]] and springs alone
    u0 = actuator_efforts(model, kin, generalised_forces(model, S, W0))
    if not model.has_drives:
        return Regressor(Y=Y, u0=u0, names=tuple(names), theta=np.array(theta))
    # the motor efforts (multibody.dynamics.actuators, Eq. A1): the joint's columns through the transmission,
    # then per drive its rotor inertia and its motor's Coulomb and viscous coefficients
    k = model.drive_ratio
    Y = Y / k[None, :, None]
    u0 = u0 / k[None, :]
    _, thd, thdd = motor_coordinates(model, kin.act_q, kin.act_qd, kin.act_qdd)
    eps = motor_eps(model)
    extra, extra_names, extra_theta = [], [], []
    for i, name in enumerate(model.drive_name):
        if name is None:
            continue
        rot = model.motor_units[i] == "rad"
        for label, col, value in ((f"{name}_rotor_inertia_{'kgm2' if rot else 'kg'}", thdd[:, i], model.drive_rotor[i]),
                                  (f"{name}_motor_coulomb", regularised_sign(thd[:, i], eps[i], False),
                                   model.drive_coulomb[i]),
                                  (f"{name}_motor_viscous", thd[:, i], model.drive_viscous[i])):
            c = np.zeros((n, model.na))
            c[:, i] = col
            extra.append(c)
            extra_names.append(label)
            extra_theta.append(float(value))
    Y = np.concatenate([Y, np.stack(extra, axis=2)], axis=2)
    return Regressor(Y=Y, u0=u0, names=tuple(names) + tuple(extra_names), theta=np.array(theta + extra_theta))
