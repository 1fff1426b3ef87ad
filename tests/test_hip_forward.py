"""Forward dynamics of the hip simulator through the generic engine's machine verbs
(:func:`pkmdyn.multibody.dynamics.verbs.machine_verbs` of the hip's description, in the upper platform's
Euler angles).

Checks: the verbs' ``M``, ``h``, ``B`` and inverse dynamics against the closed form
(``tests/oracles/hip.py``, 1e-9); forward(inverse(qdd)) = qdd with every friction term on; the
equations of motion ``M qdd + h = B u`` assembled from the separate verbs; ``M`` symmetric
positive definite and the kinetic energy computed body by body; energy conservation of free
motion; friction dissipates; the forward dynamics of Pinocchio's torques; single rows equal to
batches and bad input.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from hip_helpers import engine, random_model, rel
from oracles import hip
from pkmdyn.errors import MotionError, SingularityError
from pkmdyn.multibody.dynamics.verbs import machine_verbs

TOL = 1e-9


def _states(rng: np.random.Generator, n: int) -> tuple[np.ndarray, ...]:
    q = np.deg2rad(rng.uniform(-20.0, 20.0, (n, 3)))
    qd = rng.uniform(-2.0, 2.0, (n, 3))
    qdd = rng.uniform(-30.0, 30.0, (n, 3))
    load = rng.uniform(0.0, 3000.0, n)
    return q, qd, qdd, load


def _frictionless(model):
    """The model with every friction coefficient zero (Eq. 16 included)."""
    f = dataclasses.replace(model.friction, mu_h=0.0, mu_t=0.0, slider_coulomb=0.0, slider_viscous=0.0,
                            screw_coulomb=0.0, screw_viscous=0.0, spherical_coulomb=0.0, spherical_viscous=0.0,
                            universal_coulomb=0.0, universal_viscous=0.0)
    return dataclasses.replace(model, friction=f)


def _verbs(model):
    m = engine(model)
    return m, machine_verbs(m)


def _energy(model, q, qd):
    """Kinetic and potential energy [J], body by body from the oracle's kinematics (no mass matrix)."""
    return hip.energies(model, hip.kinematics(model, q, qd))


@pytest.mark.parametrize(("seed", "sequence"), [(1, "XYZ"), (2, "zyx"), (3, "ZXY"), (4, "yxz")])
def test_forward_inverts_inverse_with_friction_and_both_match_the_closed_form(seed: int, sequence: str) -> None:
    rng = np.random.default_rng(seed)
    model = random_model(rng, friction=True, euler_sequence=sequence)
    m, V = _verbs(model)
    q, qd, qdd, load = _states(rng, 40)
    qd[:5] *= 1e-3  # slow samples put the regularised friction laws on their steep part
    u = V.inverse_dynamics(m, q, qd, qdd, load)
    assert np.all(np.abs(u) > 0)
    assert rel(u, hip.inverse_dynamics_q(model, q, qd, qdd, load)) < TOL
    back = V.forward_dynamics(m, q, qd, u, load)
    np.testing.assert_allclose(back, qdd, rtol=0, atol=1e-9 * np.abs(qdd).max())
    assert rel(back, hip.forward_dynamics_q(model, q, qd, u, load)) < TOL
    # in the platforms' angular acceleration too
    k = hip.kinematics(model, q, qd, qdd)
    assert rel(hip.forward_dynamics_omega(model, k.R, k.omega, u, load), k.omega_dot) < TOL


def test_equations_of_motion_from_the_separate_verbs() -> None:
    rng = np.random.default_rng(11)
    model = random_model(rng, friction=True)
    m, V = _verbs(model)
    q, qd, qdd, load = _states(rng, 30)
    M = V.mass_matrix(m, q)
    h = V.bias_forces(m, q, qd, load)
    B = V.actuator_map(m, q)
    u = V.inverse_dynamics(m, q, qd, qdd, load)
    assert rel(M, hip.mass_matrix(model, q)) < TOL
    assert rel(h, hip.bias_forces(model, q, qd, load)) < TOL
    assert rel(B, hip.actuator_map(model, q)) < TOL
    lhs = np.einsum("nij,nj->ni", M, qdd) + h
    np.testing.assert_allclose(lhs, np.einsum("nij,nj->ni", B, u), rtol=0, atol=1e-10 * np.abs(lhs).max())
    # B is the transpose of the map qd -> motor rates (virtual power of the motors)
    np.testing.assert_allclose(np.einsum("nij,ni->nj", B, qd), hip.kinematics(model, q, qd).theta_dot,
                               rtol=1e-9, atol=1e-12)


def test_mass_matrix_is_spd_and_the_kinetic_energy() -> None:
    rng = np.random.default_rng(21)
    model = random_model(rng)
    m, V = _verbs(model)
    q, qd, _, _ = _states(rng, 25)
    M = V.mass_matrix(m, q)
    np.testing.assert_allclose(M, np.swapaxes(M, 1, 2), rtol=0, atol=1e-12 * np.abs(M).max())
    assert np.linalg.eigvalsh(M).min() > 0.0
    ke, _ = _energy(model, q, qd)
    np.testing.assert_allclose(0.5 * np.einsum("ni,nij,nj->n", qd, M, qd), ke, rtol=1e-9)


def test_free_motion_conserves_energy() -> None:
    """No friction, no actuation, no load, gravity on: 0.15 s of motion through the engine's
    single-sample forward dynamics, tight integration. The unactuated machine swings about the
    vertical and reaches a direct singularity (det(J_b) = 0) in about 0.2 s, where the task (the
    upper platform) no longer fixes the lower platform's orientation: the motion here stays
    clear of it (cond(J) < 10 all along, checked)."""
    rng = np.random.default_rng(5)
    model = _frictionless(random_model(rng))
    m, V = _verbs(model)
    y0 = np.concatenate((np.deg2rad(rng.uniform(-5.0, 5.0, 3)), rng.uniform(-1.0, 1.0, 3)))
    zero_u = np.zeros(3)

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        return np.concatenate((y[3:], V.forward_dynamics_one(m, y[:3], y[3:], zero_u, 0.0)))

    sol = solve_ivp(rhs, (0.0, 0.15), y0, method="DOP853", rtol=1e-12, atol=1e-12, t_eval=np.linspace(0.0, 0.15, 11))
    assert sol.success
    q, qd = sol.y[:3].T, sol.y[3:].T
    assert hip.kinematics(model, q, qd).cond_J.max() < 10.0
    ke, pe = _energy(model, q, qd)
    total = ke + pe
    # the machine moves: kinetic energy is exchanged with potential energy
    assert np.ptp(ke) > 1e-1 * ke.max()
    assert np.abs(total - total[0]).max() <= 1e-9 * ke.max()
    # the engine's accelerations along the path are the closed form's
    acc = np.array([V.forward_dynamics_one(m, a, b, zero_u, 0.0) for a, b in zip(q, qd)])
    assert rel(acc, hip.forward_dynamics_q(model, q, qd, np.zeros_like(q), np.zeros(len(q)))) < TOL


def test_friction_dissipates() -> None:
    """With friction on and no actuation, the power balance: dE/dt = -(dissipated power) < 0."""
    rng = np.random.default_rng(6)
    model = random_model(rng, friction=True)
    m, V = _verbs(model)
    q, qd, _, load = _states(rng, 10)
    qdd = V.forward_dynamics(m, q, qd, np.zeros_like(q), load)
    h = 1e-6
    dEdt = (sum(_energy(model, q + h * qd, qd + h * qdd)) - sum(_energy(model, q - h * qd, qd - h * qdd))) / (2 * h)
    # friction power: the non-conservative part of the bias forces, qd . (h - h_frictionless)
    free = _frictionless(model)
    mf, Vf = _verbs(free)
    dissipated = np.einsum("ni,ni->n", qd, V.bias_forces(m, q, qd, load) - Vf.bias_forces(mf, q, qd, load))
    assert np.all(dissipated > 0)
    np.testing.assert_allclose(dissipated, hip.dissipation(model, hip.kinematics(model, q, qd), load), rtol=1e-9)
    np.testing.assert_allclose(dEdt, -dissipated, rtol=1e-5)


def test_forward_against_pinocchio_inverse_dynamics() -> None:
    """Pinocchio's spanning tree + loop closures gives torques; the engine must give back qdd."""
    pytest.importorskip("pinocchio")
    from oracles.hip_pinocchio import reference_torques

    rng = np.random.default_rng(31)
    model = random_model(rng, friction=True)
    m, V = _verbs(model)
    q, qd, qdd, load = _states(rng, 4)
    k = hip.kinematics(model, q, qd, qdd)
    ref = reference_torques(model, np.zeros(4), k.R, k.omega, k.omega_dot, load)
    np.testing.assert_allclose(V.forward_dynamics(m, q, qd, ref["tau"], load), qdd, rtol=0, atol=1e-7 * np.abs(qdd).max())
    # friction-free torques too (a different right-hand side through the same mass matrix)
    free = _frictionless(model)
    mf, Vf = _verbs(free)
    np.testing.assert_allclose(Vf.forward_dynamics(mf, q, qd, ref["no_friction"], load), qdd, rtol=0,
                               atol=1e-7 * np.abs(qdd).max())


def test_batch_rows_match_single_rows_and_bad_input() -> None:
    rng = np.random.default_rng(41)
    model = random_model(rng, friction=True)
    m, V = _verbs(model)
    q, qd, qdd, load = _states(rng, 5)
    u = V.inverse_dynamics(m, q, qd, qdd, load)
    rows = np.vstack([V.forward_dynamics(m, q[k:k + 1], qd[k:k + 1], u[k:k + 1], load[k:k + 1]) for k in range(5)])
    np.testing.assert_allclose(rows, V.forward_dynamics(m, q, qd, u, load), rtol=1e-12, atol=1e-12 * np.abs(qdd).max())
    with pytest.raises(MotionError, match=r"u: expected shape \(n, 3\), got \(3, 5\)"):
        V.forward_dynamics(m, q, qd, u.T, load)
    lock = np.array([[0.0, np.pi / 2, 0.0]])  # XYZ: beta = 90 deg
    with pytest.raises(SingularityError, match=r"Euler angles \(XYZ\) of task body 'upper' are at their singularity"):
        V.forward_dynamics(m, lock, np.zeros((1, 3)), np.zeros((1, 3)), np.zeros(1))
