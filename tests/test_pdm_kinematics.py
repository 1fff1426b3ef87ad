"""PDM kinematics: every rate against finite differences, loop closure, an independent
per-sample inverse position, the U-joint constraint and batch consistency."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pkmdyn.errors import UnreachablePoseError
from pkmdyn.machines.pdm4 import BODY_NAMES, inverse_kinematics, inverse_position, load_params, reachable
from pkmdyn.profiles.pdm_motion import PdmMotion

MODEL = load_params()
H = 1e-5


def _smooth(t: np.ndarray, amp: np.ndarray, freq: np.ndarray, phase: np.ndarray, offset: np.ndarray):
    """q = offset + amp sin(freq t + phase) per coordinate, with exact derivatives."""
    arg = freq * t[:, None] + phase
    q = offset + amp * np.sin(arg)
    qd = amp * freq * np.cos(arg)
    qdd = -amp * freq**2 * np.sin(arg)
    return PdmMotion(t, q, qd, qdd)


def _random_motion(seed: int, t: np.ndarray) -> PdmMotion:
    rng = np.random.default_rng(seed)
    amp = rng.uniform(0.2, 1.0, 4) * np.array([0.012, 0.012, math.radians(4), math.radians(10)])
    freq = rng.uniform(1.0, 6.0, 4)
    phase = rng.uniform(0, 2 * np.pi, 4)
    offset = rng.uniform(-1, 1, 4) * np.array([0.01, 0.01, math.radians(3), math.radians(8)])
    return _smooth(t, amp, freq, phase, offset)


def _triple(seed: int, n: int = 7):
    """Kinematics at t - h, t, t + h for one random motion."""
    t = np.linspace(0.05, 1.5, n)
    return [inverse_kinematics(MODEL, _random_motion(seed, t + s)) for s in (-H, 0.0, H)]


def _cd(minus: np.ndarray, plus: np.ndarray) -> np.ndarray:
    return (plus - minus) / (2 * H)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_body_velocities_and_accelerations_match_finite_differences(seed):
    km, k0, kp = _triple(seed)
    for name in BODY_NAMES:
        bm, b0, bp = km.body(name), k0.body(name), kp.body(name)
        vs = max(1.0, np.abs(b0.v).max())
        assert np.abs(_cd(bm.p, bp.p) - b0.v).max() < 1e-6 * vs, name
        assert np.abs(_cd(bm.v, bp.v) - b0.a).max() < 1e-6 * max(1.0, np.abs(b0.a).max()), name
        assert np.abs(_cd(bm.w, bp.w) - b0.wd).max() < 1e-6 * max(1.0, np.abs(b0.wd).max()), name


@pytest.mark.parametrize("seed", [4, 5])
def test_limb_rates_match_finite_differences(seed):
    km, k0, kp = _triple(seed)
    assert np.abs(_cd(km.pos.l, kp.pos.l) - k0.ld).max() < 1e-8
    assert np.abs(_cd(km.ld, kp.ld) - k0.ldd).max() < 1e-7
    assert np.abs(_cd(km.pos.theta1, kp.pos.theta1) - k0.theta1d).max() < 1e-7
    assert np.abs(_cd(km.theta1d, kp.theta1d) - k0.theta1dd).max() < 1e-6
    assert np.abs(_cd(km.pos.theta2, kp.pos.theta2) - k0.theta2d).max() < 1e-7
    assert np.abs(_cd(km.theta2d, kp.theta2d) - k0.theta2dd).max() < 1e-6
    assert np.abs(_cd(km.rpr_angle, kp.rpr_angle) - k0.rpr_angle_d).max() < 1e-7
    assert np.abs(_cd(km.rpr_angle_d, kp.rpr_angle_d) - k0.rpr_angle_dd).max() < 1e-6
    assert np.abs(_cd(km.euler, kp.euler) - k0.euler_d).max() < 1e-7
    assert np.abs(_cd(km.euler_d, kp.euler_d) - k0.euler_dd).max() < 1e-6


def _omega_from_rotations(Rm: np.ndarray, Rp: np.ndarray, R0: np.ndarray) -> np.ndarray:
    W = _cd(Rm, Rp) @ np.swapaxes(R0, -1, -2)
    return np.stack([W[..., 2, 1], W[..., 0, 2], W[..., 1, 0]], axis=-1)


def _spu_frames(k) -> np.ndarray:
    Q = k.u[:, 2:]
    return np.stack([k.U2, np.cross(Q, k.U2), Q], axis=-1)


@pytest.mark.parametrize("seed", [6, 7])
def test_angular_velocities_match_rotation_finite_differences(seed):
    km, k0, kp = _triple(seed)
    w_mp = _omega_from_rotations(km.pos.T, kp.pos.T, k0.pos.T)
    assert np.abs(w_mp - k0.body("platform").w).max() < 1e-8
    w_spu = _omega_from_rotations(_spu_frames(km), _spu_frames(kp), _spu_frames(k0))
    for j in range(2):
        assert np.abs(w_spu[:, j] - k0.body(f"cylinder{j + 3}").w).max() < 1e-8
        assert np.allclose(k0.body(f"piston{j + 3}").w, k0.body(f"cylinder{j + 3}").w)
    for i in range(2):
        assert np.allclose(k0.body(f"crank{i + 1}").w[:, 2], k0.theta1d[:, i])
        assert np.allclose(k0.body(f"coupler{i + 1}").w[:, 2], k0.theta2d[:, i])
        assert np.allclose(k0.body(f"cylinder{i + 1}").w[:, 2], k0.rpr_angle_d[:, i])


def test_spu_euler_angles_rebuild_the_limb_frame_and_respect_the_u_joint():
    t = np.linspace(0.0, 2.0, 25)
    k = inverse_kinematics(MODEL, _random_motion(11, t))
    a, b, g = (k.euler[..., c] for c in range(3))
    ca, sa, cb, sb, cg, sg = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(g), np.sin(g)
    R = np.stack([
        np.stack([ca * cg - sa * cb * sg, -ca * sg - sa * cb * cg, sa * sb], -1),
        np.stack([sa * cg + ca * cb * sg, -sa * sg + ca * cb * cg, -ca * sb], -1),
        np.stack([sb * sg, sb * cg, cb], -1),
    ], -2)  # Eq. 23
    assert np.abs(R - _spu_frames(k)).max() < 1e-12
    # the limb turns relative to the platform only about the two U-joint axes
    w_rel = k.body("cylinder3").w - k.body("platform").w
    assert np.abs(np.einsum("na,na->n", w_rel, k.U3[:, 0])).max() < 1e-10
    U1 = k.pos.T @ MODEL.U1_local
    assert np.abs(np.einsum("na,na->n", U1, k.U2[:, 0])).max() < 1e-12
    # the actual angular velocity is not perpendicular to the limb (section 3.2.2)
    spin = np.einsum("na,na->n", k.body("cylinder3").w, k.u[:, 2])
    assert np.abs(spin).max() > 1e-3


def test_loop_closure_residuals_at_every_sample():
    t = np.linspace(0.0, 2.0, 200)
    k = inverse_kinematics(MODEL, _random_motion(12, t))
    p = k.pos
    e1 = np.stack([np.cos(p.theta1), np.sin(p.theta1), 0 * p.theta1], -1)
    e2 = np.stack([np.cos(p.theta2), np.sin(p.theta2), 0 * p.theta2], -1)
    chain = MODEL.R1[None] + MODEL.r2 * e1 + MODEL.r3 * e2
    assert np.abs(chain - p.R3).max() < 1e-13
    assert np.abs(np.linalg.norm(p.R3[:, 1] - p.R3[:, 0], axis=-1) - MODEL.r4).max() < 1e-13
    assert np.abs(p.C[:, 2]).max() < 1e-15
    assert k.residual.max() < 1e-13
    # U joints ride on the platform: fixed distances to P and C
    for j in range(2):
        assert np.allclose(np.linalg.norm(p.U[:, j] - p.C, axis=-1), np.linalg.norm(MODEL.U_local[j]), atol=1e-14)
    # platform point: z is the parasitic r0 cos(gamma), x-y as commanded
    assert np.allclose(p.P[:, 2], MODEL.r0 * np.cos(k.q[:, 3]), atol=1e-15)
    assert np.allclose(p.P[:, :2], k.q[:, :2], atol=1e-15)


def _reference_lengths(q: np.ndarray) -> np.ndarray:
    """Per-sample inverse position written from the documented layout, independently of
    Eq. 7: the elbow R2i is an intersection of two circles, picked on the outer side."""
    x, y, al, ga = q
    r0, r2, r3, r4 = MODEL.r0, MODEL.r2, MODEL.r3, MODEL.r4
    Rz = np.array([[math.cos(al), -math.sin(al), 0], [math.sin(al), math.cos(al), 0], [0, 0, 1]])
    Rx = np.array([[1, 0, 0], [0, math.cos(ga), -math.sin(ga)], [0, math.sin(ga), math.cos(ga)]])
    T = Rz @ Rx
    C = np.array([x, y, r0 * math.cos(ga)]) - T @ np.array([0, 0, r0])
    out = []
    for i, side in enumerate((-1.0, 1.0)):
        R1 = np.array([side * MODEL.r1 / 2, MODEL.n1, 0.0])
        R3 = C + Rz @ np.array([side * r4 / 2, 0, 0])
        d = np.linalg.norm(R3 - R1)
        along = (d * d + r2 * r2 - r3 * r3) / (2 * d)
        h = math.sqrt(r2 * r2 - along * along)
        e = (R3 - R1) / d
        perp = np.array([-e[1], e[0], 0.0])
        cands = [R1 + along * e + h * perp, R1 + along * e - h * perp]
        R2 = max(cands, key=lambda c: side * c[0])  # the outer elbow
        out.append(np.linalg.norm(R2 - MODEL.R4[i]))
    for j, side in enumerate((-1.0, 1.0)):
        U = C + T @ np.array([side * MODEL.U_local[1, 0], 0.0, MODEL.U_local[1, 2]])
        out.append(np.linalg.norm(U - MODEL.S[j]))
    return np.array(out)


def test_limb_lengths_agree_with_an_independent_per_sample_computation():
    rng = np.random.default_rng(3)
    q = rng.uniform(-1, 1, (40, 4)) * np.array([0.02, 0.02, math.radians(6), math.radians(15)])
    pos = inverse_position(MODEL, q, check_strokes=False)
    ref = np.array([_reference_lengths(row) for row in q])
    assert np.abs(pos.l - ref).max() < 1e-12


def test_single_rows_equal_batch_rows():
    t = np.linspace(0.0, 1.0, 9)
    motion = _random_motion(13, t)
    k = inverse_kinematics(MODEL, motion)
    for s in (0, 4, 8):
        one = inverse_kinematics(MODEL, motion.slice(s, s + 1))
        assert np.array_equal(one.ldd[0], k.ldd[s])
        for name in BODY_NAMES:
            assert np.allclose(one.body(name).a[0], k.body(name).a[s], rtol=0, atol=1e-15)


def test_home_pose_has_home_lengths_and_is_reachable():
    pos = inverse_position(MODEL, np.zeros((1, 4)))
    assert np.allclose(pos.l[0], MODEL.home_lengths, atol=1e-12)
    assert reachable(MODEL, np.zeros((1, 4)))[0]


def test_stroke_overrun_names_sample_time_and_limb():
    t = np.linspace(0.0, 1.0, 11)
    q = np.zeros((11, 4))
    q[:, 0] = np.linspace(0.0, 0.08, 11)
    motion = PdmMotion(t, q, np.zeros_like(q), np.zeros_like(q))
    with pytest.raises(UnreachablePoseError, match=r"t = 0\.\d+ s: limb \d \((RPR|SPU), l\d\d\) needs an extension"):
        inverse_kinematics(MODEL, motion)


def test_open_six_bar_loop_names_sample_time_and_limb():
    t = np.array([0.0, 0.5, 1.0])
    q = np.zeros((3, 4))
    q[2, 1] = 0.5  # pulls the output link out of reach of both cranks
    with pytest.raises(UnreachablePoseError, match=r"t = 1 s: limb 1 \(RPR, l11\): the six-bar loop R11-R21-R31 cannot close"):
        inverse_position(MODEL, q, t)
