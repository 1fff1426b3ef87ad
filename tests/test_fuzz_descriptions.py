"""Generated hostile descriptions and space files (Hypothesis): one number of a built-in
description (or of a sweep's space file) replaced by an extreme value. The promise holds for
every one: either the command succeeds and every number it wrote is finite, or it ends with one
line on stderr, exit status 2, and writes nothing."""

from __future__ import annotations

import copy
import json
import math

import numpy as np
import pytest
import tomlkit
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import multibody_examples as ex
from pkmdyn.cli import main

EXTREMES = [1e300, -1e300, 1e30, -1e30, 1e15, -1e15, 1e-300, 0.0, -0.0, math.inf, -math.inf, math.nan, 3e7, -3e7]


def _leaves(d, path=()):
    """Paths of every number in a nested dict/list."""
    if isinstance(d, dict):
        for k, v in d.items():
            yield from _leaves(v, (*path, k))
    elif isinstance(d, list):
        for i, v in enumerate(d):
            yield from _leaves(v, (*path, i))
    elif isinstance(d, (int, float)) and not isinstance(d, bool):
        yield path


def _set(d, path, value):
    for p in path[:-1]:
        d = d[p]
    d[path[-1]] = value


def _hostile(tmp_path_factory, d, pick, value, name):
    """``d`` with its number number ``pick`` (modulo their count) set to ``value``, written as
    TOML file ``name`` in a fresh folder."""
    paths = list(_leaves(d))
    _set(d, paths[pick % len(paths)], value)
    f = tmp_path_factory.mktemp("fuzz") / name
    f.write_text(tomlkit.dumps(d))
    return f


def _finite_files(folder):
    """Every number in the folder's CSV and JSON files is finite."""
    for f in folder.iterdir():
        if f.suffix == ".csv":
            data = np.genfromtxt(f, delimiter=",", skip_header=1)
            assert np.all(np.isfinite(data)), f
        elif f.suffix == ".json":
            text = f.read_text()
            assert "NaN" not in text and "Infinity" not in text, f
            json.loads(text)


def _promise(capsys, code, out):
    err = capsys.readouterr().err
    if code == 0:
        if out is not None:
            _finite_files(out)
        return
    assert code == 2, err
    assert err.count("\n") == 1 and err.startswith("pkmdyn: error:"), err
    assert out is None or not out.exists()


NAMES = ["stewart", "delta", "rrr3", "bennett"]


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(name=st.sampled_from(NAMES), pick=st.integers(0, 10_000), value=st.sampled_from(EXTREMES))
def test_describe_a_hostile_description(tmp_path_factory, capsys, name, pick, value):
    f = _hostile(tmp_path_factory, ex.builtin_dict(name), pick, value, "m.toml")
    _promise(capsys, main(["describe", "--machine", str(f)]), None)


@pytest.mark.slow
@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(name=st.sampled_from(["stewart", "rrr3"]), pick=st.integers(0, 10_000), value=st.sampled_from(EXTREMES))
def test_run_a_hostile_description(tmp_path_factory, capsys, name, pick, value):
    d = ex.builtin_dict(name)
    d.setdefault("default_motion", {})["samples"] = 21
    f = _hostile(tmp_path_factory, d, pick, value, "m.toml")
    out = f.parent / "out"
    _promise(capsys, main(["run", "--machine", str(f), "--minimum-norm-reactions", "--out", str(out)]), out)


SPACE = {
    "sampling": {"method": "sobol", "designs": 4, "seed": 3, "batch_size": 2},
    "motion": {"reactions": False},
    "parameters": {"bodies[platform].mass_kg": {"min": 0.5, "max": 1.5},
                   "default_motion.amplitude.x_m": {"min": 0.01, "max": 0.03}},
    "objectives": {"gci": "max", "peak_effort_Nm": "min"},
}


@pytest.mark.slow
@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(pick=st.integers(0, 10_000), value=st.sampled_from(EXTREMES))
def test_sweep_a_hostile_space_file(tmp_path_factory, capsys, pick, value):
    f = _hostile(tmp_path_factory, copy.deepcopy(SPACE), pick, value, "space.toml")
    out = f.parent / "out"
    code = main(["sweep", "--machine", "rrr3", "--space", str(f), "--workers", "0", "--no-plots", "--out", str(out)])
    err = capsys.readouterr().err
    if code == 0:
        summary = json.loads((out / "summary.json").read_text())
        assert summary["designs"] >= 1
        return
    assert code == 2 and err.count("\n") == 1 and err.startswith("pkmdyn: error:"), err
    assert not out.exists()
