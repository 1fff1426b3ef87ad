"""Hostile and malformed descriptions: each refused with one ParameterError line that names
the body, joint or key; and the leg generator, units and frames of good ones."""

from __future__ import annotations

import re

import numpy as np
import pytest

import multibody_examples as ex
from pkmdyn.errors import ParameterError
from pkmdyn.multibody import load_description, load_mechanism


def _bad(d, pattern):
    with pytest.raises(ParameterError, match=pattern) as info:
        load_mechanism(d)
    assert "\n" not in str(info.value)


def test_unconnected_body():
    d = ex.four_bar()
    d["bodies"].append(ex.body("loose", (0, 0, 0)))
    _bad(d, r"\[bodies\] loose: body is not joined to anything")


def test_body_not_reaching_the_ground():
    d = ex.four_bar()
    d["bodies"] += [ex.body("a", (0, 0, 0)), ex.body("b", (0, 0, 0))]
    d["joints"].append(ex.joint("ab", "revolute", "a", "b", (0, 0, 0), axis=ex.Z))
    _bad(d, r"\[bodies\] a: body is not connected to the ground")


def test_joint_naming_a_missing_body():
    d = ex.four_bar()
    d["joints"][1]["child"] = "coupplr"
    _bad(d, r"\[joints\] B: child: body 'coupplr' is not defined")


def test_zero_length_axis():
    d = ex.four_bar()
    d["joints"][2]["axis"] = [0.0, 0.0, 0.0]
    _bad(d, r"\[joints\] C: axis: axis of zero length")


def test_universal_axes_must_be_perpendicular():
    d = ex.builtin_dict("stewart")
    d["legs"][0]["joints"][0]["axes"] = [[1.0, 0.0, 0.0], [1.0, 1.0, 0.0]]
    _bad(d, r"joint U_1: axes: the two axes of a universal joint must be perpendicular")


@pytest.mark.parametrize("inertia, rule", [
    ([1.0, 1.0, -1.0, 0.0, 0.0, 0.0], "not positive definite"),
    ([0.1, 0.1, 0.5, 0.0, 0.0, 0.0], "triangle inequality"),
    ([[1.0, 0.2, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], "not symmetric"),
    ([1.0, 2.0], "give 6 values"),
])
def test_bad_inertia(inertia, rule):
    d = ex.four_bar()
    d["bodies"][1]["inertia_kgm2"] = inertia
    _bad(d, rf"\[bodies\] coupler: inertia_kgm2: .*{rule}")


def test_no_actuator():
    d = ex.four_bar()
    d["joints"][0]["actuated"] = False
    _bad(d, "no joint is actuated")


def test_actuated_joint_must_have_one_coordinate():
    d = ex.rssr()
    d["joints"][1]["actuated"] = True
    _bad(d, r"\[joints\] S1: actuated: only a joint with one coordinate")


def test_unknown_key_and_wrong_types_name_the_item():
    d = ex.four_bar()
    d["joints"][1]["axsi"] = [0, 0, 1]
    _bad(d, r"\[joints\] B axsi: unknown key")
    d = ex.four_bar()
    d["bodies"][2]["mass_kg"] = -1.0
    _bad(d, r"\[bodies\] rocker mass_kg: must be >= 0")
    d = ex.four_bar()
    d["joints"][0]["type"] = "screw"
    _bad(d, r"\[joints\] A type:")
    d = ex.four_bar()
    d["bodies"][0]["com_m"] = [0.0, float("nan"), 0.0]
    _bad(d, r"\[bodies\] crank com_m #2: must be a finite number")


def test_duplicate_and_reserved_names():
    d = ex.four_bar()
    d["bodies"][1]["name"] = "crank"
    _bad(d, "body 'crank' is defined twice")
    d = ex.four_bar()
    d["joints"][1]["name"] = "A"
    _bad(d, "joint 'A' is defined twice")
    d = ex.four_bar()
    d["bodies"][0]["name"] = "ground"
    _bad(d, "'ground' is reserved")


def test_joint_joining_a_body_to_itself():
    d = ex.four_bar()
    d["joints"][1]["child"] = "crank"
    _bad(d, r"\[joints\] B: joins body 'crank' to itself")


def test_task_errors():
    d = ex.four_bar()
    d["task"]["body"] = "nothing"
    _bad(d, r"\[task\] body: 'nothing' is not a body")
    d = ex.four_bar()
    d["task"] = {"body": "crank"}
    _bad(d, r"\[task\]: no task coordinate")
    d = ex.four_bar()
    d["task"]["euler_sequence"] = "XXY"
    _bad(d, r"\[task\] euler_sequence: 'XXY' is not a valid Euler sequence")


def test_missing_sections_and_files(tmp_path):
    _bad({"mechanism": {"name": "x"}}, r"\[task\]: missing required section")
    with pytest.raises(ParameterError, match="cannot read file"):
        load_description(tmp_path / "none.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[mechanism\nname = 1\n", encoding="utf-8")
    with pytest.raises(ParameterError, match="not valid TOML"):
        load_description(bad)


def test_limits_and_offsets_need_the_right_joint():
    d = ex.four_bar()
    d["joints"][0]["limits_m"] = [0.0, 1.0]
    _bad(d, r"\[joints\] A: limits_m: only for a joint with one linear coordinate")
    d = ex.four_bar()
    d["joints"][0]["limits_rad"] = [1.0, -1.0]
    _bad(d, r"\[joints\] A: limits: lower 1 must be below upper -1")


def test_leg_generator_names_and_places_every_copy():
    d = ex.builtin_dict("delta")
    desc = load_description(d)
    names = {b.name for b in desc.bodies}
    assert {"arm_1", "arm_2", "arm_3", "rod_a_2", "platform"} <= names
    joints = {j.name: j for j in desc.joints}
    # the copy at 120 deg is the template turned by 120 deg about z
    c, s = np.cos(np.radians(120.0)), np.sin(np.radians(120.0))
    Q = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    assert np.allclose(joints["R_2"].point, Q @ joints["R_1"].point)
    assert np.allclose(joints["R_2"].frame[:, 2], Q @ joints["R_1"].frame[:, 2])
    assert joints["Sa_platform_3"].child == "platform" and joints["Sa_platform_3"].parent == "rod_a_3"
    bodies = {b.name: b for b in desc.bodies}
    assert np.allclose(bodies["arm_2"].R0, Q @ bodies["arm_1"].R0)
    d["legs"][0]["count"] = 4
    _bad(d, r"\[legs\]\[0\] count: 4 but angles_deg has 3 entries")


def test_model_frames_put_both_sides_of_every_joint_at_one_point():
    m = load_mechanism(ex.MACHINES / "stewart" / "stewart.toml")
    for k in range(len(m.joint_names)):
        sides = []
        for b, R, p in ((m.joint_parent[k], m.joint_R_parent[k], m.joint_p_parent[k]),
                        (m.joint_child[k], m.joint_R_child[k], m.joint_p_child[k])):
            R0, p0 = (np.eye(3), np.zeros(3)) if b < 0 else (m.R0[b], m.p0[b])
            sides.append((R0 @ R, R0 @ p + p0))
        assert np.allclose(sides[0][0], sides[1][0]) and np.allclose(sides[0][1], sides[1][1])


def test_too_many_legs_are_refused_before_any_analysis():
    d = ex.builtin_dict("delta")
    d["legs"][0]["angles_deg"] = [float(a) for a in range(60)]
    d2 = ex.deep(d)
    d2["legs"] = [ex.deep(d["legs"][0]) for _ in range(6)]
    for k, leg in enumerate(d2["legs"]):
        leg["suffixes"] = [f"_{k}_{i}" for i in range(60)]
    _bad(d2, "at most 300 bodies and 600 joints")


def test_task_point_defaults_to_the_centre_of_mass():
    d = ex.slider_crank()
    d["task"] = {"body": "slider", "position": ["x"]}
    m = load_mechanism(d)
    b = m.body_names.index("slider")
    assert np.allclose(m.task_point, m.com[b])


def test_adding_a_joint_type_is_adding_a_table_entry(monkeypatch):
    """A new type (here a 'slot' joint: translation along x and rotation about z, cut with
    the rows force_y, force_z, couple_x, couple_y) works end to end from one table entry."""
    from pkmdyn.multibody.description import joint_types

    slot = joint_types.JointType("slot", "L", ("TX", "RZ"), (("T", 1), ("T", 2), ("R", 1, 2), ("R", 0, 2)), 1)
    table = joint_types.JOINT_TYPES + (slot,)
    monkeypatch.setattr(joint_types, "JOINT_TYPES", table)
    monkeypatch.setattr(joint_types, "_BY_NAME", {t.name: k for k, t in enumerate(table)})
    import pkmdyn.multibody.description.schema as description
    import pkmdyn.multibody.model.records as records
    import pkmdyn.multibody.model.topology as topology

    monkeypatch.setattr(description, "_TYPES", tuple(t.name for t in table))
    monkeypatch.setattr(records, "JOINT_TYPES", table)
    monkeypatch.setattr(topology, "JOINT_TYPES", table)
    d = ex.slider_crank()
    d["joints"][3]["type"] = "slot"  # the slider may also turn about the base z axis ...
    d["joints"][3]["axis"] = [0.0, 0.0, 1.0]
    d["joints"][3]["x_axis"] = [1.0, 0.0, 0.0]  # ... and slide along x
    m = load_mechanism(d)
    # the slider's turn about z at the rod's pin is an idle freedom: mobility 2, one idle, t = 3
    rep = m.topology
    assert (rep.kutzbach, rep.mobility, rep.idle, rep.dof, rep.overconstraints) == (-1, 2, 1, 1, 3)
    from pkmdyn.multibody import reference_task, solve_kinematics

    x = reference_task(m) + np.linspace(0.0, 0.5, 20)[:, None]
    kin = solve_kinematics(m, x)
    pin = m.joint_index("D")
    assert np.abs(kin.joint_point[:, pin, 1:]).max() < 1e-12  # the slot's point moves along x only
    assert np.ptp(kin.joint_point[:, pin, 0]) > 0.01


@pytest.mark.parametrize("edit, where", [
    (lambda d: d["bodies"][0].__setitem__("mass_kg", 1e300), "[bodies] platform mass_kg: 1e+300"),
    (lambda d: d["legs"][0]["joints"][0].__setitem__("point_m", [1e300, 0.0, 0.0]),
     "[legs][0] joints U point_m[0]: 1e+300"),
    (lambda d: d["mechanism"].__setitem__("gravity_m_s2", [0.0, 0.0, -1e9]), "[mechanism] gravity_m_s2[2]"),
    (lambda d: d["default_motion"]["amplitude"].__setitem__("x_m", 1e9), "[default_motion] amplitude x_m"),
    (lambda d: d["default_motion"].__setitem__("period_s", 1e30), "[default_motion] period_s"),
    (lambda d: d["legs"][0]["joints"][1].__setitem__("limits_m", [-1e9, 1e9]), "joints P limits_m[0]"),
])
def test_numbers_beyond_their_plausibility_limit_are_refused_by_key(edit, where):
    """A mass, a point, a gravity, a motion amplitude or period near 1e300 (or merely absurd) is
    refused before any work, naming the table, the entry and the key, and the limit to raise."""
    d = ex.builtin_dict("stewart")
    edit(d)
    with pytest.raises(ParameterError, match=re.escape(where) + ".*plausibility limit max_"):
        load_mechanism(d)


def test_drives_keep_their_own_bounds_and_fine_encoders_pass():
    """[[actuators]] entries have bounds of their own (a linear encoder of a million counts per
    metre is no length, a motor's acceleration no gravity)."""
    d = ex.builtin_dict("stewart")
    d["legs"][0]["actuators"] = [{"joint": "P", "screw_lead_m": 0.01, "encoder_counts_per_turn": 2 ** 24,
                                  "max_acceleration_rad_s2": 5e4}]
    load_mechanism(d)


def test_a_plausibility_limit_is_raised_in_the_description_or_by_the_caller():
    d = ex.builtin_dict("stewart")
    d["bodies"][0]["mass_kg"] = 2e6
    with pytest.raises(ParameterError, match="max_mass_kg"):
        load_mechanism(d)
    assert load_mechanism(d, limits={"max_mass_kg": 1e7}).mass.max() == 2e6
    d["limits"] = {"max_mass_kg": 1e7}
    assert load_mechanism(d).mass.max() == 2e6


def test_default_motion_samples_keep_the_motion_file_cap():
    d = ex.builtin_dict("stewart")
    d["default_motion"]["samples"] = 200_001
    with pytest.raises(ParameterError, match=r"\[default_motion\] samples"):
        load_mechanism(d)
