"""An under-actuated mechanism (fewer actuators than degrees of freedom): a double pendulum with
its shoulder driven and its elbow free (a pendubot). Its efforts exist only where the motion is
dynamically consistent: held still with the free link hanging straight down the shoulder torque
is the closed form; with the free link held aside no torque of the shoulder does it, and the
run is refused naming the sample; describe says what the mechanism is, and the run on defaults
drives the shoulder along the default motion's shoulder angle, the elbow simulated."""

from __future__ import annotations

import numpy as np
import pytest

import multibody_examples as ex
from pkmdyn.cli import main
from pkmdyn.errors import MotionError
from pkmdyn.multibody import load_mechanism, solve_kinematics
from pkmdyn.multibody.dynamics.newton_euler import inverse_dynamics, joint_reactions

G, M1, M2, L = 9.80665, 2.0, 1.5, 0.5
Y = [0.0, 1.0, 0.0]


E0 = np.array([L * np.sin(np.radians(30.0)), 0.0, -L * np.cos(np.radians(30.0))])  # the elbow, 30 deg out


def pendubot():
    """At the reference configuration the upper link 30 degrees out, the lower one hanging."""
    return {
        "mechanism": {"name": "pendubot", "gravity_m_s2": [0.0, 0.0, -G]},
        "bodies": [ex.body("upper", tuple(E0 / 2), mass=M1), ex.body("lower", tuple(E0 + [0, 0, -L / 2]), mass=M2)],
        "joints": [ex.joint("shoulder", "revolute", "ground", "upper", (0.0, 0.0, 0.0), axis=Y, actuated=True),
                   ex.joint("elbow", "revolute", "upper", "lower", tuple(E0), axis=Y)],
        "task": {"body": "lower", "point_m": list(E0 + [0, 0, -L]), "position": ["x", "z"]},
        "default_motion": {"amplitude": {"x_m": 0.05}},
    }


def _still(m, x):
    x = np.atleast_2d(np.asarray(x, float))
    z = np.zeros_like(x)
    return solve_kinematics(m, x, z, z, np.arange(len(x), dtype=float))


def test_held_still_with_the_free_link_hanging_the_shoulder_torque_is_the_closed_form():
    m = load_mechanism(pendubot())
    assert m.na == 1 and m.topology.dof == 2
    angles = np.radians([-30.0, -20.0, -40.0, -10.0])  # near the reference: one branch
    # the upper link turned by a about y, the lower one hanging straight down from the elbow
    elbow = np.stack([L * np.sin(-angles), -L * np.cos(angles)], axis=1)  # (x, z)
    tip = elbow + [0.0, -L]
    u = inverse_dynamics(m, _still(m, tip)).u[:, 0]
    # gravity's moment about the shoulder of both links (the lower one's weight acts at the elbow's x)
    moment = G * (M1 * elbow[:, 0] / 2 + M2 * elbow[:, 0])  # about +y: (r x (0, 0, -m g))_y = m g x
    # the torque the shoulder applies to the upper link about +y balances gravity's moment about +y
    # (m g x of each weight at x): u = -moment
    np.testing.assert_allclose(u, -moment, rtol=1e-10, atol=1e-10)
    assert np.abs(u[1:]).min() > 1.0


def test_a_motion_no_shoulder_torque_makes_is_refused_naming_the_sample():
    m = load_mechanism(pendubot())
    ref = E0[[0, 2]] + [0.0, -L]
    tips = np.array([ref, ref, [0.45, -0.8], ref])  # sample 2: the lower link held aside
    with pytest.raises(MotionError, match=r"sample 2 .*under-actuated \(1 actuators for 2 degrees of freedom\).*"
                                          r"not dynamically consistent"):
        joint_reactions(m, _still(m, tips))


def test_describe_says_it_and_the_default_run_drives_the_shoulder_and_simulates_the_elbow(tmp_path, capsys):
    import csv

    import tomlkit

    from pkmdyn.multibody import default_motion

    path = tmp_path / "pendubot.toml"
    path.write_text(tomlkit.dumps(pendubot()))
    assert main(["describe", "--machine", str(path)]) == 0
    said = capsys.readouterr().out
    assert "under-actuated: 1 actuators for 2 degrees of freedom" in said
    assert "its default motion drives the actuators and simulates the other freedoms" in said
    # the default motion as a task motion swings the free link by a sine of its own: refused
    m = load_mechanism(pendubot())
    dm = default_motion(m)
    sine = tmp_path / "sine.csv"
    with open(sine, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["t_s", "x_m", "z_m"])
        w.writerows(np.c_[dm.t, dm.x].tolist())
    out = tmp_path / "refused"
    assert main(["run", "--machine", str(path), "--motion", str(sine), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "not dynamically consistent" in err[0] and not out.exists()
    # on defaults the shoulder follows that sine's shoulder angle and the elbow swings as it must
    out = tmp_path / "run"
    assert main(["run", "--machine", str(path), "--out", str(out)]) == 0
    with open(out / "results.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    shoulder = solve_kinematics(m, dm.x, dm.xd, dm.xdd, dm.t).act_q[:, 0]
    got = np.array([float(r["shoulder_pos_rad"]) for r in rows])
    assert len(got) == len(shoulder) and np.ptp(shoulder) > 5e-3
    assert np.abs(got - shoulder).max() <= 1e-6
    x = np.array([float(r["x_m"]) for r in rows])
    assert np.abs(x - dm.x[:, 0]).max() > 1e-3  # not the sine: the elbow is free
    import json
    assert json.loads((out / "summary.json").read_text())["max_unactuated_force_ratio"] <= 1e-9
