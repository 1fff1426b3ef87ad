import numpy as np

from pkmdyn.multibody.dynamics.friction import coulomb_viscous, regularised_sign


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
    """Eq. 16 on the hip's description, by hand: at the zero pose (XYZ: Euler rates = omega) with
    the platforms turning about Z alone, the generalised force of the S0 joints' load-driven
    friction, ``(k J_ax)^T tau_hip``, is ``2 u(omega) (r_h mu_h F + r_t mu_t (F + m_m g))``."""
    from hip_helpers import engine_torques
    from pkmdyn.machines.hip_simulator import model_from_dict
    from pkmdyn.machines.hip_simulator.params import default_params_dict

    d = default_params_dict()
    d["friction"].update(hip_radius_m=0.015, hip_coefficient=0.1, thrust_radius_m=0.06, thrust_coefficient=0.02)
    d["inertia"].update(platform_mass_kg=20.0 / 9.8)  # m_m g = 20 N
    model = model_from_dict(d, "Eq. 16")
    z = np.zeros((2, 3))
    qd = np.array([[0.0, 0.0, 2.0], [0.0, 0.0, 0.0]])
    eng = engine_torques(model, z, qd, z, np.array([1000.0, 1000.0]))
    k = eng.m.drive_ratio[:3]
    Q = np.einsum("nat,na->nt", eng.kin.J_ax[:, :3] * k[None, :, None], eng.hip_friction)
    u = 2.0 / np.sqrt(4.0 + 1e-6)  # the regularised sign at 2 rad/s (eps 1e-3 rad/s)
    np.testing.assert_allclose(Q[0], [0, 0, 2 * u * (0.015 * 0.1 * 1000 + 0.06 * 0.02 * 1020)], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(eng.hip_friction[1], 0.0, atol=1e-15)
