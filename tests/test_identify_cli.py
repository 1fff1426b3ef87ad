"""``pkmdyn hip excite`` and ``pkmdyn hip identify`` end to end: round trip, files, bad input."""

import json
import tomllib

import numpy as np
import pytest

from pkmdyn.cli import main
from pkmdyn.io import read_csv_columns, write_csv
from pkmdyn.machines.hip_simulator.identify_study import truth_description
from pkmdyn.machines.hip_simulator.identify_view import engine_torques, parameter_vector, read_measured_csv
from pkmdyn.machines.hip_simulator.params import load_params, model_from_dict
from pkmdyn.profiles.iso14242 import iso14242_motion
from pkmdyn.profiles.orientation import MOTION_COLUMNS, read_motion_csv


def _tau(model, motion):
    return engine_torques(model, motion)


@pytest.fixture(scope="module")
def measured(tmp_path_factory):
    """An excitation from the command line, with torques of a non-default machine plus 1 % noise."""
    d = tmp_path_factory.mktemp("excite")
    motion_csv = d / "M.csv"
    assert main(["hip", "excite", "--iterations", "1", "--starts", "1", "--harmonics", "2", "--cycles", "3", "--design-samples", "64",
                 "--samples-per-cycle", "200", "--out", str(motion_csv)]) == 0
    truth = model_from_dict(truth_description())
    motion = read_motion_csv(motion_csv)
    tau = _tau(truth, motion)
    rng = np.random.default_rng(0)
    tau = tau + rng.normal(size=tau.shape) * 0.01 * np.sqrt(np.mean(tau**2, axis=0))
    cols = read_csv_columns(motion_csv, ("t_s",), MOTION_COLUMNS[1:])
    for k in [c for c in cols if "dot" in c]:
        del cols[k]  # measured angles only: derivatives by the smoothing differentiator
    for i in range(3):
        cols[f"tau{i + 1}_Nm"] = tau[:, i]
    path = d / "measured.csv"
    write_csv(path, cols)
    return path, cols, truth


def test_excite_writes_a_motion_within_its_limits(measured):
    path, cols, _ = measured
    assert np.all((cols["alpha_deg"] > -18) & (cols["alpha_deg"] < 25))
    assert np.all((cols["load_N"] > 300) & (cols["load_N"] < 3000))


def test_identify_round_trip_predicts_a_held_out_motion(measured, tmp_path, capsys):
    path, _, truth = measured
    out = tmp_path / "id"
    assert main(["hip", "identify", "--measured", str(path), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "slider_viscous_Ns_m" in printed and "identified:" in printed
    report = json.loads((out / "identification.json").read_text())
    assert report["rank"] < len(report["parameters_asked"])
    assert "slider_viscous_Ns_m" in report["not_separable"]
    assert set(report["residual_rms_Nm"]) == {"tau1_Nm", "tau2_Nm", "tau3_Nm"}
    for f in ("identified.toml", "torques.csv", "torque_fit.png", "residuals.png", "report.html"):
        assert (out / f).is_file()
    identified = load_params(out / "identified.toml")
    held = iso14242_motion(1.0, 200)
    tau_held = _tau(truth, held)
    err = np.sqrt(np.mean((_tau(identified, held) - tau_held) ** 2, axis=0) / np.mean(tau_held**2, axis=0))
    assert np.all(err < 0.05)
    # nothing that is only part of a combination gets a line of its own
    assert not any(line.startswith(("slider_viscous_Ns_m =", "screw_viscous_Nms_rad =")) for line in printed.splitlines())
    # the written file reproduces the identified torques on the measured motion (split back exactly)
    cols = read_csv_columns(out / "torques.csv", ("t_s",), [f"tau{i}_{k}_Nm" for i in (1, 2, 3)
                                                           for k in ("measured", "identified", "residual")])
    motion, _, _ = read_measured_csv(path)
    tau_file = _tau(identified, motion)
    tau_id = np.stack([cols[f"tau{i}_identified_Nm"] for i in (1, 2, 3)], axis=-1)
    assert np.max(np.abs(tau_file - tau_id)) <= 1e-9 * np.max(np.abs(tau_id))
    # the identified file runs through the simulator
    assert main(["hip", "run", "--params", str(out / "identified.toml"), "--samples-per-cycle", "50", "--no-plots",
                 "--out", str(tmp_path / "run")]) == 0
    # a complete parameter file: every friction key written
    fr = tomllib.loads((out / "identified.toml").read_text())["friction"]
    assert "universal_viscous_Nms_rad" in fr and "friction_velocity_eps_m_s" in fr
    # S and C, the separable friction, recovered from 1 % noise: S within 2 % of the truth, the
    # written file's split giving back the estimates, every separable parameter (S and C among
    # them) within 5 standard errors of the truth
    names = ("bearing_load_coeff_m", "bearing_weight_friction_Nm")
    assert identified_value(identified, names[0]) == pytest.approx(identified_value(truth, names[0]), rel=0.02)
    for name in names:
        assert identified_value(identified, name) == pytest.approx(report["separable"][name]["estimate"], rel=1e-9)
    assert set(names) <= set(report["separable"])
    for name, v in report["separable"].items():
        t = float(parameter_vector(truth, (name,))[0])
        assert abs(v["estimate"] - t) <= 5 * v["standard_error"] + 1e-9 * abs(t), name


def identified_value(model, name):
    return float(parameter_vector(model, (name,))[0])


@pytest.mark.parametrize("case, words", [
    ("negative_load", ("row 4", "'load_N'")),
    ("huge_torque", ("row 3", "'tau1_Nm'")),
    ("time_back", ("row 6", "'t_s'")),
])
def test_bad_rows_exit_2_naming_the_row_and_column(measured, tmp_path, capsys, case, words):
    _, cols, _ = measured
    cols = {k: v.copy() for k, v in cols.items()}
    if case == "negative_load":
        cols["load_N"][3] = -5.0
    elif case == "huge_torque":
        cols["tau1_Nm"][2] = 1e6
    else:
        cols["t_s"][5] = cols["t_s"][3]
    path = _write(tmp_path / "m.csv", cols)
    out = tmp_path / "out"
    assert main(["hip", "identify", "--no-plots", "--measured", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("pkmdyn: error:") and "\n" not in err
    for w in words:
        assert w in err, err
    assert not out.exists()


def test_a_bad_parameter_file_exits_2_naming_the_key(measured, tmp_path, capsys):
    path, _, _ = measured
    d = truth_description()
    d["friction"]["spherical_coulomb_Nm"] = -1.0
    from pkmdyn.io import dumps_toml

    params = tmp_path / "p.toml"
    params.write_text(dumps_toml(d, "bad", {}))
    out = tmp_path / "out"
    assert main(["hip", "identify", "--no-plots", "--measured", str(path), "--params", str(params),
                 "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "spherical_coulomb_Nm" in err and not out.exists()


def _write(path, cols):
    write_csv(path, cols)
    return path


@pytest.mark.parametrize("case", ["missing", "few", "still", "nan"])
def test_bad_measurements_exit_2_and_write_nothing(measured, tmp_path, capsys, case):
    _, cols, _ = measured
    cols = {k: v.copy() for k, v in cols.items()}
    if case == "missing":
        del cols["tau2_Nm"]
    elif case == "few":
        cols = {k: v[:15] for k, v in cols.items()}
    elif case == "still":
        for k in ("alpha_deg", "beta_deg", "gamma_deg"):
            cols[k][:] = 0.0
        cols["load_N"][:] = 1000.0
    path = _write(tmp_path / "m.csv", cols)
    if case == "nan":
        text = path.read_text().splitlines()
        text[5] = text[5].rsplit(",", 1)[0] + ",nan"
        path.write_text("\n".join(text) + "\n")
    out = tmp_path / "out"
    args = ["hip", "identify", "--measured", str(path), "--out", str(out)]
    if case == "few":
        args += ["--identify", "all", "--sg-window", "5", "--sg-order", "3"]
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("pkmdyn: error:") and "\n" not in err
    assert not out.exists()
    assert {"missing": "tau2_Nm", "few": "too few", "still": "rank 0", "nan": "not finite"}[case] in err


def test_measured_file_with_rates_only_derives_the_accelerations(tmp_path):
    motion = iso14242_motion(1.0, 400)
    cols = {"t_s": motion.t}
    for k, a in enumerate(("alpha", "beta", "gamma")):
        cols[f"{a}_deg"] = np.rad2deg(motion.angles[:, k])
        cols[f"{a}_dot_deg_s"] = np.rad2deg(motion.rates[:, k])
    cols["load_N"] = motion.load
    for i in range(3):
        cols[f"tau{i + 1}_Nm"] = np.zeros(401)
    write_csv(tmp_path / "m.csv", cols)
    read, _, info = read_measured_csv(tmp_path / "m.csv")
    assert info["rates"] == "given" and info["accelerations"] == "savitzky_golay"
    assert np.allclose(read.rates, motion.rates)
    scale = np.max(np.abs(motion.accels))
    assert np.max(np.abs(read.accels - motion.accels)[10:-10]) < 1e-3 * scale


def test_a_parameter_file_with_another_friction_regularisation_is_warned_of(measured, tmp_path, capsys):
    from pkmdyn.io import dumps_toml

    path, _, _ = measured
    d = truth_description()
    d["friction"]["friction_velocity_eps_rad_s"] = 2e-3
    params = tmp_path / "p.toml"
    params.write_text(dumps_toml(d, "eps", {}))
    capsys.readouterr()
    assert main(["hip", "identify", "--no-plots", "--measured", str(path), "--params", str(params),
                 "--out", str(tmp_path / "id")]) == 0
    said = [line for line in capsys.readouterr().err.splitlines() if "friction_velocity_eps_rad_s = 0.002" in line]
    assert len(said) == 1 and "not used" in said[0] and "engine regularises friction at 0.001 rad/s" in said[0]
    written = tomllib.loads((tmp_path / "id" / "identified.toml").read_text())["friction"]
    assert written["friction_velocity_eps_rad_s"] == 2e-3  # written back as it was
