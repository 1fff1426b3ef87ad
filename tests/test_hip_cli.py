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
    + [f"detJ{x}{j}" for j in (1, 2) for x in "ab"]
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
    # torque parts add up in the file too
    for i in (1, 2, 3):
        parts = sum(data[:, header.index(f"tau{i}_{p}_Nm")] for p in ("platform", "lever", "slider", "screw", "friction"))
        np.testing.assert_allclose(parts, data[:, header.index(f"tau{i}_Nm")], rtol=0, atol=1e-13 * np.abs(parts).max())


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
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "leg" in lines[0] and "t = " in lines[0] and "Traceback" not in r.stderr
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


def test_out_folder_helper_refuses_a_file(tmp_path):
    from pkmdyn.errors import PkmdynError
    from pkmdyn.io import make_out_dir

    (tmp_path / "f").write_text("x")
    with pytest.raises(PkmdynError, match="exists and is not a folder"):
        make_out_dir(tmp_path / "f")
    assert make_out_dir(tmp_path / "a" / "b").is_dir()
