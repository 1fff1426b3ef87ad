"""An under-actuated mechanism (fewer actuators than degrees of freedom): a double pendulum with
its shoulder driven and its elbow free (a pendubot). Its efforts exist only where the motion is
dynamically consistent: held still with the free link hanging straight down the shoulder torque
is the closed form; with the free link held aside no torque of the shoulder does it, and the
run is refused naming the sample; describe and the run say what the mechanism is."""

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


def test_describe_and_run_say_it(tmp_path, capsys):
    import tomlkit

    path = tmp_path / "pendubot.toml"
    path.write_text(tomlkit.dumps(pendubot()))
    assert main(["describe", "--machine", str(path)]) == 0
    assert "under-actuated: 1 actuators for 2 degrees of freedom" in capsys.readouterr().out
    out = tmp_path / "run"
    assert main(["run", "--machine", str(path), "--out", str(out)]) == 2  # its default motion swings the free link
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "not dynamically consistent" in err[0] and not out.exists()
