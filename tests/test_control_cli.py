"""``pkmdyn hip control`` and ``pkmdyn pdm control`` end to end: every controller runs on the
default machine and writes its files; bad inputs exit 2 with one line and write nothing."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from pkmdyn.cli import main


def _read(path):
    with open(path) as fh:
        rows = list(csv.reader(fh))
    return rows[0], np.array(rows[1:], dtype=float)


@pytest.mark.parametrize("controller", ["pd", "augmented-pd", "feedforward", "computed-torque"])
def test_hip_controllers_run(tmp_path, controller):
    out = tmp_path / controller
    plots = [] if controller == "augmented-pd" else ["--no-plots"]
    assert main(["hip", "control", "--controller", controller, "--cycles", "0.05", *plots, "--out", str(out)]) == 0
    header, data = _read(out / "control.csv")
    for name in ("t_s", "alpha_ref_deg", "alpha_deg", "alpha_err_deg", "gamma_attitude_deg", "tau3_Nm",
                 "motor2_enc_rad", "motor2_acc_enc_rad_s2", "load_N"):
        assert name in header
    assert data.shape == (50, len(header)) and np.all(np.isfinite(data))
    c = {n: data[:, i] for i, n in enumerate(header)}
    np.testing.assert_allclose(c["alpha_err_deg"], c["alpha_ref_deg"] - c["alpha_deg"], atol=1e-12)
    s = json.loads((out / "summary.json").read_text())
    assert s["controller"] == controller and s["cycles"] == 50
    assert s["coordinates"]["beta"]["max_abs_err_deg"] == pytest.approx(np.abs(c["beta_err_deg"]).max())
    assert s["actuators"]["tau2"]["peak_abs_Nm"] == pytest.approx(np.abs(c["tau2_Nm"]).max())
    assert (out / "posture_errors.png").exists() == (controller == "augmented-pd")


@pytest.mark.parametrize("exact", ["plant-params", "gains"])
def test_hip_feedforward_replay_from_the_command_line(tmp_path, exact):
    """The open-loop replay bound as a user checks it: `pkmdyn hip control --controller
    feedforward` on an exact plant (the model's own parameter file as --plant-params, or a
    gains file with [mismatch] factors 1.0), one ISO cycle at the default settings: every
    posture error within 1e-3 deg, in summary.json and in control.csv."""
    from importlib import resources

    out = tmp_path / "out"
    if exact == "plant-params":
        with resources.as_file(resources.files("pkmdyn.machines.hip_simulator") / "default.toml") as f:
            extra = ["--plant-params", str(f)]
            assert main(["hip", "control", "--controller", "feedforward", *extra, "--no-plots", "--out", str(out)]) == 0
    else:
        g = tmp_path / "g.toml"
        g.write_text("[mismatch]\nmass_factor = 1.0\nfriction_factor = 1.0\n")
        assert main(["hip", "control", "--controller", "feedforward", "--gains", str(g), "--no-plots",
                     "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["cycles"] == 1000 and s["integration_step_s"] == 1e-3 and s["integration_method"] == "rk3-ros2"
    header, data = _read(out / "control.csv")
    for name in ("alpha", "beta", "gamma"):
        assert s["coordinates"][name]["max_abs_err_deg"] < 1e-3
        assert np.abs(data[:, header.index(f"{name}_err_deg")]).max() < 1e-3


@pytest.mark.parametrize("controller", ["pid", "feedforward", "computed-torque"])
def test_pdm_controllers_run(tmp_path, controller):
    out = tmp_path / controller
    plots = [] if controller == "pid" else ["--no-plots"]
    assert main(["pdm", "control", "--controller", controller, "--cycles", "0.05", *plots, "--out", str(out)]) == 0
    header, data = _read(out / "control.csv")
    for name in ("x_ref_mm", "x_mm", "x_err_mm", "gamma_err_deg", "f4_N", "l23_enc_mm", "l23_rate_enc_mm_s",
                 "l23_acc_ref_mm_s2"):
        assert name in header
    assert data.shape[0] == 50 and np.all(np.isfinite(data))
    s = json.loads((out / "summary.json").read_text())
    assert set(s["encoders"]) == {"l11", "l12", "l23", "l24"}
    assert (out / "limb_tracking.png").exists() == (controller == "pid")


def test_pdm_exact_encoders_read_the_plants_limb_lengths(tmp_path):
    """``exact_encoders = 1``: the encoders count the plant's true limb lengths (its inverse
    kinematics, one sample per cycle) and the controller's pose comes from the direct kinematics
    of the reading; the reading is the truth to within one count (5 mm / 10,000 = 0.5 um)."""
    gains = tmp_path / "g.toml"
    gains.write_text("[sensors]\nexact_encoders = 1\n", encoding="utf-8")
    out = tmp_path / "out"
    assert main(["pdm", "control", "--controller", "pid", "--cycles", "0.1", "--gains", str(gains), "--no-plots",
                 "--out", str(out)]) == 0
    header, data = _read(out / "control.csv")
    count_mm = 5.0 / 10_000
    moved = 0.0
    for limb in ("l11", "l12", "l23", "l24"):
        true, enc = data[:, header.index(f"{limb}_mm")], data[:, header.index(f"{limb}_enc_mm")]
        assert np.abs(enc - true).max() <= count_mm * (1 + 1e-9)
        moved = max(moved, np.ptp(true))
    assert moved > 20 * count_mm  # the limbs travel many counts
    # the pose the controller sees, from the direct kinematics of whole counts, is near the true one
    assert np.abs(data[:, header.index("x_sensed_mm")] - data[:, header.index("x_mm")]).max() < 10 * count_mm


def test_hip_exact_encoders_read_the_plants_motor_angles(tmp_path):
    """``exact_encoders = 1`` on the hip: the motors' true angles are those of the plant's own
    slider positions, ``2 pi / p (L(q) - L(q_0))`` by the engine's batched kinematics of the
    hip's description at the recorded angles (another route than the loop's single-sample
    solve), the encoders read them to within one count, and the controller's pose from the
    direct kinematics of the counts is near the true one; the loop tracks as well as with the
    first-order encoders."""
    from pkmdyn.machines.hip_simulator.description import hip_description
    from pkmdyn.machines.hip_simulator.params import load_params
    from pkmdyn.multibody import load_mechanism, solve_kinematics

    gains = tmp_path / "g.toml"
    gains.write_text("[sensors]\nexact_encoders = 1\n", encoding="utf-8")
    runs = {}
    for label, extra in (("exact", ["--gains", str(gains)]), ("first_order", [])):
        out = tmp_path / label
        assert main(["hip", "control", "--controller", "computed-torque", "--cycles", "0.15", *extra, "--no-plots",
                     "--out", str(out)]) == 0
        runs[label] = _read(out / "control.csv")
    header, data = runs["exact"]
    model = load_params()
    q = np.deg2rad(data[:, [header.index(f"{c}_deg") for c in ("alpha", "beta", "gamma")]])
    L = solve_kinematics(load_mechanism(hip_description(model)), q).act_q
    k = 2.0 * np.pi / model.geometry.p
    count = 2.0 * np.pi / 131072
    moved = 0.0
    for i in range(3):
        true, enc = data[:, header.index(f"motor{i + 1}_rad")], data[:, header.index(f"motor{i + 1}_enc_rad")]
        assert np.abs(true - k * (L[:, i] - L[0, i])).max() < 1e-7
        assert np.abs(enc - true).max() <= count * (1 + 1e-9)
        moved = max(moved, np.ptp(true))
    assert moved > 1000 * count
    for c in ("alpha", "beta", "gamma"):
        sensed, true = data[:, header.index(f"{c}_sensed_deg")], data[:, header.index(f"{c}_deg")]
        assert np.abs(sensed - true).max() < 1e-3  # counts of 2 pi / 131072 rad: about 5e-5 deg
    h1, d1 = runs["first_order"]
    for c in ("alpha", "beta", "gamma"):
        e_exact = np.abs(data[:, header.index(f"{c}_err_deg")]).max()
        e_first = np.abs(d1[:, h1.index(f"{c}_err_deg")]).max()
        assert e_exact < 2.0 * e_first + 1e-3


def test_pdm_pid_follows_a_motion_file(tmp_path):
    """A motion file (Hermite-interpolated between its rows) at the PDM's 2 ms cycle: the joint
    reference's rate differences must stay inside the motion's time span (regression: they
    reached 2e-9 s before its start and the run failed)."""
    from pkmdyn.profiles.pdm_motion import cycloidal_motion, write_pdm_motion

    motion = tmp_path / "m.csv"
    write_pdm_motion(motion, cycloidal_motion((0.01, 0.01, 0.05, 0.05), 0.4, 81))
    out = tmp_path / "out"
    assert main(["pdm", "control", "--controller", "pid", "--motion", str(motion), "--no-plots", "--out", str(out)]) == 0
    header, data = _read(out / "control.csv")
    assert data.shape[0] == 200 and np.all(np.isfinite(data))
    assert np.abs(data[:, header.index("x_err_mm")]).max() < 1.0


def _bad(capsys, tmp_path, args):
    out = tmp_path / "out"
    code = main([*args, "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert len(err.splitlines()) == 1 and err.startswith("pkmdyn: error:")
    assert not out.exists() and not list(tmp_path.glob(".out*"))
    return err


def test_unknown_controller(tmp_path, capsys):
    err = _bad(capsys, tmp_path, ["hip", "control", "--controller", "pid", "--cycles", "0.01"])
    assert "pid" in err
    _bad(capsys, tmp_path, ["pdm", "control", "--controller", "pd", "--cycles", "0.01"])


@pytest.mark.parametrize("text, words", [
    ("[pd]\nkp_Nm_rad = [6000.0, -1.0, 6000.0]\n", "kp_Nm_rad[1]"),
    ("[pd]\nkd_Nms_rad = [130.0, inf, 130.0]\n", "kd_Nms_rad[1]"),
    ("[timing]\nintegration_step_s = 0.0003\n", "whole multiple"),
])
def test_bad_gains_file(tmp_path, capsys, text, words):
    g = tmp_path / "g.toml"
    g.write_text(text)
    err = _bad(capsys, tmp_path, ["hip", "control", "--controller", "pd", "--cycles", "0.01", "--gains", str(g)])
    assert words in err


def test_plant_file_of_the_other_machine(tmp_path, capsys):
    from pkmdyn.machines.hip_simulator.params import DEFAULT_PARAMS_TEXT
    from pkmdyn.machines.pdm4.params import default_params_path

    hip_file = tmp_path / "hip.toml"
    hip_file.write_text(DEFAULT_PARAMS_TEXT)
    _bad(capsys, tmp_path, ["pdm", "control", "--controller", "pid", "--cycles", "0.01", "--plant-params", str(hip_file)])
    _bad(capsys, tmp_path, ["hip", "control", "--controller", "pd", "--cycles", "0.01",
                            "--plant-params", str(default_params_path())])


def test_diverging_run(tmp_path, capsys):
    g = tmp_path / "g.toml"
    g.write_text("[pd]\nkp_Nm_rad = [1e8, 1e8, 1e8]\nkd_Nms_rad = [0.0, 0.0, 0.0]\n"
                 "[actuators]\neffort_limit_Nm = [1e6, 1e6, 1e6]\n")
    err = _bad(capsys, tmp_path, ["hip", "control", "--controller", "pd", "--cycles", "0.2", "--gains", str(g)])
    assert "diverged at t = " in err
