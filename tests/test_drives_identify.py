"""Identification with drives and load-driven friction: the regressor reproduces the motor
efforts, and ``pkmdyn identify`` finds the rotor inertias, the motors' friction and the hip's
hip-joint and thrust-bearing coefficients (Eq. 16) from measured motor torques."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
import tomlkit

import multibody_examples as ex
from pkmdyn.cli import main
from pkmdyn.multibody import load_mechanism, reference_task, solve_kinematics
from pkmdyn.multibody.dynamics.actuators import motor_efforts
from pkmdyn.multibody.dynamics.newton_euler import joint_reactions
from pkmdyn.multibody.analyses.regressor import regressor

TRUE = {"rotor_inertia_kgm2": 3e-5, "coulomb_torque_Nm": 0.04, "viscous_Nm_s_rad": 2e-4}
PRIOR = {"rotor_inertia_kgm2": 1e-5, "coulomb_torque_Nm": 0.01, "viscous_Nm_s_rad": 1e-5}


def _stewart(values):
    d = ex.builtin_dict("stewart")
    for leg in d["legs"]:
        leg["actuators"] = [{"joint": "P", "name": "M", "screw_lead_m": 0.005, **values}]
    return d


def _write(path, d):
    path.write_text(tomlkit.dumps(d), encoding="utf-8")
    return path


def _motion_file(m, path, seed, n=400, extra=None):
    t = np.linspace(0.0, 4.0, n)
    amp = np.where(m.task_kind == 1, 0.12, 0.04)
    x, xd, xdd = ex.smooth_motion(reference_task(m), amp, t, seed)
    cols = ["t_s"] + [f"{a}_{u}" for a, u in zip(m.task_names, m.task_units)]
    data = [t, *x.T]
    for name, v in (extra or {}).items():
        cols.append(name)
        data.append(v(t))
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(cols)
        for row in np.column_stack(data):
            w.writerow([repr(float(v)) for v in row])
    return t, x, xd, xdd


def test_regressor_with_drives_gives_the_motor_efforts():
    """Y theta + u0 equals the motor efforts (Eq. A1) of joint_reactions; the drives add their
    rotor inertia and motor friction columns, named after the drives."""
    m = load_mechanism(_stewart(TRUE))
    t = np.linspace(0, 1, 50)
    x, xd, xdd = ex.smooth_motion(reference_task(m), np.where(m.task_kind == 1, 0.05, 0.02), t, 3)
    kin = solve_kinematics(m, x, xd, xdd, t)
    reg = regressor(m, kin)
    tau = np.einsum("nap,p->na", reg.Y, reg.theta) + reg.u0
    ref = motor_efforts(m, kin.act_q, kin.act_qd, kin.act_qdd, joint_reactions(m, kin).u).effort
    assert np.abs(tau - ref).max() <= 1e-10 * np.abs(ref).max()
    for k in (1, 2, 3, 4, 5, 6):
        for p in ("rotor_inertia_kgm2", "motor_coulomb", "motor_viscous"):
            assert f"M_{k}_{p}" in reg.names


def test_identify_finds_rotor_inertia_and_motor_friction_from_motor_torques(tmp_path):
    """The true drives (rotor inertia, Coulomb and viscous friction) identified from the motor
    torques of a run of the true mechanism, starting from a prior with other values."""
    true = _write(tmp_path / "true.toml", _stewart(TRUE))
    prior = _write(tmp_path / "prior.toml", _stewart(PRIOR))
    _motion_file(load_mechanism(true), tmp_path / "excite.csv", seed=11)
    assert main(["run", "--machine", str(true), "--motion", str(tmp_path / "excite.csv"),
                 "--out", str(tmp_path / "run")]) == 0
    assert main(["identify", "--machine", str(prior), "--measured", str(tmp_path / "run" / "results.csv"),
                 "--out", str(tmp_path / "id")]) == 0
    rep = json.loads((tmp_path / "id" / "identification.json").read_text())
    assert min(rep["explained_percent"].values()) > 99.9999
    assert set(rep["explained_percent"]) == {f"M_{k}_torque_Nm" for k in (1, 2, 3, 4, 5, 6)}
    for k in (1, 2, 3, 4, 5, 6):
        for key, want in (("rotor_inertia_kgm2", TRUE["rotor_inertia_kgm2"]),
                          ("motor_coulomb", TRUE["coulomb_torque_Nm"]), ("motor_viscous", TRUE["viscous_Nm_s_rad"])):
            name = f"M_{k}_{key}"
            assert name in rep["separable"], (name, sorted(rep["separable"]))
            assert rep["separable"][name]["estimate"] == pytest.approx(want, rel=1e-5), name


@pytest.mark.parametrize("platform_mass", [3.0, 0.0])
def test_identify_finds_the_hips_load_driven_friction(tmp_path, platform_mass):
    """The hip's description with other hip-joint and thrust-bearing coefficients (Eq. 16, the
    friction.external of S0 driven by the test load): measured motor torques of the ISO cycle
    with its load, identified from the built-in description. The two platforms move alike, so
    each coefficient's upper and lower columns are one combination (the estimates split it
    evenly, recovering the true coefficients on both). With a platform mass the thrust bearing
    carries its weight too and the two coefficients separate; without one, the torques show
    their combination ``S = r_h mu_h + r_t mu_t`` only, as the hip's own identification says
    (``bearing_load_coeff_m``), and that is what is found."""
    from pkmdyn.machines.hip_simulator import model_from_dict
    from pkmdyn.machines.hip_simulator.description import hip_description
    from pkmdyn.machines.hip_simulator.params import default_params_dict
    from pkmdyn.profiles.iso14242 import iso14242_motion

    base = default_params_dict()
    base["inertia"]["platform_mass_kg"] = platform_mass
    d = default_params_dict()
    d["inertia"]["platform_mass_kg"] = platform_mass
    d["friction"]["hip_coefficient"] = 2.0 * base["friction"]["hip_coefficient"]
    d["friction"]["thrust_coefficient"] = 0.5 * base["friction"]["thrust_coefficient"]
    true = _write(tmp_path / "true.toml", hip_description(model_from_dict(d, "true")))
    prior = _write(tmp_path / "prior.toml", hip_description(model_from_dict(base, "prior")))
    mo = iso14242_motion(cycles=2, samples_per_cycle=400)
    cols = ["t_s", "euler1_rad", "euler2_rad", "euler3_rad", "hydraulic_N"]
    with (tmp_path / "iso.csv").open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(cols)
        for row in np.column_stack([mo.t, mo.angles, mo.load]):
            w.writerow([repr(float(v)) for v in row])
    assert main(["run", "--machine", str(true), "--motion", str(tmp_path / "iso.csv"), "--out", str(tmp_path / "run")]) == 0
    assert main(["identify", "--machine", str(prior), "--measured", str(tmp_path / "run" / "results.csv"),
                 "--out", str(tmp_path / "id")]) == 0
    rep = json.loads((tmp_path / "id" / "identification.json").read_text())
    assert min(rep["explained_percent"].values()) > 99.99
    est = {k: v["estimate"] for k, v in rep["parameters"].items()}
    f = d["friction"]
    mu_h, mu_t, r_h, r_t = f["hip_coefficient"], f["thrust_coefficient"], f["hip_radius_m"], f["thrust_radius_m"]
    for platform in ("upper", "lower"):
        h = est[f"S0_{platform}_external1_hydraulic_N_coefficient"]
        t = est[f"S0_{platform}_external2_hydraulic_N_coefficient"]
        assert r_h * h + r_t * t == pytest.approx(r_h * mu_h + r_t * mu_t, rel=1e-6)
        if platform_mass:
            assert h == pytest.approx(mu_h, rel=1e-5) and t == pytest.approx(mu_t, rel=1e-5)
        else:
            assert abs(h - mu_h) > 1e-3 * mu_h  # not separable: the prior decides the split
