"""The hip simulator's single-sample real-time path equals the batched path."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from hip_helpers import random_model
from pkmdyn.errors import MotionError, SingularityError, UnreachablePoseError
from pkmdyn.machine import MachineDynamics
from pkmdyn.machines.hip_simulator import minimal
from pkmdyn.machines.hip_simulator.fast import pack

FAMILIES = {
    "hip": ("mu_h", "mu_t"),
    "slider": ("slider_coulomb", "slider_viscous"),
    "screw": ("screw_coulomb", "screw_viscous"),
    "spherical": ("spherical_coulomb", "spherical_viscous"),
    "universal": ("universal_coulomb", "universal_viscous"),
}


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
    q, qd, qdd, load = _states(rng, n)
    u = minimal.inverse_dynamics(model, q, qd, qdd, load)
    back = minimal.forward_dynamics(model, q, qd, u, load)
    u_one = np.array([minimal.inverse_dynamics_one(model, q[k], qd[k], qdd[k], load[k]) for k in range(n)])
    qdd_one = np.array([minimal.forward_dynamics_one(model, q[k], qd[k], u[k], load[k]) for k in range(n)])
    np.testing.assert_allclose(u_one, u, rtol=0, atol=1e-12 * np.abs(u).max())
    np.testing.assert_allclose(qdd_one, back, rtol=0, atol=1e-12 * np.abs(back).max())


@pytest.mark.parametrize(("seed", "spin", "sequence"), [(1, "u_joint", "XYZ"), (2, "perpendicular", "XYZ"), (3, "u_joint", "zxy"), (4, "perpendicular", "YZX")])
def test_fast_equals_batched_every_friction_family(seed: int, spin: str, sequence: str) -> None:
    rng = np.random.default_rng(seed)
    model = random_model(rng, friction=True, lever_spin=spin, euler_sequence=sequence)
    _check(model, rng)
    for family in FAMILIES:
        _check(_only(model, family), rng, n=4)


def test_fast_equals_batched_default_machine_and_zero_load() -> None:
    from pkmdyn.machines.hip_simulator import load_params

    rng = np.random.default_rng(7)
    model = load_params()
    _check(model, rng)
    q, qd, qdd, _ = _states(rng, 1)
    zero = minimal.inverse_dynamics(model, q, qd, qdd, np.zeros(1))[0]
    np.testing.assert_allclose(minimal.inverse_dynamics_one(model, q[0], qd[0], qdd[0], 0.0), zero, rtol=1e-13, atol=1e-15)


def test_packing_is_cached_per_model_object() -> None:
    model = random_model(np.random.default_rng(8))
    assert pack(model) is pack(model)
    other = dataclasses.replace(model)
    assert pack(other) is not pack(model)
    np.testing.assert_array_equal(pack(other), pack(model))


def test_minimal_module_offers_every_verb() -> None:
    names = [n for n in dir(MachineDynamics) if not n.startswith("_")]
    assert {"inverse_dynamics_one", "forward_dynamics_one", "mass_matrix"} <= set(names)
    for name in names:
        assert hasattr(minimal, name), name


def test_fast_bad_input() -> None:
    model = random_model(np.random.default_rng(9))
    z = np.zeros(3)
    with pytest.raises(MotionError, match=r"qd: expected shape \(3,\)"):
        minimal.inverse_dynamics_one(model, z, np.zeros(4), z, 0.0)
    with pytest.raises(MotionError, match="load"):
        minimal.forward_dynamics_one(model, z, z, z, -1.0)
    with pytest.raises(MotionError, match="load"):
        minimal.forward_dynamics_one(model, z, z, z, float("nan"))
    with pytest.raises(MotionError, match="load"):
        minimal.inverse_dynamics_one(model, z, z, z, None)
    lock = np.array([0.0, np.pi / 2, 0.0])  # XYZ: beta = 90 deg
    assert model.geometry.euler_sequence == "XYZ"
    with pytest.raises(SingularityError, match="gimbal lock"):
        minimal.forward_dynamics(model, lock[None], z[None], z[None], np.zeros(1))
    with pytest.raises(SingularityError, match="gimbal lock"):
        minimal.forward_dynamics_one(model, lock, z, z, 0.0)
    far = np.array([0.0, 0.0, 3.0])  # IER 172 deg: leg 1 cannot reach its S joint
    with pytest.raises(UnreachablePoseError, match="leg 1"):
        minimal.inverse_dynamics(model, far[None], z[None], z[None], np.zeros(1))
    with pytest.raises(UnreachablePoseError, match="leg 1"):
        minimal.forward_dynamics_one(model, far, z, z, 0.0)
    with pytest.raises(UnreachablePoseError, match="leg 1"):
        minimal.inverse_dynamics_one(model, far, z, z, 0.0)


def test_compiled_kernels_equal_the_verbs_and_report_status() -> None:
    from pkmdyn.machines.hip_simulator.fast import kernels

    rng = np.random.default_rng(10)
    model = random_model(rng, friction=True)
    p, inverse, forward = kernels(model)
    q, qd, qdd, load = _states(rng, 3)
    for k in range(3):
        tau, back = np.empty(3), np.empty(3)
        assert inverse(p, q[k], qd[k], qdd[k], load[k], tau) == 0
        np.testing.assert_array_equal(tau, minimal.inverse_dynamics_one(model, q[k], qd[k], qdd[k], load[k]))
        assert forward(p, q[k], qd[k], tau, load[k], back) == 0
        np.testing.assert_allclose(back, qdd[k], rtol=0, atol=1e-11 * np.abs(qdd[k]).max())
    out = np.empty(3)
    assert forward(p, np.array([0.0, 0.0, 3.0]), qd[0], qdd[0], 0.0, out) == 1  # leg 1 unreachable


def test_the_plant_and_controllers_use_the_unchecked_kernels_with_the_verbs_as_fallback():
    """The plant integrator's and the controllers' per-cycle calls go through the compiled kernels
    without input checks; they equal the checked verbs, and an invalid sample still raises the
    machine's own error through the checked verb."""
    from pkmdyn.control._laws import _id_one
    from pkmdyn.machines.hip_simulator import load_params
    from pkmdyn.simulate._plant import make_plant

    model = load_params()
    rng = np.random.default_rng(7)
    plant = make_plant(minimal, model, True)
    id_one = _id_one(minimal, model, True)
    for _ in range(20):
        q, qd, x = rng.uniform(-0.3, 0.3, 3), rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3)
        load = float(rng.uniform(0, 3000))
        np.testing.assert_array_equal(plant.f(q, qd, x, load), minimal.forward_dynamics_one(model, q, qd, x, load))
        np.testing.assert_array_equal(id_one(q, qd, x, load), minimal.inverse_dynamics_one(model, q, qd, x, load))
    far = np.array([1.3, 1.3, 0.0])
    with pytest.raises(UnreachablePoseError, match="leg 1"):
        plant.f(far, np.zeros(3), np.zeros(3), 0.0)
    with pytest.raises(UnreachablePoseError, match="leg 1"):
        id_one(far, np.zeros(3), np.zeros(3), 0.0)
