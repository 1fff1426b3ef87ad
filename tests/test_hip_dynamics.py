"""Inverse dynamics of the hip simulator: power balance, decomposition, friction, bad input."""

import dataclasses

import numpy as np
import pytest

from hip_helpers import SmoothMotion, random_model
from pkmdyn.errors import MotionError
from pkmdyn.machines.hip_simulator.dynamics import inverse_dynamics
from pkmdyn.machines.hip_simulator.kinematics import inverse_kinematics
from pkmdyn.machines.hip_simulator.params import load_params
from pkmdyn.profiles.orientation import make_motion
from pkmdyn.spatial import dot


def _energy(model, kin):
    """Kinetic and potential energy of every body [J], from positions and velocities only."""
    g, m = model.geometry, model.inertia
    n_pl = g.h.shape[0]

    def rot_energy(R, I, w):
        wb = np.einsum("...ji,...j->...i", R, w)
        return 0.5 * np.sum(I * wb * wb, axis=-1)

    T = n_pl * rot_energy(kin.R, m.I_m, kin.omega)
    T = T + n_pl * np.sum(0.5 * m.m_l * dot(kin.v_lever, kin.v_lever) + rot_energy(kin.R_lever, m.I_l, kin.omega_lever), axis=1)
    T = T + np.sum(0.5 * m.m_L * kin.Ld**2, axis=(1, 2))
    T = T + np.sum(0.5 * m.I_L * (2 * np.pi * kin.Ld[:, 1] / g.p) ** 2, axis=1)
    V = m.g * (m.m_l * kin.c_lever[..., 2].sum(axis=(1, 2)) + m.m_L * kin.L.sum(axis=(1, 2)))
    return T + V


def _dissipation(model, kin, load):
    """Power [W] dissipated by every friction term, from the friction laws and velocities."""
    f, m, g = model.friction, model.inertia, model.geometry
    n_pl = g.h.shape[0]

    def u(w, eps):
        return w / np.sqrt(np.sum(w * w, axis=-1, keepdims=True) + eps**2)

    hip = (f.r_h * f.mu_h * load + f.r_t * f.mu_t * (load + m.m_m * m.g))[:, None] * u(kin.omega, f.eps_w)
    P = n_pl * dot(kin.omega, hip)
    w_s = kin.omega_lever - kin.omega[:, None]
    P = P + n_pl * np.sum(dot(w_s, f.spherical_coulomb * u(w_s, f.eps_w) + f.spherical_viscous * w_s), axis=1)
    w_u = kin.omega_lever
    P = P + n_pl * np.sum(dot(w_u, f.universal_coulomb * u(w_u, f.eps_w) + f.universal_viscous * w_u), axis=1)
    v = kin.Ld
    P = P + np.sum(v * (f.slider_coulomb * v / np.sqrt(v * v + f.eps_v**2) + f.slider_viscous * v), axis=(1, 2))
    th = 2 * np.pi * kin.Ld[:, 1] / g.p
    P = P + np.sum(th * (f.screw_coulomb * th / np.sqrt(th * th + f.eps_w**2) + f.screw_viscous * th), axis=1)
    return P


def _power_residual(model, sm, t, torques=None):
    h = 1e-5
    kin = inverse_kinematics(model, sm.motion(t))
    tq = inverse_dynamics(model, kin, sm.load(t)) if torques is None else torques
    dE = (_energy(model, inverse_kinematics(model, sm.motion(t + h))) - _energy(model, inverse_kinematics(model, sm.motion(t - h)))) / (2 * h)
    theta_dot = 2 * np.pi * kin.Ld[:, 1] / model.geometry.p
    motor_power = np.sum(tq.tau * theta_dot, axis=1)
    residual = motor_power - dE - _dissipation(model, kin, sm.load(t))
    return residual, np.abs(motor_power).max(), kin, tq


@pytest.mark.parametrize("seed", range(8))
def test_power_balance(seed):
    """sum tau_i theta_dot_i = d(T + V)/dt + dissipated power, on random machines and motions."""
    rng = np.random.default_rng(300 + seed)
    model = random_model(rng, friction=seed % 2 == 0)
    sm = SmoothMotion(rng)
    t = np.linspace(0.0, 2.0, 60)
    residual, scale, _, tq = _power_residual(model, sm, t)
    assert np.abs(residual).max() <= 1e-6 * scale
    np.testing.assert_allclose(tq.power, np.sum(tq.tau * 2 * np.pi * inverse_kinematics(model, sm.motion(t)).Ld[:, 1] / model.geometry.p, axis=1))


@pytest.mark.parametrize("part", ["platform", "lever", "slider", "screw", "friction"])
def test_power_balance_detects_a_dropped_term(part):
    """The balance is sharp enough to notice any one part of the torque missing."""
    rng = np.random.default_rng(42)
    model = random_model(rng, friction=True)
    sm = SmoothMotion(rng)
    t = np.linspace(0.0, 2.0, 60)
    _, _, kin, tq = _power_residual(model, sm, t)
    broken = dataclasses.replace(tq, tau=tq.tau - getattr(tq, part))
    residual, scale, _, _ = _power_residual(model, sm, t, broken)
    assert np.abs(residual).max() > 1e-3 * scale


def test_static_pose_needs_only_gravity_and_friction_is_finite_at_rest():
    model = load_params()
    n = 3
    z = np.zeros((n, 3))
    motion = make_motion(np.arange(n, dtype=float), np.deg2rad([[5, -3, 2]] * n), z, z, [0.0, 1000.0, 3000.0])
    tq = inverse_dynamics(model, inverse_kinematics(model, motion), motion.load)
    assert np.all(np.isfinite(tq.tau))
    np.testing.assert_allclose(tq.friction, 0.0, atol=1e-15)
    np.testing.assert_allclose(tq.platform, 0.0, atol=1e-15)
    np.testing.assert_allclose(tq.screw, 0.0, atol=1e-15)
    # the sliders' weight: p / 2 pi * 2 m_L g on each motor
    g, m = model.geometry, model.inertia
    np.testing.assert_allclose(tq.slider, g.p / (2 * np.pi) * 2 * m.m_L * m.g, rtol=1e-12)
    # levers carry weight too, and loading the platforms changes nothing at rest
    assert np.all(np.abs(tq.lever) > 0)
    np.testing.assert_allclose(tq.tau[0], tq.tau[2], rtol=1e-12)


def test_hip_friction_grows_with_load_and_opposes_motion():
    model = load_params()
    rng = np.random.default_rng(9)
    sm = SmoothMotion(rng)
    t = np.linspace(0, 1, 40)
    kin = inverse_kinematics(model, sm.motion(t))
    low = inverse_dynamics(model, kin, np.full(t.shape, 300.0))
    high = inverse_dynamics(model, kin, np.full(t.shape, 3000.0))
    theta_dot = kin.Ld[:, 1]
    p_low = np.sum(low.hip_friction * theta_dot, axis=1)
    p_high = np.sum(high.hip_friction * theta_dot, axis=1)
    assert np.all(p_low >= 0) and np.all(p_high >= p_low)
    f = model.friction
    ratio = (f.r_h * f.mu_h * 3000 + f.r_t * f.mu_t * 3000) / (f.r_h * f.mu_h * 300 + f.r_t * f.mu_t * 300)
    np.testing.assert_allclose(high.hip_friction, ratio * low.hip_friction, rtol=1e-12)


@pytest.mark.parametrize("bad, word", [(-1.0, "negative"), (np.nan, "not finite"), (np.inf, "not finite")])
def test_bad_load_names_the_row(bad, word):
    model = load_params()
    t = np.linspace(0, 1, 5)
    z = np.zeros((5, 3))
    load = np.full(5, 500.0)
    load[3] = bad
    kin = inverse_kinematics(model, make_motion(t, z, z, z))
    with pytest.raises(MotionError, match=rf"row 4 .*{word}"):
        inverse_dynamics(model, kin, load)
    with pytest.raises(MotionError, match=r"row 4"):
        make_motion(t, z, z, z, load)


def test_nan_in_motion_names_the_row():
    t = np.linspace(0, 1, 5)
    q = np.zeros((5, 3))
    q[2, 1] = np.nan
    with pytest.raises(MotionError, match=r"row 3 .*angles"):
        make_motion(t, q, np.zeros((5, 3)), np.zeros((5, 3)))


def test_perpendicular_lever_option_is_close_to_the_u_joint_model():
    """The paper's Eq. 4 assumption drops only the small lever spin (regression: any batch size)."""
    import copy

    from pkmdyn.machines.hip_simulator.params import default_params_dict, model_from_dict
    from pkmdyn.profiles.iso14242 import iso14242_motion

    d = copy.deepcopy(default_params_dict())
    d["geometry"]["lever_spin"] = "perpendicular"
    perp, ujoint = model_from_dict(d), load_params()
    motion = iso14242_motion(1, 250)
    k_p, k_u = inverse_kinematics(perp, motion), inverse_kinematics(ujoint, motion)
    tq_p = inverse_dynamics(perp, k_p, motion.load)
    tq_u = inverse_dynamics(ujoint, k_u, motion.load)
    assert np.all(np.isfinite(tq_p.tau))
    np.testing.assert_allclose(k_p.spin, 0.0)
    assert np.abs(k_u.spin).max() > 1e-3
    diff = np.abs(tq_p.lever - tq_u.lever).max()
    assert 0 < diff < 1e-2 * np.abs(tq_u.lever).max()
    np.testing.assert_array_equal(tq_p.platform, tq_u.platform)
