"""Every parameter-validation rule gives a ParameterError naming the key."""

import copy
import dataclasses

import numpy as np
import pytest

from pkmdyn.errors import ParameterError
from pkmdyn.machines.hip_simulator.params import DEFAULT_PARAMS_TEXT, default_params_dict, load_params, model_from_dict


def _with(change):
    d = copy.deepcopy(default_params_dict())
    change(d)
    return d


def test_defaults_are_the_papers_tables_in_si_units():
    m = load_params()
    g, i, f = m.geometry, m.inertia, m.friction
    assert (g.l, g.e, g.E, g.p) == (0.328, 0.144, 0.265, 0.010)
    np.testing.assert_allclose(g.h, [0.899, 0.490])
    np.testing.assert_allclose(i.I_l, [26395.81e-6, 26339.29e-6, 480.07e-6])
    np.testing.assert_allclose(i.I_m, [0.24803050, 0.24994025, 0.38650235])
    assert i.I_L == pytest.approx(54.91e-6) and i.m_L == 3.0 and i.m_l == 1.43 and i.g == 9.8
    assert (f.r_h, f.mu_h, f.r_t, f.mu_t) == (0.015, 0.095, 0.064, 0.025)
    # frames of the spec: X perpendicular to A1A2, away from A3; y_j through a_j2
    assert abs(g.A[0, 0] - g.A[1, 0]) < 1e-15 and g.A[2, 0] < 0 < g.A[0, 0]
    np.testing.assert_allclose(g.r_a[1], [0, g.e, 0], atol=1e-15)


def test_file_round_trip(tmp_path):
    p = tmp_path / "p.toml"
    p.write_text(DEFAULT_PARAMS_TEXT.replace("lever_length_m = 0.328", "lever_length_m = 0.35"))
    assert load_params(p).geometry.l == 0.35


CASES = [
    (lambda d: d["geometry"].update(lever_length_m=-0.3), r"\[geometry\] lever_length_m: must be >= 0.001"),
    (lambda d: d["geometry"].update(base_radius_m=0.0), r"\[geometry\] base_radius_m: must be >= 0.001"),
    (lambda d: d["inertia"].update(slider_mass_kg=-3.0), r"\[inertia\] slider_mass_kg: must be > 0"),
    (lambda d: d["inertia"].update(lever_inertia_kgm2=[1e-3, 0.0, 1e-3]), r"\[inertia\] lever_inertia_kgm2\[1\]: must be > 0"),
    (lambda d: d["inertia"].update(screw_inertia_kgm2=0.0), r"\[inertia\] screw_inertia_kgm2"),
    (lambda d: d["geometry"].update(module_angles_deg=[0.0, 120.0]), r"\[geometry\] module_angles_deg: has 2 entries, needs at least 3"),
    (lambda d: d["geometry"].update(platform_joint_angles_deg=[0.0, 1, 2, 3]), r"\[geometry\] platform_joint_angles_deg: has 4 entries, allows at most 3"),
    (lambda d: d["geometry"].update(platform_heights_m=[0.5]), r"\[geometry\] platform_heights_m"),
    (lambda d: d["geometry"].update(lever_length_m="long"), r"\[geometry\] lever_length_m: has the wrong type"),
    (lambda d: d["geometry"].update(euler_sequence="XXZ"), r"\[geometry\] .*euler_sequence"),
    (lambda d: d["geometry"].update(lever_spin="free"), r"\[geometry\] lever_spin"),
    (lambda d: d["geometry"].update(colour="red"), r"\[geometry\] colour: unknown key"),
    (lambda d: d.update(extra={}), r"\[extra\]: unknown section"),
    (lambda d: d["geometry"].pop("screw_lead_m"), r"\[geometry\] screw_lead_m: missing required key"),
    (lambda d: d.pop("inertia"), r"\[inertia\]: missing required section"),
    (lambda d: d["friction"].update(hip_coefficient=-0.1), r"\[friction\] hip_coefficient: must be >= 0"),
    (lambda d: d["geometry"].update(lever_length_m=0.12), r"\[geometry\] lever_length_m: .* too short for leg 1"),
    (lambda d: d["geometry"].update(platform_heights_m=[0.4, 0.5]), r"h1 must exceed h2"),
]


@pytest.mark.parametrize("change, message", CASES)
def test_rule_violations_name_the_key(change, message):
    with pytest.raises(ParameterError, match=message):
        model_from_dict(_with(change), "p.toml")


def test_bad_toml_and_missing_file(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[geometry\nx = 1")
    with pytest.raises(ParameterError, match="not valid TOML"):
        load_params(bad)
    with pytest.raises(ParameterError, match="cannot read file"):
        load_params(tmp_path / "missing.toml")


def test_model_is_immutable():
    m = load_params()
    with pytest.raises(dataclasses.FrozenInstanceError):
        m.geometry.l = 1.0  # type: ignore[misc]


def _numeric_keys():
    d = default_params_dict()
    return [(t, k) for t, table in d.items() for k, v in table.items() if isinstance(v, (float, list))]


@pytest.mark.parametrize("table, key", _numeric_keys())
@pytest.mark.parametrize("bad", [float("nan"), float("inf"), -float("inf")])
def test_every_number_must_be_finite(table, key, bad):
    def change(d):
        v = d[table][key]
        d[table][key] = [bad] + v[1:] if isinstance(v, list) else bad

    with pytest.raises(ParameterError, match=rf"\[{table}\] {key}(\[0\])?: must be a finite number"):
        model_from_dict(_with(change), "p.toml")


@pytest.mark.parametrize("table, key, value, message", [
    ("inertia", "slider_mass_kg", 1e308, "must be <= 10000"),
    ("geometry", "lever_length_m", 1e5, "must be <= 10"),
    ("geometry", "module_angles_deg", [0.0, 1e9, 2.0], r"module_angles_deg\[1\]: must be <= 360"),
    ("friction", "hip_coefficient", 50.0, "must be <= 5"),
    ("inertia", "gravity_m_s2", 1e4, "must be <= 100"),
])
def test_physically_meaningful_ranges(table, key, value, message):
    with pytest.raises(ParameterError, match=rf"\[{table}\] {message if message.startswith(key) else key + ': ' + message}"):
        model_from_dict(_with(lambda d: d[table].update({key: value})), "p.toml")


def test_limits_table_is_optional_validated_and_reaches_the_model():
    from pkmdyn.machines.hip_simulator.params import HipLimits

    assert load_params().limits == HipLimits()
    m = model_from_dict(_with(lambda d: d.update(limits={"max_load_N": 5e4, "max_samples": 10})))
    assert m.limits.max_load_N == 5e4 and m.limits.max_samples == 10 and m.limits.max_abs_angle_deg == 45.0
    for bad, message in (({"max_load_N": -1.0}, "must be > 0"), ({"max_samples": 1.5}, "wrong type"),
                         ({"max_slider_speed_m_s": float("inf")}, "finite"), ({"speed": 1.0}, "unknown key")):
        with pytest.raises(ParameterError, match=rf"\[limits\] .*{message}"):
            model_from_dict(_with(lambda d: d.update(limits=bad)), "p.toml")
