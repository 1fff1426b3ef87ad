"""The PDM's machine verbs in its minimal coordinates (x, y, alpha, gamma): the generic engine
on the PDM's description under the paper's names (what ``pkmdyn pdm control`` runs): mass
matrix, bias forces, actuator map, inverse and forward dynamics, the single-sample path.

Independent means: the hand-derived oracles (``tests/oracles/pdm_minimal.py``, virtual power on
the paper's Eq. 2-48 kinematics; ``tests/oracles/pdm_newton_euler.py``, Eq. 49-62); Lagrange's
equations from finite differences of the oracle's kinetic and potential energy (from the body
velocities and centres of mass, never through M or h); the power balance sum f_k l_dot_k =
dE/dt along smooth motions; energy conservation of free motion integrated by scipy; B against
finite differences of the limb lengths of the hand-derived inverse position.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from pkmdyn.errors import PkmdynError
from pkmdyn.machines.pdm4 import (
    default_params_path,
    inverse_kinematics,
    inverse_position,
    load_params,
    reachable,
)
from pkmdyn.machines.pdm4.control_job import control_model, verbs
from pkmdyn.machines.pdm4.params import params_from_dict
from pkmdyn.params_util import read_toml
from pkmdyn.profiles.pdm_motion import PdmMotion

from oracles import pdm_minimal as oracle
from oracles import pdm_newton_euler

BASE = load_params()
SCALE = np.array([0.012, 0.012, math.radians(6), math.radians(12)])


def _inertia(rng: np.random.Generator, size: float) -> np.ndarray:
    """A random inertia tensor [kg m^2]: positive principal moments obeying the triangle
    inequality, in a random orientation."""
    while True:
        d = rng.uniform(0.05, 1.0, 3)
        if d.sum() > 2 * d.max():
            break
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return size * Q @ np.diag(d) @ Q.T


def _geometry(rng: np.random.Generator):
    """The default description with its platform offset, U-joint placement, home limb lengths
    and limb directions perturbed (+-10 %, +-5 deg): another machine of the same topology."""
    raw = read_toml(default_params_path())
    g = raw["geometry"]
    for key in ("platform_offset_m", "u_joint_half_spacing_m", "u_joint_height_m", "rpr_home_length_m",
                "spu_home_length_m"):
        g[key] *= rng.uniform(0.9, 1.1)
    g["rpr_home_direction_deg"] = [a + rng.uniform(-5, 5) for a in g["rpr_home_direction_deg"]]
    g["spu_home_elevation_deg"] += rng.uniform(-5, 5)
    g["spu_home_azimuth_deg"] = [a + rng.uniform(-5, 5) for a in g["spu_home_azimuth_deg"]]
    return params_from_dict(raw, "perturbed")


def _machine(seed: int, gravity: np.ndarray | None = None):
    """A perturbed geometry (odd seeds; the default one for even seeds) with random masses,
    inertias, centres of mass and gravity."""
    rng = np.random.default_rng(seed)
    base = _geometry(rng) if seed % 2 else BASE
    g = rng.normal(size=3) * 5.0 if gravity is None else np.asarray(gravity, float)
    return dataclasses.replace(
        base,
        mass=rng.uniform(0.2, 4.0, 14),
        inertia=np.stack([_inertia(rng, rng.uniform(1e-4, 3e-2)) for _ in range(14)]),
        gravity=g,
        cylinder_com=rng.uniform(0.03, 0.2, 4),
        piston_com=rng.uniform(0.03, 0.15, 4),
    )


def _states(seed: int, n: int, model=BASE) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """n reachable poses with random rates and accelerations."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(-1, 1, (6 * n, 4)) * SCALE
    q = q[reachable(model, q)][:n]
    assert q.shape[0] == n
    qd = rng.normal(size=(n, 4)) * np.array([0.05, 0.05, 0.4, 0.8])
    qdd = rng.normal(size=(n, 4)) * np.array([0.3, 0.3, 2.0, 5.0])
    return q, qd, qdd


def _smooth(seed: int, t: np.ndarray) -> PdmMotion:
    """q = offset + amp sin(freq t + phase) per coordinate, with exact derivatives."""
    rng = np.random.default_rng(seed)
    amp = rng.uniform(0.2, 0.6, 4) * SCALE
    freq = rng.uniform(1.0, 6.0, 4)
    phase = rng.uniform(0, 2 * np.pi, 4)
    off = rng.uniform(-0.4, 0.4, 4) * SCALE
    arg = freq * t[:, None] + phase
    return PdmMotion(t, off + amp * np.sin(arg), amp * freq * np.cos(arg), -amp * freq**2 * np.sin(arg))


def _engine(model):
    """The engine's verbs and model of ``model`` (a :class:`PdmModel`)."""
    cm = control_model(model)
    return verbs(cm), cm


# ----------------------------------------------------------------------------- mass matrix
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_mass_matrix_is_symmetric_positive_definite(seed):
    model = _machine(seed)
    v, cm = _engine(model)
    q, _, _ = _states(seed, 20, model)
    M = v.mass_matrix(cm, q)
    assert M.shape == (20, 4, 4)
    assert np.abs(M - np.swapaxes(M, 1, 2)).max() <= 1e-14 * np.abs(M).max()
    assert np.linalg.eigvalsh(M).min() > 0.0
    # M is also the Hessian of T in qd: qd^T M qd = 2 T from the oracle's body velocities
    qd = np.random.default_rng(seed).normal(size=(20, 4))
    T = oracle.kinetic_energy(model, q, qd)
    assert np.allclose(np.einsum("ni,nij,nj->n", qd, M, qd), 2 * T, rtol=1e-10, atol=0)


# ----------------------------------------------------------------------------- Lagrange
def _lagrange(model, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """d/dt dT/dqd - dT/dq + dV/dq by central differences of the oracle's T and V (n, 4).

    T is exactly quadratic in qd, so its central difference in qd is exact for any step (step 1,
    round-off ~1e-16 T). d/dt is a central difference along q(t) = q + qd t + qdd t^2 / 2,
    qd(t) = qd + qdd t with tau = 1e-5 s: truncation tau^2/6 * (third time derivative of the
    momenta), measured ~2e-8 relative at tau = 1e-4 s and falling as tau^2, so ~2e-10 here;
    round-off ~1e-16 / tau ~ 1e-11. dT/dq, dV/dq: steps 1e-6 (m, rad) in coordinates of size
    1e-2..1e-1: truncation ~1e-12, round-off ~1e-16 * E / 1e-6 ~ 1e-10 relative. Observed
    differences are <= 3e-9 of each coordinate's largest generalised force; the tests allow 3e-8.
    """
    eye = np.eye(4)

    def T(a, b):
        return oracle.kinetic_energy(model, a, b)

    def dT_dqd(a, b):
        return np.stack([(T(a, b + e) - T(a, b - e)) / 2.0 for e in eye], axis=-1)

    tau = 1e-5
    ddt = (dT_dqd(q + qd * tau + 0.5 * qdd * tau**2, qd + qdd * tau)
           - dT_dqd(q - qd * tau + 0.5 * qdd * tau**2, qd - qdd * tau)) / (2 * tau)
    h = 1e-6
    dT_dq = np.stack([(T(q + h * e, qd) - T(q - h * e, qd)) / (2 * h) for e in eye], axis=-1)
    V = oracle.potential_energy
    dV_dq = np.stack([(V(model, q + h * e) - V(model, q - h * e)) / (2 * h) for e in eye], axis=-1)
    return ddt - dT_dq + dV_dq


@pytest.mark.parametrize("seed", [3, 4, 5])
def test_equations_of_motion_match_lagranges_equations(seed):
    model = _machine(seed)
    v, cm = _engine(model)
    q, qd, qdd = _states(seed, 8, model)
    M = v.mass_matrix(cm, q)
    h = v.bias_forces(cm, q, qd, None)
    lhs = np.einsum("nij,nj->ni", M, qdd) + h
    ref = _lagrange(model, q, qd, qdd)
    scale = np.abs(ref).max(axis=0)  # per coordinate: [N] for x, y, [N m] for alpha, gamma
    assert np.all(np.abs(lhs - ref) <= 3e-8 * scale + 1e-9)
    # and the velocity-product terms alone (gravity off, qdd = 0)
    free = dataclasses.replace(model, gravity=np.zeros(3))
    vf, cf = _engine(free)
    h0 = vf.bias_forces(cf, q, qd, None)
    ref0 = _lagrange(free, q, qd, np.zeros_like(qdd))
    assert np.all(np.abs(h0 - ref0) <= 3e-8 * np.abs(ref0).max(axis=0) + 1e-9)


@pytest.mark.parametrize("seed", [21, 22])
def test_the_engine_equals_the_hand_derived_routes(seed):
    """M, h, B and the actuator forces of the engine against the virtual-power oracle, and the
    forces against the Newton-Euler oracle (Eq. 49-62), to 1e-9 relative on random machines
    (observed about 1e-13)."""
    for model in (BASE, _machine(seed)):
        v, cm = _engine(model)
        q, qd, qdd = _states(seed, 25, model)
        for ours, theirs in ((v.mass_matrix(cm, q), oracle.mass_matrix(model, q)),
                             (v.bias_forces(cm, q, qd, None), oracle.bias_forces(model, q, qd, None)),
                             (v.actuator_map(cm, q), oracle.actuator_map(model, q))):
            assert np.abs(ours - theirs).max() <= 1e-9 * np.abs(theirs).max()
        u = v.inverse_dynamics(cm, q, qd, qdd, None)
        assert np.abs(u - oracle.inverse_dynamics(model, q, qd, qdd, None)).max() <= 1e-9 * np.abs(u).max()
        kin = inverse_kinematics(model, PdmMotion(np.arange(25.0), q, qd, qdd), check_strokes=False)
        ne = pdm_newton_euler.actuator_forces(model, kin)
        assert np.abs(u - ne).max() <= 1e-9 * np.abs(ne).max()


# ----------------------------------------------------------------------------- actuators
def test_actuator_map_is_the_transposed_limb_jacobian():
    """B = (dl/dq)^T against central differences of the inverse position's limb lengths."""
    v, cm = _engine(BASE)
    q, _, _ = _states(6, 10)
    B = v.actuator_map(cm, q)
    h = 1e-6
    dl = np.stack([
        (inverse_position(BASE, q + h * e, check_strokes=False).l
         - inverse_position(BASE, q - h * e, check_strokes=False).l) / (2 * h)
        for e in np.eye(4)
    ], axis=1)  # (n, coordinate, limb)
    assert np.abs(B - dl).max() <= 1e-8 * np.abs(B).max()


@pytest.mark.parametrize("seed", [7, 8])
def test_power_balance_along_smooth_motions(seed):
    """sum_k f_k l_dot_k = d(T + V)/dt, with l_dot from the hand-derived kinematics and dE/dt by
    central differences in time of the oracle's energies (step 1e-5 s: truncation ~1e-10,
    round-off ~1e-11 relative; observed <= 6e-10 of the peak power, allowed 1e-8)."""
    model = _machine(seed)
    v, cm = _engine(model)
    t = np.linspace(0.1, 1.9, 25)
    mo = _smooth(seed, t)
    f = v.inverse_dynamics(cm, mo.q, mo.qd, mo.qdd, None)
    ld = inverse_kinematics(model, mo).ld
    power = np.einsum("nk,nk->n", f, ld)

    def energy(s: float) -> np.ndarray:
        m = _smooth(seed, t + s)
        return oracle.kinetic_energy(model, m.q, m.qd) + oracle.potential_energy(model, m.q)

    dE = (energy(1e-5) - energy(-1e-5)) / 2e-5
    assert np.abs(power).max() > 1e-3  # the motion does work
    assert np.abs(power - dE).max() <= 1e-8 * np.abs(power).max()


@pytest.mark.parametrize("seed", [9, 10])
def test_forward_inverts_inverse_dynamics(seed):
    model = _machine(seed)
    v, cm = _engine(model)
    q, qd, qdd = _states(seed, 30, model)
    u = v.inverse_dynamics(cm, q, qd, qdd, None)
    back = v.forward_dynamics(cm, q, qd, u, None)
    assert np.abs(back - qdd).max() <= 1e-9 * np.abs(qdd).max()
    u2 = v.inverse_dynamics(cm, q, qd, back, None)
    assert np.abs(u2 - u).max() <= 1e-9 * np.abs(u).max()
    # the defining equation itself
    M = v.mass_matrix(cm, q)
    B = v.actuator_map(cm, q)
    h = v.bias_forces(cm, q, qd, None)
    res = np.einsum("nij,nj->ni", M, qdd) + h - np.einsum("nij,nj->ni", B, u)
    assert np.abs(res).max() <= 1e-10 * np.abs(h).max()


# ----------------------------------------------------------------------------- free motion
def test_energy_is_conserved_in_free_motion():
    """1 s of unactuated motion, gravity on, integrated with DOP853 at rtol = atol = 1e-12 on the
    engine's single-sample forward dynamics; the energy from the oracle's body velocities.

    Gravity is +z here (the machine mounted upside down, the platform hanging below the R4
    axis): with the default -z the platform is an inverted pendulum about R4 and falls out of
    the workspace within a fraction of a second. The start (y = -40 mm, moving) keeps every
    sample reachable for the whole second, which the test checks.
    """
    model = dataclasses.replace(BASE, gravity=np.array([0.0, 0.0, 9.80665]))
    v, cm = _engine(model)
    y0 = np.array([0.0, -0.04, 0.05, 0.1, 0.01, -0.02, 0.1, 0.3])
    zero = np.zeros(4)

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        return np.concatenate([y[4:], v.forward_dynamics_one(cm, y[:4], y[4:], zero)])

    sol = solve_ivp(rhs, (0.0, 1.0), y0, method="DOP853", rtol=1e-12, atol=1e-12, dense_output=True)
    assert sol.success
    Y = sol.sol(np.linspace(0.0, 1.0, 101)).T
    q, qd = Y[:, :4], Y[:, 4:]
    assert reachable(model, q).all()
    T = oracle.kinetic_energy(model, q, qd)
    V = oracle.potential_energy(model, q)
    E = T + V
    assert np.ptp(V) > 0.1 * T.max()  # gravity does work: energy moves between T and V
    assert np.abs(E - E[0]).max() <= 1e-6 * T.max()
    # the batched forward dynamics gives the same accelerations along the way
    qdd = v.forward_dynamics(cm, q, qd, np.zeros_like(q), None)
    one = np.array([v.forward_dynamics_one(cm, a, b, zero) for a, b in zip(q, qd)])
    assert np.abs(qdd - one).max() <= 1e-10 * np.abs(qdd).max()


# ----------------------------------------------------------------------------- single sample
@pytest.mark.parametrize("seed", [13, 14])
def test_single_sample_path_equals_batched(seed):
    model = _machine(seed)
    v, cm = _engine(model)
    q, qd, qdd = _states(seed, 12, model)
    u = v.inverse_dynamics(cm, q, qd, qdd, None)
    u1 = np.array([v.inverse_dynamics_one(cm, *row) for row in zip(q, qd, qdd)])
    assert np.abs(u1 - u).max() <= 1e-10 * np.abs(u).max()
    a = v.forward_dynamics(cm, q, qd, u, None)
    a1 = np.array([v.forward_dynamics_one(cm, *row) for row in zip(q, qd, u)])
    assert np.abs(a1 - a).max() <= 1e-10 * np.abs(a).max()
    # the verbs serve a second model of the same machine (a plant beside its controller's model)
    # with its own numbers: a heavier copy gives other forces, and the first model's stay
    heavy = control_model(dataclasses.replace(model, mass=2.0 * model.mass))
    assert np.abs(v.inverse_dynamics_one(heavy, q[0], qd[0], qdd[0]) - u1[0]).max() > 1e-6
    assert np.abs(v.inverse_dynamics_one(cm, q[0], qd[0], qdd[0]) - u1[0]).max() <= 1e-12 * np.abs(u1[0]).max()


def test_unchecked_kernels_equal_the_checked_verbs():
    """``one_sample_kernels`` (what the plant integrator and the controllers call per cycle) give
    the checked single-sample verbs' results once a checked call has primed them (a cold kernel
    says so and computes nothing)."""
    v, cm = _engine(load_params())
    p, inverse, forward = v.one_sample_kernels(cm)
    rng = np.random.default_rng(3)
    q0 = np.zeros(4)
    assert inverse(p, q0, q0, q0, 0.0, np.empty(4)) != 0  # cold: not yet primed
    v.inverse_dynamics_one(cm, q0, q0, q0)
    for _ in range(10):
        q = np.array([rng.uniform(-0.01, 0.01), rng.uniform(-0.01, 0.01), rng.uniform(-0.05, 0.05),
                      rng.uniform(-0.1, 0.1)])
        qd, x = rng.uniform(-0.05, 0.05, 4), rng.uniform(-0.1, 0.1, 4)
        out = np.empty(4)
        assert inverse(p, q, qd, x, 0.0, out) == 0
        np.testing.assert_allclose(out, v.inverse_dynamics_one(cm, q, qd, x), rtol=1e-12, atol=1e-12)
        assert forward(p, q, qd, x, 0.0, out) == 0
        np.testing.assert_allclose(out, v.forward_dynamics_one(cm, q, qd, x), rtol=1e-12, atol=1e-12)


def test_unreachable_pose_is_refused():
    v, cm = _engine(BASE)
    q, qd, qdd = _states(18, 4)
    q[2, 1] = 0.5  # far beyond the six-bar's reach
    with pytest.raises(PkmdynError, match="sample 2"):
        v.inverse_dynamics(cm, q, qd, qdd, None)


def test_names():
    v, _ = _engine(BASE)
    assert v.COORDINATES == ("x_m", "y_m", "alpha_rad", "gamma_rad")
    assert v.ACTUATORS == ("f1_N", "f2_N", "f3_N", "f4_N")
