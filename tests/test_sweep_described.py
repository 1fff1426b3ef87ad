"""Design sweeps of described mechanisms (``pkmdyn sweep --machine NAME|FILE.toml``): a
design's metrics are those its own ``pkmdyn run`` writes (efforts, rates and reactions), its
friction energy is the work of the actuators over a closed cycle (power balance), bad designs
are rows with their status, an over-constrained mechanism without compliance data is refused
before any work unless its reactions are off, and Dask gives the serial rows."""

from __future__ import annotations

import copy
import json
import tomllib

import multibody_examples as ex
import numpy as np
import pytest

from pkmdyn.cli import main
from pkmdyn.io import dumps_toml
from pkmdyn.jobs.sweep import run_sweep
from pkmdyn.machines.registry import sweep_adapter

pq = pytest.importorskip("pyarrow.parquet")


def _stewart_with_friction():
    """The built-in Stewart platform with friction in every leg joint: load-dependent in the
    universal and spherical joints, Coulomb and viscous in the prismatic actuators."""
    d = ex.builtin_dict("stewart")
    for leg in d["legs"]:
        for j in leg["joints"]:
            j["friction"] = {"universal": {"coefficient": 0.08, "pin_radius_m": 0.012},
                             "prismatic": {"coulomb_force_N": 4.0, "viscous_N_s_m": 30.0},
                             "spherical": {"coefficient": 0.06, "ball_radius_m": 0.015}}[j["type"]]
    return d


SPACE = """
[sampling]
method = "random"
designs = 3
seed = 5

[motion]
singularity_threshold = 1e-4

[parameters]
"bodies[platform].mass_kg" = { min = 5.0, max = 25.0 }
"legs[0].joints[P].friction.viscous_N_s_m" = { min = 10.0, max = 80.0 }
"default_motion.amplitude.z_m" = { min = 0.02, max = 0.08 }

[objectives]
peak_effort_N = "min"
"""


def _trapz(y, t):
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(t)))


def test_a_designs_metrics_are_those_of_its_own_run(tmp_path):
    machine = tmp_path / "stewart_friction.toml"
    machine.write_text(dumps_toml(_stewart_with_friction()), encoding="utf-8")
    space = tmp_path / "space.toml"
    space.write_text(SPACE, encoding="utf-8")
    report = run_sweep(sweep_adapter(str(machine)), space, tmp_path / "out", workers=0, plots=False)
    rows = pq.read_table(tmp_path / "out" / "designs.parquet").to_pylist()
    assert [r["status"] for r in rows] == ["ok"] * 3
    best = next(r for r in rows if r["design_id"] == report.best_design_id)
    design = tmp_path / "out" / "best_params.toml"
    d = tomllib.loads(design.read_text(encoding="utf-8"))
    assert d["bodies"][0]["name"] == "platform" and d["legs"][0]["joints"][1]["name"] == "P"
    assert d["bodies"][0]["mass_kg"] == best["bodies[platform].mass_kg"]  # the swept values went into the design
    assert d["default_motion"]["amplitude"]["z_m"] == best["default_motion.amplitude.z_m"]
    assert main(["run", "--machine", str(design), "--out", str(tmp_path / "run")]) == 0
    cols = np.genfromtxt(tmp_path / "run" / "results.csv", delimiter=",", names=True)
    npz = np.load(tmp_path / "run" / "bodies.npz")
    t = cols["t_s"]
    acts = [n[: -len("_effort_N")] for n in cols.dtype.names if n.endswith("_effort_N")]
    assert len(acts) == 6
    power = np.zeros_like(t)
    for a in acts:
        u, sd = cols[f"{a}_effort_N"], cols[f"{a}_vel_m_s"]
        power += u * sd
        T = t[-1] - t[0]
        np.testing.assert_allclose(best[f"peak_effort_{a}_N"], np.abs(u).max(), rtol=1e-9)
        np.testing.assert_allclose(best[f"rms_effort_{a}_N"], np.sqrt(_trapz(u * u, t) / T), rtol=1e-9)
        np.testing.assert_allclose(best[f"peak_speed_{a}_m_s"], np.abs(sd).max(), rtol=1e-9)
    np.testing.assert_allclose(best["peak_power_W"], power.max(), rtol=1e-9)
    names = [str(n) for n in npz["joint_names"]]
    force = np.linalg.norm(npz["joint_force"], axis=-1).max(axis=0)
    moment = np.linalg.norm(npz["joint_moment"], axis=-1).max(axis=0)
    for j, name in enumerate(names):
        np.testing.assert_allclose(best[f"peak_force_{name}_N"], force[j], rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(best[f"peak_moment_{name}_Nm"], moment[j], rtol=1e-9, atol=1e-9)
    # power balance over the closed cycle of the default motion: the actuators' work is what
    # the friction dissipates (the mechanical energy returns to its start)
    work = _trapz(power, t)
    assert best["friction_energy_per_cycle_J"] > 0.5
    np.testing.assert_allclose(best["friction_energy_per_cycle_J"], work, rtol=1e-6)
    assert d["legs"][0]["joints"][1]["friction"]["viscous_N_s_m"] == best["legs[0].joints[P].friction.viscous_N_s_m"]
    assert json.loads((tmp_path / "out" / "summary.json").read_text())["machine"] == "stewart"


def test_bad_designs_are_rows_with_their_status(tmp_path, capsys):
    space = tmp_path / "space.toml"
    space.write_text("""
[sampling]
method = "grid"

[parameters]
"default_motion.amplitude.z_m" = { values = [0.05, 3.0] }
"bodies[0].mass_kg" = { values = [1.0, -1.0] }

[objectives]
peak_effort_Nm = "min"
""", encoding="utf-8")
    assert main(["sweep", "--machine", "delta", "--space", str(space), "--workers", "0", "--no-plots",
                 "--out", str(tmp_path / "out")]) == 0
    rows = sorted(pq.read_table(tmp_path / "out" / "designs.parquet").to_pylist(), key=lambda r: r["design_id"])
    assert [r["status"] for r in rows] == ["ok", "invalid", "unreachable", "invalid"]
    assert "mass_kg" in rows[1]["reason"] and "does not close" in rows[2]["reason"]
    assert rows[0]["peak_effort_Nm"] > 0 and rows[2]["peak_effort_Nm"] is None


def _sweep_of(tmp_path, d, space_text):
    """Sweep the description ``d`` (written as a file) over the space ``space_text`` in this
    process; the rows by design id."""
    base = tmp_path / "base.toml"
    base.write_text(dumps_toml(d), encoding="utf-8")
    space = tmp_path / "space.toml"
    space.write_text(space_text, encoding="utf-8")
    assert main(["sweep", "--machine", str(base), "--space", str(space), "--workers", "0", "--no-plots",
                 "--out", str(tmp_path / "out")]) == 0
    return sorted(pq.read_table(tmp_path / "out" / "designs.parquet").to_pylist(), key=lambda r: r["design_id"])


def test_a_bounded_parameter_is_swept_and_its_best_design_file_loads(tmp_path, capsys):
    """A parameter given as ``{ value, min, max }`` is swept, by its bare name, through its
    value: a design outside its bounds is a row with the description's reason, and the best
    design's file (its bounded parameter written back as a sub-table, after the parameters that
    use it) loads with the swept value."""
    from pkmdyn.multibody import load_mechanism

    d = ex.builtin_dict("stewart", parametric=True)
    d["parameters"]["height_m"] = {"value": 1.0, "min": 0.95, "max": 1.05}
    rows = _sweep_of(tmp_path, d, """
[sampling]
method = "grid"

[parameters]
height_m = { values = [0.9, 1.02, 1.1] }

[objectives]
peak_effort_N = "min"
""")
    assert [r["status"] for r in rows] == ["invalid", "ok", "invalid"]
    assert "height_m: 0.9 is below its min 0.95" in rows[0]["reason"]
    assert "height_m: 1.1 is above its max 1.05" in rows[2]["reason"]
    best = tmp_path / "out" / "best_params.toml"
    m = load_mechanism(best)
    assert m.parameters["height_m"] == pytest.approx(1.02, abs=1e-15)
    top = tomllib.loads(best.read_text(encoding="utf-8"))["parameters"]
    assert top["height_m"] == {"value": 1.02, "min": 0.95, "max": 1.05}


def test_a_number_swept_under_two_keys_is_refused_and_a_whole_parameter_sweeps_as_real(tmp_path, capsys):
    """``height_m`` and ``parameters.height_m`` name one number: refused by name. A parameter
    written as a whole number (``height_m = 1``) is a real number: a range sweeps real values."""
    d = ex.builtin_dict("stewart", parametric=True)
    d["parameters"]["height_m"] = 1
    base = tmp_path / "whole.toml"
    base.write_text(dumps_toml(d), encoding="utf-8")
    space = tmp_path / "twice.toml"
    space.write_text("""[sampling]
method = "random"
designs = 2
[parameters]
height_m = { min = 0.95, max = 1.05 }
"parameters.height_m" = { min = 0.95, max = 1.05 }
[objectives]
peak_effort_N = "min"
""", encoding="utf-8")
    assert main(["sweep", "--machine", str(base), "--space", str(space), "--workers", "0", "--no-plots",
                 "--out", str(tmp_path / "twice")]) == 2
    err = capsys.readouterr().err
    assert "parameters.height_m: the same key as height_m" in err and len(err.strip().splitlines()) == 1
    rows = _sweep_of(tmp_path, d, """[sampling]
method = "random"
designs = 3
seed = 2
[motion]
reactions = false
stiffness = false
[parameters]
height_m = { min = 0.95, max = 1.05 }
[objectives]
peak_effort_N = "min"
""")
    values = [r["height_m"] for r in rows]
    assert all(0.95 <= v <= 1.05 for v in values) and len(set(values)) == 3 and any(v != round(v) for v in values)


def test_limit_metrics_are_those_of_the_designs_run_and_a_too_fast_motion_is_a_limit(tmp_path, capsys):
    """``joint_limit_margin`` and ``peak_effort_over_rated`` of a design are computed again from
    its own ``pkmdyn run`` files (the legs' positions against their limits, the motors' forces
    against their ratings); a design whose motion exceeds a joint speed limit is a ``limit``
    row naming the joint."""
    import csv

    d = ex.builtin_dict("stewart", parametric=True)
    d["actuators"] = [{"joint": f"P_{i}", "max_force_N": 150.0 + 10.0 * i, "moving_mass_kg": 0.4,
                       "coulomb_force_N": 2.0} for i in range(1, 7)]
    d["limits"] = {"max_joint_speed_m_s": 10.0}
    rows = _sweep_of(tmp_path, d, """
[sampling]
method = "grid"

[motion]
reactions = false
stiffness = false

[parameters]
height_m = { values = [0.95, 1.05] }
"limits.max_joint_speed_m_s" = { values = [10.0, 1e-3] }

[objectives]
peak_effort_N = "min"
""")
    slow = [r for r in rows if r["limits.max_joint_speed_m_s"] == 1e-3]
    assert len(slow) == 2 and all(r["status"] == "limit" and "max_joint_speed_m_s" in r["reason"]
                                  and "actuated joint 'P_" in r["reason"] for r in slow)
    lo, hi = d["legs"][0]["joints"][1]["limits_m"]
    for r in (r for r in rows if r["limits.max_joint_speed_m_s"] == 10.0):
        assert r["status"] == "ok"
        dd = copy.deepcopy(d)
        dd["parameters"]["height_m"] = r["height_m"]
        design = tmp_path / f"design_{r['design_id']}.toml"
        design.write_text(dumps_toml(dd), encoding="utf-8")
        out = tmp_path / f"run_{r['design_id']}"
        assert main(["run", "--machine", str(design), "--out", str(out)]) == 0
        with open(out / "results.csv", newline="") as fh:
            table = list(csv.DictReader(fh))
        legs = np.array([[float(row[f"P_{i}_pos_m"]) for i in range(1, 7)] for row in table])
        margin = np.minimum(legs - lo, hi - legs).min() / (hi - lo)
        assert r["joint_limit_margin"] == pytest.approx(margin, rel=1e-9, abs=1e-12)
        force = np.array([[float(row[f"P_{i}_motor_force_N"]) for i in range(1, 7)] for row in table])
        assert r["peak_effort_over_rated"] == pytest.approx(
            (np.abs(force) / (150.0 + 10.0 * np.arange(1, 7))).max(), rel=1e-9)


def test_overconstrained_without_sections_refused_unless_reactions_are_off(tmp_path, capsys):
    d = ex.builtin_dict("bennett")
    for b in d["bodies"]:
        b.pop("section", None)
        b.pop("material", None)
    machine = tmp_path / "bare.toml"
    machine.write_text(dumps_toml(d), encoding="utf-8")
    body = '[parameters]\n"bodies[0].mass_kg" = { min = 0.5, max = 2.0 }\n[objectives]\ngci = "max"\n'
    head = '[sampling]\nmethod = "random"\ndesigns = 2\n'
    space = tmp_path / "space.toml"
    space.write_text(head + body, encoding="utf-8")
    out = tmp_path / "out"
    assert main(["sweep", "--machine", str(machine), "--space", str(space), "--workers", "0", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "reactions = false" in err and "section" in err, err
    assert not out.exists()
    space.write_text(head + "[motion]\nreactions = false\n" + body, encoding="utf-8")
    assert main(["sweep", "--machine", str(machine), "--space", str(space), "--workers", "0", "--no-plots",
                 "--out", str(out)]) == 0
    t = pq.read_table(out / "designs.parquet")
    assert t.column("status").to_pylist() == ["ok", "ok"]
    assert not any(c.startswith("peak_force_") for c in t.column_names)


def test_described_sweep_on_dask_gives_the_serial_rows(tmp_path):
    pytest.importorskip("distributed")
    space = tmp_path / "space.toml"
    space.write_text("""
[sampling]
method = "sobol"
designs = 8
seed = 2
batch_size = 3

[parameters]
"bodies[0].mass_kg" = { min = 5.0, max = 20.0 }
"legs[1].bodies[0].mass_kg" = { min = 1.0, max = 4.0 }

[objectives]
peak_effort_N = "min"
""", encoding="utf-8")
    ad = sweep_adapter("stewart")
    run_sweep(ad, space, tmp_path / "serial", workers=0, plots=False)
    run_sweep(ad, space, tmp_path / "dask", workers=2, plots=False)
    a = pq.read_table(tmp_path / "serial" / "designs.parquet")
    b = pq.read_table(tmp_path / "dask" / "designs.parquet")
    assert a.num_rows == 8 and a.equals(b)


def test_params_of_another_mechanism_are_refused(tmp_path, capsys):
    """--params gives the swept machine other numbers; a description of another mechanism would
    be swept under this machine's name, so it is refused with one line."""
    space = tmp_path / "space.toml"
    space.write_text(SPACE, encoding="utf-8")
    other = tmp_path / "delta.toml"
    other.write_text(dumps_toml(ex.builtin_dict("delta"), "another mechanism"), encoding="utf-8")
    code = main(["sweep", "--machine", "stewart", "--space", str(space), "--params", str(other), "--workers", "0",
                 "--no-plots", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and "'delta' is not 'stewart'" in err and err.count("\n") == 1
    assert not (tmp_path / "out").exists()


def test_an_under_actuated_mechanism_sweeps_without_a_direct_measure(tmp_path):
    """A planar 2R arm with one of its two joints driven (one actuator, two task coordinates):
    the direct singularity measure is not defined, so it is no metric of the sweep, and every
    design is evaluated (a declared metric that a design cannot give makes it nonfinite). Held
    still its motion is dynamically consistent (the free joint needs no torque); a motion that
    swings the free joint is no design's (no torque of the one drive makes it)."""
    d = ex.serial_arm()
    d["joints"][1]["actuated"] = False
    d["default_motion"] = {"period_s": 1.0, "samples": 51, "amplitude": {"x_m": 0.0, "y_m": 0.0}}
    machine = tmp_path / "arm_one_drive.toml"
    machine.write_text(dumps_toml(d))
    space = tmp_path / "space.toml"
    space.write_text('[sampling]\nmethod = "random"\ndesigns = 3\nseed = 2\n[motion]\nreactions = false\n'
                     '[parameters]\n"bodies[l1].mass_kg" = { min = 0.5, max = 2.0 }\n'
                     '[objectives]\npeak_effort_Nm = "min"\n')
    out = tmp_path / "sweep"
    assert main(["sweep", "--machine", str(machine), "--space", str(space), "--workers", "0", "--no-plots",
                 "--out", str(out)]) == 0
    table = pq.read_table(out / "designs.parquet")
    assert "min_direct_measure" not in table.column_names and "min_inverse_measure" in table.column_names
    assert table.column("status").to_pylist() == ["ok"] * 3
    d["default_motion"]["amplitude"] = {"x_m": 0.05, "y_m": 0.05}
    machine.write_text(dumps_toml(d))
    moved = tmp_path / "moved"
    assert main(["sweep", "--machine", str(machine), "--space", str(space), "--workers", "0", "--no-plots",
                 "--out", str(moved)]) == 0
    assert "ok" not in pq.read_table(moved / "designs.parquet").column("status").to_pylist()
