"""Self-tests of the hip simulator's closed-form oracle (``tests/oracles/hip.py``), each against a
second route that shares no formula with it: scalar root search of the loop closure, central
finite differences of every rate, small rotations for the Jacobian, the energy of the bodies for
the mass matrix and the power balance, the forward dynamics of the inverse dynamics, integration
of free motion, and the Pinocchio reference (``tests/oracles/hip_pinocchio.py``, skipped where
Pinocchio is not installed). Some checks are also run on a deliberately wrong input, which must
fail them."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation

from hip_helpers import SmoothMotion, random_model
from oracles import hip
from pkmdyn.machines.hip_simulator.params import default_params_dict, load_params, model_from_dict

SEEDS = range(4)
PARTS = hip.PARTS


def _skew(v):
    """``[v]x (..., 3, 3)``: its row k is ``e_k x v``, so ``[v]x w = v x w``."""
    return np.cross(np.eye(3), np.asarray(v)[..., None, :])


def _frictionless(model):
    f = dataclasses.replace(model.friction, mu_h=0.0, mu_t=0.0, slider_coulomb=0.0, slider_viscous=0.0,
                            screw_coulomb=0.0, screw_viscous=0.0, spherical_coulomb=0.0, spherical_viscous=0.0,
                            universal_coulomb=0.0, universal_viscous=0.0)
    return dataclasses.replace(model, friction=f)


def _kin(model, sm, t):
    return hip.kinematics(model, *sm.angles(t))


def _states(rng, n):
    q = np.deg2rad(rng.uniform(-20.0, 20.0, (n, 3)))
    qd = rng.uniform(-2.0, 2.0, (n, 3))
    qdd = rng.uniform(-30.0, 30.0, (n, 3))
    return q, qd, qdd, rng.uniform(0.0, 3000.0, n)


# --------------------------------------------------------------------------- kinematics


@pytest.mark.parametrize("seed", SEEDS)
def test_positions_against_root_search_and_the_loop(seed):
    rng = np.random.default_rng(seed)
    model = random_model(rng)
    sm = SmoothMotion(rng)
    t = np.linspace(0, 2, 12)
    k = _kin(model, sm, t)
    g = model.geometry
    q = sm.angles(t)[0]
    for n in range(len(t)):
        R = Rotation.from_euler(g.euler_sequence, q[n]).as_matrix()
        np.testing.assert_allclose(k.R[n], R, atol=1e-14)
        for j in range(2):
            for i in range(3):
                a = g.o[j] + R @ g.r_a[i]
                L = brentq(lambda s: np.linalg.norm(a - (g.A[i] + [0, 0, s])) - g.l, a[2] - g.l, a[2],
                           xtol=1e-15, rtol=1e-15)
                assert abs(k.L[n, j, i] - L) < 1e-12
    np.testing.assert_allclose(k.L[:, 0] - k.L[:, 1], g.h[0] - g.h[1], atol=1e-12)
    for j in range(2):
        a = g.o[j] + k.r
        b = g.A + k.L[:, j, :, None] * np.array([0, 0, 1.0])
        np.testing.assert_allclose(np.linalg.norm(a - b, axis=-1), g.l, rtol=1e-12)
        np.testing.assert_allclose(a - b, k.d, atol=1e-12)
        np.testing.assert_allclose(k.c_lever[:, j], 0.5 * (a + b), atol=1e-12)
        assert np.all(a[..., 2] > b[..., 2])  # the branch: each slider below its S joint
    # the lever frame: orthonormal, z along the lever, x normal to the U joint's first axis
    Rl = k.R_lever
    np.testing.assert_allclose(np.swapaxes(Rl, -1, -2) @ Rl, np.broadcast_to(np.eye(3), Rl.shape), atol=1e-14)
    np.testing.assert_allclose(np.linalg.det(Rl), 1.0, atol=1e-14)
    np.testing.assert_allclose(Rl[..., 2], k.e_lever, atol=1e-15)
    np.testing.assert_allclose(np.einsum("lk,nlk->nl", g.t, Rl[..., 0]), 0.0, atol=1e-15)


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("spin", ["u_joint", "perpendicular"])
def test_rates_against_finite_differences(seed, spin):
    rng = np.random.default_rng(100 + seed)
    model = random_model(rng, lever_spin=spin)
    sm = SmoothMotion(rng)
    t = np.linspace(0.05, 2, 20)
    h = 1e-5
    k, kp, km = _kin(model, sm, t), _kin(model, sm, t + h), _kin(model, sm, t - h)

    def fd(name):
        return (getattr(kp, name) - getattr(km, name)) / (2 * h)

    for value, rate in (("L", "Ld"), ("Ld", "Ldd"), ("d", "d_dot"), ("d_dot", "d_ddot"), ("v_lever", "a_lever"),
                        ("omega_lever", "omega_lever_dot"), ("omega", "omega_dot")):
        ref = getattr(k, rate)
        np.testing.assert_allclose(fd(value), ref, atol=1e-6 * np.abs(ref).max(), err_msg=rate)
    for j in range(2):
        np.testing.assert_allclose(fd("c_lever")[:, j], k.v_lever, atol=1e-6 * np.abs(k.v_lever).max())
    W = fd("R") @ np.swapaxes(k.R, -1, -2)  # the platforms' angular velocity is the rate of R
    np.testing.assert_allclose(W, _skew(k.omega), atol=1e-6 * np.abs(k.omega).max())
    Wl = fd("R_lever") @ np.swapaxes(k.R_lever, -1, -2)
    e_dot = fd("e_lever")
    np.testing.assert_allclose(np.cross(k.omega_lever, k.e_lever), e_dot, atol=1e-6 * np.abs(e_dot).max())
    if spin == "u_joint":  # the lever's angular velocity is the rate of its frame (spin included)
        np.testing.assert_allclose(Wl, _skew(k.omega_lever), atol=1e-6 * np.abs(k.omega_lever).max())
        assert np.abs(k.spin).max() > 1e-3
    else:  # the paper's Eq. 4: the axis' rate with no spin, which is not the frame's rate
        np.testing.assert_allclose(np.einsum("nik,nik->ni", k.omega_lever, k.e_lever), 0, atol=1e-12)
        assert np.abs(Wl - _skew(k.omega_lever)).max() > 1e-3 * np.abs(k.omega_lever).max()


def test_skew_helper_is_the_cross_product():
    v, w = np.array([0.3, -1.2, 0.7]), np.array([-0.4, 0.2, 1.1])
    np.testing.assert_allclose(_skew(v) @ w, np.cross(v, w), atol=1e-15)


@pytest.mark.parametrize("seed", SEEDS)
def test_jacobians_against_small_rotations(seed):
    """``Ld = J omega`` and the levers' velocity Jacobians from a small rotation of the platforms."""
    rng = np.random.default_rng(200 + seed)
    model = random_model(rng)
    sm = SmoothMotion(rng)
    t = np.linspace(0, 1, 6)
    k = _kin(model, sm, t)
    h = 1e-7
    z = np.zeros((len(t), 3))
    for axis in range(3):
        dw = np.zeros(3)
        dw[axis] = h
        kp = hip.platform_kinematics(model, Rotation.from_rotvec(dw).as_matrix() @ k.R, z, z)
        km = hip.platform_kinematics(model, Rotation.from_rotvec(-dw).as_matrix() @ k.R, z, z)
        np.testing.assert_allclose((kp.L[:, 1] - km.L[:, 1]) / (2 * h), k.J[:, :, axis], atol=1e-7 * np.abs(k.J).max())
    np.testing.assert_allclose(k.J, k.Jb / k.Ja[..., None], rtol=1e-12)
    np.testing.assert_allclose(k.det_Ja, np.prod(k.Ja, axis=1), rtol=1e-12)
    np.testing.assert_allclose(np.linalg.det(k.J), k.det_Jb / k.det_Ja, rtol=1e-9)
    np.testing.assert_allclose(k.cond_J, np.linalg.cond(k.J), rtol=1e-12)
    Jvl, Jwl = hip.lever_jacobians(model, k)
    np.testing.assert_allclose(np.einsum("nlij,nj->nli", Jvl, k.omega), k.v_lever, atol=1e-13)
    np.testing.assert_allclose(np.einsum("nlij,nj->nli", Jwl, k.omega), k.omega_lever, atol=1e-13)
    E = hip.rate_map(model, sm.angles(t)[0])
    np.testing.assert_allclose(np.einsum("nij,nj->ni", E, sm.angles(t)[1]), k.omega, atol=1e-13)


def test_singular_layout():
    """psi = phi: every lever's projection through the platform centre, det(J_b) = 0 (sec. 3.3)."""
    d = default_params_dict()
    d["geometry"]["platform_joint_angles_deg"] = list(d["geometry"]["module_angles_deg"])
    k = hip.kinematics(model_from_dict(d), np.zeros((1, 3)))
    assert abs(k.det_Jb[0]) < 1e-15 and k.cond_J[0] > 1e12
    k = hip.kinematics(load_params(), np.zeros((1, 3)))
    assert abs(k.det_Jb[0]) > 1e-4 and k.cond_J[0] < 1e3


def test_unreachable_pose_is_nan():
    k = hip.kinematics(load_params(), np.deg2rad([[0, 0, 0], [0, 0, 95.0]]))
    assert np.all(np.isfinite(k.L[0])) and np.isnan(k.L[1]).any()


# --------------------------------------------------------------------------- dynamics


def _power_residual(model, sm, t, tau=None):
    h = 1e-5
    k = _kin(model, sm, t)
    tq = hip.inverse_dynamics(model, k, sm.load(t))
    tau = tq.tau if tau is None else tau
    E = [sum(hip.energies(model, _kin(model, sm, t + s * h))) for s in (-1, 1)]
    power = np.sum(tau * k.theta_dot, axis=1)
    return power - (E[1] - E[0]) / (2 * h) - hip.dissipation(model, k, sm.load(t)), np.abs(power).max(), tq


@pytest.mark.parametrize("seed", range(6))
def test_power_balance(seed):
    """sum tau theta_dot = d(T + V)/dt + the power every friction law dissipates."""
    rng = np.random.default_rng(300 + seed)
    model = random_model(rng, friction=seed % 2 == 0, lever_spin="u_joint")
    sm = SmoothMotion(rng)
    t = np.linspace(0.0, 2.0, 40)
    res, scale, tq = _power_residual(model, sm, t)
    assert np.abs(res).max() <= 1e-6 * scale
    np.testing.assert_allclose(sum(getattr(tq, p) for p in PARTS), tq.tau, rtol=1e-13, atol=1e-13 * np.abs(tq.tau).max())
    np.testing.assert_allclose(tq.power, np.sum(tq.tau * _kin(model, sm, t).theta_dot, axis=1), rtol=1e-13)


@pytest.mark.parametrize("part", PARTS)
def test_power_balance_detects_a_dropped_part(part):
    rng = np.random.default_rng(42)
    model = random_model(rng, friction=True)
    sm = SmoothMotion(rng)
    t = np.linspace(0.0, 2.0, 40)
    _, _, tq = _power_residual(model, sm, t)
    res, scale, _ = _power_residual(model, sm, t, tq.tau - getattr(tq, part))
    assert np.abs(res).max() > 1e-3 * scale


def test_perpendicular_levers_are_close_to_the_u_joint_model():
    """The paper's Eq. 4 drops only the levers' small spin: the platform part is unchanged, the
    lever part moves by less than 1 %."""
    from pkmdyn.profiles.iso14242 import iso14242_motion

    from hip_helpers import with_lever_spin

    ujoint = load_params()
    perp = with_lever_spin(ujoint, "perpendicular")
    mo = iso14242_motion(1, 250)
    kp, ku = (hip.kinematics(x, mo.angles, mo.rates, mo.accels) for x in (perp, ujoint))
    tp, tu = hip.inverse_dynamics(perp, kp, mo.load), hip.inverse_dynamics(ujoint, ku, mo.load)
    assert np.all(np.isfinite(tp.tau))
    np.testing.assert_allclose(kp.spin, 0.0)
    assert np.abs(ku.spin).max() > 1e-3
    assert 0 < np.abs(tp.lever - tu.lever).max() < 1e-2 * np.abs(tu.lever).max()
    np.testing.assert_array_equal(tp.platform, tu.platform)


def test_hip_bearing_friction_follows_eq16_by_hand():
    omega = np.array([[0.0, 0.0, 2.0], [0.0, 0.0, 0.0]])
    tau = hip.hip_bearing_friction(omega, np.array([1000.0, 1000.0]), 20.0, 0.015, 0.1, 0.06, 0.02, 1e-9)
    np.testing.assert_allclose(tau[0], [0, 0, 0.015 * 0.1 * 1000 + 0.06 * 0.02 * 1020], rtol=1e-12)
    np.testing.assert_array_equal(tau[1], 0.0)


@pytest.mark.parametrize(("seed", "spin", "sequence"),
                         [(1, "u_joint", "XYZ"), (2, "perpendicular", "XYZ"), (3, "u_joint", "zyx"), (4, "u_joint", "ZXY")])
def test_forward_of_inverse_and_the_equations_of_motion(seed, spin, sequence):
    rng = np.random.default_rng(seed)
    model = random_model(rng, friction=True, lever_spin=spin, euler_sequence=sequence)
    q, qd, qdd, load = _states(rng, 30)
    qd[:5] *= 1e-3  # the regularised friction laws on their steep part
    u = hip.inverse_dynamics_q(model, q, qd, qdd, load)
    assert np.all(np.abs(u) > 0)
    np.testing.assert_allclose(hip.forward_dynamics_q(model, q, qd, u, load), qdd, rtol=0, atol=1e-9 * np.abs(qdd).max())
    k = hip.kinematics(model, q, qd, qdd)
    wd = hip.forward_dynamics_omega(model, k.R, k.omega, u, load)
    np.testing.assert_allclose(wd, k.omega_dot, rtol=0, atol=1e-9 * np.abs(k.omega_dot).max())
    M, h, B = hip.mass_matrix(model, q), hip.bias_forces(model, q, qd, load), hip.actuator_map(model, q)
    lhs = np.einsum("nij,nj->ni", M, qdd) + h
    np.testing.assert_allclose(lhs, np.einsum("nij,nj->ni", B, u), rtol=0, atol=1e-10 * np.abs(lhs).max())
    np.testing.assert_allclose(np.einsum("nij,ni->nj", B, qd), k.theta_dot, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("spin", ["u_joint", "perpendicular"])
def test_mass_matrix_is_spd_and_the_kinetic_energy(spin):
    rng = np.random.default_rng(21)
    model = random_model(rng, lever_spin=spin)
    q, qd, _, _ = _states(rng, 20)
    M = hip.mass_matrix(model, q)
    np.testing.assert_allclose(M, np.swapaxes(M, 1, 2), rtol=0, atol=1e-14 * np.abs(M).max())
    assert np.linalg.eigvalsh(M).min() > 0.0
    k = hip.kinematics(model, q, qd)
    T, _ = hip.energies(model, k)
    np.testing.assert_allclose(0.5 * np.einsum("ni,nij,nj->n", qd, M, qd), T, rtol=1e-12)
    M_w = hip.mass_matrix_omega(model, k)
    np.testing.assert_allclose(0.5 * np.einsum("ni,nij,nj->n", k.omega, M_w, k.omega), T, rtol=1e-12)


def test_free_motion_conserves_energy():
    """No friction, torque or load, gravity on: 1 s of motion, tight integration."""
    rng = np.random.default_rng(5)
    model = _frictionless(random_model(rng))
    y0 = np.concatenate((np.deg2rad(rng.uniform(-5.0, 5.0, 3)), rng.uniform(-1.0, 1.0, 3)))
    zu, zl = np.zeros((1, 3)), np.zeros(1)

    def rhs(_t, y):
        return np.concatenate((y[3:], hip.forward_dynamics_q(model, y[None, :3], y[None, 3:], zu, zl)[0]))

    sol = solve_ivp(rhs, (0.0, 1.0), y0, method="DOP853", rtol=1e-12, atol=1e-12, t_eval=np.linspace(0.0, 1.0, 11))
    assert sol.success
    T, V = hip.energies(model, hip.kinematics(model, sol.y[:3].T, sol.y[3:].T))
    assert np.ptp(T) > 1e-2 * T.max()
    assert np.abs(T + V - T[0] - V[0]).max() <= 1e-6 * T.max()


def test_friction_dissipates():
    rng = np.random.default_rng(6)
    model = random_model(rng, friction=True)
    q, qd, _, load = _states(rng, 10)
    qdd = hip.forward_dynamics_q(model, q, qd, np.zeros_like(q), load)
    h = 1e-6
    E = [sum(hip.energies(model, hip.kinematics(model, q + s * h * qd, qd + s * h * qdd))) for s in (-1, 1)]
    dissipated = hip.dissipation(model, hip.kinematics(model, q, qd), load)
    assert np.all(dissipated > 0)
    np.testing.assert_allclose((E[1] - E[0]) / (2 * h), -dissipated, rtol=1e-5)


# --------------------------------------------------------------------------- the Pinocchio reference


PIN_CASES = {
    "builtin": lambda: load_params(),
    "all_friction": lambda: random_model(np.random.default_rng(0), 0.0, True),
    "random_1": lambda: random_model(np.random.default_rng(1), 0.15, True),
    "random_2": lambda: random_model(np.random.default_rng(2), 0.20, True),
    # strongly non-axisymmetric lever (no rigid body's; the oracle and Pinocchio take it): the
    # lever frame's orientation about its axis matters
    "asymmetric_lever": lambda: random_model(np.random.default_rng(4), 0.10, True,
                                             inertia={"lever_inertia_kgm2": [0.040, 0.012, 0.004]}),
}


@pytest.mark.parametrize("case", list(PIN_CASES))
def test_agrees_with_the_pinocchio_reference(case):
    pytest.importorskip("pinocchio")
    from oracles.hip_pinocchio import reference_torques

    model = PIN_CASES[case]()
    rng = np.random.default_rng(10 + list(PIN_CASES).index(case))
    sm = SmoothMotion(rng)
    t = np.linspace(0.0, 1.2, 15)
    k = _kin(model, sm, t)
    ours = hip.inverse_dynamics(model, k, sm.load(t))
    ref = reference_torques(model, t, k.R, k.omega, k.omega_dot, sm.load(t))
    scale = np.abs(ref["tau"]).max()
    for part in (*PARTS, "tau", "hip_friction"):
        assert np.abs(getattr(ours, part) - ref[part]).max() < 1e-6 * scale, part
    np.testing.assert_allclose(ref["L"], k.L[:, 1], atol=1e-10)
    # the forward dynamics gives the reference's accelerations back from its torques
    wd = hip.forward_dynamics_omega(model, k.R, k.omega, ref["tau"], sm.load(t))
    np.testing.assert_allclose(wd, k.omega_dot, rtol=0, atol=1e-7 * np.abs(k.omega_dot).max())
    if case == "asymmetric_lever":  # the lever's I_xx and I_yy swapped: far off
        swapped = random_model(np.random.default_rng(4), 0.10, True, inertia={"lever_inertia_kgm2": [0.012, 0.040, 0.004]})
        other = reference_torques(swapped, t, k.R, k.omega, k.omega_dot, sm.load(t))["tau"]
        assert np.abs(ours.tau - other).max() > 1e-3 * scale
