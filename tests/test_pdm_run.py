"""``pkmdyn pdm run`` end to end: results agree with finite differences and with an
independent inverse position from geometry.json; mobility.json; errors as one line + status 2."""

from __future__ import annotations

import csv
import json
import math
import tomllib

import numpy as np
import pytest

from pkmdyn.cli import main
from pkmdyn.machines.pdm4 import default_params_path
from pkmdyn.profiles.pdm_motion import cycloidal_motion, read_pdm_motion, write_pdm_motion


def _read(path):
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return {name: np.array([float(r[k]) for r in rows[1:]]) for k, name in enumerate(rows[0])}


@pytest.fixture(scope="module")
def fine_run(tmp_path_factory):
    d = tmp_path_factory.mktemp("pdm")
    motion = cycloidal_motion((0.015, -0.01, math.radians(4), math.radians(12)), 1.0, 2001)
    write_pdm_motion(d / "motion.csv", motion)
    assert main(["pdm", "run", "--motion", str(d / "motion.csv"), "--no-plots", "--out", str(d / "out")]) == 0
    return d / "out"


def test_limb_rates_in_results_match_finite_differences(fine_run):
    cols = _read(fine_run / "results.csv")
    t = cols["t_s"]
    dt = t[1] - t[0]
    for k in range(1, 5):
        l, ld, ldd = cols[f"l{k}_m"], cols[f"ld{k}_m_s"], cols[f"ldd{k}_m_s2"]
        fd = (l[2:] - l[:-2]) / (2 * dt)
        fdd = (l[2:] - 2 * l[1:-1] + l[:-2]) / dt**2
        assert np.abs(fd - ld[1:-1]).max() < 1e-4 * np.abs(ld).max()
        assert np.abs(fdd - ldd[1:-1]).max() < 1e-3 * np.abs(ldd).max()
    assert cols["loop_residual_m"].max() < 1e-12
    assert list(cols)[:17] == ["t_s", "x_m", "y_m", "alpha_rad", "gamma_rad"] + [
        f"{p}{k}_{u}" for k in range(1, 5) for p, u in (("l", "m"), ("ld", "m_s"), ("ldd", "m_s2"))]


def test_limb_lengths_match_an_inverse_position_from_the_documented_geometry(fine_run):
    cols = _read(fine_run / "results.csv")
    geo = json.loads((fine_run / "geometry.json").read_text())
    g = tomllib.loads(default_params_path().read_text())["geometry"]
    r0, r2, r3 = g["platform_offset_m"], g["crank_length_m"], g["coupler_length_m"]
    for s in range(0, len(cols["t_s"]), 250):
        x, y, a, gm = (cols[c][s] for c in ("x_m", "y_m", "alpha_rad", "gamma_rad"))
        ca, sa, cg, sg = math.cos(a), math.sin(a), math.cos(gm), math.sin(gm)
        T = np.array([[ca, -sa * cg, sa * sg], [sa, ca * cg, -ca * sg], [0, sg, cg]])
        C = np.array([x, y, r0 * cg]) - T @ np.array(geo["P_platform_m"])
        for i, (r1n, r3n, r4n) in enumerate((("R11", "R31", "R41"), ("R12", "R32", "R42"))):
            R1 = np.array(geo["R1_m"][r1n])
            R3 = C + T @ np.array(geo["R3_output_link_m"][r3n])  # gamma does not move it: on the R4 axis
            d = np.linalg.norm(R3 - R1)
            e = (R3 - R1) / d
            along = (d * d + r2 * r2 - r3 * r3) / (2 * d)
            h = math.sqrt(r2 * r2 - along * along)
            side = -1 if i == 0 else 1
            perp = np.array([-e[1], e[0], 0.0])
            R2 = max((R1 + along * e + h * perp, R1 + along * e - h * perp), key=lambda p: side * p[0])
            assert abs(np.linalg.norm(R2 - np.array(geo["R4_m"][r4n])) - cols[f"l{i + 1}_m"][s]) < 1e-9
        for j, (un, sn) in enumerate((("U23", "S23"), ("U24", "S24"))):
            U = C + T @ np.array(geo["U_platform_m"][un])
            assert abs(np.linalg.norm(U - np.array(geo["S_m"][sn])) - cols[f"l{j + 3}_m"][s]) < 1e-9


def test_mobility_json(fine_run):
    mob = json.loads((fine_run / "mobility.json").read_text())
    assert mob["t"] == 9 and mob["t_screw"] == 9 and mob["dof"] == 4
    assert mob["joint_counts"] == {"R": 11, "P": 4, "S": 2, "U": 2} and mob["moving_links"] == 14
    assert len(mob["overconstrained_subchains"]) == 3
    for sub in mob["overconstrained_subchains"]:
        assert sub["directions"] == ["force_z", "couple_x", "couple_y"]
        assert sub["constraint_wrenches"] == [[0, 0, 1, 0, 0, 0], [0, 0, 0, 1, 0, 0], [0, 0, 0, 0, 1, 0]]


def test_default_run_with_plots(tmp_path, capsys):
    assert main(["pdm", "run", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    for name in ("results.csv", "mobility.json", "geometry.json", "workspace.csv", "workspace_xy.csv",
                 "limbs.png", "workspace.png", "schematic.png"):
        assert (tmp_path / name).stat().st_size > 0
        assert name in out
    text = (tmp_path / "results.csv").read_text()
    assert "nan" not in text.lower()


def test_bad_parameter_file_is_one_line_and_status_2(tmp_path, capsys):
    text = default_params_path().read_text().replace("crank_length_m = 0.240", "crank_length_m = -0.240")
    (tmp_path / "p.toml").write_text(text)
    assert main(["pdm", "run", "--params", str(tmp_path / "p.toml"), "--no-plots", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"pkmdyn: error: {tmp_path / 'p.toml'}: [geometry] crank_length_m: must be > 0, got -0.24"


def test_unreachable_motion_names_time_and_limb(tmp_path, capsys):
    motion = cycloidal_motion((0.12, 0.0, 0.0, 0.0), 1.0, 51)
    write_pdm_motion(tmp_path / "m.csv", motion)
    assert main(["pdm", "run", "--motion", str(tmp_path / "m.csv"), "--no-plots", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err
    assert err.startswith("pkmdyn: error: t = ") and " s: limb " in err
    assert not (tmp_path / "o").exists()


def test_out_path_that_is_a_file_is_one_line_and_status_2(tmp_path, capsys):
    (tmp_path / "o").write_text("not a folder")
    assert main(["pdm", "run", "--no-plots", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "is a file" in err


def test_missing_out_option_is_a_usage_error(capsys):
    assert main(["pdm", "run"]) == 2
    assert "--out" in capsys.readouterr().err


def test_motion_file_rows_follow_the_limits_table(tmp_path, capsys):
    """``[limits] max_samples`` of the parameter file caps the rows of a motion file too: below the
    file's rows it refuses the run (naming the limit), raised above them it lets it run."""
    motion = tmp_path / "m.csv"
    write_pdm_motion(motion, cycloidal_motion((0.005, 0.005, 0.02, 0.02), 1.0, 41))
    base = default_params_path().read_text(encoding="utf-8")
    base = base.replace("samples = 401", "samples = 11")  # the built-in trajectory stays under both caps
    assert "samples = 11" in base
    tight = tmp_path / "tight.toml"
    tight.write_text(base + "\n[limits]\nmax_samples = 30\n", encoding="utf-8")
    out = tmp_path / "out"
    assert main(["pdm", "run", "--params", str(tight), "--motion", str(motion), "--no-plots", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "max_samples" in err[0] and str(motion) in err[0]
    assert not out.exists()
    loose = tmp_path / "loose.toml"
    loose.write_text(base + "\n[limits]\nmax_samples = 41\n", encoding="utf-8")
    assert main(["pdm", "run", "--params", str(loose), "--motion", str(motion), "--no-plots", "--out", str(out)]) == 0


def _closed_form_columns(pm, motion):
    """The paper's columns from the hand-derived Eq. 2-83 (kinematics of every body and the
    Newton-Euler reactions with compliance), independent of the engine that ``pdm run`` uses."""
    from pkmdyn.machines.pdm4 import inverse_kinematics
    from oracles.pdm_newton_euler import JOINTS, REDUNDANT_LABELS, inverse_dynamics

    kin = inverse_kinematics(pm, motion)
    reac = inverse_dynamics(pm, kin)
    cols = {"t_s": kin.t}
    for k, names in enumerate((("x_m", "xd_m_s", "xdd_m_s2"), ("y_m", "yd_m_s", "ydd_m_s2"),
                               ("alpha_rad", "alphad_rad_s", "alphadd_rad_s2"),
                               ("gamma_rad", "gammad_rad_s", "gammadd_rad_s2"))):
        for name, x in zip(names, (kin.q, kin.qd, kin.qdd)):
            cols[name] = x[:, k]
    for k in range(4):
        cols[f"l{k + 1}_m"], cols[f"ld{k + 1}_m_s"], cols[f"ldd{k + 1}_m_s2"] = kin.pos.l[:, k], kin.ld[:, k], kin.ldd[:, k]
        cols[f"s{k + 1}_m"] = kin.pos.l[:, k] - pm.home_lengths[k]
        cols[f"f{k + 1}_N"] = reac.force[:, k]
    cols["z_m"] = kin.pos.P[:, 2]
    for i in range(2):
        for sym, v in ((f"crank{i + 1}_theta", (kin.pos.theta1, kin.theta1d, kin.theta1dd)),
                       (f"coupler{i + 1}_theta", (kin.pos.theta2, kin.theta2d, kin.theta2dd)),
                       (f"rpr{i + 1}_phi", (kin.rpr_angle, kin.rpr_angle_d, kin.rpr_angle_dd))):
            for suffix, x in zip(("_rad", "d_rad_s", "dd_rad_s2"), v):
                cols[sym + suffix] = x[:, i]
    for j in range(2):
        for e, ang in enumerate(("alpha", "beta", "gamma")):
            for suffix, x in zip(("_rad", "d_rad_s", "dd_rad_s2"), (kin.euler, kin.euler_d, kin.euler_dd)):
                cols[f"spu{j + 3}_{ang}{suffix}"] = x[:, j, e]
    for b in kin.bodies:
        for f, unit in (("p", "m"), ("v", "m_s"), ("a", "m_s2"), ("w", "rad_s"), ("wd", "rad_s2")):
            for c in range(3):
                cols[f"{b.name}_{f}{'xyz'[c]}_{unit}"] = getattr(b, f)[:, c]
    for c, label in enumerate(REDUNDANT_LABELS):
        cols[label] = reac.redundant[:, c]
    cols["U23_torque_Nm"], cols["U24_torque_Nm"] = reac.u_joint_torque[:, 0], reac.u_joint_torque[:, 1]
    npz = {f: np.stack([getattr(b, f) for b in kin.bodies], axis=1) for f in ("R", "p", "v", "w", "a", "wd")}
    npz.update(joint_point=reac.joint_point, joint_force=reac.joint_force, joint_moment=reac.joint_moment)
    return cols, npz, [j[0] for j in JOINTS], [b.name for b in kin.bodies]


@pytest.mark.parametrize("seed", [3, 4])
def test_run_agrees_with_the_closed_forms_of_the_paper(seed, tmp_path):
    """``pkmdyn pdm run`` (the generic engine on the PDM's description) against the hand-derived
    kinematics and Newton-Euler reactions with compliance, computed here on a random variant
    and a random Eq. 84 motion: every column of results.csv and every array of bodies.npz to
    1e-9 of its column's scale (the loop residual, zero in both, below 1e-12 m)."""
    from test_pdm_description import _variant

    from pkmdyn.machines.pdm4 import load_params

    pm = _variant(seed, tmp_path)
    rng = np.random.default_rng(seed)
    tr = pm.trajectory
    strokes = tuple(np.array(tr.strokes) * rng.uniform(-1, 1, 4))
    motion = cycloidal_motion(strokes, tr.period_s * rng.uniform(0.5, 2.0), 157)
    write_pdm_motion(tmp_path / "m.csv", motion)
    params = tmp_path / f"pdm_{seed}.toml"
    assert main(["pdm", "run", "--params", str(params), "--motion", str(tmp_path / "m.csv"), "--no-plots",
                 "--out", str(tmp_path / "out")]) == 0
    got = _read(tmp_path / "out" / "results.csv")
    pm = load_params(params)
    want, npz, joints, bodies = _closed_form_columns(pm, read_pdm_motion(tmp_path / "m.csv"))
    assert set(got) == set(want) | {"loop_residual_m"}
    for name, ref in want.items():
        scale = max(float(np.abs(ref).max()), 1e-300)
        assert np.abs(got[name] - ref).max() <= 1e-9 * scale + 1e-12, name
    assert got["loop_residual_m"].max() < 1e-12
    z = np.load(tmp_path / "out" / "bodies.npz")
    assert list(z["joint_names"]) == joints and list(z["body_names"]) == bodies
    for name, ref in npz.items():
        assert np.abs(z[name] - ref).max() <= 1e-9 * np.abs(ref).max(), name


def test_a_limb_along_the_base_z_axis_is_named_as_the_euler_singularity():
    """The SPU limbs' z-x-z angles of results.csv are singular where a limb stands along the base
    z axis: one line naming the sample and the limb (the engine itself is regular there)."""
    from pkmdyn.errors import SingularityError
    from pkmdyn.machines.pdm4 import paper

    R = np.tile(np.eye(3), (3, 1, 1))
    R[1] = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])  # limb (x axis) along base z
    w = np.zeros((3, 3))
    with pytest.raises(SingularityError, match=r"t = 0\.5 s: limb 3 \(SPU, l23\) is parallel to the base z axis"):
        paper._spu_euler(R, w, w, np.array([0.0, 0.5, 1.0]), paper.LIMB_LABELS[2])
    e, ed, edd = paper._spu_euler(R[[0, 2]], w[:2], w[:2], None, paper.LIMB_LABELS[2])
    assert np.allclose(e[:, 1], np.pi / 2) and np.all(ed == 0) and np.all(edd == 0)
