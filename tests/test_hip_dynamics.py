"""Inverse dynamics of the hip simulator through the generic engine (its description, the joint
reactions with the effort split and the lead screws' motor efforts): against the closed form of
Eq. 7-16 (``tests/oracles/hip.py``) part by part, the power balance, a static pose by hand, the
hip-joint friction's load, and bad input."""

import numpy as np
import pytest

from hip_helpers import SmoothMotion, engine, engine_torques, random_model, rel
from oracles import hip
from pkmdyn.errors import MotionError, ParameterError
from pkmdyn.machines.hip_simulator.params import load_params
from pkmdyn.multibody.dynamics.verbs import machine_verbs
from pkmdyn.profiles.orientation import make_motion

PARTS = ("tau", *hip.PARTS, "hip_friction", "power")
TOL = 1e-9


def _both(model, sm, t):
    q, qd, qdd = sm.angles(t)
    return engine_torques(model, q, qd, qdd, sm.load(t), t), hip.inverse_dynamics(model, hip.kinematics(model, q, qd, qdd), sm.load(t))


@pytest.mark.parametrize("seed", range(4))
def test_every_part_against_the_closed_form(seed):
    """Motor torques and every part of Eq. 14 plus friction, with every friction family on
    (seeds 0, 2) or the hip joints' Eq. 16 alone (1, 3), to 1e-9 of each part's largest value."""
    rng = np.random.default_rng(300 + seed)
    model = random_model(rng, friction=seed % 2 == 0, euler_sequence=["XYZ", "zxy", "ZYX", "xyz"][seed])
    sm = SmoothMotion(rng)
    t = np.linspace(0.0, 2.0, 50)
    eng, ref = _both(model, sm, t)
    for part in PARTS:
        assert rel(getattr(eng, part), getattr(ref, part)) < TOL, part
    assert np.abs(ref.friction).max() > 1e-3 * np.abs(ref.tau).max()  # friction counts
    assert eng.r.residual.max() < 1e-9 * np.abs(eng.r.joint_force).max()


def _power_residual(model, sm, t, tau):
    """Motor power minus the rate of the machine's energy (central differences of the oracle's
    body-by-body energy) minus the power every friction law dissipates."""
    h = 1e-5
    E = [sum(hip.energies(model, hip.kinematics(model, *sm.angles(t + s * h)))) for s in (-1, 1)]
    k = hip.kinematics(model, *sm.angles(t))
    power = np.sum(tau * k.theta_dot, axis=1)
    return power - (E[1] - E[0]) / (2 * h) - hip.dissipation(model, k, sm.load(t)), np.abs(power).max()


@pytest.mark.parametrize("seed", range(4))
def test_power_balance(seed):
    """sum tau_i theta_dot_i = d(T + V)/dt + dissipated power, on random machines and motions."""
    rng = np.random.default_rng(400 + seed)
    model = random_model(rng, friction=seed % 2 == 0)
    sm = SmoothMotion(rng)
    t = np.linspace(0.0, 2.0, 40)
    eng, _ = _both(model, sm, t)
    res, scale = _power_residual(model, sm, t, eng.tau)
    assert np.abs(res).max() <= 1e-6 * scale
    np.testing.assert_allclose(eng.power, np.sum(eng.tau * hip.kinematics(model, *sm.angles(t)).theta_dot, axis=1),
                               rtol=1e-12, atol=1e-12 * np.abs(eng.power).max())


@pytest.mark.parametrize("part", hip.PARTS)
def test_power_balance_detects_a_dropped_part(part):
    """The balance is sharp enough to notice any one part of the engine's torque missing, and
    the parts add up to the torque."""
    rng = np.random.default_rng(42)
    model = random_model(rng, friction=True)
    sm = SmoothMotion(rng)
    t = np.linspace(0.0, 2.0, 40)
    eng, _ = _both(model, sm, t)
    assert rel(sum(getattr(eng, p) for p in hip.PARTS), eng.tau) < 1e-12
    res, scale = _power_residual(model, sm, t, eng.tau - getattr(eng, part))
    assert np.abs(res).max() > 1e-3 * scale


def test_static_pose_needs_only_gravity_and_friction_is_finite_at_rest():
    model = load_params()
    n = 3
    z = np.zeros((n, 3))
    q = np.deg2rad([[5, -3, 2]] * n)
    eng = engine_torques(model, q, z, z, np.array([0.0, 1000.0, 3000.0]))
    assert np.all(np.isfinite(eng.tau))
    np.testing.assert_allclose(eng.friction, 0.0, atol=1e-15)
    np.testing.assert_allclose(eng.platform, 0.0, atol=1e-13)
    np.testing.assert_allclose(eng.screw, 0.0, atol=1e-15)
    # the sliders' weight: p / 2 pi * 2 m_L g on each motor
    g, m = model.geometry, model.inertia
    np.testing.assert_allclose(eng.slider, g.p / (2 * np.pi) * 2 * m.m_L * m.g, rtol=1e-12)
    # levers carry weight too, and loading the platforms changes nothing at rest
    assert np.all(np.abs(eng.lever) > 0)
    np.testing.assert_allclose(eng.tau[0], eng.tau[2], rtol=1e-12)


def test_hip_friction_grows_with_load_and_opposes_motion():
    """Eq. 16 through the load-driven friction of S0: it dissipates, grows with the load and is
    proportional to r_h mu_h F + r_t mu_t (F + m_m g) (the default platform mass is zero)."""
    model = load_params()
    sm = SmoothMotion(np.random.default_rng(9))
    t = np.linspace(0, 1, 40)
    q, qd, qdd = sm.angles(t)
    low = engine_torques(model, q, qd, qdd, np.full(t.shape, 300.0))
    high = engine_torques(model, q, qd, qdd, np.full(t.shape, 3000.0))
    theta_dot = low.kin.act_qd[:, :3]
    p_low = np.sum(low.hip_friction * theta_dot, axis=1)
    p_high = np.sum(high.hip_friction * theta_dot, axis=1)
    assert np.all(p_low >= 0) and np.all(p_high >= p_low) and p_low.max() > 0
    np.testing.assert_allclose(high.hip_friction, 10.0 * low.hip_friction, rtol=1e-9, atol=1e-12)
    # without the load there is no hip friction at all (m_m = 0)
    none = engine_torques(model, q, qd, qdd, np.zeros(t.shape))
    np.testing.assert_allclose(none.hip_friction, 0.0, atol=1e-15)


def test_bad_load_names_the_sample_and_the_motion_row():
    model = load_params()
    m = engine(model)
    t = np.linspace(0, 1, 5)
    z = np.zeros((5, 3))
    load = np.full(5, 500.0)
    load[3] = np.nan
    with pytest.raises(ParameterError, match=r"load 'hydraulic_N': sample 3 is not finite"):
        machine_verbs(m).inverse_dynamics(m, z, z, z, load)
    for bad, word in ((-1.0, "negative"), (np.nan, "not finite"), (np.inf, "not finite")):
        load[3] = bad
        with pytest.raises(MotionError, match=rf"row 4 .*{word}"):
            make_motion(t, z, z, z, load)


def test_nan_in_motion_names_the_row():
    t = np.linspace(0, 1, 5)
    q = np.zeros((5, 3))
    q[2, 1] = np.nan
    with pytest.raises(MotionError, match=r"row 3 .*angles"):
        make_motion(t, q, np.zeros((5, 3)), np.zeros((5, 3)))
