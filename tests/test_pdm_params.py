"""PDM parameter file: validation errors name the key; the derived layout is consistent."""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from pkmdyn.errors import ParameterError
from pkmdyn.machines.pdm4 import default_params_path, load_params
from pkmdyn.machines.pdm4.params import params_from_dict


def _raw():
    return tomllib.loads(default_params_path().read_text(encoding="utf-8"))


def test_default_parameters_load_in_si_units():
    m = load_params()
    raw = _raw()["geometry"]
    assert m.r2 == raw["crank_length_m"] and m.r3 == raw["coupler_length_m"]
    assert m.R1.shape == m.R4.shape == m.S.shape == (2, 3)
    assert not m.R1.flags.writeable
    assert math.isclose(m.min_transmission, math.radians(_raw()["limbs"]["min_transmission_angle_deg"]))


def test_layout_is_mirror_symmetric_and_planar_where_it_should_be():
    m = load_params()
    mirror = np.array([-1.0, 1.0, 1.0])
    for arr in (m.R1, m.R4, m.S, m.U_local, m.R3_local):
        assert np.allclose(arr[0] * mirror, arr[1], atol=1e-15)
    assert np.all(m.R1[:, 2] == 0) and np.all(m.R4[:, 2] == 0)
    # the derived ground joints reproduce the documented home limb lengths and directions
    g = _raw()["geometry"]
    R2_home = m.R4 + g["rpr_home_length_m"] * np.array(
        [[math.cos(math.radians(a)), math.sin(math.radians(a)), 0.0] for a in g["rpr_home_direction_deg"]])
    assert np.allclose(np.linalg.norm(R2_home - m.R1, axis=1), m.r2, atol=1e-12)
    assert np.allclose(np.linalg.norm(R2_home - (m.R3_local + [0, 0, 0]), axis=1), m.r3, atol=1e-12)
    assert np.allclose(np.linalg.norm(m.U_local - m.S, axis=1), g["spu_home_length_m"], atol=1e-12)


@pytest.mark.parametrize(
    "section, key, value, message",
    [
        ("geometry", "crank_length_m", -0.1, r"\[geometry\] crank_length_m: must be > 0"),
        ("geometry", "assembly_branch", [1, 0], r"\[geometry\] assembly_branch: each entry must be 1 or -1"),
        ("geometry", "rpr_home_direction_deg", [45.0], r"\[geometry\] rpr_home_direction_deg: "),
        ("limbs", "stroke_limit_m", "50 mm", r"\[limbs\] stroke_limit_m: has the wrong type"),
        ("geometry", "spu_home_elevation_deg", 95.0, r"\[geometry\] spu_home_elevation_deg: must be < 90"),
        ("trajectory", "samples", 3, r"\[trajectory\] samples: must be >= 6"),
    ],
)
def test_bad_values_name_the_key(section, key, value, message):
    raw = _raw()
    raw[section][key] = value
    with pytest.raises(ParameterError, match=r"^test\.toml: " + message):
        params_from_dict(raw, "test.toml")


def test_unknown_and_missing_keys_are_named():
    raw = _raw()
    raw["geometry"]["crank_lenght_m"] = 0.2
    with pytest.raises(ParameterError, match=r"\[geometry\] crank_lenght_m: unknown key"):
        params_from_dict(raw, "p.toml")
    raw = _raw()
    del raw["limbs"]["stroke_limit_m"]
    with pytest.raises(ParameterError, match=r"\[limbs\] stroke_limit_m: missing required key"):
        params_from_dict(raw, "p.toml")
    raw = _raw()
    del raw["workspace"]
    with pytest.raises(ParameterError, match=r"p.toml: \[workspace\]: missing required section"):
        params_from_dict(raw, "p.toml")


def test_six_bar_that_cannot_close_at_home_is_a_parameter_error():
    raw = _raw()
    raw["geometry"]["crank_pivot_y_m"] = -0.6
    with pytest.raises(ParameterError, match=r"\[geometry\] crank_pivot_y_m: the six-bar cannot close"):
        params_from_dict(raw, "p.toml")


def test_unreadable_and_malformed_files(tmp_path):
    with pytest.raises(ParameterError, match="cannot read file"):
        load_params(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[geometry\n", encoding="utf-8")
    with pytest.raises(ParameterError, match="bad.toml: not valid TOML"):
        load_params(bad)
