"""The NSGA-II search of pkmdyn sweep (method = "nsga2"): seeded and reproducible, resumable,
its Pareto set non-dominated among every feasible design, its convergence recorded, its Pareto
designs written as description files that pkmdyn run takes; bad space files refused."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from pkmdyn.cli import main

pq = pytest.importorskip("pyarrow.parquet")

SPACE = """[sampling]
method = "nsga2"
designs = 8
generations = 2
seed = 5
batch_size = 8
[motion]
reactions = false
[parameters]
"parameters.base_radius_m" = { min = 0.8, max = 1.2 }
"parameters.platform_radius_m" = { min = 0.4, max = 0.6 }
"parameters.drive_stiffness_N_m" = { min = 1.0e7, max = 4.0e7, scale = "log" }
[constraints]
min_direct_measure = { min = 0.005 }
[objectives]
peak_effort_N = "min"
min_stiffness_N_m = "max"
"""


def _sweep(tmp_path, name, text=SPACE):
    space = tmp_path / f"{name}.toml"
    space.write_text(text)
    out = tmp_path / name
    rc = main(["sweep", "--machine", "stewart", "--space", str(space), "--workers", "0", "--no-plots", "--out", str(out)])
    return rc, out


def _rows(out):
    return sorted(pq.read_table(out / "designs.parquet").to_pylist(), key=lambda r: r["design_id"])


def test_nsga2_is_reproducible_resumable_and_its_front_is_non_dominated(tmp_path):
    rc, a = _sweep(tmp_path, "a")
    assert rc == 0
    rows = _rows(a)
    assert len(rows) == 8 * 3 and [r["design_id"] for r in rows] == list(range(24))
    keys = ["parameters.base_radius_m", "parameters.platform_radius_m", "parameters.drive_stiffness_N_m"]
    X = np.array([[r[k] for k in keys] for r in rows])
    assert len({tuple(x) for x in X}) > 16  # the generations explore, not repeat

    # the same space file: the same designs and metrics
    rc, b = _sweep(tmp_path, "b")
    assert rc == 0 and _rows(b) == rows

    # an interrupted run (its last generation's part removed) resumes to the same rows
    parts = sorted((a / "parts").glob("part-*.parquet"))
    last = max(parts, key=lambda p: pq.read_table(p).column("design_id").to_pylist()[0])
    assert min(pq.read_table(last).column("design_id").to_pylist()) == 16
    last.unlink()
    rc, _ = _sweep(tmp_path, "a")
    assert rc == 0 and _rows(a) == rows

    # the Pareto set: exactly the non-dominated feasible designs (checked by brute force)
    feas = [r for r in rows if r["feasible"]]
    F = np.array([[r["peak_effort_N"], -r["min_stiffness_N_m"]] for r in feas])
    dominated = [bool(np.any(np.all(F <= f, axis=1) & np.any(F < f, axis=1))) for f in F]
    expect = sorted(r["design_id"] for r, d in zip(feas, dominated) if not d)
    front = sorted(pq.read_table(a / "pareto.parquet").column("design_id").to_pylist())
    assert front == expect

    summary = json.loads((a / "summary.json").read_text())
    hv = [g["hypervolume"] for g in summary["generations"]]
    assert len(hv) == 3 and hv[-1] > hv[0]  # the generations improved on the first population
    files = sorted(p.name for p in (a / "pareto_designs").iterdir())
    assert files == sorted(f"design_{i}.toml" for i in front)


def test_a_pareto_design_file_runs_as_it_is(tmp_path):
    rc, a = _sweep(tmp_path, "a")
    assert rc == 0
    design = next((a / "pareto_designs").iterdir())
    out = tmp_path / "run"
    assert main(["run", "--machine", str(design), "--out", str(out)]) == 0
    i = int(design.stem.split("_")[1])
    row = next(r for r in _rows(a) if r["design_id"] == i)
    import csv

    peak = max(abs(float(r[f"P_{k}_effort_N"])) for r in csv.DictReader((out / "results.csv").open())
               for k in range(1, 7))
    assert peak == pytest.approx(row["peak_effort_N"], rel=1e-9)


def test_a_foreign_file_in_the_pareto_designs_folder_is_not_replaced(tmp_path):
    rc, a = _sweep(tmp_path, "a")
    assert rc == 0
    (a / "pareto_designs" / "notes.txt").write_text("mine")
    rc, _ = _sweep(tmp_path, "a")
    assert rc == 2 and (a / "pareto_designs" / "notes.txt").read_text() == "mine"
    shutil.rmtree(a / "pareto_designs")


def test_the_distribution_indices_reach_the_search(tmp_path):
    """``crossover_eta`` and ``mutation_eta``: the same first (random) population as the
    defaults, other offspring; the defaults are pymoo's (15 and 20: given explicitly, the same
    designs as without)."""
    _, a = _sweep(tmp_path, "a")
    _, b = _sweep(tmp_path, "b", SPACE.replace("seed = 5\n", "seed = 5\ncrossover_eta = 60\nmutation_eta = 60\n"))
    _, c = _sweep(tmp_path, "c", SPACE.replace("seed = 5\n", "seed = 5\ncrossover_eta = 15\nmutation_eta = 20\n"))
    ra, rb, rc = _rows(a), _rows(b), _rows(c)
    key = "parameters.base_radius_m"
    assert [r[key] for r in ra[:8]] == [r[key] for r in rb[:8]]
    assert [r[key] for r in ra[8:]] != [r[key] for r in rb[8:]]
    assert rc == ra


def test_search_option_takes_the_place_of_the_space_files_method(tmp_path, capsys):
    """``--search nsga2`` on a space file that says ``method = "sobol"`` runs the NSGA-II of the
    same file with the method written ``nsga2`` (same rows); without it the file's own
    method refuses the NSGA-II keys."""
    text = SPACE.replace('method = "nsga2"', 'method = "sobol"')
    space = tmp_path / "s.toml"
    space.write_text(text)
    rc = main(["sweep", "--machine", "stewart", "--space", str(space), "--workers", "0", "--no-plots",
               "--search", "nsga2", "--out", str(tmp_path / "by_option")])
    assert rc == 0
    rc_file, by_file = _sweep(tmp_path, "by_file")
    assert rc_file == 0
    a, b = _rows(tmp_path / "by_option"), _rows(by_file)
    assert len(a) == 8 * 3 and [r["design_id"] for r in a] == [r["design_id"] for r in b]
    for ra, rb in zip(a, b):
        assert ra["parameters.base_radius_m"] == rb["parameters.base_radius_m"]
        assert ra["status"] == rb["status"]
    assert (tmp_path / "by_option" / "pareto_designs").is_dir()
    capsys.readouterr()
    rc = main(["sweep", "--machine", "stewart", "--space", str(space), "--workers", "0", "--no-plots",
               "--out", str(tmp_path / "refused")])
    assert rc == 2 and "generations" in capsys.readouterr().err


@pytest.mark.parametrize("change, words", [
    (lambda s: s.replace("generations = 2\n", ""), "generations"),
    (lambda s: s.replace('method = "nsga2"', 'method = "sobol"'), "generations"),
    (lambda s: s + "[refine]\nrounds = 2\n", "[refine]"),
    (lambda s: s.replace("designs = 8", "designs = 2"), "at least 4"),
    (lambda s: s.replace('method = "nsga2"', 'method = "sobol"').replace("generations = 2\n", "crossover_eta = 30\n"),
     "crossover_eta"),
    (lambda s: s.replace("seed = 5\n", "seed = 5\nmutation_eta = 0\n"), "mutation_eta"),
])
def test_bad_nsga2_space_files(tmp_path, capsys, change, words):
    rc, out = _sweep(tmp_path, "bad", change(SPACE))
    assert rc == 2
    assert words in capsys.readouterr().err
    assert not out.exists()


def test_convergence_fronts_equal_the_pareto_sets_of_the_designs_so_far():
    """The per-generation Pareto sets, kept incrementally, against the Pareto set of every
    feasible design so far computed afresh, on values with ties, duplicates and infeasible rows."""
    from types import SimpleNamespace

    import pyarrow as pa

    from pkmdyn.jobs.sweep import _convergence
    from pkmdyn.sweep.pareto import minimised, pareto_mask
    from pkmdyn.sweep.search import hypervolumes, normalise

    rng = np.random.default_rng(4)
    N, gens = 12, 9
    n = N * gens
    a = np.round(rng.uniform(0, 1, n), 1)  # coarse values: ties and duplicate points
    b = np.round(rng.uniform(0, 1, n), 1)
    feasible = rng.uniform(size=n) > 0.2
    table = pa.table({"design_id": np.arange(n), "feasible": feasible, "cost": a, "gain": b})
    space = SimpleNamespace(objectives=(("cost", "min"), ("gain", "max")), designs=N)
    rows = _convergence(table, space, n)
    F = minimised(np.column_stack([a, b])[feasible], ["min", "max"])
    ids = np.arange(n)[feasible]
    Fn, ref, _ = normalise(F)
    fronts = []
    for g, row in enumerate(rows):
        Fg = Fn[ids < (g + 1) * N]
        front = Fg[pareto_mask(Fg)]
        fronts.append(front)
        assert row["pareto_designs"] == len(front) and row["feasible"] == len(Fg) and row["designs"] == (g + 1) * N
    assert [r["hypervolume"] for r in rows] == pytest.approx(hypervolumes(fronts, ref), rel=1e-12)
    assert len(rows) == gens and rows[-1]["pareto_designs"] > 1
