"""The least singularity measures of a run (pkmdyn.multibody.kinematics.singularity.measures.least_measures): equal,
bit for bit, to the least of every sample's singular value decompositions
(``singularity_measures``), whatever the order of the samples (a smooth motion, shuffled poses,
one pose repeated, a pose near a singularity), on every built-in mechanism and on mechanisms
without a direct measure or without loop rows; given the least of other samples (``below``),
the least of both; and the brackets it decides by, the anchors' and the screened samples'
Weyl bounds alike, hold every sample's decomposition (to its rounding)."""

from __future__ import annotations

import numpy as np
import pytest

import multibody_examples as ex
from pkmdyn.machines.registry import resolve
from pkmdyn.multibody import default_motion, load_mechanism, solve_kinematics
from pkmdyn.multibody.kinematics.singularity._kernels import measure_brackets
from pkmdyn.multibody.kinematics.singularity.measures import SCREEN_STRIDE, _measure_arguments, least_measures, singularity_measures
from pkmdyn.multibody.model.compiler import compile_model
from pkmdyn.multibody.description.schema import load_description


def _reference(model, q):
    sm = singularity_measures(model, q)
    return {"inverse": float(sm.inverse.min()), "constraint": float(sm.constraint.min()),
            "direct": float("nan") if np.isnan(sm.direct).all() else float(np.nanmin(sm.direct))}


def _same(a, b):
    return all((np.isnan(a[k]) and np.isnan(b[k])) or a[k] == b[k] for k in a)


def _fine(q, factor):
    """``q`` with ``factor - 1`` poses linearly between each two (a finer motion)."""
    s = np.linspace(0, q.shape[0] - 1, (q.shape[0] - 1) * factor + 1)
    return np.stack([np.interp(s, np.arange(q.shape[0]), q[:, j]) for j in range(q.shape[1])], axis=1)


def _builtin(name):
    entry, path = resolve(name)
    m = load_mechanism(path if entry is None else entry.description())
    mo = default_motion(m)
    return m, solve_kinematics(m, mo.x, mo.xd, mo.xdd, mo.t).q


@pytest.mark.parametrize("name", ["stewart", "delta", "rrr3", "bennett", "pdm", "hip"])
def test_equal_to_every_samples_decomposition(name):
    m, q = _builtin(name)
    rng = np.random.default_rng(3)
    for order in (_fine(q, 4), q[rng.permutation(q.shape[0])], np.repeat(q[:7], 3, axis=0), q[:1]):
        assert _same(least_measures(m, order), _reference(m, order))


def _brackets(m, q, below=(np.inf, np.inf, np.inf), stride=SCREEN_STRIDE):
    lohi = np.ones((q.shape[0], 3, 2))
    measure_brackets(*_measure_arguments(m, q), stride, np.asarray(below, dtype=float), lohi)
    return lohi


@pytest.mark.parametrize("name", ["stewart", "delta", "rrr3"])
def test_brackets_hold_every_samples_decomposition(name):
    m, q = _builtin(name)
    q = np.concatenate([_fine(q, 3), q[::-1]])  # a jump back to the start, then backwards
    sm = singularity_measures(m, q)
    vals = np.stack([sm.constraint, sm.inverse, sm.direct], axis=1)
    have = ~np.isnan(vals)
    fine = (q.shape[0] - q.shape[0] // 4) // 2  # about the first half of the fine motion
    for stride in (1, SCREEN_STRIDE, 50):
        lohi = _brackets(m, q, stride=stride)
        lo, hi = lohi[:, :, 0], lohi[:, :, 1]
        # the decomposition's own rounding: relative 1e-12 of each value (least_measures allows 1e-8)
        assert np.all((lo <= vals * (1 + 1e-12) + 1e-15)[have]) and np.all((vals <= hi * (1 + 1e-12) + 1e-15)[have])
        assert np.all(lo <= hi)
        width = (hi - lo) / vals
        # the first sample's bracket as tight as rounding allows (its state by an eigendecomposition)
        assert np.all(width[0][have[0]] < 1e-6)
        if stride < 50:  # the samples bracketed along the fine motion, narrowly: few decompositions
            anchors = np.zeros(q.shape[0], dtype=bool)
            anchors[::stride] = True
            bracketed = ((hi < 1.0) | anchors[:, None]) & have
            assert np.nanmedian(width[:fine][bracketed[:fine]]) < 1e-2


def _svd_measure(A):
    sv = np.linalg.svd(A, compute_uv=False)
    return sv[-1] / sv[0] if sv[0] > 0 else 0.0


def test_the_screen_holds_where_weyls_bound_is_nearly_tight():
    """Three coordinates, two loop rows and one task row, the task row's entry ``b`` falling from
    0.5 to 0.2 over 33 samples (nearly diagonal: each singular value moves by about as much as the
    matrix, so a screen that leaves out a part of the difference, or takes another anchor's
    bounds, places samples above their measure); one sample's matrix all zero (no bounds proven
    there, nor from it: its small neighbour is not screened by an earlier anchor's bounds). Every bracket, anchors' and screened samples' alike, holds the measure
    of each sample's matrices by their own singular value decompositions."""
    n = 33
    b = np.linspace(0.5, 0.2, n)
    J = np.zeros((n, 3, 3))
    J[:, 0, 0], J[:, 0, 1], J[:, 1, 1], J[:, 2, 2], J[:, 2, 0] = 1.0, 0.02, 0.9, b, 0.01 * b
    J[16] = 0.0  # an anchor at stride 2, 4, 8 and 16
    J[17] = 1e-4 * np.diag([1.0, 1e-2, 1e-2])  # beside it, small: its measures about 1e-2
    cut, task, act = np.array([0, 1]), np.array([2]), np.array([2])
    unit = np.zeros((1, 3))
    unit[0, 2] = 1.0
    true = np.array([[_svd_measure(J[s, cut]), _svd_measure(J[s]), _svd_measure(np.vstack([J[s, cut], unit]))]
                     for s in range(n)])
    for stride in (2, 4, 8, 16, 100):
        for below in (np.inf, 0.3, 0.0):
            out = np.ones((n, 3, 2))
            measure_brackets(J, np.ones(3), np.ones(3), cut, task, np.zeros((0, 3)), act, True, stride,
                             np.full(3, below), out)
            lo, hi = out[:, :, 0], out[:, :, 1]
            assert np.all(lo <= true * (1 + 1e-12) + 1e-15) and np.all(true <= hi * (1 + 1e-12) + 1e-15), \
                (stride, below)
    empty = np.ones((0, 3, 2))  # no samples: nothing to do (nothing read or written)
    measure_brackets(J[:0], np.ones(3), np.ones(3), cut, task, np.zeros((0, 3)), act, True, 8, np.full(3, np.inf),
                     empty)


def test_no_samples_and_measures_without_rows():
    """No samples: each measure 1, as before (the direct one NaN where it does not apply); a
    measure without rows (a serial arm's loop measure) is 1 at every sample, so with ``below``
    the least of both."""
    m, q = _builtin("stewart")
    assert least_measures(m, q[:0]) == {"constraint": 1.0, "inverse": 1.0, "direct": 1.0}
    arm = compile_model(load_description(ex.serial_arm()))
    mo = default_motion(arm)
    qa = solve_kinematics(arm, mo.x, mo.xd, mo.xdd, mo.t).q
    ref = _reference(arm, qa)
    assert ref["constraint"] == 1.0
    got = least_measures(arm, qa, below={"constraint": 0.5, "inverse": 2.0})
    assert got["constraint"] == 0.5 and got["inverse"] == ref["inverse"]


@pytest.mark.parametrize("name", ["stewart", "hip", "rrr3"])
def test_below_gives_the_least_of_both(name):
    """``below`` (a least found elsewhere): the least of it and of the samples, whether it lies
    above every sample's measure, below every one or between; the motion taken in pieces, each
    given the least of those before (as a run takes its chunks), gives the whole motion's."""
    m, q = _builtin(name)
    ref = _reference(m, q)
    keys = ("constraint", "inverse", "direct")
    for scale in (2.0, 0.5, 1.0 + 1e-3):
        below = {k: ref[k] * scale for k in keys}
        want = {k: float(np.min([ref[k], below[k]])) for k in keys}
        if np.isnan(ref["direct"]):
            want["direct"] = float("nan")
        assert _same(least_measures(m, q, below=below), want), scale
    half = _reference(m, q[: q.shape[0] // 2])
    assert _same(least_measures(m, q, below={k: v for k, v in half.items() if not np.isnan(v)}), ref)
    running = {k: np.inf for k in keys}
    for piece in np.array_split(q, 5):
        found = least_measures(m, piece, below=running)
        running = {k: min(running[k], found[k]) if not np.isnan(found[k]) else running[k] for k in keys}
    assert _same({k: (running[k] if np.isfinite(running[k]) else float("nan")) for k in keys}, ref)
    # a below under every sample's measure: along a fine motion, nothing but the anchors bracketed
    qf = _fine(q, 4)
    ref = _reference(m, qf)
    half = [0.5 * ref["constraint"], 0.5 * ref["inverse"], 0.5 * np.nan_to_num(ref["direct"])]
    assert np.mean(_brackets(m, qf, below=half)[:, :2, 1] < 1.0) <= 1.0 / SCREEN_STRIDE + 2.0 / qf.shape[0]


def test_near_a_singularity_and_without_a_direct_measure():
    """A Gough-Stewart platform turned about its vertical axis through its type II singularity
    (the direct measure near 0 about 1.6 rad), forwards and backwards; and mechanisms whose
    direct measure does not apply (a planar platform with redundant rows) or without loop rows
    (a serial arm)."""
    m, q = _builtin("stewart")
    xs = np.tile(default_motion(m).x[0], (301, 1))
    xs[:, 5] += np.linspace(0.0, 3.0, 301)
    kin = solve_kinematics(m, xs, np.zeros_like(xs), np.zeros_like(xs), None)
    ref = _reference(m, kin.q)
    assert ref["direct"] < 0.1 * _reference(m, q)["direct"]  # the path passes near the singularity
    assert _same(least_measures(m, kin.q), ref) and _same(least_measures(m, kin.q[::-1]), ref)
    for d in (ex.rrr3_planar_platform(), ex.serial_arm(), ex.four_bar(), ex.sarrus()):
        mm = compile_model(load_description(d))
        mo = default_motion(mm)
        qm = solve_kinematics(mm, mo.x, mo.xd, mo.xdd, mo.t).q
        got, ref = least_measures(mm, qm), _reference(mm, qm)
        assert _same(got, ref), (mm.name, got, ref)


@pytest.mark.parametrize("name", ["stewart", "delta", "rrr3"])
def test_one_measure_alone_is_that_field_of_all_three(name):
    m, q = _builtin(name)
    full = singularity_measures(m, q)
    for key in ("inverse", "direct", "constraint"):
        one = singularity_measures(m, q, only=key)
        assert np.array_equal(getattr(one, key), getattr(full, key), equal_nan=True)
        assert all(np.isnan(getattr(one, other)).all() for other in ("inverse", "direct", "constraint") if other != key)
    with pytest.raises(ValueError, match="not a singularity measure"):
        singularity_measures(m, q, only="worst")


def test_a_pose_that_is_not_a_number_fails_as_every_samples_decompositions_do():
    m, q = _builtin("bennett")
    bad = q.copy()
    bad[3, 0] = np.nan
    with pytest.raises(np.linalg.LinAlgError):
        singularity_measures(m, bad)
    with pytest.raises(np.linalg.LinAlgError):  # (its bracket is not a number: decided by its decomposition)
        least_measures(m, bad)


@pytest.mark.parametrize("name", ["stewart", "delta"])
def test_a_sweeps_measure_metrics_are_every_samples_decompositions(name, tmp_path):
    """The sweep's conditioning index (the time mean of the direct measure) and least measures of
    a design, against every sample's three decompositions; a threshold above the least names the
    sample where the worst measure is least, as before."""
    from pkmdyn.machines.registry import sweep_adapter
    from pkmdyn.multibody.analyses.designs import evaluate_one
    from pkmdyn.sweep_protocol import time_mean

    ad = sweep_adapter(name)
    d = ad.base_description(None)
    ctx = ad.prepare(d, {}, tmp_path)
    out = evaluate_one(d, ctx)
    m = load_mechanism(d)
    mo = default_motion(m)
    sm = singularity_measures(m, solve_kinematics(m, mo.x, mo.xd, mo.xdd, mo.t).q)
    assert out.metrics["gci"] == float(time_mean(sm.direct, mo.t))
    assert out.metrics["min_inverse_measure"] == float(sm.inverse.min())
    assert out.metrics["min_constraint_measure"] == float(sm.constraint.min())
    assert out.metrics["min_direct_measure"] == float(sm.direct.min())
    worst = np.minimum(sm.inverse, sm.direct)
    k = int(np.argmin(worst))
    high = ad.prepare(d, {"singularity_threshold": float(worst[k]) * 1.5}, tmp_path)
    singular = evaluate_one(d, high)
    assert singular.status == "singular" and f"(sample {k + 1})" in singular.reason


def test_a_runs_least_measures_over_its_chunks_are_every_samples(tmp_path, capsys):
    """``pkmdyn run`` of 3,001 samples (three chunks, each given the least of those before):
    its summary's least measures are the least of every sample's decompositions."""
    import json

    from pkmdyn.cli import main
    from pkmdyn.jobs.run import CHUNK

    m, _ = _builtin("stewart")
    assert main(["run", "--machine", "stewart", "--samples-per-cycle", "3000", "--out", str(tmp_path / "r")]) == 0
    capsys.readouterr()
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    mo = default_motion(m, samples_per_cycle=3000)
    assert len(mo) > 2 * CHUNK and summary["samples"] == len(mo)
    ref = _reference(m, solve_kinematics(m, mo.x, mo.xd, mo.xdd, mo.t).q)
    for key in ("inverse", "direct", "constraint"):
        assert summary[f"min_{key}_singularity_measure"] == pytest.approx(ref[key], rel=1e-12), key

