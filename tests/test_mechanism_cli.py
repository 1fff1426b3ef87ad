"""The machine-independent commands: pkmdyn machines, describe, run; their files, and user
errors (one line, exit status 2, nothing written)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import multibody_examples as ex
from pkmdyn.cli import main


def _run(capsys, *args):
    code = main(list(args))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_machines_lists_every_builtin_one_per_line(capsys):
    code, out, _ = _run(capsys, "machines")
    assert code == 0
    assert out.split() == sorted(["bennett", "delta", "hip", "pdm", "rrr3", "rrr4", "stewart", "stewart7"])


def test_describe_prints_topology(capsys):
    code, out, _ = _run(capsys, "describe", "--machine", "rrr3")
    assert code == 0
    assert "Grubler-Kutzbach mobility: -3" in out
    assert "mobility (rank at the reference configuration): 3" in out
    assert "over-constraints: 6" in out
    code, out, _ = _run(capsys, "describe", "--machine", "delta")
    assert "idle freedoms: 6" in out and "degrees of freedom: 3" in out


def test_describe_a_description_file(capsys, tmp_path):
    f = tmp_path / "bennett_copy.toml"
    f.write_text((ex.MACHINES / "bennett" / "bennett.toml").read_text(encoding="utf-8"), encoding="utf-8")
    code, out, _ = _run(capsys, "describe", "--machine", str(f))
    assert code == 0 and "over-constraints: 3" in out


@pytest.mark.parametrize("name", ["stewart", "delta", "rrr3", "bennett"])
def test_run_writes_results_model_and_bodies(capsys, tmp_path, name):
    out_dir = tmp_path / "out"
    code, out, err = _run(capsys, "run", "--machine", name, "--out", str(out_dir))
    assert code == 0, err
    names = {p.name for p in out_dir.iterdir()}
    assert {"results.csv", "model.json", "bodies.npz", "summary.json"} <= names
    header = (out_dir / "results.csv").read_text(encoding="utf-8").splitlines()[0].split(",")
    model = json.loads((out_dir / "model.json").read_text(encoding="utf-8"))
    assert header[0] == "t_s"
    for a in model["actuators"]:
        unit = "m" if next(j for j in model["joints"] if j["name"] == a)["type"] == "prismatic" else "rad"
        assert {f"{a}_pos_{unit}", f"{a}_vel_{unit}_s", f"{a}_acc_{unit}_s2"} <= set(header)
    _check_rebuild(model, np.load(out_dir / "bodies.npz"))


def _rot(m, a):
    c, s = np.cos(a), np.sin(a)
    i = "XYZ".index(m[1])
    R = np.eye(3)
    j, k = (i + 1) % 3, (i + 2) % 3
    R[j, j], R[k, k], R[j, k], R[k, j] = c, c, -s, s
    return R


def _check_rebuild(model, npz):
    """From model.json and bodies.npz alone: every joint's two frames, carried by the two
    bodies' poses, differ by the product of the joint's elementary motions (tree joints, with
    the coordinates of bodies.npz), or satisfy the cut joint's constraints (cut joints)."""
    bodies = {b["name"]: k for k, b in enumerate(model["bodies"])}
    R, origin = npz["R"], npz["origin"]
    coord_joints = list(npz["coordinate_joints"])
    q = npz["q"]
    for j in model["joints"]:
        def pose(body, fr):
            Rf = np.column_stack([fr["x_axis"], fr["y_axis"], fr["z_axis"]])
            if body == "ground":
                return np.broadcast_to(Rf, (q.shape[0], 3, 3)), np.broadcast_to(np.array(fr["origin_m"]), (q.shape[0], 3))
            b = bodies[body]
            return R[:, b] @ Rf, origin[:, b] + np.einsum("nij,j->ni", R[:, b], fr["origin_m"])
        RP, oP = pose(j["parent"], j["parent_frame"])
        RC, oC = pose(j["child"], j["child_frame"])
        if j["cut"]:
            rel = np.einsum("nji,njk->nik", RP, RC)
            d = np.einsum("nji,nj->ni", RP, oC - oP)
            if j["type"] in ("spherical", "revolute", "universal"):
                assert np.abs(d).max() < 1e-9
            if j["type"] == "revolute":
                assert np.abs(rel[:, :2, 2]).max() < 1e-9
            continue
        idx = [k for k, n in enumerate(coord_joints) if n == j["name"]]
        motions = j["motions"][::-1] if j["traversed_backwards"] else j["motions"]
        sign = -1.0 if j["traversed_backwards"] else 1.0
        off = j["position_at_reference"] if len(idx) == 1 else 0.0
        for s in range(0, q.shape[0], 37):
            Rm, om = np.eye(3), np.zeros(3)
            for m, c in zip(motions, idx):
                v = sign * (q[s, c] - off)
                if m[0] == "R":
                    Rm = Rm @ _rot(m, v)
                else:
                    om = om + Rm[:, "XYZ".index(m[1])] * v
            if j["traversed_backwards"]:
                want_R, want_o = RP[s] @ Rm.T, oP[s] - RP[s] @ Rm.T @ om
                assert np.allclose(RC[s], want_R, atol=1e-10) and np.allclose(oC[s], want_o, atol=1e-10)
            else:
                assert np.allclose(RC[s], RP[s] @ Rm, atol=1e-10) and np.allclose(oC[s], oP[s] + RP[s] @ om, atol=1e-10)


def test_run_with_a_motion_file(capsys, tmp_path):
    t = np.linspace(0.0, 1.0, 50)
    x = 1.0471975511965976 + 0.3 * np.sin(2 * np.pi * t)
    f = tmp_path / "m.csv"
    f.write_text("t_s,euler1_rad\n" + "\n".join(f"{a:.17g},{b:.17g}" for a, b in zip(t, x)) + "\n", encoding="utf-8")
    code, _, err = _run(capsys, "run", "--machine", "bennett", "--motion", str(f), "--out", str(tmp_path / "o"))
    assert code == 0, err
    cols = np.genfromtxt(tmp_path / "o" / "results.csv", delimiter=",", names=True)
    assert np.allclose(cols["J1_pos_rad"], x, atol=1e-12)
    # rates from the quintic spline through the samples
    assert np.allclose(cols["J1_vel_rad_s"][5:-5], 0.6 * np.pi * np.cos(2 * np.pi * t[5:-5]), rtol=1e-3, atol=1e-3)


@pytest.mark.parametrize("args, pattern", [
    (["run", "--machine", "nosuch"], "unknown machine"),
    (["describe", "--machine", "nosuch"], "unknown machine"),
    (["run", "--machine", "MISSING.toml"], "cannot read file"),
    (["run", "--machine", "designs/missing"], "no such file"),  # a path, not a name
    (["describe", "--machine", "stewrt"], "did you mean stewart?"),
])
def test_user_errors_are_one_line_and_write_nothing(capsys, tmp_path, args, pattern):
    out_dir = tmp_path / "out"
    full = args + (["--out", str(out_dir)] if args[0] == "run" else [])
    code, _, err = _run(capsys, *full)
    assert code == 2
    assert pattern in err and err.count("\n") == 1
    assert not out_dir.exists() and list(tmp_path.iterdir()) == []


def test_hostile_description_file_is_refused(capsys, tmp_path):
    d = (ex.MACHINES / "rrr3" / "rrr3.toml").read_text(encoding="utf-8").replace(
        'inertia_kgm2 = [0.002, 0.002, 0.004, 0.0, 0.0, 0.0]', 'inertia_kgm2 = [0.002, 0.002, 0.005, 0.0, 0.0, 0.0]')
    f = tmp_path / "bad.toml"
    f.write_text(d, encoding="utf-8")
    code, _, err = _run(capsys, "run", "--machine", str(f), "--out", str(tmp_path / "o"))
    assert code == 2 and "[bodies] platform: inertia_kgm2" in err and "triangle inequality" in err
    assert not (tmp_path / "o").exists()


def test_unreachable_motion_is_refused_and_nothing_written(capsys, tmp_path):
    f = tmp_path / "m.csv"
    rows = [(0.1 * k, -1.0 - 0.15 * k) for k in range(10)]  # below the reach (1.768 m) from the 6th row
    f.write_text("t_s,x_m,y_m,z_m,xd_m_s,yd_m_s,zd_m_s\n" + "".join(f"{t:g},0,0,{z:g},0,0,0\n" for t, z in rows),
                 encoding="utf-8")
    code, _, err = _run(capsys, "run", "--machine", "delta", "--motion", str(f), "--out", str(tmp_path / "o"))
    assert code == 2 and "sample 6 (t = 0.6 s)" in err and "unreachable" in err
    assert not (tmp_path / "o").exists()


def test_the_worked_example_of_the_format_document_runs_as_documented(capsys, tmp_path):
    from pathlib import Path

    doc = (Path(__file__).resolve().parents[1] / "docs" / "mechanism_format.md").read_text(encoding="utf-8")
    block = doc.split("## Worked example")[1].split("```toml\n")[1].split("```")[0]
    f = tmp_path / "four_bar.toml"
    f.write_text(block, encoding="utf-8")
    code, out, err = _run(capsys, "describe", "--machine", str(f))
    assert code == 0, err
    assert "spanning tree: A, B, C" in out and "cut joints (independent loops 1): D" in out
    assert "Grubler-Kutzbach mobility: -2" in out and "mobility (rank at the reference configuration): 1" in out
    assert "over-constraints: 3 (D force_z, D couple_x, D couple_y)" in out
    code, _, err = _run(capsys, "run", "--machine", str(f), "--out", str(tmp_path / "o"))
    assert code == 0, err


def test_describe_the_hip_and_the_pdm_from_their_parameters(capsys):
    code, out, _ = _run(capsys, "describe", "--machine", "hip")
    assert code == 0
    assert "moving bodies: 11" in out and "degrees of freedom: 3" in out and "over-constraints: 0" in out
    code, out, _ = _run(capsys, "describe", "--machine", "pdm")
    assert code == 0 and "moving bodies: 14" in out and "over-constraints: 9 (R21' force_z" in out


@pytest.mark.parametrize("name, actuator", [("hip", "P_1_pos_m"), ("pdm", "P11_pos_m")])
def test_run_a_hand_built_machine_writes_the_common_files(capsys, tmp_path, name, actuator):
    from pkmdyn.machines.registry import generated

    code, _, err = _run(capsys, "run", "--machine", name, "--out", str(tmp_path / "o"))
    assert code == 0, err
    assert {"results.csv", "model.json", "bodies.npz", "summary.json"} <= {p.name for p in (tmp_path / "o").iterdir()}
    cols = np.genfromtxt(tmp_path / "o" / "results.csv", delimiter=",", names=True)
    assert actuator in cols.dtype.names and "euler1_rad" in cols.dtype.names
    assert np.allclose(cols["t_s"], generated(name).default_motion().t)


def test_registry_reads_the_machine_folders():
    """Every folder with ``<name>.toml`` or a ``machine.py`` is a built-in machine; a hand-built
    entry provides what the machine-independent commands use, and an unknown name is refused."""
    from pkmdyn.errors import ParameterError
    from pkmdyn.machines import registry

    hand = registry.generated_machines()
    assert set(hand) == {"hip", "pdm"}
    assert set(registry.described_machines()) >= {"stewart", "delta", "rrr3", "bennett"}
    assert registry.builtin_names() == sorted({*hand, *registry.described_machines()})
    for name, entry in hand.items():
        assert entry.NAME == name and entry.CONTROL_SETTINGS.is_file() and entry.TITLE
        assert "[geometry]" in entry.default_params_text()
        assert isinstance(entry.description(), dict) and len(entry.default_motion().t) > 1
    with pytest.raises(ParameterError, match="unknown machine"):
        registry.resolve("no-such-machine")
    with pytest.raises(ParameterError, match="not a generated machine"):
        registry.generated("stewart")


def test_control_takes_every_machine_of_the_registry(capsys, tmp_path):
    """``pkmdyn control --machine hip`` is ``pkmdyn hip control`` (the same table, byte for byte);
    a described mechanism tracks its default motion; options of the other kind are refused."""
    args = ["--controller", "augmented-pd", "--cycles", "0.05", "--no-plots"]
    assert _run(capsys, "control", "--machine", "hip", *args, "--out", str(tmp_path / "a"))[0] == 0
    assert _run(capsys, "hip", "control", *args, "--out", str(tmp_path / "b"))[0] == 0
    assert (tmp_path / "a" / "control.csv").read_bytes() == (tmp_path / "b" / "control.csv").read_bytes()
    code, _, err = _run(capsys, "control", "--machine", "stewart", "--duration", "0.05", "--out", str(tmp_path / "s"))
    assert code == 0, err
    cols = np.genfromtxt(tmp_path / "s" / "control.csv", delimiter=",", names=True)
    assert cols.shape[0] >= 20 and all(np.isfinite(cols[n]).all() for n in cols.dtype.names)
    for bad in (["--machine", "stewart", "--cycles", "2"], ["--machine", "hip"],
                ["--machine", "hip", "--controller", "pd", "--duration", "1"],
                ["--machine", "stewart", "--controller", "pdx"]):
        code, _, err = _run(capsys, "control", *bad, "--out", str(tmp_path / "refused"))
        assert code == 2 and len(err.strip().splitlines()) == 1 and not (tmp_path / "refused").exists()


def test_run_machine_hip_carries_the_iso_load_and_matches_the_hip_job(tmp_path, capsys):
    """``pkmdyn run --machine hip``: the ISO cycle with its load as the named load hydraulic_N;
    the slider efforts, taken to the motors (lead screw rotor and friction added, none in the
    default file), equal the torques of ``pkmdyn hip run`` on the same cycle (every friction
    family of the default file, Eq. 16 under the load included)."""
    import csv

    from pkmdyn.machines.hip_simulator import load_params

    assert _run(capsys, "run", "--machine", "hip", "--out", str(tmp_path / "g"))[0] == 0
    assert _run(capsys, "hip", "run", "--no-plots", "--out", str(tmp_path / "h"))[0] == 0
    g = list(csv.DictReader((tmp_path / "g" / "results.csv").open()))
    h = list(csv.DictReader((tmp_path / "h" / "results.csv").open()))
    load = np.array([float(r["hydraulic_N"]) for r in g])
    assert load.max() > 1000.0
    hip = load_params()
    assert hip.friction.screw_coulomb == 0.0 and hip.friction.screw_viscous == 0.0
    gear = hip.geometry.p / (2 * np.pi)
    tg = np.array([[gear * float(r[f"P_{i}_effort_N"]) + hip.inertia.I_L * float(r[f"P_{i}_acc_m_s2"]) / gear
                    for i in (1, 2, 3)] for r in g])
    tcols = ["tau1_Nm", "tau2_Nm", "tau3_Nm"]
    th = np.array([[float(r[c]) for c in tcols] for r in h])
    assert tg.shape == th.shape
    assert np.abs(tg - th).max() <= 1e-8 * np.abs(th).max()


def test_a_floating_point_warning_inside_a_command_is_one_line(capsys, monkeypatch):
    """numpy's overflow warning anywhere in a command ends it with one line and exit 2 (not the
    warning's lines on stderr and a run written with infinities)."""
    import pkmdyn.jobs.describe as describe_job

    def overflowing(*args, **kwargs):
        np.exp(np.array([1000.0]))
        raise AssertionError("the overflow should have stopped the command")

    monkeypatch.setattr(describe_job, "load_machine", overflowing)
    code, _, err = _run(capsys, "describe", "--machine", "stewart")
    assert code == 2 and "overflow" in err and err.count("\n") == 1, err
