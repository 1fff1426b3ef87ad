"""``pkmdyn identify --machine``: a mechanism's inertial parameters and joint friction from
measured efforts (``pkmdyn.identify.described``, ``pkmdyn.jobs.identify``)."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
import tomlkit

import multibody_examples as ex
from pkmdyn.cli import main
from pkmdyn.multibody import load_mechanism, reference_task, solve_kinematics
from pkmdyn.multibody.dynamics.newton_euler import joint_reactions
from pkmdyn.multibody.analyses.regressor import regressor

AMP = np.array([0.04, 0.04, 0.04, 0.12, 0.12, 0.12])


def _files(tmp_path):
    """The true Stewart platform (masses changed, guide friction) and the prior description
    the identification starts from."""
    d = ex.builtin_dict("stewart")
    for b in d["bodies"]:
        b["mass_kg"] *= 1.3
    for leg in d["legs"]:
        for b in leg["bodies"]:
            b["mass_kg"] *= 0.8
        for j in leg["joints"]:
            if j["type"] == "prismatic":
                j["friction"] = {"coulomb_force_N": 3.0, "viscous_N_s_m": 15.0}
    (tmp_path / "true.toml").write_text(tomlkit.dumps(d))
    for leg in d["legs"]:
        for j in leg["joints"]:
            if j["type"] == "prismatic":
                j["friction"] = {"coulomb_force_N": 1.0, "viscous_N_s_m": 1.0}
    for b in d["bodies"]:
        b["mass_kg"] /= 1.3
    (tmp_path / "prior.toml").write_text(tomlkit.dumps(d))
    return tmp_path / "true.toml", tmp_path / "prior.toml"


def _motion_file(m, path, seed, n=400):
    t = np.linspace(0.0, 4.0, n)
    x, xd, xdd = ex.smooth_motion(reference_task(m), AMP, t, seed)
    cols = ["t_s"] + [f"{a}_{u}" for a, u in zip(m.task_names, m.task_units)]
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(cols)
        for i in range(n):
            w.writerow([repr(float(v)) for v in (t[i], *x[i])])
    return t, x, xd, xdd


def test_identification_recovers_friction_and_predicts_another_motion(tmp_path):
    """Efforts of the true mechanism (``pkmdyn run``) identified from the prior description:
    every effort explained, the guides' Coulomb and viscous coefficients found, and the
    identified parameters predict the efforts of a motion not used in the fit."""
    true, prior = _files(tmp_path)
    mt = load_mechanism(true)
    _motion_file(mt, tmp_path / "excite.csv", seed=11)
    assert main(["run", "--machine", str(true), "--motion", str(tmp_path / "excite.csv"),
                 "--out", str(tmp_path / "run")]) == 0
    assert main(["identify", "--machine", str(prior), "--measured", str(tmp_path / "run" / "results.csv"),
                 "--out", str(tmp_path / "id")]) == 0
    rep = json.loads((tmp_path / "id" / "identification.json").read_text())
    assert min(rep["explained_percent"].values()) > 99.9999
    # the library's fit of the same log turns into the efforts table the command wrote
    import pkmdyn
    from pkmdyn.identify.described import read_measured

    mp = load_mechanism(prior)
    t, x, xd, xdd, u, named = read_measured(mp, tmp_path / "run" / "results.csv", 15, 5)
    fit = pkmdyn.identification(mp, solve_kinematics(mp, x, xd, xdd, t), u, loads=named)
    with open(tmp_path / "id" / "efforts.csv") as fh:
        rows = list(csv.reader(fh))
    cols = fit.columns(t)
    assert list(cols) == rows[0] and len(rows[0]) == 1 + 2 * mp.na
    for k, name in enumerate(rows[0]):
        np.testing.assert_allclose(cols[name], [float(r[k]) for r in rows[1:]], rtol=1e-12, atol=1e-9, err_msg=name)
    for k in (1, 2, 3, 4, 5, 6):
        for law, want in (("coulomb", 3.0), ("viscous", 15.0)):
            name = f"P_{k}_{law}"
            assert name in rep["separable"], (name, sorted(rep["separable"]))
            assert rep["separable"][name]["estimate"] == pytest.approx(want, rel=1e-6)
    # prediction on another motion: Y theta_hat + u0 against the true mechanism's efforts
    theta = np.array([rep["parameters"][nm]["estimate"] for nm in rep["parameters_asked"]])
    mp = load_mechanism(prior)
    t, x, xd, xdd = _motion_file(mp, tmp_path / "check.csv", seed=5, n=120)
    reg = regressor(mp, solve_kinematics(mp, x, xd, xdd, t))
    assert list(reg.names) == rep["parameters_asked"]
    u_true = joint_reactions(mt, solve_kinematics(mt, x, xd, xdd, t)).u
    u_hat = np.einsum("nap,p->na", reg.Y, theta) + reg.u0
    assert np.abs(u_hat - u_true).max() <= 1e-6 * np.abs(u_true).max()
    u_prior = np.einsum("nap,p->na", reg.Y, reg.theta) + reg.u0
    assert np.abs(u_prior - u_true).max() > 1e-2 * np.abs(u_true).max()  # the prior alone is wrong


def test_identify_refuses_what_it_cannot_fit(tmp_path, capsys):
    true, prior = _files(tmp_path)
    m = load_mechanism(true)
    _motion_file(m, tmp_path / "motion.csv", seed=1, n=50)
    # no effort columns
    code = main(["identify", "--machine", str(prior), "--measured", str(tmp_path / "motion.csv"),
                 "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "P_1_effort_N" in err and len(err.splitlines()) == 1 and not (tmp_path / "o").exists()
    # reaction-dependent friction is not linear in the parameters
    d = ex.builtin_dict("stewart")
    d["legs"][0]["joints"][-1]["friction"] = {"coefficient": 0.1, "ball_radius_m": 0.01}
    (tmp_path / "mu.toml").write_text(tomlkit.dumps(d))
    assert main(["run", "--machine", str(true), "--motion", str(tmp_path / "motion.csv"),
                 "--out", str(tmp_path / "run")]) == 0
    code = main(["identify", "--machine", str(tmp_path / "mu.toml"), "--measured",
                 str(tmp_path / "run" / "results.csv"), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "coefficient" in err and len(err.splitlines()) == 1 and not (tmp_path / "o").exists()


def test_identify_never_replaces_its_input(tmp_path, capsys):
    """The folder holding the measured file (an earlier pkmdyn run) and a device are refused
    as --out, with one line and nothing changed."""
    true, prior = _files(tmp_path)
    _motion_file(load_mechanism(true), tmp_path / "motion.csv", seed=2, n=60)
    run = tmp_path / "run"
    assert main(["run", "--machine", str(true), "--motion", str(tmp_path / "motion.csv"), "--out", str(run)]) == 0
    capsys.readouterr()
    before = {p: p.read_bytes() for p in run.iterdir()}
    for out in (run, "/dev/null"):
        code = main(["identify", "--machine", str(prior), "--measured", str(run / "results.csv"), "--out", str(out)])
        err = capsys.readouterr().err.strip()
        assert code == 2 and len(err.splitlines()) == 1, err
    assert {p: p.read_bytes() for p in run.iterdir()} == before


def test_identify_refuses_a_misspelt_column_and_too_few_samples(tmp_path, capsys):
    true, prior = _files(tmp_path)
    m = load_mechanism(true)
    _motion_file(m, tmp_path / "motion.csv", seed=3, n=300)
    run = tmp_path / "run"
    assert main(["run", "--machine", str(true), "--motion", str(tmp_path / "motion.csv"), "--out", str(run)]) == 0
    rows = (run / "results.csv").read_text().splitlines()
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join([rows[0] + ",psuh_N"] + [r + ",1.0" for r in rows[1:]]) + "\n")
    few = tmp_path / "few.csv"
    few.write_text("\n".join(rows[:9]) + "\n")
    capsys.readouterr()
    for measured, word in ((bad, "psuh_N"), (few, "too few")):
        code = main(["identify", "--machine", str(prior), "--measured", str(measured), "--out", str(tmp_path / "o")])
        err = capsys.readouterr().err.strip()
        assert code == 2 and word in err and len(err.splitlines()) == 1, err
        assert not (tmp_path / "o").exists()


def test_identification_from_a_log_in_actuator_coordinates(tmp_path):
    """A real machine's log: time, the actuated joints' positions and the efforts, no task
    column. The pose by the direct kinematics; the identification is the one of the full
    results file (the same friction coefficients), with the rates given or derived from the
    positions (Savitzky-Golay, or the spline for exact positions)."""
    true, prior = _files(tmp_path)
    mt = load_mechanism(true)
    _motion_file(mt, tmp_path / "excite.csv", seed=11)
    assert main(["run", "--machine", str(true), "--motion", str(tmp_path / "excite.csv"),
                 "--out", str(tmp_path / "run")]) == 0
    with (tmp_path / "run" / "results.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    effort = [f"P_{k}_effort_N" for k in range(1, 7)]
    pos = [f"P_{k}_pos_m" for k in range(1, 7)]
    rates = [f"P_{k}_vel_m_s" for k in range(1, 7)] + [f"P_{k}_acc_m_s2" for k in range(1, 7)]
    for name, cols, extra in (("rates", pos + rates, []), ("spline", pos, ["--sg-window", "0"]),
                              ("smoothed", pos, ["--sg-window", "9", "--sg-order", "4"])):
        log = tmp_path / f"log_{name}.csv"
        with log.open("w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["t_s", *cols, *effort])
            for r in rows:
                w.writerow([r[c] for c in ("t_s", *cols, *effort)])
        assert main(["identify", "--machine", str(prior), "--measured", str(log), *extra,
                     "--out", str(tmp_path / f"id_{name}")]) == 0
        rep = json.loads((tmp_path / f"id_{name}" / "identification.json").read_text())
        rel = {"rates": 1e-9, "spline": 1e-4, "smoothed": 5e-3}[name]
        for k in (1, 2, 3, 4, 5, 6):
            for law, want in (("coulomb", 3.0), ("viscous", 15.0)):
                assert rep["separable"][f"P_{k}_{law}"]["estimate"] == pytest.approx(want, rel=rel), (name, k, law)


def test_an_actuator_log_without_positions_is_refused(tmp_path, capsys):
    true, prior = _files(tmp_path)
    log = tmp_path / "log.csv"
    log.write_text("t_s," + ",".join(f"P_{k}_effort_N" for k in range(1, 7)) + "\n"
                   + "".join(f"{0.01 * i}," + ",".join("1.0" for _ in range(6)) + "\n" for i in range(20)))
    assert main(["identify", "--machine", str(prior), "--measured", str(log), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "P_1_pos_m" in err and err.count("\n") == 1
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("value, pattern", [("0.0", "is zero: nothing to identify"),
                                            ("1e15", "column 'P_1_effort_N': 1e+15 is beyond the plausibility limit")])
def test_identify_refuses_implausible_or_empty_efforts(tmp_path, capsys, value, pattern):
    """As the hip's identification does: all-zero efforts, or one beyond its plausibility limit."""
    true, prior = _files(tmp_path)
    m = load_mechanism(true)
    t, x, _, _ = _motion_file(m, tmp_path / "m.csv", seed=3, n=40)
    log = tmp_path / "log.csv"
    names = [f"{a}_{u}" for a, u in zip(m.task_names, m.task_units)]
    with log.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["t_s", *names, *(f"P_{k}_effort_N" for k in range(1, 7))])
        for i in range(len(t)):
            w.writerow([repr(float(v)) for v in (t[i], *x[i])] + [value if k == 0 or value == "0.0" else "1.0"
                                                                  for k in range(6)])
    assert main(["identify", "--machine", str(prior), "--measured", str(log), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert pattern in err and err.count("\n") == 1, err
    assert not (tmp_path / "o").exists()
