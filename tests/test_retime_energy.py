"""The least-energy timing of a path for a given cycle time and the Pareto curve (``pkmdyn retime
--cycle-time``, ``--pareto``; :mod:`pkmdyn.multibody.analyses.retime_energy`).

Oracles written apart from the program:
- a slider of mass m moved over d from rest to rest in the time T with the least integral of its
  squared force: the force is ``m a + g_s`` with ``a`` linear in time (the cubic ``x = d (3 tau^2 -
  2 tau^3)``), whence ``int F^2 dt = 12 m^2 d^2 / T^3 + g_s^2 T`` for a constant ``g_s`` (gravity
  along the rail and Coulomb friction; the cross term vanishes because ``int a dt = 0``), and the
  friction dissipates ``f d``;
- any other timing of the same path with the same cycle time costs at least as much (the
  least-time timing slowed down uniformly), both measured through ``pkmdyn run``'s inverse
  dynamics."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from slider_machine import K_F, MASS, OHM
from slider_machine import slider as _slider

import pkmdyn
from pkmdyn.cli import main
from pkmdyn.errors import LimitError, ParameterError
from pkmdyn.multibody.analyses.retime import (
    RetimeLimits,
    limit_use,
    retime,
    task_path,
    timing_energy,
)
from pkmdyn.multibody.analyses.retime_energy import pareto_front, retime_energy
from pkmdyn.multibody.kinematics.motion import TaskMotion

G = 9.80665


def _limits(model, effort: float) -> RetimeLimits:
    nj = len(model.joint_names)
    return RetimeLimits(np.full(model.na, effort), np.full(nj, np.inf), np.full(nj, np.inf), {})


def _energy(model, t, x, xd, xdd) -> dict:
    """Eq. (E1) through the engine's kinematics and inverse dynamics, as ``pkmdyn run`` computes them."""
    kin = pkmdyn.kinematics(model, TaskMotion(t, x, xd, xdd, {}))
    return timing_energy(model, kin, pkmdyn.dynamics(model, kin).reactions)


@pytest.mark.parametrize("vertical, f, motor", [(False, 0.0, False), (True, 3.0, False), (True, 3.0, True)])
def test_slider_reaches_the_least_squared_force_closed_form(tmp_path, vertical, f, motor):
    model = pkmdyn.load(_slider(tmp_path, vertical, f, motor))
    d, T = 0.3, 0.35
    e = retime_energy(model, task_path(model, np.array([[0.0], [d]])), T, 1001, _limits(model, 80.0))
    gs = (MASS * G if vertical else 0.0) + f
    squared = 12 * MASS ** 2 * d ** 2 / T ** 3 + gs ** 2 * T
    w = OHM / K_F ** 2 if motor else 1.0
    r = e.timing
    assert r.cycle_time == pytest.approx(T, rel=1e-6) and r.cycle_time <= T
    assert not e.beyond_least_energy
    checked = _energy(model, r.t, r.x, r.xd, r.xdd)
    # the check integrates over the timed motion's samples, whose first and last steps are each
    # about 2 % of the cycle (a uniform grid in s leaves rest slowly), with the regularised
    # friction zero at the samples at rest: an error of order sqrt(grid step) there, 0.6 % here
    assert checked["copper_loss_J"] == pytest.approx(w * squared, rel=2e-2)
    assert checked["friction_dissipation_J"] == pytest.approx(f * d, rel=1e-3, abs=1e-12)
    assert e.energy_J == pytest.approx(w * squared + f * d, rel=1e-4)  # (1.6e-5 at most measured)
    # the speed profile of the closed form, 6 d / T tau (1 - tau), at the timing's own times
    tau = r.t / r.cycle_time
    assert np.max(np.abs(r.xd[:, 0] - 6 * d / T * tau * (1 - tau))) <= 2e-3 * 1.5 * d / T


def test_least_energy_is_reached_sooner_where_holding_the_weight_costs_more(tmp_path):
    """The vertical slider's energy 12 m^2 d^2 / T^3 + (m g)^2 T is least at T* = sqrt(6 m d / (m g)):
    within a longer cycle time the timing stops there."""
    model = pkmdyn.load(_slider(tmp_path, True))
    d = 0.3
    t_star = np.sqrt(6 * MASS * d / (MASS * G))
    e = retime_energy(model, task_path(model, np.array([[0.0], [d]])), 1.5 * t_star, 1001, _limits(model, 80.0))
    assert e.beyond_least_energy
    assert e.timing.cycle_time == pytest.approx(t_star, rel=2e-3)


def _pick_and_place() -> np.ndarray:
    """The Delta's pick-and-place path: 305 mm across along a 25 mm arch at z = -1 m."""
    u = np.linspace(0.0, 1.0, 101)
    w = u ** 3 * (10.0 - 15.0 * u + 6.0 * u ** 2)
    return np.column_stack([-0.1525 + 0.305 * w, 0.0 * u, -1.0 + 0.025 * np.sin(np.pi * w)])


def test_delta_least_energy_timing_costs_less_than_the_fastest_slowed_down_and_meets_every_bound():
    model = pkmdyn.load("delta")
    path = task_path(model, _pick_and_place())
    lim = _limits(model, 30.0)
    fastest = retime(model, path, 400, lim)
    T = 1.4 * fastest.cycle_time
    e = retime_energy(model, path, T, 400, lim, fastest=fastest)
    r = e.timing
    assert r.cycle_time == pytest.approx(T, rel=1e-6) and r.cycle_time <= T
    kin = pkmdyn.kinematics(model, r.motion())
    reac = pkmdyn.dynamics(model, kin).reactions
    assert limit_use(model, kin, reac, lim).largest.max() <= 1.0 + 1e-6
    least = timing_energy(model, kin, reac)["energy_J"]
    assert least == pytest.approx(e.energy_J, rel=5e-3)
    # the fastest timing slowed down uniformly to T: same path, same cycle time
    a = T / fastest.cycle_time
    slow = _energy(model, fastest.t * a, fastest.x, fastest.xd / a, fastest.xdd / a ** 2)["energy_J"]
    assert least < slow
    fast = _energy(model, fastest.t, fastest.x, fastest.xd, fastest.xdd)["energy_J"]
    assert least < fast


def test_pareto_curve_falls_with_the_cycle_time_and_starts_at_the_fastest(tmp_path):
    model = pkmdyn.load(_slider(tmp_path, False))
    d = 0.3
    path = task_path(model, np.array([[0.0], [d]]))
    lim = _limits(model, 10.0)
    fastest = retime(model, path, 501, lim)
    times = fastest.cycle_time * np.array([1.0, 1.25, 1.5, 2.0, 3.0])
    front = pareto_front(model, path, times, 501, lim, fastest=fastest)
    assert len(front) == 5
    assert front[0].timing is fastest
    E = [f.energy_J for f in front]
    assert all(b < a for a, b in zip(E, E[1:]))
    for f in front[1:]:  # the closed form once the force bound no longer acts
        T = f.timing.cycle_time
        if 6 * MASS * d / T ** 2 < 10.0:
            assert f.energy_J == pytest.approx(12 * MASS ** 2 * d ** 2 / T ** 3, rel=2e-3)
    with pytest.raises(ParameterError, match="ascending"):
        pareto_front(model, path, times[::-1], 501, lim, fastest=fastest)


def test_cycle_time_below_the_fastest_is_refused(tmp_path):
    model = pkmdyn.load(_slider(tmp_path, False))
    path = task_path(model, np.array([[0.0], [0.3]]))
    fastest = retime(model, path, 201, _limits(model, 10.0))
    with pytest.raises(LimitError, match="fastest timing within the limits takes"):
        retime_energy(model, path, 0.9 * fastest.cycle_time, 201, _limits(model, 10.0), fastest=fastest)


def test_command_writes_the_least_energy_timing_and_the_pareto_curve(tmp_path, capsys):
    desc = _slider(tmp_path, True, 3.0, True)
    out = tmp_path / "out"
    path = tmp_path / "path.csv"
    path.write_text("z_m\n0.0\n0.3\n")
    rc = main(["retime", "--machine", str(desc), "--path", str(path), "--points", "301", "--max-effort", "P=80",
               "--cycle-time", "0.35", "--pareto", "4", "--pareto-span", "2.5", "--no-plots", "--out", str(out)])
    assert rc == 0
    doc = json.loads((out / "retime.json").read_text())
    assert doc["objective"] == "least energy within the cycle time"
    assert doc["cycle_time_s"] <= 0.35 and doc["cycle_time_s"] == pytest.approx(0.35, rel=1e-6)
    assert doc["copper_loss_coefficients"][0]["copper_loss_coefficient_W_per_effort2"] == pytest.approx(OHM / K_F ** 2)
    assert doc["copper_loss_coefficients"][0]["from_description"] is True
    assert doc["energy_J"] == pytest.approx(doc["copper_loss_J"] + doc["friction_dissipation_J"])
    with open(out / "pareto.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert 2 <= len(rows) <= 4
    T = [float(r["cycle_time_s"]) for r in rows]
    E = [float(r["energy_J"]) for r in rows]
    assert all(b > a for a, b in zip(T, T[1:])) and all(b < a for a, b in zip(E, E[1:]))
    assert all(float(r["largest_use_ratio"]) <= 1 + 1e-6 for r in rows)
    # the timed motion is a motion file pkmdyn run takes
    assert main(["run", "--machine", str(desc), "--motion", str(out / "timed_motion.csv"),
                 "--out", str(tmp_path / "run")]) == 0


def test_command_refuses_a_cycle_time_below_the_fastest_writing_nothing(tmp_path, capsys):
    desc = _slider(tmp_path, False)
    out = tmp_path / "out"
    rc = main(["retime", "--machine", str(desc), "--points", "101", "--max-effort", "P=10", "--cycle-time", "0.01",
               "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and not out.exists()
    assert len(err) == 1 and "cycle time 0.01 s" in err[0]


@pytest.mark.parametrize("replacement", ["", "winding_resistance_ohm = 0.0\n"])
def test_a_motor_constant_without_a_positive_resistance_is_refused(tmp_path, replacement):
    text = _slider(tmp_path, False, motor=True).read_text().replace(f"winding_resistance_ohm = {OHM}\n", replacement)
    f = tmp_path / "bad.toml"
    f.write_text(text)
    with pytest.raises(ParameterError, match="winding_resistance_ohm"):
        pkmdyn.load(f)
