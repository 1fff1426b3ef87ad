"""Joint springs (``[joints] spring``): the power balance with the springs' own potential
energy, computed here from the joint coordinates (``1/2 k (q - q_s)^2``), on a four-bar (torsion
springs) and a slider-crank (a linear spring on the slider); a pendulum held by its drive against
a torsion spring, in closed form; and the refusals. MuJoCo's own passive spring forces agree with
the description's in tests/test_import.py (the five-bar with springs)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import multibody_examples as ex
from pkmdyn.errors import ParameterError
from pkmdyn.multibody import load_mechanism, reference_task, solve_kinematics
from pkmdyn.multibody.dynamics.newton_euler import energies, inverse_dynamics, joint_reactions


def _springs(d, k_rot=7.0, k_lin=900.0, shift=0.1):
    """A spring on every passive one-coordinate joint but one, which is cut to close the loop
    (a cut joint has no coordinate to stretch a spring), slack ``shift`` from the reference."""
    passive = [j for j in d["joints"] if not j.get("actuated") and j["type"] == "revolute"]
    d["mechanism"]["cut_joints"] = [passive[-1]["name"]]
    for j in d["joints"]:
        if j.get("actuated") or j["name"] == passive[-1]["name"]:
            continue
        if j["type"] == "revolute":
            j["spring"] = {"stiffness_Nm_rad": k_rot, "reference_rad": j.get("angle_at_reference_rad", 0.0) + shift}
        elif j["type"] == "prismatic":
            j["spring"] = {"stiffness_N_m": k_lin, "reference_m": j.get("position_at_reference_m", 0.0) + shift}
    return d


def _power_balance(m, seed):
    """Actuator power against d(T + V)/dt (fourth-order central differences) along a smooth
    motion, ``V`` gravity's (the engine's, springs left out) plus the springs' own
    ``1/2 k (q - q_s)^2`` computed here from the joint coordinates; returns the pieces."""
    springs = [(j, sp) for j, sp in enumerate(m.joint_spring) if sp is not None]
    h = 2e-4
    tt = (np.linspace(0.0, 0.4, 9)[:, None] + h * np.array([-2, -1, 0, 1, 2])[None]).reshape(-1)
    x, xd, xdd = ex.smooth_motion(reference_task(m), np.where(m.task_kind == 1, 0.3, 0.02), tt, seed)
    kin = solve_kinematics(m, x, xd, xdd, tt)
    T, Vg = energies(dataclasses.replace(m, joint_spring=()), kin)
    Vs = sum(0.5 * k * (kin.q[:, m.joint_q0[j]] - qs) ** 2 for j, (k, qs) in springs)
    E = (T + Vg + Vs).reshape(-1, 5)
    dE = (E[:, 0] - 8 * E[:, 1] + 8 * E[:, 3] - E[:, 4]) / (12 * h)
    u = inverse_dynamics(m, kin).u
    P = np.einsum("na,na->n", u, kin.act_qd).reshape(-1, 5)[:, 2]
    assert np.abs(P - dE).max() <= 1e-7 * max(np.abs(P).max(), 1e-3)
    return kin, u, T, Vg, Vs


@pytest.mark.parametrize("make", [ex.four_bar, ex.slider_crank])
def test_the_power_balance_holds_with_the_springs_energy(make):
    m = load_mechanism(_springs(make()))
    springs = [(j, sp) for j, sp in enumerate(m.joint_spring) if sp is not None]
    assert springs
    bare = dataclasses.replace(m, joint_spring=())
    kin, u, T, Vg, Vs = _power_balance(m, 3)
    # the springs change the efforts visibly, and the engine's own energies carry them
    assert np.abs(u - inverse_dynamics(bare, kin).u).max() > 1e-2 * np.abs(u).max()
    np.testing.assert_allclose(sum(energies(m, kin)), T + Vg + Vs, rtol=1e-12, atol=1e-12)
    # the reactions (planar loops: over-constrained in space, minimum-norm) give the same efforts
    np.testing.assert_allclose(joint_reactions(m, kin, overconstrained="minimum-norm").u, u, rtol=1e-9, atol=1e-9)


def test_a_pendulum_held_against_its_spring():
    """A rod on a driven revolute joint about y with a torsion spring on that joint, held still:
    u = k (q - q_s) + m g l sin(q) (the drive balances spring and gravity), signs as the axis."""
    k, qs, mass, l, g = 12.0, 0.3, 2.0, 0.4, 9.80665
    d = {"mechanism": {"name": "sprung_pendulum", "gravity_m_s2": [0.0, 0.0, -g]},
         "bodies": [ex.body("rod", (0.0, 0.0, -l), mass=mass)],
         "joints": [ex.joint("pin", "revolute", "ground", "rod", (0.0, 0.0, 0.0), axis=[0.0, 1.0, 0.0], actuated=True,
                             spring={"stiffness_Nm_rad": k, "reference_rad": qs})],
         "task": {"body": "rod", "euler_sequence": "XYZ", "orientation": [2]}}
    m = load_mechanism(d)
    q = np.array([[-0.4], [0.0], [0.25], [0.9]])
    kin = solve_kinematics(m, q, np.zeros_like(q), np.zeros_like(q))
    u = inverse_dynamics(m, kin).u[:, 0]
    # the rod's centre at (-l sin q, -l cos q) after a turn q about +y; gravity's moment about +y
    # is m g x = -m g l sin q, the spring's -k (q - q_s): the drive gives the opposite of their sum
    want = k * (kin.q[:, 0] - qs) + mass * g * l * np.sin(kin.q[:, 0])
    np.testing.assert_allclose(u, want, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("spring, words", [
    ({"stiffness_N_m": 10.0}, "a revolute joint's spring takes stiffness_Nm_rad"),
    ({"reference_rad": 0.1}, "a revolute joint's spring takes stiffness_Nm_rad"),
    ({"stiffness_Nm_rad": -1.0}, "spring"),
])
def test_bad_springs_are_refused(spring, words):
    d = ex.four_bar()
    next(j for j in d["joints"] if not j.get("actuated"))["spring"] = spring
    with pytest.raises(ParameterError, match=words):
        load_mechanism(d)


def test_a_spring_on_a_cut_joint_is_refused():
    d = ex.four_bar_cut_b()
    cut = d["mechanism"]["cut_joints"][0]
    next(j for j in d["joints"] if j["name"] == cut)["spring"] = {"stiffness_Nm_rad": 3.0}
    with pytest.raises(ParameterError, match=f"{cut} spring: the joint is cut to close a loop"):
        load_mechanism(d)


def test_springs_survive_an_mjcf_round_trip(tmp_path):
    import tomllib

    pytest.importorskip("mujoco")
    from pkmdyn.multibody.formats.importer import import_description
    from pkmdyn.multibody.formats.mjcf_out import mechanism_mjcf

    m0 = load_mechanism(_springs(ex.four_bar()))
    src = tmp_path / "sprung.xml"
    src.write_text(mechanism_mjcf(m0))
    text, _ = import_description(src, "mjcf")
    m1 = load_mechanism(tomllib.loads(text))
    for j, sp in enumerate(m0.joint_spring):
        got = m1.joint_spring[m1.joint_names.index(m0.joint_names[j])]
        assert (got is None) == (sp is None) and (sp is None or np.allclose(got, sp, rtol=1e-15, atol=1e-15))


def test_a_spring_on_a_joint_described_child_first():
    """A sprung joint whose description names the body nearer the ground as its child (the tree
    traverses it backwards): the power balance still holds with its energy in the description's
    own coordinate."""
    d = _springs(ex.four_bar())
    sprung = [j for j in d["joints"] if "spring" in j and j["parent"] != "ground" and j["child"] != "ground"]
    assert sprung
    j = sprung[0]
    j["parent"], j["child"] = j["child"], j["parent"]
    m = load_mechanism(d)
    k = m.joint_index(j["name"])
    assert m.joint_flipped[k]
    _power_balance(m, 5)


@pytest.mark.parametrize("make", [ex.four_bar, ex.slider_crank])
def test_the_automatic_cut_keeps_the_sprung_joints_in_the_tree(make):
    """Without [mechanism] cut_joints the spanning tree takes the sprung joints as it takes the
    actuated ones, so the loop is cut at a joint without a spring."""
    d = _springs(make())
    plain = d["mechanism"].pop("cut_joints")[0]
    m = load_mechanism(d)
    assert [m.joint_names[k] for k in np.flatnonzero(m.joint_cut)] == [plain]
    assert all(not m.joint_cut[k] for k, sp in enumerate(m.joint_spring) if sp is not None)
