"""Shared fixtures for the hip-simulator tests: random models, smooth analytic motions, and the
hip through the generic engine (its description, :mod:`pkmdyn.multibody`) in the closed-form
oracle's terms (``tests/oracles/hip.py``)."""

from __future__ import annotations

import copy
from types import SimpleNamespace

import numpy as np

from pkmdyn.machines.hip_simulator.params import HipModel, default_params_dict, model_from_dict
from pkmdyn.profiles.orientation import OrientationMotion, make_motion

#: the regularisation velocities of the engine's friction laws [rad/s, m/s] (a model compared
#: with the engine must carry the same in its parameter file)
ENGINE_EPS = (1e-3, 1e-4)


def random_model(
    rng: np.random.Generator, spread: float = 0.15, friction: bool = False, inertia: dict | None = None,
    eps: tuple[float, float] = ENGINE_EPS, **geometry
) -> HipModel:
    """The paper's machine with every length, mass and inertia scaled by up to +-spread.

    Angles move by up to +-8 deg, which keeps each S joint well ahead of its module. With
    ``friction`` every friction coefficient is non-zero, regularised by ``eps`` (rad/s, m/s; the
    engine's by default); ``inertia`` and ``geometry`` override keys of those tables.
    """
    d = copy.deepcopy(default_params_dict())

    def jitter(x: float) -> float:
        return float(x * (1.0 + spread * rng.uniform(-1, 1)))

    g = d["geometry"]
    for key in ("base_radius_m", "platform_radius_m", "lever_length_m", "screw_lead_m"):
        g[key] = jitter(g[key])
    h2 = jitter(g["platform_heights_m"][1])
    g["platform_heights_m"] = [h2 + jitter(0.409), h2]
    g["module_angles_deg"] = [a + rng.uniform(-8, 8) for a in g["module_angles_deg"]]
    g["platform_joint_angles_deg"] = [a + rng.uniform(-8, 8) for a in g["platform_joint_angles_deg"]]
    spin = geometry.pop("lever_spin", g.get("lever_spin", "u_joint"))
    g.update(geometry)
    i = d["inertia"]
    for key in ("slider_mass_kg", "lever_mass_kg", "screw_inertia_kgm2", "gravity_m_s2"):
        i[key] = jitter(i[key])
    i["platform_mass_kg"] = float(rng.uniform(0.5, 5.0))
    # principal moments that a rigid body can have (I1 + I2 >= I3, as the engine requires): the
    # slender lever's two large moments scaled together, each within 0.5 % of the other's scale
    lever = i["lever_inertia_kgm2"]
    while True:
        s = jitter(1.0)
        li = [lever[0] * s * (1 + 0.005 * rng.uniform(-1, 1)), lever[1] * s * (1 + 0.005 * rng.uniform(-1, 1)),
              jitter(lever[2])]
        pi = [jitter(x) for x in i["platform_inertia_kgm2"]]
        if all(sum(sorted(v)[:2]) >= max(v) for v in (li, pi)):
            break
    i["lever_inertia_kgm2"], i["platform_inertia_kgm2"] = li, pi
    i.update(inertia or {})
    if friction:
        f = d["friction"]
        for key in ("hip_radius_m", "hip_coefficient", "thrust_radius_m", "thrust_coefficient"):
            f[key] = jitter(f[key])
        f.update(
            slider_coulomb_N=rng.uniform(1, 20),
            slider_viscous_Ns_m=rng.uniform(1, 50),
            screw_coulomb_Nm=rng.uniform(0.001, 0.05),
            screw_viscous_Nms_rad=rng.uniform(1e-5, 1e-3),
            spherical_coulomb_Nm=rng.uniform(0.01, 0.5),
            spherical_viscous_Nms_rad=rng.uniform(0.001, 0.05),
            universal_coulomb_Nm=rng.uniform(0.01, 0.5),
            universal_viscous_Nms_rad=rng.uniform(0.001, 0.05),
            friction_velocity_eps_rad_s=eps[0],
            friction_velocity_eps_m_s=eps[1],
        )
    return with_lever_spin(model_from_dict(d, "random model"), spin)


def with_lever_spin(model: HipModel, spin: str) -> HipModel:
    """``model`` with ``lever_spin = spin``: the paper's ``"perpendicular"`` assumption (Eq. 4)
    is a variant of the closed form only (the parameter file refuses it, since the engine's
    levers turn as their U joints let them), so it is set here past the file's validation."""
    import dataclasses

    return dataclasses.replace(model, geometry=dataclasses.replace(model.geometry, lever_spin=spin))


class SmoothMotion:
    """Euler angles as sums of sinusoids, with exact rates and accelerations; a positive load."""

    def __init__(self, rng: np.random.Generator, amplitude_deg: float = 15.0, harmonics: int = 3):
        self.amp = np.deg2rad(amplitude_deg) * rng.uniform(0.2, 1.0, (harmonics, 3)) / np.arange(1, harmonics + 1)[:, None]
        self.freq = 2 * np.pi * rng.uniform(0.5, 1.5) * np.arange(1, harmonics + 1)
        self.phase = rng.uniform(0, 2 * np.pi, (harmonics, 3))
        self.offset = np.deg2rad(rng.uniform(-5, 5, 3))
        self.load_mean = rng.uniform(300, 2000)
        self.load_amp = rng.uniform(0, 0.9) * self.load_mean

    def angles(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        arg = self.freq[None, :, None] * t[:, None, None] + self.phase[None]
        q = self.offset + np.sum(self.amp * np.sin(arg), axis=1)
        qd = np.sum(self.amp * self.freq[None, :, None] * np.cos(arg), axis=1)
        qdd = -np.sum(self.amp * self.freq[None, :, None] ** 2 * np.sin(arg), axis=1)
        return q, qd, qdd

    def load(self, t: np.ndarray) -> np.ndarray:
        return self.load_mean + self.load_amp * np.sin(self.freq[0] * t + 0.3)

    def motion(self, t: np.ndarray) -> OrientationMotion:
        q, qd, qdd = self.angles(t)
        return make_motion(t, q, qd, qdd, self.load(t))


# --------------------------------------------------------------------------- the engine's hip


_ENGINES: dict[int, tuple[HipModel, object]] = {}


def engine(model: HipModel):
    """The model's description (:func:`~pkmdyn.machines.hip_simulator.description.hip_description`)
    loaded by the generic engine (cached per model object)."""
    from pkmdyn.machines.hip_simulator.description import hip_description
    from pkmdyn.multibody import load_mechanism

    hit = _ENGINES.get(id(model))
    if hit is None or hit[0] is not model:
        hit = (model, load_mechanism(hip_description(model)))
        _ENGINES[id(model)] = hit
    return hit[1]


def sliders(m) -> list[int]:
    """The actuators ``P_1 .. P_3`` (the modules' sliders) in the engine's actuator order."""
    return [m.actuator_names.index(f"P_{i + 1}") for i in range(3)]


def engine_kinematics(model: HipModel, q, qd=None, qdd=None, t=None):
    """``(m, kin)``: the engine's kinematics along the upper platform's Euler angles (its task)."""
    from pkmdyn.multibody import solve_kinematics

    m = engine(model)
    return m, solve_kinematics(m, np.atleast_2d(q), None if qd is None else np.atleast_2d(qd),
                               None if qdd is None else np.atleast_2d(qdd), t)


def engine_torques(model: HipModel, q, qd, qdd, load, t=None, friction: bool = True):
    """The engine's motor torques and their parts along a motion, with the oracle's names
    (``tau, platform, lever, slider, screw, friction, hip_friction, power``, ``(n, 3)`` per
    module i, ``power (n,)``), from the joint reactions with the effort split
    (:func:`pkmdyn.multibody.dynamics.newton_euler.joint_reactions`) and the drives' motor efforts
    (:func:`pkmdyn.multibody.dynamics.actuators.motor_efforts`); ``kin`` and the reactions ``r`` too."""
    from pkmdyn.multibody.dynamics.actuators import motor_efforts
    from pkmdyn.multibody.dynamics.newton_euler import joint_reactions

    m, kin = engine_kinematics(model, q, qd, qdd, t)
    r = joint_reactions(m, kin, named={"hydraulic_N": np.asarray(load, dtype=float)}, split=True, friction=friction)
    sl = sliders(m)
    k = m.drive_ratio[sl]
    mot = motor_efforts(m, kin.act_q, kin.act_qd, kin.act_qdd, r.u)
    groups = {name: r.shares.groups[:, sl, m.group_names.index(name)] / k for name in ("platform", "lever", "slider")}
    hip_joints = [m.joint_names.index(f"S0_{p}") for p in ("upper", "lower")]
    tau = mot.effort[:, sl]
    return SimpleNamespace(
        tau=tau, **groups, screw=mot.rotor[:, sl],
        friction=r.shares.friction[:, sl].sum(axis=2) / k + mot.friction[:, sl],
        hip_friction=r.shares.friction[:, sl][:, :, hip_joints].sum(axis=2) / k,
        power=np.sum(tau * mot.theta_dot[:, sl], axis=1), kin=kin, r=r, m=m)


def rel(a, b) -> float:
    """The largest difference relative to the largest value of ``b``."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return float(np.abs(a - b).max() / max(float(np.abs(b).max()), 1e-300))


def kinematics_against_oracle(model, q, qd, qdd, t=None, tol: float = 1e-9) -> float:
    """Every body's motion by the engine against the closed-form oracle (``tests/oracles/hip.py``)
    along Euler angles ``q`` and rates: sliders, platforms, levers (centre, velocity, acceleration,
    angular motion, frame), the S and U joint centres and ``J_ax = J E``, each to ``tol`` of its
    largest value; returns the largest relative difference."""
    from oracles import hip

    PLATFORMS = ("upper", "lower")
    m, kin = engine_kinematics(model, q, qd, qdd, t)
    ref = hip.kinematics(model, q, qd, qdd)
    zero = hip.kinematics(model, np.zeros((1, 3)))
    sl = sliders(m)
    worst = [rel(kin.act_q[:, sl], ref.L[:, 1]), rel(kin.act_qd[:, sl], ref.Ld[:, 1]),
             rel(kin.act_qdd[:, sl], ref.Ldd[:, 1])]
    for name in PLATFORMS:
        b = m.body_names.index(name)
        worst += [rel(kin.R[:, b], ref.R), rel(kin.w[:, b], ref.omega), rel(kin.wd[:, b], ref.omega_dot)]
    for j, name in enumerate(PLATFORMS):
        for i in range(3):
            b = m.body_names.index(f"lever_{name}_{i + 1}")
            worst += [rel(kin.p[:, b], ref.c_lever[:, j, i]), rel(kin.v[:, b], ref.v_lever[:, i]),
                      rel(kin.a[:, b], ref.a_lever[:, i]), rel(kin.w[:, b], ref.omega_lever[:, i]),
                      rel(kin.wd[:, b], ref.omega_lever_dot[:, i]),
                      # the lever frame turns with the body (the body's frame is the base frame at the zero pose)
                      rel(kin.R[:, b] @ zero.R_lever[0, i], ref.R_lever[:, i]),
                      # the S joint at the platform point, the U joint at the slider
                      rel(kin.joint_point[:, m.joint_names.index(f"S_{name}_{i + 1}")], model.geometry.o[j] + ref.r[:, i]),
                      rel(kin.joint_point[:, m.joint_names.index(f"U_{name}_{i + 1}")],
                          model.geometry.o[j] + ref.r[:, i] - ref.d[:, i])]
    # J_ax = dL/dq = J E (Eq. 3 and the Euler-rate map)
    E = hip.rate_map(model, q)
    worst.append(rel(kin.J_ax[:, sl], ref.J @ E))
    np.testing.assert_allclose(np.linalg.det(kin.J_ax[:, sl]), ref.det_Jb / ref.det_Ja * np.linalg.det(E), rtol=1e-9)
    assert max(worst) < tol, max(worst)
    return max(worst)
