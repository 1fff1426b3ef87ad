"""Parametric descriptions (pkmdyn.multibody.description.expressions): named design parameters, expressions
in numeric fields, the safe grammar, the built-in Stewart platform written in its designer's
parameters (the same model as its earlier all-numbers file), and a sweep of its base radius."""

from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np
import pytest

import multibody_examples as ex
from pkmdyn.cli import main
from pkmdyn.errors import ParameterError
from pkmdyn.multibody import load_mechanism
from pkmdyn.multibody.description.expressions import evaluate, parameter_values

DATA = Path(__file__).parent / "data"


@pytest.mark.parametrize("text, want", [
    ("2 * r_m + 1", 3.0),
    ("sqrt(2) * cosd(45)", 1.0),
    ("sind(30) + cos(pi) + tand(45)", 0.5),
    ("norm([3, 4, 12]) / 13", 1.0),
    ("rotz(pi / 2) @ [r_m, 0, 0]", [0.0, 1.0, 0.0]),
    ("rotzd(90) @ [1, 0, 0] + [0, 0, r_m]", [0.0, 1.0, 1.0]),
    ("rotx(90 * deg) @ [0, 1, 0]", [0.0, 0.0, 1.0]),
    ("roty(pi / 2) @ [0, 0, 1]", [1.0, 0.0, 0.0]),
    ("cross([1, 0, 0], [0, 1, 0])", [0.0, 0.0, 1.0]),
    ("dot(unit([3, 4, 0]), [3, 4, 0])", 5.0),
    ("-(r_m ** 2) + atan2(1, 1) * 4 / pi", 0.0),
    ("hypot(3, 4) - max(1, 2) + min(1, 2) + abs(-1)", 5.0),
    ("(rotzd(90) @ [2, 0, 0])[1] + [1, 2, 3][2]", 5.0),
])
def test_the_grammar_computes_what_it_says(text, want):
    got = evaluate(text, {"r_m": 1.0})
    assert np.allclose(got, want, rtol=0, atol=1e-12), (text, got)


@pytest.mark.parametrize("text, word", [
    ("__import__('os').system('true')", "is not part of"),
    ("__import__('os')", "unknown function '__import__'"),
    ("r_m.real", "'Attribute' is not part of the expression grammar"),
    ("[1, 2, 3][r_m]", "'Subscript' is not part of"),
    ("[1, 2, 3][3]", "takes an entry of a vector"),
    ("(lambda: 1)()", "is not part of"),
    ("[x for x in [1]]", "is not part of"),
    ("r_m if 1 else 2", "is not part of"),
    ("sqrt(x=2)", "is not part of"),
    ("open('f')", "unknown function 'open'"),
    ("width_m * 2", "unknown name 'width_m'"),
    ("1 / 0", "division by zero"),
    ("10.0 ** 400", "overflows"),
    ("exp(1000)", "overflows"),
    ("sqrt(-1)", "sqrt"),
    ("(-2.0e14) ** 0.5", "not a real number"),
    ("(-r_m) ** 1.5", "not a real number"),
    ("unit([0, 0, 0])", "unit: of a zero vector"),
    ("rotz(1) @ 2", "@ multiplies a matrix and a vector"),
    ("r_m +", "is not an expression"),
    ("'text'", "is not part of"),
])
def test_anything_else_is_refused_naming_the_key(text, word):
    with pytest.raises(ParameterError, match=rf"^\[task\] point_m: .*{_escape(word)}"):
        evaluate(text, {"r_m": 1.0}, "[task] point_m")


def _escape(s: str) -> str:
    import re

    return re.escape(s)


def test_parameters_in_order_with_bounds_and_derived_values():
    raw = {"parameters": {"a_m": 2.0, "b_m": {"value": "a_m * 3", "min": 1.0, "max": 10.0}, "v_m": "[a_m, b_m, 0]",
                          "len_m": "norm(v_m)"}}
    p = parameter_values(raw, "d")
    assert p == {"a_m": 2.0, "b_m": 6.0, "v_m": [2.0, 6.0, 0.0], "len_m": pytest.approx(math.sqrt(40.0))}
    bad = copy.deepcopy(raw)
    bad["parameters"]["b_m"]["max"] = 5.0
    with pytest.raises(ParameterError, match=r"\[parameters\] b_m: 6.0 is above its max 5"):
        parameter_values(bad, "d")
    # a parameter may use one written below it (a file written back puts bounded parameters, its
    # sub-tables, last); the values come back in the file's order
    later = {"parameters": {"b_m": "a_m * 3", "v_m": "[b_m, c_m, 0]", "a_m": 2.0, "c_m": {"value": "a_m + 1"}}}
    p = parameter_values(later, "d")
    assert list(p) == ["b_m", "v_m", "a_m", "c_m"] and p["v_m"] == [6.0, 3.0, 0.0]
    for name in ("sqrt", "pi", "1x", "a b"):
        with pytest.raises(ParameterError, match="not a usable parameter name"):
            parameter_values({"parameters": {name: 1.0}}, "d")


def test_an_unknown_name_lists_every_parameter():
    with pytest.raises(ParameterError, match=r"\[parameters\] a_m: unknown name 'zz_m' \(the parameters are: a_m, "
                                             r"b_m, c_m\)$"):
        parameter_values({"parameters": {"a_m": "zz_m * 2", "b_m": 1.0, "c_m": "sqrt(b_m) + pi"}}, "d")


@pytest.mark.parametrize("table, pattern", [
    ({"a_m": "a_m + 1"}, r"\[parameters\] a_m: uses itself$"),
    ({"a_m": "b_m - 1", "b_m": "a_m + 1"}, r"\[parameters\] a_m: a cycle between parameters: a_m -> b_m -> a_m$"),
    ({"x_m": 1.0, "a_m": "[x_m, c_m, 0]", "b_m": {"value": "norm(a_m)", "max": 9.0}, "c_m": "b_m * 2"},
     r"\[parameters\] a_m: a cycle between parameters: a_m -> c_m -> b_m -> a_m$"),
    ({"a_m": 1.0, "b_m": "c_m", "c_m": "d_m + a_m", "d_m": "2 * b_m"},
     r"\[parameters\] b_m: a cycle between parameters: b_m -> c_m -> d_m -> b_m$"),
])
def test_cycles_are_named(table, pattern):
    """A parameter that reads itself and a cycle (named in its order) are each refused in one
    line naming the parameters."""
    with pytest.raises(ParameterError, match=pattern) as err:
        parameter_values({"parameters": table}, "d")
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("name", ["stewart", "delta", "rrr3", "bennett"])
def test_the_parametric_built_ins_are_the_numeric_ones(name):
    """Each built-in file, written in its designer's parameters, compiles to the model of the
    earlier file that spelt every number (kept as tests/data/<name>_numeric.toml)."""
    a = load_mechanism(ex.MACHINES / name / f"{name}.toml")
    b = load_mechanism(DATA / f"{name}_numeric.toml")
    assert a.parameters and not b.parameters
    for field in ("joint_p_parent", "joint_p_child", "joint_R_parent", "joint_R_child", "com", "inertia", "mass",
                  "tree_p_parent", "tree_R_parent", "coord_offset", "task_point", "p0", "R0"):
        x, y = getattr(a, field), getattr(b, field)
        assert x.shape == y.shape and np.abs(x - y).max() <= 1e-12, field
    assert [e.get("section") for e in a.body_extra] == [e.get("section") for e in b.body_extra]
    if name == "stewart":
        assert a.parameters["base_radius_m"] == 1.0 and a.parameters["leg_length_m"] == pytest.approx(1.218177145115201)


def test_one_parameter_moves_every_number_that_depends_on_it():
    """A larger base radius moves the base joints to that radius, the legs' axes and reference
    lengths with them: the leg length stays the distance between its joint centres."""
    d = ex.builtin_dict("stewart", parametric=True)
    d["parameters"]["base_radius_m"] = 1.3
    m = load_mechanism(d)
    base = [m.joint_index(f"U_{i}") for i in range(1, 7)]
    top = [m.joint_index(f"S_{i}") for i in range(1, 7)]
    Pb = np.array([m.joint_p_parent[k] for k in base])  # in the ground's frame
    assert np.allclose(np.hypot(Pb[:, 0], Pb[:, 1]), 1.3, atol=1e-12)
    from pkmdyn.multibody import reference_task, solve_kinematics

    kin = solve_kinematics(m, reference_task(m)[None])
    legs = np.linalg.norm(kin.joint_point[0, top] - kin.joint_point[0, base], axis=1)
    order = [m.actuator_names.index(f"P_{i}") for i in range(1, 7)]
    assert np.allclose(kin.act_q[0, order], legs, atol=1e-12)
    assert np.allclose(legs, m.parameters["leg_length_m"], atol=1e-12)


def test_a_bad_expression_in_a_field_names_the_field(capsys, tmp_path):
    text = (ex.MACHINES / "stewart" / "stewart.toml").read_text().replace(
        'com_m = "[0, 0, height_m]"', 'com_m = "[0, 0, heigth_m]"')
    f = tmp_path / "s.toml"
    f.write_text(text)
    assert main(["describe", "--machine", str(f)]) == 2
    err = capsys.readouterr().err
    assert "[bodies][0] com_m" in err and "unknown name 'heigth_m'" in err and err.count("\n") == 1


def test_describe_prints_the_parameters(capsys):
    assert main(["describe", "--machine", "stewart"]) == 0
    out = capsys.readouterr().out
    assert "parameters: base_radius_m = 1; platform_radius_m = 0.5;" in out


def test_describe_prints_the_bounds_of_a_bounded_parameter(capsys, tmp_path):
    text = (ex.MACHINES / "stewart" / "stewart.toml").read_text().replace(
        "base_radius_m = 1.0", "base_radius_m = { value = 1.0, min = 0.75, max = 1.25 }", 1)
    assert "min = 0.75" in text
    f = tmp_path / "s.toml"
    f.write_text(text)
    assert main(["describe", "--machine", str(f)]) == 0
    out = capsys.readouterr().out
    assert "parameters: base_radius_m = 1 (min 0.75, max 1.25); platform_radius_m = 0.5;" in out


def test_a_sweep_varies_a_dimension_that_many_numbers_share(tmp_path):
    """The base radius of the Stewart platform (every base joint, leg axis and reference length
    depends on it), swept: the designs differ, and the best design's file stays parametric."""
    pq = pytest.importorskip("pyarrow.parquet")
    space = tmp_path / "space.toml"
    space.write_text('[sampling]\nmethod = "grid"\n[motion]\nreactions = false\n[parameters]\n'
                     '"parameters.base_radius_m" = { values = [0.9, 1.1] }\n[objectives]\ngci = "max"\n')
    out = tmp_path / "out"
    assert main(["sweep", "--machine", "stewart", "--space", str(space), "--workers", "0", "--no-plots",
                 "--out", str(out)]) == 0
    rows = sorted(pq.read_table(out / "designs.parquet").to_pylist(), key=lambda r: r["design_id"])
    assert [r["status"] for r in rows] == ["ok", "ok"]
    assert rows[0]["gci"] != rows[1]["gci"]
    best = (out / "best_params.toml").read_text()
    assert 'base_even_m = "rotzd(-base_half_angle_deg) @ [base_radius_m, 0, 0]"' in best
    m = load_mechanism(out / "best_params.toml")
    assert m.parameters["base_radius_m"] in (0.9, 1.1)
