"""Design sweeps in this process: space files, Pareto sets, metrics recomputed from the machines'
public functions, invalid designs as rows, resume after an interruption, bad space files."""

from __future__ import annotations

import math
import textwrap
import tomllib
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")

from pkmdyn.cli import main  # noqa: E402
from pkmdyn.errors import (  # noqa: E402
    LimitError,
    ParameterError,
    PkmdynError,  # noqa: E402
)
from pkmdyn.io import dumps_toml  # noqa: E402
from pkmdyn.jobs.sweep import run_sweep
from pkmdyn.machines.registry import sweep_adapter  # noqa: E402
from pkmdyn.sweep import pareto_mask  # noqa: E402
from pkmdyn.sweep.pareto import best_index, minimised  # noqa: E402
from pkmdyn.sweep.space import get_value, parse_path, sample_designs  # noqa: E402

HIP_SPACE = """
[sampling]
method = "sobol"
designs = 32
seed = 7
batch_size = 8

[motion]
samples_per_cycle = 120
workspace_points = 64

[parameters]
"geometry.base_radius_m" = { min = 0.22, max = 0.32 }
"geometry.lever_length_m" = { min = 0.12, max = 0.40 }
"geometry.platform_heights_m[1]" = { values = [0.45, 0.49] }

[constraints]
max_spherical_angle_deg = { max = 29.0 }

[objectives]
peak_drive_force_N = "min"
gci = "max"
"""


def _write(tmp_path: Path, text: str, name: str = "space.toml") -> Path:
    p = tmp_path / name
    p.write_text(textwrap.dedent(text), encoding="utf-8")
    return p


def _rows(path: Path) -> list[dict]:
    return pq.read_table(path).to_pylist()


# ----------------------------------------------------------------------------- Pareto set
def test_pareto_constructed_example():
    # minimise both: (1, 5), (2, 2), (5, 1) are the front; (3, 3) is dominated by (2, 2);
    # (2, 2) twice: equal points do not dominate each other; (5, 5) dominated by all
    F = np.array([[1, 5], [2, 2], [3, 3], [5, 1], [2, 2], [5, 5], [1, 6]], dtype=float)
    assert pareto_mask(F).tolist() == [True, True, False, True, True, False, False]


def test_pareto_against_brute_force_with_a_maximised_objective():
    rng = np.random.default_rng(3)
    raw = rng.integers(0, 6, size=(300, 3)).astype(float)  # many ties
    F = minimised(raw, ["min", "max", "min"])
    expected = [not any(np.all(F[j] <= F[i]) and np.any(F[j] < F[i]) for j in range(len(F))) for i in range(len(F))]
    assert pareto_mask(F, chunk=7).tolist() == expected
    b = best_index(F)
    assert expected[b]
    assert F[b, 0] == F[:, 0].min()


# ----------------------------------------------------------------------------- space files
def test_parse_path_and_grid_order(tmp_path):
    assert parse_path("geometry.platform_heights_m[1]") == ("geometry", "platform_heights_m", 1)
    from pkmdyn.sweep.space import ByName, index_path

    d = {"bodies": [{"name": "base", "m": 1.0}, {"name": "arm.2", "m": 2.0, "c": [0.0, 3.0]}]}
    path = parse_path("bodies[arm.2].c[1]")
    assert path == ("bodies", "arm.2", "c", 1) and isinstance(path[1], ByName)
    assert index_path(d, path) == ("bodies", 1, "c", 1) and get_value(d, path) == 3.0
    with pytest.raises(KeyError, match="no entries named 'arm' in bodies .names: base, arm.2"):
        get_value(d, parse_path("bodies[arm].m"))
    for bad in ("bodies[arm].", "bodies..m", "bodies[arm]x"):
        with pytest.raises(ParameterError, match="not a dotted key path"):
            parse_path(bad)
    space_file = _write(tmp_path, """
        [sampling]
        method = "grid"
        [parameters]
        "geometry.base_radius_m" = { min = 0.2, max = 0.3, points = 3 }
        "geometry.module_angles_deg[2]" = { values = [170.0, 180.0] }
        [objectives]
        peak_torque_Nm = "min"
        """)
    from pkmdyn.sweep.space import load_space

    ad = sweep_adapter("hip")
    space, _ = load_space(space_file, ad.base_description, ad.metrics)
    X = sample_designs(space)
    assert X.shape == (6, 2)
    np.testing.assert_array_equal(X[:, 1], [170, 180] * 3)  # the last parameter varies fastest
    np.testing.assert_allclose(X[::2, 0], [0.2, 0.25, 0.3])


def test_integer_key_sampled_on_integers(tmp_path):
    space_file = _write(tmp_path, """
        [sampling]
        method = "random"
        designs = 50
        [parameters]
        "trajectory.samples" = { min = 20, max = 30 }
        [objectives]
        peak_force_N = "min"
        """)
    from pkmdyn.sweep.space import load_space

    ad = sweep_adapter("pdm")
    space, _ = load_space(space_file, ad.base_description, ad.metrics)
    X = sample_designs(space)
    assert np.all(X == np.round(X)) and X.min() >= 20 and X.max() <= 30


BAD_SPACES = {
    "unknown key": ('"geometry.nope_m" = { min = 0.1, max = 0.2 }', "unknown key"),
    "index out of range": ('"geometry.platform_heights_m[2]" = { min = 0.1, max = 0.2 }', "out of range"),
    "not numeric": ('"geometry.euler_sequence" = { values = [1.0] }', "not a numeric key"),
    "empty range": ('"geometry.base_radius_m" = { min = 0.3, max = 0.3 }', "empty range"),
    "empty values": ('"geometry.base_radius_m" = { values = [] }', "empty range"),
    "every design invalid": ('"geometry.lever_length_m" = { min = 20.0, max = 30.0 }', "invalid"),
}


@pytest.mark.parametrize("case", sorted(BAD_SPACES))
def test_bad_space_file_one_line_exit_2_nothing_written(tmp_path, capsys, case):
    line, words = BAD_SPACES[case]
    space = _write(tmp_path, f"""
        [sampling]
        method = "random"
        designs = 16
        [parameters]
        {line}
        [objectives]
        peak_torque_Nm = "min"
        """)
    out = tmp_path / "out"
    assert main(["sweep", "--machine", "hip", "--space", str(space), "--out", str(out), "--workers", "0"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err and "Traceback" not in err
    assert not out.exists()


def test_unknown_metric_and_motion_option_refused(tmp_path, capsys):
    base = """
        [sampling]
        method = "random"
        designs = 4
        [parameters]
        "geometry.base_radius_m" = { min = 0.2, max = 0.3 }
        """
    space = _write(tmp_path, base + '[objectives]\nno_such_metric = "min"\n', "a.toml")
    assert main(["sweep", "--machine", "hip", "--space", str(space), "--out", str(tmp_path / "o1")]) == 2
    assert "unknown metric" in capsys.readouterr().err
    space = _write(tmp_path, base + '[motion]\nsamples_per_cyle = 100\n[objectives]\ngci = "max"\n', "b.toml")
    assert main(["sweep", "--machine", "hip", "--space", str(space), "--out", str(tmp_path / "o2")]) == 2
    assert "samples_per_cyle" in capsys.readouterr().err
    assert main(["sweep", "--machine", "nosuch", "--space", str(space), "--out", str(tmp_path / "o3")]) == 2
    assert "unknown machine" in capsys.readouterr().err


def test_grid_beyond_the_design_limit_refused_before_work_and_raisable(tmp_path, capsys):
    space = _write(tmp_path, """
        [sampling]
        method = "grid"
        [motion]
        samples_per_cycle = 20
        workspace_points = 0
        [parameters]
        "geometry.base_radius_m" = { min = 0.2, max = 0.3, points = 100 }
        "geometry.platform_radius_m" = { min = 0.1, max = 0.2, points = 100 }
        "geometry.lever_length_m" = { min = 0.3, max = 0.4, points = 100 }
        [objectives]
        peak_torque_Nm = "min"
        """)
    out = tmp_path / "out"
    assert main(["sweep", "--machine", "hip", "--space", str(space), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "1,000,000 designs exceed the limit max_designs = 100,000" in err and err.count("\n") == 1
    assert not out.exists()
    small = _write(tmp_path, """
        [sampling]
        method = "grid"
        max_designs = 5
        [motion]
        samples_per_cycle = 20
        workspace_points = 0
        [parameters]
        "geometry.base_radius_m" = { min = 0.2, max = 0.3, points = 3 }
        "geometry.lever_length_m" = { min = 0.3, max = 0.4, points = 2 }
        [objectives]
        peak_torque_Nm = "min"
        """, "small.toml")
    ad = sweep_adapter("hip")
    with pytest.raises(LimitError, match="6 designs exceed"):
        run_sweep(ad, small, out, workers=0, plots=False)
    report = run_sweep(ad, small, out, workers=0, plots=False, max_designs=6)
    assert report.designs == 6


def test_base_parameters_invalid_for_the_motion_refused(tmp_path):
    space = _write(tmp_path, """
        [sampling]
        method = "random"
        designs = 4
        [motion]
        file = "missing.csv"
        [parameters]
        "geometry.base_radius_m" = { min = 0.2, max = 0.3 }
        [objectives]
        gci = "max"
        """)
    with pytest.raises(Exception, match="missing.csv"):
        run_sweep(sweep_adapter("hip"), space, tmp_path / "out", workers=0)
    assert not (tmp_path / "out").exists()


# ----------------------------------------------------------------------------- a hip sweep
@pytest.fixture(scope="module")
def hip_sweep(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("hip_sweep")
    space = _write(tmp, HIP_SPACE)
    report = run_sweep(sweep_adapter("hip"), space, tmp / "out", workers=0, progress=False)
    return tmp, report


def test_hip_sweep_files_and_statuses(hip_sweep):
    tmp, report = hip_sweep
    rows = _rows(tmp / "out" / "designs.parquet")
    assert [r["design_id"] for r in rows] == list(range(32))
    statuses = {r["status"] for r in rows}
    # lever lengths from 0.12 m: some too short to reach (an invalid row, never a crash)
    assert "invalid" in statuses and "ok" in statuses
    for r in rows:
        if r["status"] == "invalid":
            assert "lever_length_m" in r["reason"] and r["gci"] is None and not r["reachable"]
        if r["status"] == "infeasible":
            assert "max_spherical_angle_deg" in r["reason"] and r["max_spherical_angle_deg"] > 29.0
        if r["status"] == "ok":
            assert r["feasible"] and r["max_spherical_angle_deg"] <= 29.0 and r["reason"] == ""
    for name in ("pareto.parquet", "best_params.toml", "summary.json", "pareto_front.png",
                 "metric_vs_parameter.png", "scatter_matrix.png"):
        assert (tmp / "out" / name).is_file(), name
    # the Pareto set: feasible, mutually non-dominated, and nothing feasible dominates it
    front = _rows(tmp / "out" / "pareto.parquet")
    ok = [r for r in rows if r["feasible"]]
    F = np.array([[r["peak_drive_force_N"], -r["gci"]] for r in ok])
    mask = pareto_mask(F)
    assert sorted(r["design_id"] for r in front) == sorted(ok[i]["design_id"] for i in np.flatnonzero(mask))
    assert report.best_design_id == front[0]["design_id"]
    assert front[0]["peak_drive_force_N"] == min(r["peak_drive_force_N"] for r in ok)


def test_hip_best_design_file_runs_and_holds_its_values(hip_sweep, tmp_path):
    tmp, report = hip_sweep
    best = tomllib.loads((tmp / "out" / "best_params.toml").read_text(encoding="utf-8"))
    row = _rows(tmp / "out" / "designs.parquet")[report.best_design_id]
    assert best["geometry"]["base_radius_m"] == row["geometry.base_radius_m"]
    assert best["geometry"]["platform_heights_m"][1] == row["geometry.platform_heights_m[1]"]
    assert main(["hip", "run", "--params", str(tmp / "out" / "best_params.toml"), "--no-plots",
                 "--samples-per-cycle", "100", "--out", str(tmp_path / "run")]) == 0


def _hip_reference(params: dict, samples_per_cycle: int) -> dict[str, float]:
    """The hip metrics from the closed-form oracle of Eq. 1-16 (``tests/oracles/hip.py``, numpy,
    nothing of the engine): per-sample np.linalg.cond of its J, the zero pose from its kinematics
    at zero angles."""
    from oracles import hip as oracle

    from pkmdyn.machines.hip_simulator.params import model_from_dict
    from pkmdyn.profiles.iso14242 import iso14242_motion

    model = model_from_dict(params)
    motion = iso14242_motion(1.0, samples_per_cycle)
    kin = oracle.kinematics(model, motion.angles, motion.rates, motion.accels)
    tq = oracle.inverse_dynamics(model, kin, motion.load)
    e0 = oracle.kinematics(model, np.zeros((1, 3))).e_lever[0]
    inv = np.array([1.0 / np.linalg.cond(J) for J in kin.J])
    sph = max(math.degrees(math.acos(min(1.0, float(kin.R[k].T @ kin.e_lever[k, i] @ e0[i]))))
              for k in range(len(motion)) for i in range(3))
    omega_motor = kin.theta_dot
    t = motion.t
    return {
        "min_inverse_condition": inv.min(),
        "gci": np.trapezoid(inv, t) / (t[-1] - t[0]),
        "max_spherical_angle_deg": sph,
        "stroke_m": float(np.ptp(kin.L[:, 1], axis=0).max()),
        "peak_torque_Nm": np.abs(tq.tau).max(),
        "peak_drive_force_N": np.abs(tq.tau).max() * 2 * math.pi / model.geometry.p,
        "peak_motor_speed_rad_s": np.abs(omega_motor).max(),
        "rms_torque_Nm": max(math.sqrt(np.trapezoid(tq.tau[:, i] ** 2, t) / (t[-1] - t[0])) for i in range(3)),
        "friction_energy_per_cycle_J": np.trapezoid(np.sum(tq.friction * omega_motor, axis=1), t),
        "peak_power_W": tq.power.max(),
    }


def test_hip_metrics_recomputed_independently(hip_sweep):
    tmp, _ = hip_sweep
    from pkmdyn.sweep.space import design_description, load_space

    ad = sweep_adapter("hip")
    base_description = ad.base_description
    space, base = load_space(tmp / "space.toml", ad.base_description, ad.metrics)
    rows = _rows(tmp / "out" / "designs.parquet")
    checked = [r for r in rows if r["status"] in ("ok", "infeasible")][:3]
    assert len(checked) == 3
    for r in checked:
        X = sample_designs(space)[r["design_id"]]
        ref = _hip_reference(design_description(base_description(None), space.parameters, X), 120)
        for k, v in ref.items():
            # the sweep's 1/cond is a closed form of the engine's J, np.linalg.cond an SVD of
            # the closed form's: agreement to ~1e-10; the rest the engine against the closed
            # forms (about 1e-13 observed)
            rtol = 1e-8 if k in ("gci", "min_inverse_condition") else 1e-9
            assert r[k] == pytest.approx(v, rel=rtol, abs=1e-9), k
        assert 0.0 < r["orientation_workspace_fraction"] <= 1.0
        assert r["friction_energy_per_cycle_J"] > 0.0


def test_orientation_workspace_against_a_plain_reach_check():
    """The workspace fraction against a per-orientation loop over the loop-closure equation."""
    from pkmdyn.machines.hip_simulator import load_params
    from pkmdyn.machines.hip_simulator.described_sweep import (
        _workspace_fraction,
        _workspace_rotations,
    )

    model = load_params()
    g = model.geometry
    R = _workspace_rotations("XYZ", 200, 60.0)
    count = 0
    for Rk in R:
        legs = []
        for i in range(3):
            r = Rk @ g.r_a[i]
            h2 = (r[0] - g.A[i, 0]) ** 2 + (r[1] - g.A[i, 1]) ** 2
            legs.append(h2 < g.l**2)
        if all(legs):
            e = np.array([[r[0] - g.A[i, 0], r[1] - g.A[i, 1], math.sqrt(g.l**2 - (r[0] - g.A[i, 0]) ** 2
                           - (r[1] - g.A[i, 1]) ** 2)] for i, r in ((i, Rk @ g.r_a[i]) for i in range(3))]) / g.l
            J = np.array([np.cross(Rk @ g.r_a[i], e[i]) / e[i, 2] for i in range(3)])
            count += 1.0 / np.linalg.cond(J) >= 1e-3
    frac = _workspace_fraction(model, R, 1e-3)
    assert frac == pytest.approx(count / 200)
    assert 0.0 < frac < 1.0  # 60 degrees: some orientations out of reach


# ----------------------------------------------------------------------------- resume
def _interrupting(adapter, after_calls: int):
    calls = {"n": 0}

    def evaluate(descriptions, context):
        calls["n"] += 1
        if calls["n"] > after_calls:
            raise KeyboardInterrupt
        return adapter.evaluate(descriptions, context)

    return SimpleNamespace(**{k: getattr(adapter, k) for k in
                              ("NAME", "base_description", "check_description", "metrics", "prepare")},
                           evaluate=evaluate)


def test_interrupted_run_resumes_without_loss_or_duplicates(hip_sweep, tmp_path):
    tmp, _ = hip_sweep
    ad = sweep_adapter("hip")
    out = tmp_path / "out"
    with pytest.raises(KeyboardInterrupt):
        run_sweep(_interrupting(ad, 2), tmp / "space.toml", out, workers=0, plots=False)
    parts = sorted((out / "parts").glob("part-*.parquet"))
    assert len(parts) == 2 and not (out / "designs.parquet").exists()
    report = run_sweep(ad, tmp / "space.toml", out, workers=0, plots=False)
    assert report.evaluated == 32 - 16
    ids = np.concatenate([pq.read_table(p).column("design_id").to_numpy() for p in (out / "parts").iterdir()])
    assert sorted(ids.tolist()) == list(range(32))
    assert pq.read_table(out / "designs.parquet").equals(pq.read_table(tmp / "out" / "designs.parquet"))


def test_rerun_with_another_space_is_refused(hip_sweep, tmp_path):
    tmp, _ = hip_sweep
    other = _write(tmp_path, HIP_SPACE.replace("seed = 7", "seed = 8"))
    with pytest.raises(Exception, match="different space"):
        run_sweep(sweep_adapter("hip"), other, tmp / "out", workers=0)
    stranger = tmp_path / "stranger"
    stranger.mkdir()
    (stranger / "notes.txt").write_text("mine")
    with pytest.raises(Exception, match="holds no pkmdyn sweep"):
        run_sweep(sweep_adapter("hip"), other, stranger, workers=0)


# ----------------------------------------------------------------------------- the PDM
PDM_SPACE = """
[sampling]
method = "lhs"
designs = 6
seed = 2

[parameters]
"geometry.crank_length_m" = { min = 0.22, max = 0.27 }
"trajectory.stroke_y_m" = { values = [0.01, 0.03] }

[objectives]
peak_force_N = "min"
"""


def test_pdm_metrics_recomputed_independently(tmp_path):
    """The sweep's metrics (the generic engine on the PDM's description) against the hand-derived
    oracles (Eq. 2-83), to 1e-9 relative (observed about 1e-13)."""
    from oracles import pdm_minimal as minimal
    from oracles.pdm_newton_euler import JOINTS, inverse_dynamics

    from pkmdyn.machines.pdm4 import inverse_kinematics, load_params
    from pkmdyn.profiles.pdm_motion import cycloidal_motion

    space = _write(tmp_path, PDM_SPACE)
    report = run_sweep(sweep_adapter("pdm"), space, tmp_path / "out", workers=0, plots=False)
    rows = _rows(tmp_path / "out" / "designs.parquet")
    assert report.best_design_id is not None
    # the best design's file, read back by the machine's own loader, gives the row's metrics
    r = rows[report.best_design_id]
    model = load_params(tmp_path / "out" / "best_params.toml")
    assert model.r2 == r["geometry.crank_length_m"]
    tr = model.trajectory
    motion = cycloidal_motion(tr.strokes, tr.period_s, tr.samples)
    kin = inverse_kinematics(model, motion)
    reac = inverse_dynamics(model, kin)
    assert r["peak_force_N"] == pytest.approx(np.abs(reac.force).max(), rel=1e-9)
    assert r["stroke_m"] == pytest.approx(np.ptp(kin.pos.l, axis=0).max(), rel=1e-9)
    for j, (name, *_) in enumerate(JOINTS):
        col = f"peak_force_{name.replace(chr(39), 'p')}_N"
        assert r[col] == pytest.approx(max(np.linalg.norm(f) for f in reac.joint_force[:, j]), rel=1e-9)
    B = minimal.actuator_map(model, motion.q)
    scale = np.diag([1.0, 1.0, 1.0 / model.r4, 1.0 / model.r4])
    inv = np.array([1.0 / np.linalg.cond(b.T @ scale) for b in B])
    assert r["min_inverse_condition"] == pytest.approx(inv.min(), rel=1e-9)
    sines = np.abs(np.sin(kin.pos.theta2 - kin.pos.theta1)).min()
    assert r["min_transmission_angle_deg"] == pytest.approx(np.degrees(np.arcsin(sines)), rel=1e-9)
    assert "friction_energy_per_cycle_J" not in r  # no friction model: no friction metric


def test_toml_writer_round_trips_nested_descriptions():
    from pkmdyn.machines.pdm4.sweep import base_description

    d = base_description(None)
    d["inertia"]["bodies"] = {"platform": {"mass_kg": 5.0, "inertia_kgm2": [[0.01, 0, 0], [0, 0.02, 0], [0, 0, 0.02]]}}
    d["material"]["stiffness_diameters_m"] = {"coupler2": 0.04}
    d["geometry"]["platform_offset_m"] = 0.1 + 0.2  # not a short decimal
    assert tomllib.loads(dumps_toml(d, "header\nline")) == d
    with pytest.raises(PkmdynError, match="non-finite"):
        dumps_toml({"a": {"x": float("nan")}})


def test_unknown_machine_is_a_parameter_error():
    with pytest.raises(ParameterError, match="unknown machine"):
        sweep_adapter("no_such_machine")


# ----------------------------------------------------------------------------- refinement
REFINE = """
[refine]
rounds = 2
designs = 12
shrink = 0.5
"""


def test_refinement_rounds_sample_around_the_pareto_set(tmp_path):
    from pkmdyn.sweep.space import load_space

    space_file = _write(tmp_path, HIP_SPACE + REFINE)
    ad = sweep_adapter("hip")
    report = run_sweep(ad, space_file, tmp_path / "out", workers=0, plots=False)
    rows = _rows(tmp_path / "out" / "designs.parquet")
    assert report.designs == len(rows) == 32 + 2 * 12
    assert [r["round"] for r in rows] == [0] * 32 + [1] * 12 + [2] * 12
    space, _ = load_space(space_file, ad.base_description, ad.metrics)
    keys = [p.key for p in space.parameters]
    ranges = {p.key: (p.lo, p.hi) for p in space.parameters if p.values is None}
    for r in (1, 2):
        earlier = [x for x in rows if x["round"] < r and x["feasible"]]
        F = np.array([[x["peak_drive_force_N"], -x["gci"]] for x in earlier])
        front = [earlier[i] for i in np.flatnonzero(pareto_mask(F))]
        half = 0.5 * 0.5**r
        for new in (x for x in rows if x["round"] == r):
            # within the box of half-width shrink^r / 2 of each range around some Pareto design
            assert any(all(abs(new[k] - c[k]) <= half * (hi - lo) * (1 + 1e-12) for k, (lo, hi) in ranges.items())
                       for c in front)
            for k, (lo, hi) in ranges.items():
                assert lo <= new[k] <= hi
            assert new["geometry.platform_heights_m[1]"] in (0.45, 0.49)
    # the Pareto set and the best design account for every round
    first = min(x["peak_drive_force_N"] for x in rows if x["feasible"] and x["round"] == 0)
    best = rows[report.best_design_id]
    assert best["peak_drive_force_N"] == min(x["peak_drive_force_N"] for x in rows if x["feasible"]) <= first
    assert set(keys) <= set(best)


def test_refinement_resumes_after_an_interruption(tmp_path):
    space_file = _write(tmp_path, HIP_SPACE + REFINE)
    ad = sweep_adapter("hip")
    # the sample takes 4 batches of 8; the first refinement round 2 batches: stop inside it
    with pytest.raises(KeyboardInterrupt):
        run_sweep(_interrupting(ad, 5), space_file, tmp_path / "cut", workers=0, plots=False)
    ids = np.concatenate([pq.read_table(p).column("design_id").to_numpy()
                          for p in (tmp_path / "cut" / "parts").iterdir()])
    assert sorted(ids.tolist()) == list(range(32)) + list(range(32, 40))
    report = run_sweep(ad, space_file, tmp_path / "cut", workers=0, plots=False)
    assert report.evaluated == 56 - 40
    run_sweep(ad, space_file, tmp_path / "clean", workers=0, plots=False)
    assert pq.read_table(tmp_path / "cut" / "designs.parquet").equals(pq.read_table(tmp_path / "clean" / "designs.parquet"))


def test_docs_worked_example_figures_of_the_paper_design():
    """docs/sweep.md quotes these for the paper's design under examples/hip_table1_space.toml."""
    from pkmdyn.jobs.sweep import prepare_sweep

    example = Path(__file__).resolve().parents[1] / "examples" / "hip_table1_space.toml"
    prep = prepare_sweep(sweep_adapter("hip"), example)
    assert prep.X.shape == (4096, 4) and prep.space.refine_rounds == 2
    hip_sweep_adapter = sweep_adapter("hip")
    base = hip_sweep_adapter.base_description(None)
    outcome = hip_sweep_adapter.evaluate([base], prep.job.context)[0]
    m = outcome.metrics
    assert outcome.status == "ok"
    assert (round(m["peak_drive_force_N"], 1), round(m["stroke_m"], 3), round(m["max_spherical_angle_deg"], 1),
            round(m["gci"], 3), round(m["min_inverse_condition"], 3), round(m["orientation_workspace_fraction"], 3)) \
        == (249.9, 0.118, 27.0, 0.518, 0.392, 0.996)


def test_interrupted_before_any_batch_leaves_no_folder(hip_sweep, tmp_path):
    tmp, _ = hip_sweep
    out = tmp_path / "new" / "out"
    (tmp_path / "new").mkdir()
    with pytest.raises(KeyboardInterrupt):
        run_sweep(_interrupting(sweep_adapter("hip"), 0), tmp / "space.toml", out, workers=0, plots=False)
    assert not out.exists()


def test_base_parameters_from_the_space_file_and_from_params(tmp_path):
    base = sweep_adapter("hip").base_description(None)
    base["geometry"]["screw_lead_m"] = 0.02
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "base.toml").write_text(dumps_toml(base), encoding="utf-8")
    text = HIP_SPACE.replace("[sampling]", 'params = "sub/base.toml"\n\n[sampling]', 1)
    space = _write(tmp_path, text)
    run_sweep(sweep_adapter("hip"), space, tmp_path / "a", workers=0, plots=False)
    best = tomllib.loads((tmp_path / "a" / "best_params.toml").read_text(encoding="utf-8"))
    assert best["geometry"]["screw_lead_m"] == 0.02  # relative to the space file, unswept keys kept
    # --params overrides the space file's params; a rerun into the same folder with another base is refused
    plain = _write(tmp_path, HIP_SPACE, "plain.toml")
    run_sweep(sweep_adapter("hip"), plain, tmp_path / "b", workers=0, plots=False,
              params=tmp_path / "sub" / "base.toml")
    assert tomllib.loads((tmp_path / "b" / "best_params.toml").read_text(encoding="utf-8"))["geometry"]["screw_lead_m"] == 0.02
    with pytest.raises(Exception, match="different base description"):
        run_sweep(sweep_adapter("hip"), plain, tmp_path / "b", workers=0, plots=False)


# ----------------------------------------------------------------------------- the output rule
def test_a_symlinked_out_is_refused_and_nothing_written_through_it(hip_sweep, tmp_path, capsys):
    tmp, _ = hip_sweep
    target = tmp_path / "elsewhere"
    target.mkdir()
    link = tmp_path / "link"
    link.symlink_to(target, target_is_directory=True)
    code = main(["sweep", "--machine", "hip", "--space", str(tmp / "space.toml"), "--workers", "0",
                 "--out", str(link)])
    err = capsys.readouterr().err
    assert code == 2 and "symbolic link" in err and err.count("\n") == 1
    assert list(target.iterdir()) == []


def test_the_space_file_inside_out_is_refused(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    space = _write(out, HIP_SPACE)
    code = main(["sweep", "--machine", "hip", "--space", str(space), "--workers", "0", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and "an input of this run" in err
    assert sorted(p.name for p in out.iterdir()) == ["space.toml"]


def _copy_sweep(src: Path, dst: Path) -> None:
    import shutil

    shutil.copytree(src, dst, copy_function=shutil.copy2)  # keeps the modification times


def test_a_foreign_file_where_the_sweep_writes_is_never_replaced(hip_sweep, tmp_path, capsys):
    """A best_params.toml (or a plot) that this sweep did not write, or that changed since: a
    rerun refuses with one line and leaves it as it is."""
    tmp, _ = hip_sweep
    out = tmp_path / "out"
    _copy_sweep(tmp / "out", out)
    mine = out / "best_params.toml"
    mine.write_text("# my own notes\n")
    code = main(["sweep", "--machine", "hip", "--space", str(tmp / "space.toml"), "--workers", "0",
                 "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and "best_params.toml was not written by this sweep" in err and err.count("\n") == 1
    assert mine.read_text() == "# my own notes\n"


def test_a_sweep_without_feasible_design_never_deletes_a_best_design_it_did_not_write(tmp_path, capsys):
    """No design feasible: no best_params.toml. One the user put there afterwards is not this
    sweep's, and a rerun refuses to replace (or delete) it."""
    space = _write(tmp_path, HIP_SPACE.replace("designs = 32", "designs = 8").replace(
        "max_spherical_angle_deg = { max = 29.0 }", "max_spherical_angle_deg = { max = 0.001 }"))
    out = tmp_path / "out"
    report = run_sweep(sweep_adapter("hip"), space, out, workers=0, plots=False, progress=False)
    assert report.best_design_id is None and not (out / "best_params.toml").exists()
    mine = out / "best_params.toml"
    mine.write_text("# the design I chose by hand\n")
    code = main(["sweep", "--machine", "hip", "--space", str(space), "--workers", "0", "--no-plots", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and "best_params.toml was not written by this sweep" in err
    assert mine.read_text() == "# the design I chose by hand\n"


def test_two_runs_into_one_folder_with_other_batch_sizes_resume_to_one_row_per_design(hip_sweep, tmp_path):
    """Two runs at once with other batch sizes may both evaluate a design (other part files);
    the rows agree, and the folder resumes to the same results with each design once."""
    tmp, _ = hip_sweep
    out = tmp_path / "out"
    _copy_sweep(tmp / "out", out)
    parts = sorted((out / "parts").glob("part-*.parquet"))
    both = pa.concat_tables([pq.read_table(p) for p in parts[:2]])
    pq.write_table(both.slice(3, 8), out / "parts" / "part-000000003.parquet")  # designs 3..10 again
    run_sweep(sweep_adapter("hip"), tmp / "space.toml", out, workers=0, plots=False, progress=False)
    ids = pq.read_table(out / "designs.parquet").column("design_id").to_numpy()
    assert ids.tolist() == list(range(32))
    assert pq.read_table(out / "designs.parquet").equals(pq.read_table(tmp / "out" / "designs.parquet"))


@pytest.mark.parametrize("address, pattern", [("http://head:8786", "unknown scheme 'http'"),
                                              ("head", "expected [scheme://]host:port"),
                                              ("tcp://head", "expected [scheme://]host:port"),
                                              ("tcp://head:99999", "port 99999")])
def test_a_malformed_scheduler_address_is_one_line(hip_sweep, tmp_path, capsys, address, pattern):
    tmp, _ = hip_sweep
    code = main(["sweep", "--machine", "hip", "--space", str(tmp / "space.toml"), "--scheduler", address,
                 "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 2 and pattern in err and err.count("\n") == 1
    assert not (tmp_path / "o").exists()
