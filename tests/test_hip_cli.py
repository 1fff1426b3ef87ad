"""The hip command line end to end: files, columns, agreement, exit status and one-line errors."""

import csv
import json
import subprocess
import sys

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from hip_helpers import SmoothMotion
from pkmdyn.cli import main
from pkmdyn.machines.hip_simulator.params import DEFAULT_PARAMS_TEXT, load_params

SPEC_COLUMNS = (
    ["t_s"]
    + [f"{q}{j}{i}_{u}" for j in (1, 2) for i in (1, 2, 3) for q, u in (("L", "m"), ("Ld", "m_s"), ("Ldd", "m_s2"))]
    + ["detJa", "detJb_m3"]
    + [f"tau{i}_{p}Nm" for i in (1, 2, 3) for p in ("", "platform_", "lever_", "slider_", "screw_", "friction_")]
)


def _read(path):
    with open(path) as fh:
        rows = list(csv.reader(fh))
    return rows[0], np.array(rows[1:], dtype=float)


def test_run_default_writes_everything(tmp_path, capsys):
    out = tmp_path / "res"
    assert main(["hip", "run", "--out", str(out), "--samples-per-cycle", "200"]) == 0
    header, data = _read(out / "results.csv")
    assert header[: len(SPEC_COLUMNS)] == SPEC_COLUMNS
    assert data.shape == (201, len(header)) and np.all(np.isfinite(data))
    summary = json.loads((out / "summary.json").read_text())
    col = header.index("L12_m")
    assert summary["sliders"]["S12"]["max_position_m"] == pytest.approx(data[:, col].max())
    col = header.index("Ldd23_m_s2")
    assert summary["sliders"]["S23"]["max_abs_acceleration_m_s2"] == pytest.approx(np.abs(data[:, col]).max())
    for name in ("motion_load", "slider_motion", "torque_parts", "torques", "friction_vs_load"):
        assert (out / f"{name}.png").stat().st_size > 10_000
    # the file's torques and their parts are the engine's on the same motion, computed here from
    # the description through the engine's public functions (the engine's torques are checked
    # against the closed form of Eq. 7-16 and Pinocchio in the oracle tests)
    from pkmdyn.machines.hip_simulator.description import hip_description
    from pkmdyn.multibody import load_mechanism, solve_kinematics
    from pkmdyn.multibody.dynamics.actuators import motor_efforts
    from pkmdyn.multibody.dynamics.newton_euler import joint_reactions
    from pkmdyn.profiles.iso14242 import iso14242_motion

    motion = iso14242_motion(cycles=1, samples_per_cycle=200)
    m = load_mechanism(hip_description(load_params()))
    kin = solve_kinematics(m, motion.angles, motion.rates, motion.accels, motion.t)
    r = joint_reactions(m, kin, named={"hydraulic_N": motion.load}, split=True)
    tau = motor_efforts(m, kin.act_q, kin.act_qd, kin.act_qdd, r.u).effort
    np.testing.assert_array_equal(data[:, header.index("t_s")], motion.t)
    scale = np.abs(tau).max()
    for i in (1, 2, 3):
        a = m.actuator_names.index(f"P_{i}")
        np.testing.assert_allclose(data[:, header.index(f"tau{i}_Nm")], tau[:, a], rtol=0, atol=1e-12 * scale)
        parts = sum(data[:, header.index(f"tau{i}_{p}_Nm")] for p in ("platform", "lever", "slider", "screw", "friction"))
        np.testing.assert_allclose(parts, tau[:, a], rtol=0, atol=1e-12 * scale)
        np.testing.assert_allclose(data[:, header.index(f"L2{i}_m")], kin.act_q[:, a], rtol=0, atol=1e-15)


def _write_params(path, rng):
    text = DEFAULT_PARAMS_TEXT
    for key, value in (("lever_length_m = 0.328", f"lever_length_m = {0.328 * rng.uniform(0.95, 1.1):.6f}"),
                       ("platform_radius_m = 0.144", f"platform_radius_m = {0.144 * rng.uniform(0.9, 1.1):.6f}"),
                       ("base_radius_m = 0.265", f"base_radius_m = {0.265 * rng.uniform(0.95, 1.05):.6f}")):
        text = text.replace(key, value)
    path.write_text(text)


@pytest.mark.parametrize("seed", range(3))
def test_results_agree_with_an_independent_computation(tmp_path, seed):
    """Positions by brute geometry, velocities and accelerations by finite differences of it."""
    rng = np.random.default_rng(500 + seed)
    params = tmp_path / "p.toml"
    _write_params(params, rng)
    sm = SmoothMotion(rng, amplitude_deg=12)
    t = np.linspace(0, 1.5, 31)
    q, qd, qdd = sm.angles(t)
    motion = tmp_path / "m.csv"
    names = ["t_s", "alpha_deg", "beta_deg", "gamma_deg", "alpha_dot_deg_s", "beta_dot_deg_s", "gamma_dot_deg_s",
             "alpha_ddot_deg_s2", "beta_ddot_deg_s2", "gamma_ddot_deg_s2", "load_N"]
    table = np.column_stack([t, np.rad2deg(q), np.rad2deg(qd), np.rad2deg(qdd), sm.load(t)])
    np.savetxt(motion, table, delimiter=",", header=",".join(names), comments="", fmt="%.17g")
    out = tmp_path / "out"
    assert main(["hip", "run", "--params", str(params), "--motion", str(motion), "--no-plots", "--out", str(out)]) == 0
    header, data = _read(out / "results.csv")
    g = load_params(params).geometry

    def slider_heights(tt):
        qq = sm.angles(tt)[0]
        R = Rotation.from_euler("XYZ", qq).as_matrix()
        res = np.empty((len(tt), 2, 3))
        for j in range(2):
            a = g.o[j] + np.einsum("nab,ib->nia", R, g.r_a)
            horiz = np.linalg.norm(a[..., :2] - g.A[:, :2], axis=-1)
            res[:, j] = a[..., 2] - np.sqrt(g.l**2 - horiz**2)
        return res

    h = 1e-4
    L = slider_heights(t)
    Ld = (slider_heights(t + h) - slider_heights(t - h)) / (2 * h)
    Ldd = (slider_heights(t + h) - 2 * L + slider_heights(t - h)) / h**2
    for j in range(2):
        for i in range(3):
            np.testing.assert_allclose(data[:, header.index(f"L{j + 1}{i + 1}_m")], L[:, j, i], rtol=1e-9)
            np.testing.assert_allclose(data[:, header.index(f"Ld{j + 1}{i + 1}_m_s")], Ld[:, j, i], rtol=1e-6, atol=1e-6 * np.abs(Ld).max())
            np.testing.assert_allclose(data[:, header.index(f"Ldd{j + 1}{i + 1}_m_s2")], Ldd[:, j, i], rtol=1e-5, atol=1e-5 * np.abs(Ldd).max())


def _cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "pkmdyn.cli", *args], capture_output=True, text=True, cwd=cwd)


def test_unreachable_motion_exits_2_with_one_line(tmp_path):
    motion = tmp_path / "m.csv"
    motion.write_text("t_s,alpha_deg,beta_deg,gamma_deg\n" + "".join(f"{k / 10},0,0,{k * 12}\n" for k in range(10)))
    r = _cli("hip", "run", "--motion", str(motion), "--out", str(tmp_path / "o"), cwd=tmp_path)
    assert r.returncode == 2 and "max_abs_angle_deg = 45" in r.stderr  # refused by the angle limit first
    r = _cli("hip", "run", "--motion", str(motion), "--limit", "max_abs_angle_deg=180", "--out", str(tmp_path / "o"),
             cwd=tmp_path)
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    # the row at t = 0.7 s is the file's eighth: samples are counted from 1, as rows are
    assert len(lines) == 1 and "unreachable" in lines[0] and "sample 8 (t = 0.7 s)" in lines[0]
    assert "Traceback" not in r.stderr
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(
    "edit, word",
    [
        (lambda s: s.replace("lever_mass_kg = 1.43", "lever_mass_kg = -1.43"), "lever_mass_kg"),
        (lambda s: s.replace("[inertia]", "[inertia]\nbogus_key = 1"), "bogus_key"),
        (lambda s: s.replace("screw_lead_m = 0.010", "screw_lead_m = "), "TOML"),
    ],
)
def test_malformed_params_exit_2_with_one_line(tmp_path, edit, word):
    p = tmp_path / "p.toml"
    p.write_text(edit(DEFAULT_PARAMS_TEXT))
    r = _cli("hip", "run", "--params", str(p), "--out", str(tmp_path / "o"), cwd=tmp_path)
    assert r.returncode == 2
    assert len(r.stderr.strip().splitlines()) == 1 and word in r.stderr


def test_bad_option_exits_2_with_one_line(tmp_path):
    for args in (["hip", "run", "--out", "o", "--cycles", "0"], ["hip", "run"], ["hip", "run", "--out", "o", "--frobnicate"]):
        r = _cli(*args, cwd=tmp_path)
        assert r.returncode == 2, args
        assert len(r.stderr.strip().splitlines()) == 1, r.stderr


def test_out_path_that_is_a_file_is_one_line_and_status_2(tmp_path, capsys):
    (tmp_path / "o").write_text("not a folder")
    assert main(["hip", "run", "--no-plots", "--samples-per-cycle", "20", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "is a file" in err


def test_profile_command_writes_a_readable_motion(tmp_path):
    p = tmp_path / "motion.csv"
    assert main(["hip", "profile", "--samples-per-cycle", "100", "--out", str(p)]) == 0
    out = tmp_path / "o"
    assert main(["hip", "run", "--motion", str(p), "--no-plots", "--out", str(out)]) == 0
    header, data = _read(out / "results.csv")
    assert data.shape[0] == 101 and not list(out.glob("*.png"))


def test_streamed_run_equals_the_in_memory_path(tmp_path):
    """run_hip in blocks of 7 samples (file + summary) against one solve of the whole motion."""
    from pkmdyn.machines.hip_simulator.job import run_hip
    from pkmdyn.machines.hip_simulator.paper import RESULTS_COLUMNS, PaperView, SummaryAccumulator, block_columns
    from pkmdyn.profiles.iso14242 import iso14242_motion

    files = run_hip(tmp_path / "o", cycles=1.5, samples_per_cycle=40, make_plots=False, chunk=7).files
    header, data = _read(files["results"])
    motion = iso14242_motion(1.5, 40)
    whole = PaperView(load_params()).solve(motion)
    cols = block_columns(motion.t, whole)
    assert header == list(cols) == list(RESULTS_COLUMNS)
    tau_scale = np.abs(cols["tau1_Nm"]).max()
    for k, name in enumerate(header):  # blocks warm-started from the block before: the same solution
        scale = max(np.abs(cols[name]).max(), tau_scale if name.startswith("tau") else 0.0)
        assert np.abs(data[:, k] - cols[name]).max() <= 1e-12 * scale, name
    written = json.loads(files["summary"].read_text())
    col = {name: data[:, k] for k, name in enumerate(header)}  # extremes by brute force over the file
    for j in (1, 2):
        for i in (1, 2, 3):
            s = written["sliders"][f"S{j}{i}"]
            assert s["max_position_m"] == col[f"L{j}{i}_m"].max() and s["min_position_m"] == col[f"L{j}{i}_m"].min()
            assert s["max_abs_velocity_m_s"] == np.abs(col[f"Ld{j}{i}_m_s"]).max()
            assert s["max_abs_acceleration_m_s2"] == np.abs(col[f"Ldd{j}{i}_m_s2"]).max()
    for i in (1, 2, 3):
        assert written["motors"][f"motor{i}"]["max_abs_tau_Nm"] == np.abs(col[f"tau{i}_Nm"]).max()
        assert written["motors"][f"motor{i}"]["max_abs_tau_lever_Nm"] == np.abs(col[f"tau{i}_lever_Nm"]).max()
    assert written["max_condJ"] == col["condJ"].max() and written["min_abs_detJb_m3"] == np.abs(col["detJb_m3"]).min()
    assert written["samples"] == data.shape[0] == 61 and written["duration_s"] == 1.5
    acc = SummaryAccumulator()
    acc.add(motion.t, whole)
    assert acc.result()["max_abs_power_W"] == pytest.approx(written["max_abs_power_W"], rel=1e-12)


def test_parquet_and_csv_hold_the_same_numbers(tmp_path):
    import pyarrow.parquet as pq

    assert main(["hip", "run", "--no-plots", "--samples-per-cycle", "30", "--out", str(tmp_path / "c")]) == 0
    assert main(["hip", "run", "--no-plots", "--samples-per-cycle", "30", "--format", "parquet",
                 "--out", str(tmp_path / "p")]) == 0
    header, data = _read(tmp_path / "c" / "results.csv")
    table = pq.read_table(tmp_path / "p" / "results.parquet")
    assert table.column_names == header
    np.testing.assert_array_equal(np.column_stack([table.column(k).to_numpy() for k in header]), data)


def test_plot_envelope_is_the_min_and_max_of_each_bin():
    from pkmdyn.machines.hip_simulator import figures as hrun
    from pkmdyn.report import PLOT_BINS

    rng = np.random.default_rng(8)
    n = 12_345
    x = rng.standard_normal((n, 3))
    col = hrun.PlotCollector(n)
    assert col.envelope
    s = 0
    while s < n:
        k = int(rng.integers(1, 3000))
        sl = slice(s, s + k)
        col.add(s, {"t": np.arange(n, dtype=float)[sl], "tau": x[sl]}, np.zeros(min(k, n - s)), x[sl])
        s += k
    bins = np.arange(n) * PLOT_BINS // n
    data = col.data("")
    for b in (0, 17, PLOT_BINS - 1):
        np.testing.assert_array_equal(data.lo["tau"][b], x[bins == b].min(axis=0))
        np.testing.assert_array_equal(data.hi["tau"][b], x[bins == b].max(axis=0))
        np.testing.assert_allclose(data.t[b], np.arange(n)[bins == b].mean(), rtol=1e-12)
    assert data.t.shape == (PLOT_BINS,) and len(data.scatter_load) <= hrun.SCATTER_MAX
    assert "envelope (min-max) of 12345 samples in 1000 bins" in data.note


def test_multi_cycle_plots_show_the_first_cycle(tmp_path):
    out = tmp_path / "o"
    assert main(["hip", "run", "--cycles", "4", "--samples-per-cycle", "50", "--out", str(out)]) == 0
    from pkmdyn.machines.hip_simulator.figures import PlotCollector

    col = PlotCollector(51)
    assert not col.envelope
    assert (out / "torques.png").stat().st_size > 10_000


def test_limits_from_the_parameter_file_and_the_command_line(tmp_path, capsys):
    p = tmp_path / "p.toml"
    p.write_text(DEFAULT_PARAMS_TEXT + "\n[limits]\nmax_load_N = 1000.0\n")
    assert main(["hip", "run", "--params", str(p), "--no-plots", "--samples-per-cycle", "20", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "3000 N exceeds the limit max_load_N = 1000 N" in err and not (tmp_path / "o").exists()
    assert main(["hip", "run", "--params", str(p), "--limit", "max_load_N=5000", "--no-plots", "--samples-per-cycle",
                 "20", "--out", str(tmp_path / "o")]) == 0
    assert json.loads((tmp_path / "o" / "summary.json").read_text())["limits"]["max_load_N"] == 5000
    for bad in ("max_load_N=inf", "max_load_N=-1", "colour=3", "max_samples=1.5", "max_load_N"):
        assert main(["hip", "run", "--limit", bad, "--no-plots", "--out", str(tmp_path / "x")]) == 2
    assert main(["hip", "run", "--limit", "max_samples=100", "--no-plots", "--out", str(tmp_path / "x")]) == 2
    assert "exceeds the limit max_samples = 100" in capsys.readouterr().err and not (tmp_path / "x").exists()


def test_fast_motion_is_refused_by_the_slider_speed_limit(tmp_path, capsys):
    """The ISO cycle squeezed into 1 ms: the slider speed limit names the sample and the slider."""
    from pkmdyn.profiles.iso14242 import iso14242_motion
    from pkmdyn.profiles.orientation import make_motion, write_motion_csv

    m = iso14242_motion(1, 100)
    k = 1e3
    fast = make_motion(m.t / k, m.angles, m.rates * k, m.accels * k * k, m.load)
    write_motion_csv(tmp_path / "m.csv", fast)
    assert main(["hip", "run", "--motion", str(tmp_path / "m.csv"), "--no-plots", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "exceeds the limit max_slider_speed_m_s = 2 m/s" in err and "slider" in err
    assert not (tmp_path / "o").exists() and not [p for p in tmp_path.iterdir() if ".partial" in p.name]


def test_profile_help_documents_every_option():
    from click.testing import CliRunner

    from pkmdyn.cli import cli

    for cmd in ("profile", "run"):
        command = cli.commands["hip"].commands[cmd]
        for param in command.params:
            assert getattr(param, "help", None), (cmd, param.name)
        text = CliRunner().invoke(cli, ["hip", cmd, "--help"]).output
        assert "--samples-per-cycle" in text and "--out" in text


def test_profile_into_a_missing_folder_creates_it_and_says_so(tmp_path, capsys):
    out = tmp_path / "new" / "m.csv"
    assert main(["hip", "profile", "--samples-per-cycle", "10", "--out", str(out)]) == 0
    assert "created folder" in capsys.readouterr().err
    assert out.read_text().startswith("t_s,alpha_deg") and [p.name for p in out.parent.iterdir()] == ["m.csv"]


@pytest.mark.parametrize("args, word", [
    (["--cycles", "inf"], "finite"), (["--cycles", "nan"], "finite"), (["--cycles", "0.0001"], "fewer than 2 samples"),
    (["--cycles", "1e9"], "max_samples"), (["--samples-per-cycle", "99999999999999999999"], "max_samples"),
    (["--singularity-threshold", "nan"], "finite"), (["--singularity-threshold", "2"], "not in"),
])
def test_sizes_and_numbers_of_options_are_checked(tmp_path, capsys, args, word):
    assert main(["hip", "run", *args, "--no-plots", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and word in err and not list(tmp_path.iterdir())


def test_library_entry_checks_name_the_expected_shape():
    from pkmdyn.errors import MotionError
    from pkmdyn.profiles.orientation import make_motion

    n = 5
    t = np.linspace(0, 1, n)
    z = np.zeros((n, 3))
    with pytest.raises(MotionError, match=r"angles: expected shape \(5, 3\), got \(3, 5\)"):
        make_motion(t, z.T, z, z)
    with pytest.raises(MotionError, match=r"rates: expected shape \(5, 3\), got \(15,\)"):
        make_motion(t, z, z.ravel(), z)
    with pytest.raises(MotionError, match="expected a float array"):
        make_motion(t, "angles", z, z)


@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM"])
def test_interrupting_a_run_leaves_nothing(tmp_path, sig):
    """Ctrl-C (or SIGTERM) while results are being written: one line, and no trace of the run."""
    import signal
    import time

    out = tmp_path / "o"
    proc = subprocess.Popen([sys.executable, "-m", "pkmdyn.cli", "hip", "run", "--no-plots", "--cycles", "2000",
                             "--out", str(out)], cwd=tmp_path, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not any(tmp_path.glob(".o.partial-*/results.csv")):
        time.sleep(0.05)
    assert any(tmp_path.glob(".o.partial-*/results.csv")), "the run never started writing"
    proc.send_signal(getattr(signal, sig))
    _, err = proc.communicate(timeout=60)
    lines = err.strip().splitlines()
    assert lines[0].startswith("pkmdyn: note: the results table will hold 2,000,001 rows"), err  # 1.6 GB: said first
    assert proc.returncode == 130 and lines[1:] == [
        "pkmdyn: interrupted; --out holds either the whole new run or what it held before"], err
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_motion_model_paper_fit_is_the_fitted_cycle(tmp_path, capsys):
    """``--motion-model paper-fit`` runs the fitted ISO cycle: the run's slider maxima are those of
    the preset computed by the library, and differ from the default cycle's."""
    from pkmdyn.machines.hip_simulator.paper import iso_cycle_preset, slider_maxima

    out = tmp_path / "fit"
    assert main(["hip", "run", "--motion-model", "paper-fit", "--samples-per-cycle", "400", "--no-plots",
                 "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert "paper-fit" in s["motion"]
    got = np.array([s["sliders"][f"S1{i}"]["max_position_m"] for i in (1, 2, 3)])
    model = load_params()
    expected = slider_maxima(model, iso_cycle_preset("paper-fit"), samples=400)[:3]
    default = slider_maxima(model, iso_cycle_preset("default"), samples=400)[:3]
    np.testing.assert_allclose(got, expected, rtol=1e-12)
    assert np.abs(expected - default).max() > 1e-4
    capsys.readouterr()
    motion = tmp_path / "m.csv"
    assert main(["hip", "profile", "--cycles", "0.01", "--out", str(motion)]) == 0
    capsys.readouterr()
    assert main(["hip", "run", "--motion", str(motion), "--motion-model", "paper-fit", "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--motion-model" in err[0]
    assert not (tmp_path / "x").exists()


def test_a_run_shorter_than_a_cycle_tracks_a_whole_cycle(tmp_path):
    """wear.json is one cycle's wear whatever the run's length: a quarter cycle's run gives the
    tracks and wear of the whole cycle, as a run of one cycle does."""
    for name, cycles in (("quarter", "0.25"), ("one", "1")):
        assert main(["hip", "run", "--cycles", cycles, "--samples-per-cycle", "100", "--no-plots",
                     "--out", str(tmp_path / name)]) == 0
    q, o = (_read(tmp_path / n / "markers_S0_upper_on_cup.csv") for n in ("quarter", "one"))
    assert q[0] == o[0]
    np.testing.assert_allclose(q[1], o[1], rtol=1e-12, atol=1e-15)
    wear = q[0].index("wear_mm3_per_million_cycles")
    assert np.all(q[1][:, wear] > 0)


def test_hip_control_says_a_friction_regularisation_it_does_not_use(tmp_path, capsys):
    """A parameter file whose friction_velocity_eps_* differ from the engine's: hip control says
    once (the controller's file, and the plant made of it) that they are not used, as hip run and
    hip identify say it; the built-in file says nothing."""
    params = tmp_path / "p.toml"
    params.write_text(DEFAULT_PARAMS_TEXT.replace("friction_velocity_eps_rad_s = 1e-3",
                                                  "friction_velocity_eps_rad_s = 0.002"))
    assert "0.002" in params.read_text()
    assert main(["hip", "control", "--controller", "pd", "--params", str(params), "--cycles", "0.01", "--no-plots",
                 "--out", str(tmp_path / "c")]) == 0
    said = [ln for ln in capsys.readouterr().err.splitlines() if "friction_velocity_eps_rad_s = 0.002" in ln]
    assert len(said) == 1 and "not used" in said[0]
    assert main(["hip", "control", "--controller", "pd", "--cycles", "0.01", "--no-plots",
                 "--out", str(tmp_path / "d")]) == 0
    assert "friction_velocity_eps" not in capsys.readouterr().err
