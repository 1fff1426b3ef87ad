"""The task body's whole pose and the described outputs in results.csv: a 3-RPS's parasitic
motions against their closed form (tests/oracles/rps3.py, Lee & Shah 1988), the task columns
against the pose columns on the built-ins, and the refusals of bad ``[[outputs]]``."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from oracles import rps3
from pkmdyn.cli import main

RPS = Path(__file__).parent / "data" / "rps3.toml"
A, B, H = 0.5, 0.25, 0.6  # the description's parameters


def _table(path):
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return {k: np.array([float(r[i]) for r in rows[1:]]) for i, k in enumerate(rows[0])}


def test_the_oracle_meets_every_legs_plane():
    """The closed form keeps each spherical centre in its leg's plane; a wrong platform radius
    does not (so the check can fail)."""
    rng = np.random.default_rng(3)
    al, be = rng.uniform(-0.4, 0.4, 50), rng.uniform(-0.4, 0.4, 50)
    for radius, ok in ((B, True), (1.3 * B, False)):
        x, y, g = rps3.parasitic(al, be, radius)
        R = rps3.rotation(al, be, g)
        p = np.stack([x, y, np.full_like(x, H)], axis=1)
        worst = 0.0
        for th in np.radians([0.0, 120.0, 240.0]):
            s = B * np.array([np.cos(th), np.sin(th), 0.0])
            t = np.array([-np.sin(th), np.cos(th), 0.0])
            worst = max(worst, float(np.abs((p + R @ s) @ t).max()))
        assert (worst < 1e-14) == ok


def test_a_3rps_run_writes_its_parasitic_motions(tmp_path):
    out = tmp_path / "run"
    assert main(["run", "--machine", str(RPS), "--out", str(out)]) == 0
    c = _table(out / "results.csv")
    al, be = c["euler1_rad"], c["euler2_rad"]
    assert np.ptp(al) > 0.2 and np.ptp(be) > 0.15
    x, y, g = rps3.parasitic(al, be, B)
    assert np.abs(x).max() > 1e-4 and np.abs(y).max() > 1e-3 and np.abs(g).max() > 1e-3  # the motions are there to see
    np.testing.assert_allclose(c["task_body_x_m"], x, rtol=0, atol=1e-10)
    np.testing.assert_allclose(c["task_body_y_m"], y, rtol=0, atol=1e-10)
    np.testing.assert_allclose(c["task_body_euler3_rad"], g, rtol=0, atol=1e-10)
    # the task's own coordinates, where they are pose coordinates, are the same numbers
    for task, pose in (("z_m", "task_body_z_m"), ("euler1_rad", "task_body_euler1_rad"),
                       ("euler2_rad", "task_body_euler2_rad")):
        np.testing.assert_allclose(c[pose], c[task], rtol=0, atol=1e-12)
    # [[outputs]] leg1_tip: the first leg's spherical centre on its piston, the piston tilted
    # about the leg's revolute axis (y) only
    p = np.stack([x, y, c["z_m"]], axis=1)
    C, tilt = rps3.leg_tilt(p, rps3.rotation(al, be, g), A, B, H)
    for k, name in enumerate("xyz"):
        np.testing.assert_allclose(c[f"leg1_tip_{name}_m"], C[:, k], rtol=0, atol=1e-10)
    np.testing.assert_allclose(c["leg1_tip_euler2_rad"], tilt, rtol=0, atol=1e-10)
    assert np.abs(tilt).max() > 1e-2
    np.testing.assert_allclose(c["leg1_tip_euler1_rad"], 0.0, atol=1e-10)
    np.testing.assert_allclose(c["leg1_tip_euler3_rad"], 0.0, atol=1e-10)
    assert all(np.isfinite(v).all() for v in c.values())


def test_the_report_plots_the_poses(tmp_path):
    out = tmp_path / "run"
    assert main(["run", "--machine", str(RPS), "--out", str(out)]) == 0
    page = (out / "report.html").read_text()
    assert "Poses: positions (task body and outputs)" in page and "leg1_tip_euler2_rad" in page
    assert "task_body_euler3_rad" in page


@pytest.mark.parametrize("name", ["stewart", "rrr3", "delta", "bennett"])
def test_the_task_columns_are_the_pose_columns_where_they_are_the_same(tmp_path, name):
    out = tmp_path / name
    assert main(["run", "--machine", name, "--out", str(out)]) == 0
    c = _table(out / "results.csv")
    import json

    task = json.loads((out / "model.json").read_text())["task"]["coordinates"]
    assert task
    for entry in task:
        pose = (f"task_body_{'xyz'[entry['component']]}_m" if entry["kind"] == "position"
                else f"task_body_euler{entry['angle']}_rad")
        np.testing.assert_allclose(c[pose], c[entry["column"]], rtol=0, atol=1e-12)


@pytest.mark.parametrize("entry, words", [
    ('name = "tip"\nbody = "nobody"', "[outputs][0] body: 'nobody' is not a body"),
    ('name = "task_body"\nbody = "platform"', "[outputs][0] name: 'task_body' is taken"),
    ('name = "P_pos_m"\nbody = "platform"', "[outputs][0] name: 'P_pos_m' reads as a joint's column"),
    ('name = "1tip"\nbody = "platform"', "[outputs] 1tip name: String should match"),
])
def test_bad_outputs_are_refused(tmp_path, capsys, entry, words):
    text = RPS.read_text().replace('name = "leg1_tip"\nbody = "piston_1"\npoint_m = "top_m"', entry)
    assert text != RPS.read_text()
    path = tmp_path / "bad.toml"
    path.write_text(text)
    out = tmp_path / "out"
    assert main(["run", "--machine", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0], err
    assert not out.exists()
