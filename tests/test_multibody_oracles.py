"""The generic engine against independent closed-form kinematics (tests/oracles): the
Gough-Stewart platform, the Delta robot, the planar 3-RRR and the Bennett linkage, each built
in as a description file, on their default motions and on random smooth motions."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from oracles import bennett, delta, rrr3, stewart
from pkmdyn.multibody import default_motion, load_mechanism, solve_kinematics

MACHINES = Path(__file__).resolve().parents[1] / "src" / "pkmdyn" / "machines"


def _model(name):
    return load_mechanism(MACHINES / name / f"{name}.toml")


def _wrap(a):
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def _smooth(rng, x0, amp, n=300, period=1.5):
    """x0 + sum of two random sinusoids per coordinate, with exact rates and accelerations."""
    t = np.linspace(0.0, period, n)
    k = x0.size
    a1, a2 = rng.uniform(-1, 1, (2, k)) * amp
    w1, w2 = rng.uniform(2, 6, (2, k))
    ph = rng.uniform(0, 2 * np.pi, (2, k))
    s1, s2 = np.sin(w1 * t[:, None] + ph[0]), np.sin(w2 * t[:, None] + ph[1])
    c1, c2 = np.cos(w1 * t[:, None] + ph[0]), np.cos(w2 * t[:, None] + ph[1])
    x = x0 + a1 * (s1 - np.sin(ph[0])) + a2 * (s2 - np.sin(ph[1]))
    xd = a1 * w1 * c1 + a2 * w2 * c2
    xdd = -a1 * w1**2 * s1 - a2 * w2**2 * s2
    return t, x, xd, xdd


def _motion(m, seed, x0, amp):
    """The mechanism's default motion (``seed`` None), or :func:`_smooth` about ``x0``."""
    if seed is None:
        mo = default_motion(m)
        return mo.t, mo.x, mo.xd, mo.xdd
    return _smooth(np.random.default_rng(seed), x0, amp)


def _close(a, b, rel=1e-9):
    scale = max(float(np.abs(b).max()), 1e-12)
    assert float(np.abs(np.asarray(a) - np.asarray(b)).max()) <= rel * scale


@pytest.fixture(scope="module")
def stewart_model():
    return _model("stewart")


@pytest.mark.parametrize("seed", [None, 1, 2])
def test_stewart_against_oracle(stewart_model, seed):
    m = stewart_model
    t, x, xd, xdd = _motion(m, seed, np.array([0.0, 0.0, 1.0, 0.0, 0.0, 0.0]),
                            np.array([0.06, 0.06, 0.06, 0.08, 0.08, 0.1]))
    kin = solve_kinematics(m, x, xd, xdd, t)
    a, b, _ = stewart.default_geometry()
    ref = stewart.inverse_kinematics(a, b, x[:, :3], x[:, 3:], "XYZ", xd[:, :3], xd[:, 3:], xdd[:, :3], xdd[:, 3:])
    legs = [m.actuator_names.index(f"P_{i + 1}") for i in range(6)]
    _close(kin.act_q[:, legs], ref["L"])
    _close(kin.act_qd[:, legs], ref["Ld"])
    _close(kin.act_qdd[:, legs], ref["Ldd"])
    pl = m.body_names.index("platform")
    _close(kin.R[:, pl], ref["R"])
    _close(kin.w[:, pl], ref["omega"])
    _close(kin.wd[:, pl], ref["omega_dot"])
    spheres = [m.joint_names.index(f"S_{i + 1}") for i in range(6)]
    _close(kin.joint_point[:, spheres], ref["B"])
    # Jacobian: Ld = J [v; omega], omega = E(angles) angles_d  ->  dL/dx = J diag(I, E)
    E = np.stack([stewart.euler_kinematics(x[:, 3:], "XYZ", np.eye(3)[k][None].repeat(len(t), 0))["omega"]
                  for k in range(3)], axis=-1)
    Jx = np.concatenate([ref["J"][:, :, :3], np.einsum("nij,njk->nik", ref["J"][:, :, 3:], E)], axis=-1)
    _close(kin.J_ax[:, legs], Jx)
    # cylinder angular motion behind a U joint whose first axis is fixed in the base
    for i in range(6):
        cyl = m.body_names.index(f"cylinder_{i + 1}")
        U = m.joint_index(f"U_{i + 1}")
        n1 = m.joint_R_parent[U][:, 0]
        w, wd, _ = stewart.ups_leg_angular_velocity(ref["u"][:, i], ref["ud"][:, i], ref["udd"][:, i], n1)
        _close(kin.w[:, cyl], w)
        _close(kin.wd[:, cyl], wd, 1e-8)


@pytest.mark.parametrize("seed", [None, 3, 4])
def test_delta_against_oracle(seed):
    m = _model("delta")
    t, x, xd, xdd = _motion(m, seed, np.array([0.0, 0.0, -1.0]), np.array([0.2, 0.2, 0.15]))
    kin = solve_kinematics(m, x, xd, xdd, t)
    g = delta.williams_irb360_geometry()
    ref = delta.kinematics(x, g["R_b"], g["R_p"], g["L_A"], g["L_B"], xd, xdd)
    legs = [m.actuator_names.index(f"R_{i + 1}") for i in range(3)]
    _close(kin.act_q[:, legs], ref["theta"])
    _close(kin.act_qd[:, legs], ref["thetad"])
    _close(kin.act_qdd[:, legs], ref["thetadd"])
    _close(kin.J_ax[:, legs], ref["J"])
    for i in range(3):
        ea, eb = m.joint_index(f"Sa_elbow_{i + 1}"), m.joint_index(f"Sb_elbow_{i + 1}")
        _close(0.5 * (kin.joint_point[:, ea] + kin.joint_point[:, eb]), ref["C"][:, i])
    pl = m.body_names.index("platform")
    # the parallelograms keep the platform parallel to the base
    assert np.abs(kin.R[:, pl] - np.eye(3)).max() < 1e-9
    assert np.abs(kin.w[:, pl]).max() < 1e-9 and np.abs(kin.wd[:, pl]).max() < 1e-8


@pytest.mark.parametrize("seed", [None, 5, 6])
def test_rrr3_against_oracle(seed):
    m = _model("rrr3")
    t, x, xd, xdd = _motion(m, seed, np.zeros(3), np.array([0.05, 0.05, 0.25]))
    kin = solve_kinematics(m, x, xd, xdd, t)
    g = rrr3.symmetric_geometry()
    ref = rrr3.inverse_kinematics(x, g["A"], g["c"], g["l1"], g["l2"], (1, 1, 1), xd, xdd)
    legs = [m.actuator_names.index(f"RA_{i + 1}") for i in range(3)]
    # a leg copy keeps the template's reference angle: its coordinate is measured in the leg's own
    # frame, turned by the leg angle (0, 120, 240 deg) from the base frame the oracle uses
    turn = np.radians([0.0, 120.0, 240.0])
    assert np.abs(_wrap(kin.act_q[:, legs] + turn - ref["theta"])).max() < 1e-10
    _close(kin.act_qd[:, legs], ref["thetad"])
    _close(kin.act_qdd[:, legs], ref["thetadd"])
    _close(kin.J_ax[:, legs], ref["J"])
    for i in range(3):
        rb, rc = m.joint_index(f"RB_{i + 1}"), m.joint_index(f"RC_{i + 1}")
        _close(kin.joint_point[:, rb, :2], ref["Bpts"][:, i])
        _close(kin.joint_point[:, rc, :2], ref["C"][:, i])
        dist = m.body_names.index(f"distal_{i + 1}")
        _close(kin.w[:, dist, 2], ref["psid"][:, i])
        _close(kin.wd[:, dist, 2], ref["psidd"][:, i])
    assert np.abs(kin.joint_point[..., 2]).max() < 1e-12  # the robot stays in its plane


@pytest.mark.parametrize("seed", [None, 7])
def test_bennett_against_oracle(seed):
    m = _model("bennett")
    t, x, xd, xdd = _motion(m, seed, np.array([np.pi / 3]), np.array([0.5]))
    kin = solve_kinematics(m, x, xd, xdd, t)
    a, alpha, beta = 0.2, np.radians(30.0), np.radians(60.0)
    b = bennett.bennett_b(a, alpha, beta)
    ref = bennett.input_output(x[:, 0], alpha, beta, xd[:, 0], xdd[:, 0])
    for name, key in (("J2", "theta2"), ("J3", "theta3")):
        c = m.joint_q0[m.joint_index(name)]
        assert np.abs(_wrap(kin.q[:, c] - ref[key])).max() < 1e-10
        _close(kin.qd[:, c], ref[key + "_d"])
        _close(kin.qdd[:, c], ref[key + "_dd"])
    th = np.stack([x[:, 0], ref["theta2"], ref["theta3"], ref["theta4"]], axis=-1)
    frames = bennett.joint_frames(th, a, alpha, b, beta)
    for k, name in enumerate(("J1", "J2", "J3", "J4")):
        _close(kin.joint_point[:, m.joint_index(name)], frames[:, k, :3, 3])


def test_delta_workspace_against_the_closed_form_reach():
    """Reachable task points of the Delta against the oracle's inverse kinematics (finite
    angles on the elbow-out branch), away from the boundary by a margin."""
    from pkmdyn.multibody import reachable

    m = _model("delta")
    g = delta.williams_irb360_geometry()
    rng = np.random.default_rng(8)
    pts = np.column_stack([rng.uniform(-0.9, 0.9, 120), rng.uniform(-0.9, 0.9, 120), rng.uniform(-1.8, -0.4, 120)])
    with np.errstate(invalid="ignore"):
        theta = delta.inverse_kinematics(pts, g["R_b"], g["R_p"], g["L_A"], g["L_B"])
        inner = delta.inverse_kinematics(pts * np.array([1.03, 1.03, 1.0]) + [0, 0, -0.02], g["R_b"], g["R_p"],
                                         g["L_A"], g["L_B"])
        outer = delta.inverse_kinematics(pts * np.array([0.97, 0.97, 1.0]) + [0, 0, 0.02], g["R_b"], g["R_p"],
                                         g["L_A"], g["L_B"])
    ok = np.all(np.isfinite(theta), axis=1)
    clear = ok & np.all(np.isfinite(inner), axis=1) & np.all(np.isfinite(outer), axis=1) & (np.abs(theta) < 1.2).all(axis=1)
    out = ~ok & ~np.all(np.isfinite(inner), axis=1) & ~np.all(np.isfinite(outer), axis=1)
    got = reachable(m, pts)
    assert clear.sum() >= 10 and out.sum() >= 10
    assert np.all(got[clear]) and not np.any(got[out])
