"""Slide tracks, cross-shear and wear of spherical joints (pkmdyn.multibody.analyses.wear), against
analytic results: straight tracks of a single rotation, circles of two rotations in quadrature,
the sliding distance of a great-circle marker, the inverse motion, Archard's law; and the
commands (pkmdyn wear, pkmdyn hip run's wear.json)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from pkmdyn.cli import main
from pkmdyn.errors import ParameterError
from pkmdyn.multibody import load_mechanism, solve_kinematics
from pkmdyn.multibody.analyses.wear import (ASPECT_CAP, joint_slide_tracks, marker_count, marker_grid, motion_axis,
                                             slide_tracks)
from pkmdyn.spatial import euler_to_matrix


def _cycle(n=4001):
    return np.linspace(0.0, 1.0, n)


def _rotations(t, amps, phases, seq="XYZ"):
    ang = np.stack([a * np.sin(2 * np.pi * t + p) for a, p in zip(amps, phases)], axis=1)
    return euler_to_matrix(seq, ang), ang


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_a_single_rotation_draws_straight_tracks_without_cross_shear(axis):
    t = _cycle()
    amps = [0.0, 0.0, 0.0]
    amps[axis] = np.radians(21.5)
    R, _ = _rotations(t, amps, [0.0, 0.0, 0.0])
    st = slide_tracks(R, t, np.full(t.size, 2000.0), 0.014, grid=marker_grid(10.0, 80.0))
    moving = st.sliding_distance > 1e-9
    assert moving.sum() >= len(st.weights) - 1  # only a marker on the axis itself stays put
    assert np.all(st.aspect_ratio[moving] > 100)
    assert np.all(st.cross_shear <= 1e-12)
    e = np.zeros(3)
    e[axis] = 1.0
    assert abs(abs(motion_axis(R, t) @ e) - 1.0) < 1e-12


@pytest.mark.parametrize("seq", ["XYZ", "ZXY", "YXZ"])
@pytest.mark.parametrize("amp_deg", [5.0, 15.0, 25.0])
def test_two_rotations_in_quadrature_draw_a_circle_at_the_pole(seq, amp_deg):
    """Equal amplitudes about two axes normal to the pole, 90 degrees out of phase: the pole
    marker's track is a circle (aspect ratio 1 to 1e-3) with cross-shear near 1/2."""
    t = _cycle()
    a = np.radians(amp_deg)
    amps = [a if c in "XY" else 0.0 for c in seq]
    phases = [np.pi / 2 if c == "Y" else 0.0 for c in seq]
    R, _ = _rotations(t, amps, phases, seq)
    st = slide_tracks(R, t, np.full(t.size, 1000.0), 0.014)
    assert st.aspect_ratio[0] == pytest.approx(1.0, abs=1e-3)
    assert st.cross_shear[0] == pytest.approx(0.5, abs=0.02)


def test_sliding_distance_of_a_great_circle_marker():
    """Flexion-extension of total swing 43 deg of a 28 mm head: a marker on the great circle
    normal to the axis slides R dtheta = 10.5 mm per half cycle."""
    t = _cycle(4001)  # the extremes are samples
    swing = np.radians(43.0)
    R, _ = _rotations(t, [swing / 2, 0.0, 0.0], [0.0, 0.0, 0.0])
    st = slide_tracks(R, t, np.full(t.size, 1.0), 0.014)
    assert st.sliding_distance[0] / 2 == pytest.approx(0.014 * swing, rel=1e-9)
    assert 0.014 * swing == pytest.approx(10.5e-3, abs=0.01e-3)
    # every marker slides its distance from the axis times the swing, twice a cycle; off the
    # great circle the small-circle arcs are summed as great-circle arcs between samples, short
    # by at most delta^2 / 24 of each (delta <= 0.375 * 2 pi / 4000 rad a step: 1.4e-8)
    d = np.linalg.norm(np.cross(st.markers, [1.0, 0.0, 0.0]), axis=1)
    assert st.sliding_distance == pytest.approx(2 * 0.014 * swing * d, rel=1e-7, abs=1e-15)


def test_archard_wear_and_the_cross_shear_law():
    t = _cycle(2001)
    R, _ = _rotations(t, [0.35, 0.12, 0.1], [0.0, 1.2, 0.4])
    load = 1500.0 + 800.0 * np.sin(2 * np.pi * t) ** 2
    k = 1.0e-6
    st = slide_tracks(R, t, load, 0.016, wear_factor_mm3_N_m=k, cycles=1.0)
    ds = np.diff(st.points, axis=0)
    # the track integral of load against chords (arcs converge to them at this sampling)
    chords = np.linalg.norm(ds, axis=-1)
    ref = (0.5 * (load[1:] + load[:-1])[:, None] * chords).sum(axis=0)
    assert st.load_integral == pytest.approx(ref, rel=1e-5)
    assert st.wear == pytest.approx(k * st.load_integral, rel=1e-12)
    assert st.wear_per_million_cycles == pytest.approx(1e6 * np.sum(st.weights * st.wear) / np.sum(st.weights))
    law = slide_tracks(R, t, load, 0.016, wear_factor_mm3_N_m=k, cross_shear_law="0.5 + 3 * cs")
    assert law.wear == pytest.approx(k * (0.5 + 3 * st.cross_shear) * st.load_integral, rel=1e-12)


def _hip():
    from pkmdyn.machines.hip_simulator import load_params
    from pkmdyn.machines.hip_simulator.description import hip_description
    from pkmdyn.machines.hip_simulator.machine import default_motion

    hp = load_params()
    return load_mechanism(hip_description(hp)), default_motion(), hp


def test_the_hip_head_in_its_cup_and_the_inverse_motion():
    """The hip's upper station through the engine's kinematics against the rotations of the task's
    Euler angles themselves; the cup moving about a fixed head is the inverse motion."""
    m, mo, hp = _hip()
    mo_t = mo.t[::4]
    kin = solve_kinematics(m, mo.x[::4], mo.xd[::4], mo.xdd[::4], mo_t)
    load = mo.loads["hydraulic_N"][::4]
    st = joint_slide_tracks(m, kin, "S0_upper", load, 0.014)
    R = euler_to_matrix(hp.geometry.euler_sequence, mo.x[::4])
    ref = slide_tracks(R, mo_t, load, 0.014)
    assert np.abs(st.points - ref.points).max() < 1e-12
    assert st.aspect_ratio == pytest.approx(ref.aspect_ratio, rel=1e-9)
    # the head on the frame and the cup on the platform: the inverse relative rotation
    inv = joint_slide_tracks(m, kin, "S0_upper", load, 0.014, head="parent")
    ref_inv = slide_tracks(np.swapaxes(R, 1, 2), mo_t, load, 0.014)
    assert np.abs(inv.points - ref_inv.points).max() < 1e-12


def test_hip_run_writes_wear_json(tmp_path):
    out = tmp_path / "run"
    assert main(["hip", "run", "--no-plots", "--samples-per-cycle", "400", "--out", str(out)]) == 0
    doc = json.loads((out / "wear.json").read_text())
    assert [j["joint"] for j in doc["joints"]] == ["S0_upper", "S0_lower"]
    for j in doc["joints"]:
        s = j["tracks_on_cup"]
        assert j["load"] == "named load hydraulic_N" and j["head_radius_m"] > 0
        assert 0 <= s["share_aspect_ratio_above_5_5"] <= 1
        assert s["aspect_ratio"]["min"] >= 1 and 0 <= s["cross_shear"]["max"] <= 0.5
        assert j["wear_volume_mm3_per_million_cycles"] > 0
    assert (out / "markers_S0_upper_on_cup.csv").exists() and not list(out.glob("*.png"))  # --no-plots


def test_wear_command_on_a_described_mechanism_uses_the_joint_reaction(tmp_path):
    """The hip's description through pkmdyn wear with the joint's own reaction as the load: the
    reaction carries the test load and the platform's weight and inertia, so its track integral
    exceeds the test load's."""
    out1, out2 = tmp_path / "reaction", tmp_path / "named"
    assert main(["wear", "--machine", "hip", "--joint", "S0_upper", "--radius-m", "0.014", "--out", str(out1)]) == 0
    assert main(["wear", "--machine", "hip", "--joint", "S0_upper", "--radius-m", "0.014", "--load", "hydraulic_N",
                 "--out", str(out2)]) == 0
    a = json.loads((out1 / "wear.json").read_text())["joints"][0]
    b = json.loads((out2 / "wear.json").read_text())["joints"][0]
    assert a["load"] == "the reaction force of joint S0_upper"
    page = (out1 / "report.html").read_text()
    assert 'id="views"' in page and "scatter3d" in page  # the tracks in 3D
    assert a["tracks_on_cup"]["aspect_ratio"] == b["tracks_on_cup"]["aspect_ratio"]  # the same kinematics
    assert a["tracks_on_cup"]["track_load_integral_per_cycle_N_m"]["mean"] != \
        b["tracks_on_cup"]["track_load_integral_per_cycle_N_m"]["mean"]
    # the library's tracks turn into the markers' tables the command wrote (SlideTracks.columns)
    import pkmdyn

    from pkmdyn.machines.registry import resolve

    m = pkmdyn.load("hip")
    mo = resolve("hip")[0].default_motion()  # the command's motion: the machine's own (the ISO cycle)
    on_cup, on_head, _ = pkmdyn.wear(m, pkmdyn.kinematics(m, mo), "S0_upper", radius_m=0.014, loads=mo.loads)
    for surface, tracks in (("cup", on_cup), ("head", on_head)):
        rows = [ln.split(",") for ln in (out1 / f"markers_S0_upper_on_{surface}.csv").read_text().splitlines()]
        cols = tracks.columns()
        assert list(cols) == rows[0]
        for k, name in enumerate(rows[0]):
            np.testing.assert_allclose(cols[name], [float(r[k]) for r in rows[1:]], rtol=1e-9, atol=1e-15,
                                       err_msg=name)


@pytest.mark.parametrize("args, words", [
    (["--joint", "P_1", "--radius-m", "0.014"], "prismatic joint"),
    (["--joint", "nope", "--radius-m", "0.014"], "'nope'"),
    (["--joint", "S0_upper"], "no head radius"),
    (["--joint", "S0_upper", "--radius-m", "0"], "--radius-m"),
    (["--joint", "S0_upper", "--radius-m", "0.014", "--wear-factor", "-1e-7"], "--wear-factor"),
    (["--joint", "S0_upper", "--radius-m", "0.014", "--cap-deg", "-5"], "--cap-deg"),
    (["--joint", "S0_upper", "--radius-m", "0.014", "--cap-deg", "0"], "--cap-deg"),  # docs/wear.md: refused
    (["--joint", "S0_upper", "--radius-m", "0.014", "--load", "push_N"], "push_N"),
    (["--joint", "S0_upper", "--radius-m", "0.014", "--cross-shear-law", "cs - 1"], "cross-shear-law"),
    (["--joint", "S0_upper", "--radius-m", "0.014", "--cross-shear-law", "(-cs - 1) ** 0.5"], "not a real number"),
    (["--joint", "S0_upper", "--radius-m", "0.014", "--spacing-deg", "1e-4"], "exceeds the limit max_wear_track_points"),
    (["--joint", "S0_upper", "--radius-m", "0.014", "--spacing-deg", "1e-300"], "exceeds the limit max_wear_track_points"),
])
def test_bad_wear_input_exit_2_nothing_written(tmp_path, capsys, args, words):
    out = tmp_path / "out"
    assert main(["wear", "--machine", "hip", *args, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert lines and words in err, err
    assert not out.exists()


@pytest.mark.parametrize("spacing, cap", [(10.0, 60.0), (0.7, 180.0), (3.3, 91.0), (90.0, 180.0), (10.0, 0.5),
                                          (25.0, 50.0), (1.0, 60.0)])
def test_the_markers_are_counted_before_the_grid_is_built(spacing, cap):
    assert marker_count(spacing, cap) == len(marker_grid(spacing, cap).u)


def test_the_library_grid_is_bounded_before_it_is_built():
    from pkmdyn.errors import LimitError

    with pytest.raises(LimitError, match=rf"{marker_count(0.01, 60.0):,} markers .* exceed the 1,000 allowed"):
        marker_grid(0.01, 60.0, max_markers=1000)
    with pytest.raises(LimitError, match="exceed the 1,000,000 allowed"):
        marker_grid(1e-300, 60.0)
    assert len(marker_grid(10.0, 60.0, max_markers=119).u) == 119


def test_a_raised_limit_lets_a_fine_grid_run(tmp_path, capsys):
    out = tmp_path / "fine"
    args = ["wear", "--machine", "hip", "--joint", "S0_upper", "--radius-m", "0.014", "--spacing-deg", "2",
            "--cap-deg", "30", "--out", str(out)]
    n = marker_count(2.0, 30.0)  # the hip's default motion: 1,001 samples
    assert main([*args[:-2], "--limit", f"max_wear_track_points={n * 1001 - 1}", *args[-2:]]) == 2
    assert "max_wear_track_points" in capsys.readouterr().err and not out.exists()
    assert main([*args[:-2], "--limit", f"max_wear_track_points={n * 1001}", *args[-2:]]) == 0
    assert json.loads((out / "wear.json").read_text())["joints"][0]["marker_grid"]["markers"] == n


@pytest.mark.parametrize("spacing, cap", [(10.0, 60.0), (10.0, 58.0), (7.0, 45.0), (15.0, 10.0), (10.0, 0.5)])
def test_marker_grid_areas(spacing, cap):
    g = marker_grid(spacing, cap)
    assert g.w.sum() == pytest.approx(2 * np.pi * (1 - np.cos(np.radians(cap))), rel=1e-12)
    assert np.allclose(np.linalg.norm(g.u, axis=1), 1.0)
    assert g.u[0] == pytest.approx([0.0, 0.0, 1.0])
    assert ASPECT_CAP >= 1e9


def test_a_cap_that_is_not_positive_is_refused():
    with pytest.raises(ParameterError, match=r"marker cap: 0\.0 deg is not in \(0, 180\]"):
        marker_grid(10.0, 0.0)


def test_the_share_above_5_5_by_markers_and_by_area():
    """Both shares from the markers' own aspect ratios and weights, computed here."""
    from pkmdyn.multibody.analyses.wear import ASPECT_LIMIT, WearOptions, joint_wear

    m, mo, _ = _hip()
    kin = solve_kinematics(m, mo.x, mo.xd, mo.xdd, mo.t)
    on_cup, _, _ = joint_wear(m, kin, "S0_upper", WearOptions(radius_m=0.014), mo.loads)
    s = on_cup.summary()
    thin = on_cup.aspect_ratio > ASPECT_LIMIT
    assert 0 < thin.sum() < len(thin)
    assert s["share_aspect_ratio_above_5_5"] == pytest.approx(thin.mean(), abs=1e-15)
    assert s["area_share_aspect_ratio_above_5_5"] == pytest.approx(on_cup.weights[thin].sum() / on_cup.weights.sum(),
                                                                   abs=1e-15)
