"""Long control runs stream: the loop runs span by span with its state carried (the spans join
to the whole run), the table is written span by span (CSV or Parquet, the same numbers), memory
does not grow with the run, and multi-cycle plots show the first cycle over the band of all."""

from __future__ import annotations

import json
import tracemalloc

import numpy as np
import pyarrow.parquet as pq
import pytest

from pkmdyn.cli import main
from pkmdyn.jobs.control import machine_setup
from pkmdyn.report import PLOT_RAW_MAX, Curves
from pkmdyn.control import gains, load_settings, loop_settings
from pkmdyn.simulate import track, track_spans
from pkmdyn.simulate import _run


@pytest.mark.parametrize("machine, kind, n", [("hip", "augmented-pd", 3), ("hip", "computed-torque", 3),
                                              ("pdm", "pid", 4)])
def test_spans_join_to_the_whole_run(machine, kind, n):
    s = load_settings(machine)
    ls = loop_settings(s)  # the hip's pose sensor: noise and a delay of 2 cycles, carried across spans
    su = machine_setup(machine, None, None, None, 0.4, s)
    g = gains(s, kind, n)
    whole = track(su.verbs, su.model, su.plant_model, su.motion, 0.25, kind, g, ls, su.has_load,
                  joint_accelerations=True)
    parts = list(track_spans(su.verbs, su.model, su.plant_model, su.motion, 0.25, kind, g, ls, su.has_load,
                             joint_accelerations=True, span_cycles=37))
    assert len(parts) > 3
    for f in ("t", "q", "qd", "u", "q_s", "q_att", "s", "s_enc", "sd_enc", "sdd_enc"):
        joined = np.concatenate([getattr(p.result, f) for p in parts])
        np.testing.assert_allclose(joined, getattr(whole.result, f), rtol=0, atol=1e-9, err_msg=f)
    for f in ("s", "sd", "sdd"):
        joined = np.concatenate([getattr(p.joint, f)[:-1] for p in parts])
        np.testing.assert_allclose(joined, getattr(whole.joint, f)[:-1], rtol=0, atol=1e-12, err_msg=f)


def test_a_run_does_not_depend_on_what_the_verbs_solved_before():
    """The PDM's PID run from rest, once on fresh verbs and once after another run has left its
    warm starts (the solvers' last solutions) elsewhere: the same records. Two of the PDM's
    coordinates stay at rest by symmetry; their velocities' rounding signs once decided whether
    the first steps were refined (5e-6 rad apart in gamma)."""
    s = load_settings("pdm")
    ls = loop_settings(s)
    g = gains(s, "pid", 4)

    def run(su, duration):
        return track(su.verbs, su.model, su.plant_model, su.motion, duration, "pid", g, ls, su.has_load).result.q

    fresh = run(machine_setup("pdm", None, None, None, 0.4, s), 0.25)
    for before in (0.1, 0.17, 0.2, 0.3):
        su = machine_setup("pdm", None, None, None, 0.4, s)
        run(su, before)
        np.testing.assert_allclose(run(su, 0.25), fresh, rtol=0, atol=1e-9, err_msg=f"after a run of {before} s")


def test_parquet_holds_the_numbers_of_the_csv(tmp_path):
    base = ["hip", "control", "--controller", "pd", "--no-plots", "--cycles", "0.05"]
    assert main([*base, "--out", str(tmp_path / "c")]) == 0
    assert main([*base, "--format", "parquet", "--out", str(tmp_path / "p")]) == 0
    table = pq.read_table(tmp_path / "p" / "control.parquet")
    header = (tmp_path / "c" / "control.csv").read_text().splitlines()[0].split(",")
    data = np.loadtxt(tmp_path / "c" / "control.csv", delimiter=",", skiprows=1)
    assert table.column_names == header
    for i, name in enumerate(header):
        np.testing.assert_array_equal(table.column(name).to_numpy(), data[:, i])
    assert json.loads((tmp_path / "p" / "summary.json").read_text())["results_format"] == "parquet"


def _peak_bytes(args):
    tracemalloc.start()
    try:
        assert main(args) == 0
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


@pytest.mark.slow
def test_memory_does_not_grow_with_the_run(tmp_path, monkeypatch):
    monkeypatch.setattr(_run, "SPAN_CYCLES", 500)
    base = ["hip", "control", "--controller", "augmented-pd", "--no-plots", "--format", "parquet"]
    _peak_bytes([*base, "--cycles", "0.5", "--out", str(tmp_path / "w")])  # one-time costs (imports, compiles)
    short = _peak_bytes([*base, "--cycles", "2", "--out", str(tmp_path / "a")])  # 2,000 cycles: 4 spans
    long = _peak_bytes([*base, "--cycles", "8", "--out", str(tmp_path / "b")])  # 8,000 cycles: 16 spans
    assert long < 1.3 * short, (short, long)
    print(short, long)  # all at once, the long run's arrays alone are 4 times the short run's


def test_multi_cycle_plots_keep_the_first_cycle_and_the_band_of_every_cycle():
    T, fold = 0.001, 1000
    K = 12_000
    c = Curves(K, fold=fold)
    assert c.mode == "fold" and c.size == 1000
    t = np.arange(K) * T
    wave = np.sin(2 * np.pi * t)[:, None] * (1 + np.floor(t)[:, None])  # cycle i has amplitude i + 1
    for start in range(0, K, 700):
        c.add(start, t[start:start + 700], {"x": wave[start:start + 700]})
    d = c.data()
    tt, first, hi, note = d.t, d.first, d.hi, d.note
    assert tt.shape == (1000,) and np.allclose(tt, t[:1000])
    np.testing.assert_allclose(first["x"][:, 0], wave[:1000, 0])
    np.testing.assert_allclose(hi["x"][250, 0], 12.0)  # the largest cycle's peak at the quarter phase
    np.testing.assert_allclose(d.lo["x"][750, 0], -12.0)
    assert "12 motion cycles" in note
    assert Curves(PLOT_RAW_MAX, fold=fold).mode == "raw" and Curves(K).mode == "bins"


def test_a_many_cycle_run_writes_readable_plots(tmp_path):
    assert main(["hip", "control", "--controller", "pd", "--cycles", "6", "--out", str(tmp_path / "o")]) == 0
    assert {p.name for p in (tmp_path / "o").iterdir()} >= {"posture_errors.png", "efforts.png", "control.csv"}
