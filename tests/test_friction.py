import numpy as np

from pkmdyn.friction import coulomb_viscous, regularised_sign
from pkmdyn.machines.hip_simulator.dynamics import hip_bearing_friction


def test_regularised_sign_is_bounded_smooth_and_zero_at_rest():
    w = np.linspace(-1, 1, 2001)
    u = regularised_sign(w, 1e-2, vector=False)
    assert u[1000] == 0 and np.all(np.abs(u) < 1) and np.all(np.diff(u) > 0)
    v = np.random.default_rng(0).normal(size=(50, 3))
    uv = regularised_sign(v, 1e-3, vector=True)
    np.testing.assert_allclose(np.linalg.norm(uv, axis=1), np.linalg.norm(v, axis=1) / np.sqrt(np.sum(v * v, axis=1) + 1e-6))
    np.testing.assert_array_equal(regularised_sign(np.zeros((2, 3)), 1e-3, vector=True), 0.0)


def test_friction_always_dissipates():
    rng = np.random.default_rng(1)
    w = rng.normal(size=(100, 3))
    f = coulomb_viscous(w, 0.3, 0.05, 1e-3, vector=True)
    assert np.all(np.sum(w * f, axis=1) >= 0)
    s = rng.normal(size=100)
    assert np.all(s * coulomb_viscous(s, 2.0, 1.0, 1e-4, vector=False) >= 0)


def test_hip_friction_magnitude_follows_eq16():
    omega = np.array([[0.0, 0.0, 2.0], [0.0, 0.0, 0.0]])
    tau = hip_bearing_friction(omega, np.array([1000.0, 1000.0]), 20.0, 0.015, 0.1, 0.06, 0.02, 1e-9)
    np.testing.assert_allclose(tau[0], [0, 0, 0.015 * 0.1 * 1000 + 0.06 * 0.02 * 1020], rtol=1e-12)
    np.testing.assert_array_equal(tau[1], 0.0)
