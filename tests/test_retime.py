"""The fastest timing of a path (``pkmdyn retime``, :mod:`pkmdyn.multibody.analyses.retime`)
against closed forms of a slider (bang-bang and trapezoidal profiles, with gravity and Coulomb
friction), and its timed motions rerun through ``pkmdyn run``: every bound met, one at its
bound almost everywhere (time-optimality's signature); bad paths and limits refused."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest
from slider_machine import MASS
from slider_machine import slider as _slider

import pkmdyn
from pkmdyn.cli import main
from pkmdyn.errors import LimitError, MotionError
from pkmdyn.multibody.analyses.retime import RetimeLimits, limit_use, retime, task_path

DATA = Path(__file__).parent / "data"
G = 9.80665


def _bang_bang(d: float, m: float, up: float, down: float, vmax: float = math.inf) -> float:
    """Rest-to-rest time over ``d`` with the greatest acceleration ``up`` and deceleration
    ``down`` (each > 0) and the speed bound ``vmax``: the closed form of the time-optimal
    (bang-bang, or trapezoidal where the speed bound is reached) profile."""
    d1 = d * down / (up + down)  # distance accelerating
    v = math.sqrt(2 * up * d1)
    if v <= vmax:
        return v / up + v / down
    cruise = d - vmax ** 2 / (2 * up) - vmax ** 2 / (2 * down)
    return vmax / up + vmax / down + cruise / vmax


def _limits(model, effort: float) -> RetimeLimits:
    nj = len(model.joint_names)
    return RetimeLimits(np.full(model.na, effort), np.full(nj, np.inf), np.full(nj, np.inf), {})


def test_horizontal_slider_reaches_the_bang_bang_time(tmp_path):
    model = pkmdyn.load(_slider(tmp_path, False))
    d, F = 0.3, 10.0
    r = retime(model, task_path(model, np.array([[0.0], [d]])), 1001, _limits(model, F))
    assert r.cycle_time == pytest.approx(_bang_bang(d, MASS, F / MASS, F / MASS), rel=1e-6)


def test_vertical_slider_with_gravity_and_coulomb_friction_reaches_the_closed_form(tmp_path):
    """Up against gravity with Coulomb friction f: accelerating at (F - m g - f)/m, braking at
    (F + m g + f)/m; without friction the time is shorter."""
    d, F, f = 0.3, 50.0, 3.0
    model = pkmdyn.load(_slider(tmp_path, True, f))
    path = task_path(model, np.array([[0.0], [d]]))
    with_f = retime(model, path, 1001, _limits(model, F))
    assert with_f.cycle_time == pytest.approx(_bang_bang(d, MASS, (F - MASS * G - f) / MASS, (F + MASS * G + f) / MASS),
                                              rel=1e-5)
    without = retime(model, path, 1001, _limits(model, F), friction=False)
    assert without.cycle_time == pytest.approx(_bang_bang(d, MASS, (F - MASS * G) / MASS, (F + MASS * G) / MASS),
                                               rel=1e-6)
    assert without.cycle_time < with_f.cycle_time
    # the timed motion through the engine's inverse dynamics: the effort within its bound, and at it
    kin = pkmdyn.kinematics(model, with_f.motion())
    u = pkmdyn.dynamics(model, kin).reactions.u[:, 0]
    assert np.max(np.abs(u)) <= F * (1 + 1e-6)
    assert np.mean(np.abs(u) >= 0.99 * F) >= 0.95


def test_a_speed_limit_gives_the_trapezoidal_time(tmp_path):
    model = pkmdyn.load(_slider(tmp_path, False))
    d, F, v = 0.3, 10.0, 0.8
    lim = RetimeLimits(np.full(1, F), np.full(1, np.inf), np.full(1, np.inf), {"max_joint_speed_m_s": v})
    r = retime(model, task_path(model, np.array([[0.0], [d]])), 2001, lim)
    assert r.cycle_time == pytest.approx(_bang_bang(d, MASS, F / MASS, F / MASS, v), rel=1e-5)
    assert np.max(r.xd) <= v * (1 + 1e-9)


def test_a_reaction_bound_is_met_and_slows_the_stewart_platform():
    model = pkmdyn.load("stewart")
    path = task_path(model, pkmdyn.default_motion(model).x)
    nj = len(model.joint_names)
    free = retime(model, path, 300, RetimeLimits(np.full(model.na, 3000.0), np.full(nj, np.inf), np.full(nj, np.inf), {}))
    kin = pkmdyn.kinematics(model, free.motion())
    F = np.linalg.norm(pkmdyn.dynamics(model, kin).reactions.joint_force, axis=-1).max()
    bound = RetimeLimits(np.full(model.na, 3000.0), np.full(nj, 0.8 * F), np.full(nj, np.inf), {})
    held = retime(model, path, 300, bound)
    assert held.cycle_time > free.cycle_time
    kin = pkmdyn.kinematics(model, held.motion())
    use = limit_use(model, kin, pkmdyn.dynamics(model, kin).reactions, bound)
    forces = np.linalg.norm(pkmdyn.dynamics(model, kin).reactions.joint_force, axis=-1)
    assert forces.max() <= 0.8 * F * (1 + 1e-6)
    assert use.largest.max() <= 1 + 1e-6


def _column(path: Path, names: list[str]) -> np.ndarray:
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return np.array([[float(r[n]) for n in names] for r in rows])


def test_the_delta_pick_and_place_timed_then_run(tmp_path, capsys):
    """The Delta benchmark's cycle (305 mm across along a 25 mm arch and back): its timed motion,
    run through ``pkmdyn run``, uses its effort bound at most 100 % + 1e-6 and at 99 % or more at
    95 % of the samples."""
    t = np.linspace(0.0, 0.5, 201)
    s = np.where(t <= 0.25, t / 0.25, 2.0 - t / 0.25)
    w = s ** 3 * (10.0 - 15.0 * s + 6.0 * s ** 2)
    path = tmp_path / "pick.csv"
    np.savetxt(path, np.column_stack([-0.1525 + 0.305 * w, 0.0 * t, -1.0 + 0.025 * np.sin(np.pi * w)]),
               delimiter=",", header="x_m,y_m,z_m", comments="", fmt="%.12g")
    bound = 30.0
    assert main(["retime", "--machine", "delta", "--path", str(path), "--max-effort", f"all={bound}",
                 "--points", "600", "--out", str(tmp_path / "t")]) == 0
    doc = json.loads((tmp_path / "t" / "retime.json").read_text())
    assert doc["largest_use_ratio"] <= 1 + 1e-6
    assert main(["run", "--machine", "delta", "--motion", str(tmp_path / "t" / "timed_motion.csv"),
                 "--out", str(tmp_path / "r")]) == 0
    capsys.readouterr()
    model = pkmdyn.load("delta")
    u = np.abs(_column(tmp_path / "r" / "results.csv", [f"{a}_effort_Nm" for a in model.actuator_names]))
    assert u.max() <= bound * (1 + 1e-6)
    assert np.mean(u.max(axis=1) >= 0.99 * bound) >= 0.95
    assert doc["cycle_time_s"] == pytest.approx(_column(tmp_path / "r" / "results.csv", ["t_s"])[-1, 0], rel=1e-12)


def _one_error(capsys, *words):
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("pkmdyn: error: "), err
    for w in words:
        assert w in err, err


def test_gravity_beyond_the_effort_bound_is_refused_naming_the_point_and_bound(tmp_path, capsys):
    machine = _slider(tmp_path, True)
    path = tmp_path / "up.csv"
    path.write_text("z_m\n0.0\n0.3\n")
    out = tmp_path / "o"
    assert main(["retime", "--machine", str(machine), "--path", str(path), "--max-effort", "P=15",
                 "--out", str(out)]) == 2
    _one_error(capsys, "path point", "effort of P", "15")
    assert not out.exists()


def test_a_path_with_a_repeated_row_is_refused_naming_the_row(tmp_path, capsys):
    path = tmp_path / "rep.csv"
    path.write_text("x_m\n0.0\n0.1\n0.1\n0.2\n")
    out = tmp_path / "o"
    assert main(["retime", "--machine", str(_slider(tmp_path, False)), "--path", str(path), "--max-effort",
                 "all=10", "--out", str(out)]) == 2
    _one_error(capsys, "row 3 repeats row 2")
    assert not out.exists()
    with pytest.raises(MotionError, match="row 3 repeats row 2"):
        model = pkmdyn.load(_slider(tmp_path, False))
        task_path(model, np.array([[0.0], [0.1], [0.1]]))


def test_a_path_out_of_the_workspace_and_unknown_bounds_are_refused(tmp_path, capsys):
    path = tmp_path / "far.csv"
    path.write_text("x_m,y_m,z_m\n0,0,-1\n0,0,-4\n")  # the Delta's arms do not reach 4 m down
    out = tmp_path / "o"
    assert main(["retime", "--machine", "delta", "--path", str(path), "--out", str(out)]) == 2
    _one_error(capsys, "path", "unreachable")
    assert main(["retime", "--machine", "stewart", "--max-effort", "Q_9=10", "--out", str(out)]) == 2
    _one_error(capsys, "--max-effort", "Q_9")
    assert main(["retime", "--machine", "stewart", "--max-effort", "all=-1", "--out", str(out)]) == 2
    _one_error(capsys, "--max-effort", "> 0")
    assert not out.exists()


def test_limits_no_timing_meets_raise_a_limit_error(tmp_path):
    model = pkmdyn.load(_slider(tmp_path, True))
    with pytest.raises(LimitError, match=r"path point 0 .*effort of P"):
        retime(model, task_path(model, np.array([[0.0], [0.3]])), 101, _limits(model, 0.5 * MASS * G))
