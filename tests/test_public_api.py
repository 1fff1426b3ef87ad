"""The library's public verbs (``import pkmdyn``): the example script written with them alone
runs, its results are the files' (``pkmdyn run``'s columns), and ``load`` takes every kind of
machine and refuses what does not fit."""

from __future__ import annotations

import csv
import importlib.util
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import pkmdyn
from pkmdyn.cli import main

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def example():
    spec = importlib.util.spec_from_file_location("library_example", ROOT / "examples" / "library.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.main()


def test_the_example_runs_and_its_routes_agree(example):
    kin = example["kin"]
    assert np.abs(example["direct"].x - kin.x).max() < 1e-9            # direct of inverse
    assert np.abs(example["xdd"] - kin.xdd[:5]).max() < 1e-9 * max(np.abs(kin.xdd).max(), 1.0)  # forward of inverse
    assert example["hip"].name == "hip" and example["model"].na == 6


def test_the_dynamics_columns_are_the_runs(example, tmp_path, capsys):
    """``Dynamics.columns()`` holds what ``pkmdyn run`` writes for the same motion, column by column."""
    assert main(["run", "--machine", "stewart", "--out", str(tmp_path / "run")]) == 0
    capsys.readouterr()
    with open(tmp_path / "run" / "results.csv") as fh:
        rows = list(csv.reader(fh))
    table = {name: np.array([float(r[k]) for r in rows[1:]]) for k, name in enumerate(rows[0])}
    cols = example["columns"]
    assert cols and set(cols) <= set(table)
    for name, v in cols.items():
        np.testing.assert_allclose(v, table[name], rtol=1e-12, atol=1e-12 * max(np.abs(v).max(), 1.0), err_msg=name)


def test_load_takes_names_files_dicts_and_parameter_files(tmp_path):
    from pkmdyn.machines.hip_simulator.params import paper_params_path
    from pkmdyn.machines.registry import description_path
    from pkmdyn.params_util import read_toml

    path = description_path("delta")
    by_name, by_file, by_dict = pkmdyn.load("delta"), pkmdyn.load(path), pkmdyn.load(read_toml(path))
    for m in (by_file, by_dict):
        assert m.body_names == by_name.body_names and np.array_equal(m.mass, by_name.mass)
    spec, paper = pkmdyn.load("hip"), pkmdyn.load("hip", params=paper_params_path())
    assert spec.task_names == paper.task_names and not np.allclose(
        pkmdyn.kinematics(spec).act_q, pkmdyn.kinematics(paper).act_q)  # the paper's Euler sequence
    with pytest.raises(pkmdyn.ParameterError, match="params"):
        pkmdyn.load("delta", params=paper_params_path())
    with pytest.raises(pkmdyn.ParameterError, match="params"):
        pkmdyn.load(read_toml(path), params=paper_params_path())
    with pytest.raises(pkmdyn.ParameterError, match="unknown machine"):
        pkmdyn.load("no-such-machine")


def test_importing_pkmdyn_loads_no_engine():
    code = "import sys, pkmdyn; print(int('numba' in sys.modules), int('scipy' in sys.modules), len(pkmdyn.__all__))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out[:2] == ["0", "0"] and int(out[2]) > 10
