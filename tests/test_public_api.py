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


@pytest.mark.parametrize("name", ["hip", "pdm"])
def test_a_papers_machine_moves_as_its_commands(name, tmp_path, capsys):
    """A paper's machine loaded by name keeps its commands' default motion (the hip's ISO 14242-1
    cycle with its hydraulic load; the PDM's Eq. 84 motion), so that ``kinematics`` and
    ``dynamics`` on it give what ``pkmdyn run --machine NAME`` writes, column by column."""
    assert main(["run", "--machine", name, "--out", str(tmp_path / "run")]) == 0
    capsys.readouterr()
    with open(tmp_path / "run" / "results.csv") as fh:
        rows = list(csv.reader(fh))
    table = {col: np.array([float(r[k]) for r in rows[1:]]) for k, col in enumerate(rows[0])}
    m = pkmdyn.load(name)
    kin = pkmdyn.kinematics(m)
    assert len(kin) == len(rows) - 1 and np.array_equal(kin.t, table["t_s"])
    cols = pkmdyn.dynamics(m, kin).columns()
    assert cols and set(cols) <= set(table)
    for col, v in cols.items():
        np.testing.assert_allclose(v, table[col], rtol=1e-12, atol=1e-12 * max(np.abs(v).max(), 1.0), err_msg=col)
    # a description of the same machine, given as a dict, has its own [default_motion]
    assert len(pkmdyn.kinematics(pkmdyn.load(resolve_description(name)))) != len(kin)


def resolve_description(name):
    from pkmdyn.machines.registry import resolve

    return resolve(name)[0].description(None)


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


def test_the_workspace_verb_is_the_commands(example, tmp_path, capsys):
    """``pkmdyn.workspace`` on a grid gives what ``pkmdyn workspace`` writes for the same grid, and
    every inside pose is reached with its singularity measure at least the threshold."""
    ws = example["workspace"]
    grid = "x_m=-0.2:0.2:9,y_m=-0.2:0.2:9"
    assert main(["workspace", "--machine", "stewart", "--grid", grid, "--out", str(tmp_path / "ws")]) == 0
    capsys.readouterr()
    with open(tmp_path / "ws" / "workspace.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == len(ws.x)
    cols = ws.columns()  # the file's columns, each
    assert list(cols) == list(rows[0])
    for name, v in cols.items():
        np.testing.assert_allclose([float(r[name]) for r in rows], v, rtol=1e-15, atol=0, err_msg=name)
    assert np.all(ws.reached[ws.inside]) and np.all(ws.measure[ws.inside] >= ws.threshold)
    far = pkmdyn.workspace(example["model"], "x_m=-3:3:5", pose="z_m=0.6")
    assert not far.inside.all() and far.inside[2] == far.inside.any()  # the grid's middle, if any pose


def test_identification_recovers_a_changed_machine(tmp_path):
    """Efforts of a machine whose platform is 30 % heavier, fitted from the original description:
    the identified efforts are the changed machine's (the efforts are linear in the parameters),
    and the platform's mass moves from the description's value towards the changed one."""
    from pkmdyn.machines.registry import description_path
    from pkmdyn.params_util import read_toml

    d = read_toml(description_path("stewart"))
    m0 = pkmdyn.load(d)
    body = m0.body_names[m0.task_body]
    heavy = dict(d, bodies=[dict(b, mass_kg=b["mass_kg"] * 1.3) if b["name"] == body else b for b in d["bodies"]])
    m1 = pkmdyn.load(heavy)
    kin0, kin1 = pkmdyn.kinematics(m0), pkmdyn.kinematics(m1)
    u = pkmdyn.dynamics(m1, kin1).motors.effort
    fit = pkmdyn.identification(m0, kin0, u)
    assert np.abs(fit.u_identified - u).max() < 1e-8 * np.abs(u).max()
    assert np.abs(pkmdyn.dynamics(m0, kin0).motors.effort - u).max() > 1e-3 * np.abs(u).max()  # a change that shows
    k = fit.names.index(f"{body}_m_kg")
    assert fit.estimate.theta[k] != pytest.approx(fit.prior[k], rel=1e-6)
    with pytest.raises(pkmdyn.ParameterError, match="u: expected efforts of shape"):
        pkmdyn.identification(m0, kin0, u[:, :-1])


def test_the_readmes_library_section_runs_as_written():
    """Every ``python`` block of the README's "Library" section, run as it stands."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("\n## Library\n", 1)[1].split("\n## ", 1)[0]
    blocks = section.split("```python\n")[1:]
    assert blocks, "the README's Library section has no python block"
    for block in blocks:
        scope: dict = {}
        exec(compile(block.split("```", 1)[0], "README.md", "exec"), scope)  # noqa: S102
        assert scope["m"].name == "stewart" and np.abs(scope["xdd"] - scope["kin"].xdd).max() < 1e-8


def test_designs_are_the_sweeps_and_each_is_its_own_machine(tmp_path):
    """``pkmdyn.designs`` returns the rows ``pkmdyn sweep`` writes; the best design, loaded from
    its parameter file and run through ``pkmdyn.dynamics``, has the sweep's peak effort, and the
    Pareto set of one minimised objective is the best design."""
    space = tmp_path / "space.toml"
    space.write_text('[sampling]\nmethod = "random"\ndesigns = 4\nseed = 2\n\n[parameters]\n'
                     '"bodies[platform].mass_kg" = { min = 5.0, max = 25.0 }\n\n[objectives]\npeak_effort_N = "min"\n',
                     encoding="utf-8")
    d = pkmdyn.designs("stewart", space, tmp_path / "out")
    cols = d.columns
    np.testing.assert_array_equal(cols["design_id"], np.arange(4))
    assert list(cols["status"]) == ["ok"] * 4 and len(set(cols["bodies[platform].mass_kg"])) == 4
    best = int(np.argmin(cols["peak_effort_N"]))
    assert d.best_design_id == best and list(d.pareto_ids) == [best]
    m = pkmdyn.load(d.files["best_params"])
    u = pkmdyn.dynamics(m, pkmdyn.kinematics(m)).reactions.u
    assert np.abs(u).max() == pytest.approx(cols["peak_effort_N"][best], rel=1e-9)
    assert main(["sweep", "--machine", "stewart", "--space", str(space), "--workers", "0", "--no-plots",
                 "--out", str(tmp_path / "cli")]) == 0
    import pyarrow.parquet as pq

    table = pq.read_table(tmp_path / "cli" / "designs.parquet").to_pydict()
    for name, v in cols.items():
        if v.dtype.kind == "f":
            np.testing.assert_array_equal(np.array(table[name], dtype=float), v, err_msg=name)


def test_every_generated_machine_loads_with_and_without_its_parameter_file(tmp_path):
    """``pkmdyn.load(name, params=...)`` for every generated machine: its built-in parameter file
    written out and read back gives the same mechanism as the built-in parameters."""
    from pkmdyn.machines.registry import generated_machines

    names = sorted(generated_machines())
    assert len(names) >= 2
    for name in names:
        assert main([name, "params", "--out", str(tmp_path / f"{name}.toml")]) == 0
        a, b = pkmdyn.load(name), pkmdyn.load(name, params=tmp_path / f"{name}.toml")
        assert a.body_names == b.body_names and np.array_equal(a.mass, b.mass), name
        assert len(pkmdyn.kinematics(a)) > 1, name
