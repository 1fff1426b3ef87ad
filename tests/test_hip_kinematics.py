"""Kinematics of the hip simulator through the generic engine (its description): against the
closed form of Eq. 1-6 (``tests/oracles/hip.py``), a scalar root search of the loop closure, the
loop itself, finite differences, and the engine's messages on poses it cannot take."""

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation

from hip_helpers import SmoothMotion, engine, engine_kinematics, kinematics_against_oracle, random_model, sliders
from oracles import hip
from pkmdyn.errors import ParameterError, UnreachablePoseError
from pkmdyn.machines.hip_simulator.params import default_params_dict, load_params, model_from_dict
from pkmdyn.multibody import solve_kinematics
from pkmdyn.multibody.kinematics.singularity.measures import singularity_measures

SEEDS = range(4)
PLATFORMS = ("upper", "lower")


def _independent_L(model, angles):
    """Slider heights by a scalar root search on |a_ji - b_ji| = l, one sample and leg at a time."""
    g = model.geometry
    out = np.empty((len(angles), 2, 3))
    for n, q in enumerate(angles):
        R = Rotation.from_euler(g.euler_sequence, q).as_matrix()
        for j in range(2):
            for i in range(3):
                a = g.o[j] + R @ g.r_a[i]
                out[n, j, i] = brentq(lambda s: np.linalg.norm(a - (g.A[i] + [0, 0, s])) - g.l, a[2] - g.l, a[2],
                                      xtol=1e-15, rtol=1e-15)
    return out


@pytest.mark.parametrize("seed", SEEDS)
def test_positions_against_root_search_and_the_loop(seed):
    rng = np.random.default_rng(seed)
    model = random_model(rng)
    sm = SmoothMotion(rng)
    t = np.linspace(0, 2, 30)
    q, qd, qdd = sm.angles(t)
    m, kin = engine_kinematics(model, q, qd, qdd, t)
    ref = _independent_L(model, q)
    np.testing.assert_allclose(kin.act_q[:, sliders(m)], ref[:, 1], rtol=1e-9, atol=1e-12)
    g = model.geometry
    for j, name in enumerate(PLATFORMS):
        for i in range(3):
            a = kin.joint_point[:, m.joint_names.index(f"S_{name}_{i + 1}")]
            b = kin.joint_point[:, m.joint_names.index(f"U_{name}_{i + 1}")]
            np.testing.assert_allclose(np.linalg.norm(a - b, axis=-1), g.l, rtol=1e-12)
            np.testing.assert_allclose(b[:, :2], np.broadcast_to(g.A[i, :2], b[:, :2].shape), atol=1e-12)
            np.testing.assert_allclose(b[:, 2], ref[:, j, i], rtol=1e-9, atol=1e-12)  # both sliders of a screw
            np.testing.assert_allclose(kin.p[:, m.body_names.index(f"lever_{name}_{i + 1}")], 0.5 * (a + b), atol=1e-12)


@pytest.mark.parametrize("seed", SEEDS)
def test_every_body_against_the_closed_form(seed):
    rng = np.random.default_rng(100 + seed)
    model = random_model(rng, euler_sequence=["XYZ", "zyx", "ZXY", "YZX"][seed])
    sm = SmoothMotion(rng)
    t = np.linspace(0.05, 2, 40)
    kinematics_against_oracle(model, *sm.angles(t), t)


def test_lever_angular_velocity_is_the_rate_of_its_frame():
    """The engine's lever turns on its U joint: its angular velocity (spin included) is the rate
    of its frame, by central differences of the engine's own rotations."""
    rng = np.random.default_rng(7)
    model = random_model(rng)
    sm = SmoothMotion(rng)
    t = np.linspace(0.05, 1, 8)
    h = 1e-5
    m, k = engine_kinematics(model, *sm.angles(t), t)
    _, kp = engine_kinematics(model, *sm.angles(t + h))
    _, km = engine_kinematics(model, *sm.angles(t - h))
    W = (kp.R - km.R) / (2 * h) @ np.swapaxes(k.R, -1, -2)
    levers = [m.body_names.index(f"lever_{p}_{i + 1}") for p in PLATFORMS for i in range(3)]
    w = k.w[:, levers]
    skew = np.cross(np.eye(3), w[..., None, :])
    np.testing.assert_allclose(W[:, levers], skew, atol=1e-6 * np.abs(w).max())
    # the spin about the lever axis is there (the perpendicular-only rate of Eq. 4 would miss it)
    e = hip.kinematics(model, *sm.angles(t)).e_lever
    assert np.abs(np.einsum("nli,nli->nl", w[:, :3], e)).max() > 1e-3


def test_batch_of_one_equals_batch_of_many():
    model = load_params()
    sm = SmoothMotion(np.random.default_rng(7))
    t = np.linspace(0, 1, 11)
    q, qd, qdd = sm.angles(t)
    m, full = engine_kinematics(model, q, qd, qdd, t)
    for n in (0, 5, 10):
        one = solve_kinematics(m, q[n:n + 1], qd[n:n + 1], qdd[n:n + 1])
        for field in ("act_q", "act_qd", "act_qdd", "w", "wd", "a", "J_ax"):
            np.testing.assert_allclose(getattr(one, field)[0], getattr(full, field)[n], rtol=1e-12, atol=1e-13)


def test_unreachable_pose_names_the_sample_time_and_loop():
    """A quarter turn about Z pulls the S joints out of the levers' reach."""
    t = np.array([0.0, 0.1, 0.2])
    q = np.deg2rad([[0, 0, 0], [0, 0, 0], [0, 0, 95.0]])
    assert np.isnan(hip.kinematics(load_params(), q).L[2]).any()
    with pytest.raises(UnreachablePoseError, match=r"\(t = 0\.2 s\): the task pose is unreachable: loop \d+ "
                                                   r"\(cut S_(upper|lower)_\d\)"):
        engine_kinematics(load_params(), q, np.zeros((3, 3)), np.zeros((3, 3)), t)


def test_singular_layout_is_refused_and_the_default_is_not_singular():
    """psi = phi puts every lever's projection through the platform centre: det(J_b) = 0 at the
    zero pose (sec. 3.3), where the engine counts a fourth freedom and refuses the description."""
    d = default_params_dict()
    d["geometry"]["platform_joint_angles_deg"] = list(d["geometry"]["module_angles_deg"])
    singular = model_from_dict(d)
    assert abs(hip.kinematics(singular, np.zeros((1, 3))).det_Jb[0]) < 1e-15
    with pytest.raises(ParameterError, match=r"the mechanism has 4 degree\(s\) of freedom"):
        engine(singular)
    model = load_params()
    m, kin = engine_kinematics(model, np.zeros((1, 3)))
    ref = hip.kinematics(model, np.zeros((1, 3)))
    assert abs(ref.det_Jb[0]) > 1e-4
    assert singularity_measures(m, kin.q).direct[0] > 1e-3
    # near the singular layout the engine's direct measure falls with det(J_b)
    d["geometry"]["platform_joint_angles_deg"] = [a + 3.0 for a in d["geometry"]["module_angles_deg"]]
    near = model_from_dict(d)
    mn, kn = engine_kinematics(near, np.zeros((1, 3)))
    assert singularity_measures(mn, kn.q).direct[0] < 0.2 * singularity_measures(m, kin.q).direct[0]
    assert abs(hip.kinematics(near, np.zeros((1, 3))).det_Jb[0]) < 0.2 * abs(ref.det_Jb[0])
