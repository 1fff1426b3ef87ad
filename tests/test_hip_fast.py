"""The hip simulator's single-sample path: the engine's one-sample verbs and compiled kernels of
the hip's description (what a controller and the plant call once per cycle) against the closed
form of Eq. 1-16 (``tests/oracles/hip.py``), friction family by friction family, and the
engine's messages on samples it cannot take."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from hip_helpers import engine, random_model
from oracles import hip
from pkmdyn.errors import SingularityError, UnreachablePoseError
from pkmdyn.machine_protocol import MachineDynamics
from pkmdyn.machines.hip_simulator.params import load_params
from pkmdyn.multibody.dynamics.verbs import machine_verbs

FAMILIES = {
    "hip": ("mu_h", "mu_t"),
    "slider": ("slider_coulomb", "slider_viscous"),
    "screw": ("screw_coulomb", "screw_viscous"),
    "spherical": ("spherical_coulomb", "spherical_viscous"),
    "universal": ("universal_coulomb", "universal_viscous"),
}
TOL = 1e-9


def _only(model, family: str):
    """The model with one friction family kept and every other one zero."""
    zero = {k: 0.0 for fam, keys in FAMILIES.items() if fam != family for k in keys}
    return dataclasses.replace(model, friction=dataclasses.replace(model.friction, **zero))


def _states(rng: np.random.Generator, n: int):
    q = np.deg2rad(rng.uniform(-20.0, 20.0, (n, 3)))
    qd = rng.uniform(-2.0, 2.0, (n, 3)) * 10.0 ** rng.uniform(-4, 0, (n, 1))
    qdd = rng.uniform(-30.0, 30.0, (n, 3))
    load = rng.uniform(0.0, 3000.0, n)
    return q, qd, qdd, load


def _check(model, rng: np.random.Generator, n: int = 12) -> None:
    m = engine(model)
    V = machine_verbs(m)
    q, qd, qdd, load = _states(rng, n)
    u = hip.inverse_dynamics_q(model, q, qd, qdd, load)
    u_one = np.array([V.inverse_dynamics_one(m, q[k], qd[k], qdd[k], load[k]) for k in range(n)])
    qdd_one = np.array([V.forward_dynamics_one(m, q[k], qd[k], u[k], load[k]) for k in range(n)])
    np.testing.assert_allclose(u_one, u, rtol=0, atol=TOL * np.abs(u).max())
    np.testing.assert_allclose(qdd_one, qdd, rtol=0, atol=TOL * np.abs(qdd).max())


@pytest.mark.parametrize(("seed", "sequence"), [(1, "XYZ"), (2, "zyx"), (3, "zxy"), (4, "YZX")])
def test_one_sample_verbs_equal_the_closed_form_every_friction_family(seed: int, sequence: str) -> None:
    rng = np.random.default_rng(seed)
    model = random_model(rng, friction=True, euler_sequence=sequence)
    _check(model, rng)
    for family in FAMILIES:
        _check(_only(model, family), rng, n=4)


def test_one_sample_verbs_default_machine_and_zero_load() -> None:
    rng = np.random.default_rng(7)
    model = load_params()
    _check(model, rng)
    m = engine(model)
    q, qd, qdd, _ = _states(rng, 1)
    zero = hip.inverse_dynamics_q(model, q, qd, qdd, np.zeros(1))[0]
    np.testing.assert_allclose(machine_verbs(m).inverse_dynamics_one(m, q[0], qd[0], qdd[0], 0.0), zero, rtol=0,
                               atol=TOL * np.abs(zero).max())


def test_the_engine_offers_every_verb() -> None:
    names = [n for n in dir(MachineDynamics) if not n.startswith("_")]
    assert {"inverse_dynamics_one", "forward_dynamics_one", "mass_matrix"} <= set(names)
    V = machine_verbs(engine(load_params()))
    for name in names:
        assert hasattr(V, name), name


def test_one_sample_bad_input() -> None:
    model = random_model(np.random.default_rng(9))
    m = engine(model)
    V = machine_verbs(m)
    z = np.zeros(3)
    lock = np.array([0.0, np.pi / 2, 0.0])  # XYZ: beta = 90 deg
    assert model.geometry.euler_sequence == "XYZ"
    with pytest.raises(SingularityError, match=r"Euler angles \(XYZ\) of task body 'upper' are at their singularity"):
        V.forward_dynamics_one(m, lock, z, z, 0.0)
    far = np.array([0.0, 0.0, 3.0])  # IER 172 deg: the levers cannot reach their S joints
    assert np.isnan(hip.kinematics(model, far[None]).L).any()
    for verb in (V.forward_dynamics_one, V.inverse_dynamics_one):
        with pytest.raises(UnreachablePoseError, match=r"the task pose is unreachable: loop \d+ \(cut S_"):
            verb(m, far, z, z, 0.0)


def test_compiled_kernels_equal_the_closed_form_and_report_status() -> None:
    rng = np.random.default_rng(10)
    model = random_model(rng, friction=True)
    m = engine(model)
    V = machine_verbs(m)
    kernels = V.one_sample_kernels(m)
    assert kernels is not None
    p, inverse, forward = kernels
    q, qd, qdd, load = _states(rng, 3)
    V.forward_dynamics_one(m, q[0], qd[0], qdd[0], load[0])  # primes the warm start
    ref = hip.inverse_dynamics_q(model, q, qd, qdd, load)
    for k in range(3):
        tau, back = np.empty(3), np.empty(3)
        assert inverse(p, q[k], qd[k], qdd[k], load[k], tau) == 0
        np.testing.assert_allclose(tau, ref[k], rtol=0, atol=TOL * np.abs(ref[k]).max())
        assert forward(p, q[k], qd[k], tau, load[k], back) == 0
        np.testing.assert_allclose(back, qdd[k], rtol=0, atol=TOL * np.abs(qdd[k]).max())
    out = np.empty(3)
    assert forward(p, np.array([0.0, 0.0, 3.0]), qd[0], qdd[0], 0.0, out) != 0  # unreachable
