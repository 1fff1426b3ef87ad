"""Kinematics of the hip simulator against independent computations and finite differences."""

import warnings

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation

from hip_helpers import SmoothMotion, random_model
from pkmdyn.errors import SingularityWarning, UnreachablePoseError
from pkmdyn.machines.hip_simulator.kinematics import inverse_kinematics, platform_kinematics
from pkmdyn.machines.hip_simulator.params import default_params_dict, load_params, model_from_dict
from pkmdyn.profiles.orientation import make_motion
from pkmdyn.spatial import skew

SEEDS = range(6)


def _independent_L(model, angles):
    """Slider heights by a scalar root search on |a_ji - b_ji| = l, one sample and leg at a time."""
    g = model.geometry
    out = np.empty((len(angles), 2, 3))
    for n, q in enumerate(angles):
        R = Rotation.from_euler(g.euler_sequence, q).as_matrix()
        for j in range(2):
            for i in range(3):
                a = g.o[j] + R @ g.r_a[i]

                def f(L):
                    return np.linalg.norm(a - (g.A[i] + [0, 0, L])) - g.l

                out[n, j, i] = brentq(f, a[2] - g.l, a[2], xtol=1e-15, rtol=1e-15)
    return out


@pytest.mark.parametrize("seed", SEEDS)
def test_positions_against_root_search_and_constraints(seed):
    rng = np.random.default_rng(seed)
    model = random_model(rng)
    sm = SmoothMotion(rng)
    t = np.linspace(0, 2, 40)
    kin = inverse_kinematics(model, sm.motion(t))
    ref = _independent_L(model, sm.angles(t)[0])
    np.testing.assert_allclose(kin.L, ref, rtol=1e-9, atol=1e-12)
    g = model.geometry
    np.testing.assert_allclose(kin.L[:, 0] - kin.L[:, 1], g.h[0] - g.h[1], atol=1e-12)
    for j in range(2):
        a = g.o[j] + kin.r
        b = g.A + kin.L[:, j, :, None] * np.array([0, 0, 1.0])
        np.testing.assert_allclose(np.linalg.norm(a - b, axis=-1), g.l, rtol=1e-12)
        np.testing.assert_allclose(kin.c_lever[:, j], 0.5 * (a + b), atol=1e-12)


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("spin", ["u_joint", "perpendicular"])
def test_time_derivatives_against_finite_differences(seed, spin):
    rng = np.random.default_rng(100 + seed)
    model = random_model(rng, lever_spin=spin)
    sm = SmoothMotion(rng)
    t = np.linspace(0.05, 2, 30)
    h = 1e-5

    def kin_at(tt):
        return inverse_kinematics(model, sm.motion(tt))

    k = kin_at(t)
    kp, km = kin_at(t + h), kin_at(t - h)

    def check(name, value, deriv, scale=None):
        fd = (getattr(kp, value) - getattr(km, value)) / (2 * h)
        ref = getattr(k, deriv)
        tol = 1e-6 * (np.abs(ref).max() if scale is None else scale)
        np.testing.assert_allclose(fd, ref, atol=tol, err_msg=name)

    check("slider velocity", "L", "Ld")
    check("slider acceleration", "Ld", "Ldd")
    check("lever vector rate", "d", "d_dot")
    check("lever vector acceleration", "d_dot", "d_ddot")
    fd_c = (kp.c_lever - km.c_lever) / (2 * h)
    np.testing.assert_allclose(fd_c[:, 0], k.v_lever, atol=1e-6 * np.abs(k.v_lever).max())
    np.testing.assert_allclose(fd_c[:, 1], k.v_lever, atol=1e-6 * np.abs(k.v_lever).max())
    check("lever centre acceleration", "v_lever", "a_lever")
    check("lever angular acceleration", "omega_lever", "omega_lever_dot")
    # lever angular velocity: for the U joint it is the true rate of the lever frame,
    # for the perpendicular option it is the rate of the lever axis with no spin.
    Rdot = (kp.R_lever - km.R_lever) / (2 * h)
    W = Rdot @ np.swapaxes(k.R_lever, -1, -2)
    if spin == "u_joint":
        np.testing.assert_allclose(W, skew(k.omega_lever), atol=1e-6 * np.abs(k.omega_lever).max())
    else:
        e_dot = (kp.e_lever - km.e_lever) / (2 * h)
        np.testing.assert_allclose(np.cross(k.omega_lever, k.e_lever), e_dot, atol=1e-6 * np.abs(e_dot).max())
        np.testing.assert_allclose(np.einsum("nik,nik->ni", k.omega_lever, k.e_lever), 0, atol=1e-12)


@pytest.mark.parametrize("seed", SEEDS)
def test_jacobians_against_finite_differences(seed):
    """Ld = J omega and the lever rate follow from a small rotation applied to the platform."""
    rng = np.random.default_rng(200 + seed)
    model = random_model(rng)
    sm = SmoothMotion(rng)
    t = np.linspace(0, 1, 8)
    k = inverse_kinematics(model, sm.motion(t))
    h = 1e-7
    for axis in range(3):
        dw = np.zeros(3)
        dw[axis] = h
        Rp = Rotation.from_rotvec(dw).as_matrix() @ k.R
        Rm = Rotation.from_rotvec(-dw).as_matrix() @ k.R
        z = np.zeros((len(t), 3))
        kp = platform_kinematics(model, t, Rp, z, z)
        km = platform_kinematics(model, t, Rm, z, z)
        dL = (kp.L[:, 1] - km.L[:, 1]) / (2 * h)
        np.testing.assert_allclose(dL, k.J[:, :, axis], atol=1e-7 * np.abs(k.J).max())
        # J = J_a^-1 J_b (Eq. 3)
        np.testing.assert_allclose(k.J, k.Jb / k.Ja[..., None], rtol=1e-12)
    np.testing.assert_allclose(k.det_Ja, np.prod(k.Ja, axis=1), rtol=1e-12)
    np.testing.assert_allclose(k.det_Jb, np.linalg.det(k.Jb), rtol=1e-9)


def test_batch_of_one_equals_batch_of_many():
    model = load_params()
    rng = np.random.default_rng(7)
    sm = SmoothMotion(rng)
    t = np.linspace(0, 1, 11)
    full = inverse_kinematics(model, sm.motion(t))
    for n in (0, 5, 10):
        one = inverse_kinematics(model, sm.motion(t[n : n + 1]))
        for field in ("L", "Ld", "Ldd", "omega_lever", "omega_lever_dot", "a_lever", "J"):
            np.testing.assert_allclose(getattr(one, field)[0], getattr(full, field)[n], rtol=1e-14, atol=1e-15)


def test_unreachable_pose_names_time_and_leg():
    model = load_params()
    t = np.array([0.0, 0.1, 0.2])
    q = np.deg2rad([[0, 0, 0], [0, 0, 0], [0, 0, 95.0]])  # a quarter turn about Z pulls a joint out of reach
    with pytest.raises(UnreachablePoseError, match=r"t = 0\.2 s \(sample 3\): leg \d"):
        inverse_kinematics(model, make_motion(t, q, np.zeros((3, 3)), np.zeros((3, 3))))


def test_singular_layout_is_detected():
    """psi = phi puts every lever's projection through the platform centre: det(J_b) = 0 (§3.3)."""
    d = default_params_dict()
    d["geometry"]["platform_joint_angles_deg"] = list(d["geometry"]["module_angles_deg"])
    model = model_from_dict(d)
    motion = make_motion(np.array([0.0]), np.zeros((1, 3)), np.zeros((1, 3)), np.zeros((1, 3)))
    with pytest.warns(SingularityWarning, match=r"t = 0 s \(sample 1\)"):
        kin = inverse_kinematics(model, motion)
    assert abs(kin.det_Jb[0]) < 1e-15
    # and the default layout is not reported as singular at its zero pose
    with warnings.catch_warnings():
        warnings.simplefilter("error", SingularityWarning)
        kin = inverse_kinematics(load_params(), motion)
    assert abs(kin.det_Jb[0]) > 1e-4
