"""Forward dynamics of the hip simulator and its minimal-coordinate verbs.

Checks: forward(inverse(qdd)) = qdd with every friction term on; the equations of motion
``M qdd + h = B u`` assembled from the separate verbs; ``M`` symmetric positive definite and
equal to the Hessian of the kinetic energy computed body by body from the kinematics; energy
conservation of free motion; the forward dynamics against Pinocchio's spanning-tree inverse
dynamics; shapes and bad input.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from hip_helpers import random_model
from pkmdyn.errors import MotionError
from pkmdyn.machines import hip_simulator as hip
from pkmdyn.machines.hip_simulator import minimal
from pkmdyn.machines.hip_simulator.forward import mass_matrix_omega
from pkmdyn.machines.hip_simulator.kinematics import platform_kinematics
from pkmdyn.spatial import euler_kinematics


def _states(rng: np.random.Generator, n: int) -> tuple[np.ndarray, ...]:
    q = np.deg2rad(rng.uniform(-20.0, 20.0, (n, 3)))
    qd = rng.uniform(-2.0, 2.0, (n, 3))
    qdd = rng.uniform(-30.0, 30.0, (n, 3))
    load = rng.uniform(0.0, 3000.0, n)
    return q, qd, qdd, load


def _frictionless(model: hip.HipModel) -> hip.HipModel:
    """The model with every friction coefficient zero (Eq. 16 included)."""
    f = dataclasses.replace(
        model.friction,
        mu_h=0.0,
        mu_t=0.0,
        slider_coulomb=0.0,
        slider_viscous=0.0,
        screw_coulomb=0.0,
        screw_viscous=0.0,
        spherical_coulomb=0.0,
        spherical_viscous=0.0,
        universal_coulomb=0.0,
        universal_viscous=0.0,
    )
    return dataclasses.replace(model, friction=f)


def _energies(model: hip.HipModel, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Kinetic and potential energy [J], body by body from the kinematics (no mass matrix)."""
    g, m = model.geometry, model.inertia
    R, w, _ = euler_kinematics(g.euler_sequence, q, qd, np.zeros_like(q))
    kin = platform_kinematics(model, np.zeros(len(q)), R, w, np.zeros_like(q), check_conditioning=False)
    gear = g.p / (2.0 * np.pi)
    I_platform = np.einsum("nik,k,njk->nij", R, m.I_m, R)
    I_lever = np.einsum("nlik,k,nljk->nlij", kin.R_lever, m.I_l, kin.R_lever)
    Ld = kin.Ld[:, 1]
    ke = 2 * 0.5 * np.einsum("ni,nij,nj->n", w, I_platform, w)
    ke += 2 * 0.5 * m.m_l * np.sum(kin.v_lever**2, axis=(1, 2))
    ke += 2 * 0.5 * np.einsum("nli,nlij,nlj->n", kin.omega_lever, I_lever, kin.omega_lever)
    ke += 2 * 0.5 * m.m_L * np.sum(Ld**2, axis=1) + 0.5 * m.I_L * np.sum((Ld / gear) ** 2, axis=1)
    pe = m.g * (m.m_L * kin.L.sum(axis=(1, 2)) + m.m_l * kin.c_lever[..., 2].sum(axis=(1, 2)))
    return ke, pe


@pytest.mark.parametrize(
    ("seed", "spin", "sequence"),
    [(1, "u_joint", "XYZ"), (2, "perpendicular", "XYZ"), (3, "u_joint", "zyx"), (4, "perpendicular", "ZXY")],
)
def test_forward_inverts_inverse_with_friction(seed: int, spin: str, sequence: str) -> None:
    rng = np.random.default_rng(seed)
    model = random_model(rng, friction=True, lever_spin=spin, euler_sequence=sequence)
    q, qd, qdd, load = _states(rng, 40)
    # slow samples put the regularised friction laws on their steep part
    qd[:5] *= 1e-3
    u = minimal.inverse_dynamics(model, q, qd, qdd, load)
    assert np.all(np.abs(u) > 0)
    back = minimal.forward_dynamics(model, q, qd, u, load)
    np.testing.assert_allclose(back, qdd, rtol=0, atol=1e-9 * np.abs(qdd).max())
    # the platform-level function
    R, w, wd = euler_kinematics(model.geometry.euler_sequence, q, qd, qdd)
    kin = platform_kinematics(model, np.zeros(len(q)), R, w, wd, check_conditioning=False)
    tau = hip.inverse_dynamics(model, kin, load).tau
    np.testing.assert_allclose(tau, u, rtol=1e-13, atol=1e-13 * np.abs(u).max())
    wd_back = hip.forward_dynamics(model, R, w, tau, load)
    np.testing.assert_allclose(wd_back, wd, rtol=0, atol=1e-9 * np.abs(wd).max())


def test_equations_of_motion_from_the_separate_verbs() -> None:
    rng = np.random.default_rng(11)
    model = random_model(rng, friction=True)
    q, qd, qdd, load = _states(rng, 30)
    M = minimal.mass_matrix(model, q)
    h = minimal.bias_forces(model, q, qd, load)
    B = minimal.actuator_map(model, q)
    u = minimal.inverse_dynamics(model, q, qd, qdd, load)
    lhs = np.einsum("nij,nj->ni", M, qdd) + h
    np.testing.assert_allclose(lhs, np.einsum("nij,nj->ni", B, u), rtol=0, atol=1e-10 * np.abs(lhs).max())
    # B is the transpose of the map qd -> motor rates (virtual power of the motors)
    R, w, _ = euler_kinematics(model.geometry.euler_sequence, q, qd, np.zeros_like(q))
    kin = platform_kinematics(model, np.zeros(len(q)), R, w, np.zeros_like(q), check_conditioning=False)
    theta_dot = kin.Ld[:, 1] * 2.0 * np.pi / model.geometry.p
    np.testing.assert_allclose(np.einsum("nij,ni->nj", B, qd), theta_dot, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("spin", ["u_joint", "perpendicular"])
def test_mass_matrix_is_spd_and_the_kinetic_energy_hessian(spin: str) -> None:
    rng = np.random.default_rng(21)
    model = random_model(rng, lever_spin=spin)
    q, qd, _, _ = _states(rng, 25)
    M = minimal.mass_matrix(model, q)
    np.testing.assert_allclose(M, np.swapaxes(M, 1, 2), rtol=0, atol=1e-14 * np.abs(M).max())
    assert np.linalg.eigvalsh(M).min() > 0.0
    ke, _ = _energies(model, q, qd)
    np.testing.assert_allclose(0.5 * np.einsum("ni,nij,nj->n", qd, M, qd), ke, rtol=1e-12)
    # in omega: T = omega . M_w omega / 2, checked at the same poses with other velocities
    R, w, _ = euler_kinematics(model.geometry.euler_sequence, q, qd, np.zeros_like(q))
    kin = platform_kinematics(model, np.zeros(len(q)), R, w, np.zeros_like(q), check_conditioning=False)
    M_w = mass_matrix_omega(model, kin)
    np.testing.assert_allclose(0.5 * np.einsum("ni,nij,nj->n", w, M_w, w), ke, rtol=1e-12)


def test_free_motion_conserves_energy() -> None:
    """No friction, no actuation, no load, gravity on: 1 s of motion, tight integration."""
    rng = np.random.default_rng(5)
    model = _frictionless(random_model(rng))
    y0 = np.concatenate((np.deg2rad(rng.uniform(-5.0, 5.0, 3)), rng.uniform(-1.0, 1.0, 3)))
    zero_u, zero_load = np.zeros((1, 3)), np.zeros(1)

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        qdd = minimal.forward_dynamics(model, y[None, :3], y[None, 3:], zero_u, zero_load)[0]
        return np.concatenate((y[3:], qdd))

    sol = solve_ivp(rhs, (0.0, 1.0), y0, method="DOP853", rtol=1e-12, atol=1e-12, t_eval=np.linspace(0.0, 1.0, 11))
    assert sol.success
    q, qd = sol.y[:3].T, sol.y[3:].T
    ke, pe = _energies(model, q, qd)
    total = ke + pe
    # the machine moves: kinetic energy is exchanged with potential energy
    assert np.ptp(ke) > 1e-2 * ke.max()
    assert np.abs(total - total[0]).max() <= 1e-6 * ke.max()


def test_friction_dissipates() -> None:
    """With friction on and no actuation, the power balance: dE/dt = -(dissipated power) < 0."""
    rng = np.random.default_rng(6)
    model = random_model(rng, friction=True)
    q, qd, _, load = _states(rng, 10)
    u = np.zeros_like(q)
    qdd = minimal.forward_dynamics(model, q, qd, u, load)
    h = 1e-6
    e_plus = sum(_energies(model, q + h * qd, qd + h * qdd))
    e_minus = sum(_energies(model, q - h * qd, qd - h * qdd))
    dEdt = (e_plus - e_minus) / (2 * h)
    # friction power: minus the non-conservative part of the bias forces, qd . (h - h_frictionless)
    h_all = minimal.bias_forces(model, q, qd, load)
    h_free = minimal.bias_forces(_frictionless(model), q, qd, load)
    dissipated = np.einsum("ni,ni->n", qd, h_all - h_free)
    assert np.all(dissipated > 0)
    np.testing.assert_allclose(dEdt, -dissipated, rtol=1e-5)


def test_forward_against_pinocchio_inverse_dynamics() -> None:
    """Pinocchio's spanning tree + loop closures gives torques; ours must give back omega_dot."""
    pytest.importorskip("pinocchio")
    from oracles.hip_pinocchio import reference_torques

    rng = np.random.default_rng(31)
    model = random_model(rng, friction=True)
    q, qd, qdd, load = _states(rng, 4)
    R, w, wd = euler_kinematics(model.geometry.euler_sequence, q, qd, qdd)
    ref = reference_torques(model, np.zeros(4), R, w, wd, load)
    wd_ours = hip.forward_dynamics(model, R, w, ref["tau"], load)
    np.testing.assert_allclose(wd_ours, wd, rtol=0, atol=1e-7 * np.abs(wd).max())
    # friction-free torques too (a different right-hand side through the same mass matrix)
    wd_free = hip.forward_dynamics(_frictionless(model), R, w, ref["no_friction"], load)
    np.testing.assert_allclose(wd_free, wd, rtol=0, atol=1e-7 * np.abs(wd).max())


def test_batch_rows_match_single_rows_and_bad_input() -> None:
    rng = np.random.default_rng(41)
    model = random_model(rng, friction=True)
    q, qd, qdd, load = _states(rng, 5)
    u = minimal.inverse_dynamics(model, q, qd, qdd, load)
    rows = np.vstack([minimal.forward_dynamics(model, q[k : k + 1], qd[k : k + 1], u[k : k + 1], load[k : k + 1]) for k in range(5)])
    np.testing.assert_allclose(rows, minimal.forward_dynamics(model, q, qd, u, load), rtol=1e-14, atol=1e-12)
    with pytest.raises(MotionError, match=r"u: expected shape \(5, 3\)"):
        minimal.forward_dynamics(model, q, qd, u.T, load)
    with pytest.raises(MotionError, match="load"):
        minimal.forward_dynamics(model, q, qd, u, -load)
    with pytest.raises(MotionError, match="tau"):
        hip.forward_dynamics(model, np.eye(3)[None], np.zeros((1, 3)), np.zeros(3), np.zeros(1))
    assert minimal.COORDINATES == ("alpha_rad", "beta_rad", "gamma_rad")
    assert minimal.ACTUATORS == ("tau1_Nm", "tau2_Nm", "tau3_Nm")
