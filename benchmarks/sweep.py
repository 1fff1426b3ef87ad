"""Speed of design sweeps, in this process and on 1 and 2 Dask workers, and the convergence of
an NSGA-II search. Prints one JSON object; with ``--json`` nothing else is printed.

    python benchmarks/sweep.py --json [--part hip,stewart,delta] [--designs 10000]
        [--stewart-designs 10000] [--delta-population 20 --delta-generations 200 --delta-seed 3]
        [--delta-refine 4]
        [--delta-fronts FRONTS.csv]

**hip** (``--designs``): the hip simulator, Sobol over five geometry keys, one ISO 14242-1
cycle of 500 samples; every design: validation, kinematics and conditioning along the cycle,
the orientation workspace, inverse dynamics with friction, every metric. The same space is
run three times with the same batches: in this process (``--workers 0``), on a local cluster
of 1 worker and of 2 workers. Fields: designs; seconds_2_workers (the whole library call on 2
workers: cluster start, evaluation, part files, designs.parquet, Pareto set, best design,
plots); evaluate_s_* (the evaluation phase alone: batches dispatched, computed, part files
written; cluster start excluded) for in_process, 1_worker, 2_workers; cluster_start_s_*;
throughput_ratio_2_vs_1 = evaluate_s_1_worker / evaluate_s_2_workers; dask_share = 1 -
evaluate_s_in_process / evaluate_s_1_worker (the share of a 1-worker run's evaluation time that
the same batches do not need in-process: scheduling, serialisation, transfer);
dask_share_2_workers = 1 - evaluate_s_in_process / (2 x evaluate_s_2_workers) (also counts any
imbalance or contention of the two workers); designs_per_s_2_workers; cpu_s_* (CPU seconds of
the evaluation: the calling process, scheduler included, plus every worker process) and
dask_share_cpu = 1 - cpu_s_in_process / cpu_s_1_worker, dask_share_cpu_2_workers likewise: the
same shares by CPU time, which the other load of a shared machine does not inflate; the
1-minute load average before and after each run; targets and whether each is met.

**stewart** (``--stewart-designs``): the built-in Gough-Stewart platform's geometry by its
parameters (base and platform radii, the two pair half-angles, the home height; Sobol), every
design with its kinematics, efforts and every joint reaction along its default motion and its
constant-orientation workspace on a 16 x 16 x 16 grid (4,096 poses), on 1 and on 2 workers
with the same batches; no stiffness metrics (``stiffness = false``: the target names none)
and no least singularity measure over the workspace (``workspace_measure = false``: likewise;
the workspace's poses are still inside only where every measure is proven at least the
threshold).
Fields ``stewart_geometry_designs``, ``stewart_geometry_seconds_2_workers`` (the whole library call),
``stewart_geometry_evaluate_s_<1_worker|2_workers>``,
``stewart_geometry_throughput_ratio_2_vs_1``, ``stewart_geometry_ms_per_design_2_workers``,
``stewart_geometry_status_counts``.

**delta** (``--delta-population``, ``--delta-generations``): NSGA-II over the Delta robot's
arm, forearm, base and platform sizes (the sides of the two triangles; their inradii are
side x sqrt(3) / 6), maximising the workspace volume (a 13 x 13 x 9 grid, the size refined by
where the boundary crosses the grid's edges, ``workspace_refine``, ``--delta-refine``, 4 steps
an edge by default: a volume that moves continuously with the design, where the count of inside
poses moves in whole cells, ``docs/workspace.md``) and minimising the peak motor torque on a
pick-and-place cycle (a 305 mm arch 25 mm high and back, 0.5 s), keeping the least direct
singularity measure along the cycle (the inverse of a condition number) at least 0.023, run
for G generations and for 10 G generations with the same seed (population 20, G = 200 by
default; the distribution indices of crossover and mutation 30, which converged faster on this
problem than pymoo's 15 and 20, ``docs/sweep.md``).
``delta_nsga2_hypervolume_rel_gap`` = 1 - HV(short) / HV(long), each the hypervolume of that
run's feasible Pareto set with both runs' objectives scaled together to [0, 1] (reference
point 1.1); ``delta_nsga2_designs_short``, ``delta_nsga2_designs_long``,
``delta_nsga2_seconds_short``, ``delta_nsga2_seconds_long`` (2 workers),
``delta_nsga2_workspace_refine``. ``--delta-fronts FILE``
writes both runs' Pareto fronts (``run_long_0_1,workspace_size_m3,peak_effort_Nm``).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

SPACE = """
[sampling]
method = "sobol"
designs = {designs}
seed = 17

[motion]
samples_per_cycle = 500

[parameters]
"geometry.base_radius_m" = {{ min = 0.22, max = 0.32 }}
"geometry.platform_radius_m" = {{ min = 0.11, max = 0.18 }}
"geometry.lever_length_m" = {{ min = 0.26, max = 0.40 }}
"geometry.platform_heights_m[1]" = {{ min = 0.44, max = 0.54 }}
"geometry.screw_lead_m" = {{ values = [0.005, 0.010, 0.016, 0.020] }}

[constraints]
max_spherical_angle_deg = {{ max = 30.0 }}
stroke_m = {{ max = 0.12 }}

[objectives]
peak_drive_force_N = "min"
gci = "max"
"""


STEWART_SPACE = """
[sampling]
method = "sobol"
designs = {designs}
seed = 11

[motion]
workspace_grid = "x=-0.4:0.4:16,y=-0.4:0.4:16,z=0.7:1.3:16"
workspace_measure = false
stiffness = false

[parameters]
"parameters.base_radius_m" = {{ min = 0.8, max = 1.2 }}
"parameters.platform_radius_m" = {{ min = 0.4, max = 0.6 }}
"parameters.base_half_angle_deg" = {{ min = 5.0, max = 20.0 }}
"parameters.platform_half_angle_deg" = {{ min = 40.0, max = 55.0 }}
"parameters.height_m" = {{ min = 0.9, max = 1.1 }}

[objectives]
workspace_size_m3 = "max"
peak_effort_N = "min"
"""

DELTA_SPACE = """
[sampling]
method = "nsga2"
designs = {population}
generations = {generations}
seed = {seed}
crossover_eta = 30
mutation_eta = 30

[motion]
file = "pick_and_place.csv"
reactions = false
stiffness = false
workspace_grid = "x=-1.5:1.5:13,y=-1.5:1.5:13,z=-2.2:-0.2:9"
workspace_measure = false
workspace_refine = {refine}

[parameters]
"parameters.base_side_m" = {{ min = 0.45, max = 0.70 }}
"parameters.platform_side_m" = {{ min = 0.05, max = 0.10 }}
"parameters.upper_arm_m" = {{ min = 0.40, max = 0.65 }}
"parameters.forearm_m" = {{ min = 1.0, max = 1.4 }}

[constraints]
min_direct_measure = {{ min = 0.023 }}

[objectives]
workspace_size_m3 = "max"
peak_effort_Nm = "min"
"""


def _pick_and_place(path: Path) -> None:
    """The cycle of the Delta benchmark: 305 mm across and back along an arch 25 mm high at
    z = -1 m, quintic time law, 0.5 s, 201 samples (``docs/mechanism_format.md``, motion files)."""
    import numpy as np

    t = np.linspace(0.0, 0.5, 201)
    u = np.where(t <= 0.25, t / 0.25, 2.0 - t / 0.25)
    w = u ** 3 * (10.0 - 15.0 * u + 6.0 * u ** 2)
    x, z = -0.1525 + 0.305 * w, -1.0 + 0.025 * np.sin(np.pi * w)
    np.savetxt(path, np.column_stack([t, x, 0.0 * t, z]), delimiter=",", header="t_s,x_m,y_m,z_m", comments="",
               fmt="%.12g")


def _stewart(designs: int, result: dict, quiet: bool) -> None:
    from pkmdyn.jobs.sweep import run_sweep
    from pkmdyn.machines.registry import sweep_adapter
    from pkmdyn.sweep.execute import default_batch_size

    adapter = sweep_adapter("stewart")
    batch = default_batch_size(designs, 2)
    with tempfile.TemporaryDirectory() as tmp:
        space = Path(tmp) / "space.toml"
        space.write_text(STEWART_SPACE.format(designs=designs), encoding="utf-8")
        evaluate = {}
        for label, workers in (("1_worker", 1), ("2_workers", 2)):
            t0 = time.perf_counter()
            report = run_sweep(adapter, space, Path(tmp) / label, workers=workers, batch_size=batch,
                               plots=False, progress=False)
            total = time.perf_counter() - t0
            evaluate[label] = report.stats.evaluate_s
            result[f"stewart_geometry_evaluate_s_{label}"] = report.stats.evaluate_s
            if not quiet:
                print(f"stewart {label}: {total:.1f} s in all, evaluation {report.stats.evaluate_s:.1f} s",
                      file=sys.stderr)
            if workers == 2:
                result["stewart_geometry_seconds_2_workers"] = total
                result["stewart_geometry_status_counts"] = report.counts
    result["stewart_geometry_designs"] = designs
    result["stewart_geometry_workspace_poses"] = 4096
    result["stewart_geometry_throughput_ratio_2_vs_1"] = evaluate["1_worker"] / evaluate["2_workers"]
    result["stewart_geometry_ms_per_design_2_workers"] = 1e3 * evaluate["2_workers"] / designs
    result.setdefault("targets", {}).update({"stewart_geometry_seconds_2_workers_max_for_10000": 600.0,
                                             "stewart_geometry_throughput_ratio_2_vs_1_min": 1.7})
    result.setdefault("targets_met", {}).update({
        "stewart_geometry_seconds_2_workers": designs >= 10_000 and result["stewart_geometry_seconds_2_workers"] <= 600.0,
        "stewart_geometry_throughput_ratio_2_vs_1": result["stewart_geometry_throughput_ratio_2_vs_1"] >= 1.7,
    })


def _front_objectives(out: Path) -> "object":
    """The feasible Pareto set's minimised objectives of a finished sweep."""
    import numpy as np
    import pyarrow.parquet as pq

    from pkmdyn.sweep.pareto import minimised, pareto_mask

    rows = pq.read_table(out / "designs.parquet").to_pylist()
    names = [("workspace_size_m3", "max"), ("peak_effort_Nm", "min")]
    F = np.array([[r[m] for m, _ in names] for r in rows if r["status"] == "ok"], dtype=float)
    F = minimised(F, [s_ for _, s_ in names])
    return F[pareto_mask(F)]


def _delta(population: int, generations: int, result: dict, quiet: bool, fronts_csv: str | None = None,
           seed: int = 3, refine: int = 4) -> None:
    import numpy as np

    from pkmdyn.jobs.sweep import run_sweep
    from pkmdyn.machines.registry import sweep_adapter
    from pkmdyn.sweep.search import hypervolumes

    adapter = sweep_adapter("delta")
    fronts = {}
    with tempfile.TemporaryDirectory() as tmp:
        _pick_and_place(Path(tmp) / "pick_and_place.csv")
        for label, gens in (("short", generations), ("long", 10 * generations)):
            text = DELTA_SPACE.format(population=population, generations=gens, seed=seed, refine=refine)
            space = Path(tmp) / f"space_{label}.toml"
            space.write_text(text, encoding="utf-8")
            t0 = time.perf_counter()
            run_sweep(adapter, space, Path(tmp) / label, workers=2, batch_size=-(-population // 2), plots=False,
                      progress=False)
            result[f"delta_nsga2_seconds_{label}"] = time.perf_counter() - t0
            result[f"delta_nsga2_designs_{label}"] = population * (gens + 1)
            fronts[label] = _front_objectives(Path(tmp) / label)
            if not quiet:
                print(f"delta nsga2 {label}: {result[f'delta_nsga2_seconds_{label}']:.1f} s, "
                      f"{len(fronts[label])} Pareto designs", file=sys.stderr)
    if fronts_csv:  # both fronts in the objectives' own units, for a look at where they differ
        rows = [(k, -f[0], f[1]) for k in ("short", "long") for f in fronts[k]]  # (the volume was negated)
        np.savetxt(fronts_csv, np.array([(0 if k == "short" else 1, a, b) for k, a, b in rows]), delimiter=",",
                   header="run_long_0_1,workspace_size_m3,peak_effort_Nm", comments="", fmt="%.12g")
    both = np.vstack([fronts["short"], fronts["long"]])
    lo, hi = both.min(axis=0), both.max(axis=0)
    span = np.where(hi > lo, hi - lo, 1.0)
    hv_short, hv_long = hypervolumes([(fronts[k] - lo) / span for k in ("short", "long")], np.full(2, 1.1))
    result["delta_nsga2_population"] = population
    result["delta_nsga2_seed"] = seed
    result["delta_nsga2_workspace_refine"] = refine
    result["delta_nsga2_generations_short"] = generations
    result["delta_nsga2_hypervolume_short"] = hv_short
    result["delta_nsga2_hypervolume_long"] = hv_long
    result["delta_nsga2_hypervolume_rel_gap"] = 1.0 - hv_short / hv_long
    result.setdefault("targets", {})["delta_nsga2_hypervolume_rel_gap_max"] = 0.02
    result.setdefault("targets_met", {})["delta_nsga2_hypervolume_rel_gap"] = result["delta_nsga2_hypervolume_rel_gap"] <= 0.02


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print only the JSON object")
    ap.add_argument("--part", default="hip,stewart,delta", help="which benchmarks, comma-separated")
    ap.add_argument("--designs", type=int, default=10_000, help="hip designs")
    ap.add_argument("--stewart-designs", type=int, default=10_000)
    ap.add_argument("--delta-population", type=int, default=20)
    ap.add_argument("--delta-generations", type=int, default=200, help="the short run's (the long run: 10x)")
    ap.add_argument("--delta-seed", type=int, default=3, help="the NSGA-II seed of both runs")
    ap.add_argument("--delta-refine", type=int, default=4,
                    help="steps along each boundary edge for the refined workspace size (0: inside poses times the cell)")
    ap.add_argument("--delta-fronts", default=None, help="a CSV file for both runs' Pareto fronts (objectives)")
    args = ap.parse_args()
    parts = {p.strip() for p in args.part.split(",") if p.strip()}
    result: dict[str, object] = {"cpu_count": os.cpu_count(), "load_average_1min_before": os.getloadavg()[0]}
    if "hip" in parts:
        _hip(args.designs, result, args.json)
    if "stewart" in parts:
        _stewart(args.stewart_designs, result, args.json)
    if "delta" in parts:
        _delta(args.delta_population, args.delta_generations, result, args.json, args.delta_fronts, args.delta_seed,
               args.delta_refine)
    print(json.dumps(result, indent=2))


def _hip(designs: int, result: dict, quiet: bool) -> None:
    from pkmdyn.jobs.sweep import run_sweep
    from pkmdyn.machines.registry import sweep_adapter
    from pkmdyn.sweep.execute import default_batch_size

    adapter = sweep_adapter("hip")
    batch = default_batch_size(designs, 2)
    result.update({"designs": designs, "samples_per_design": 501, "batch_size": batch})
    with tempfile.TemporaryDirectory() as tmp:
        space = Path(tmp) / "space.toml"
        space.write_text(SPACE.format(designs=designs), encoding="utf-8")
        runs = {"in_process": 0, "1_worker": 1, "2_workers": 2}
        for label, workers in runs.items():
            t0 = time.perf_counter()
            report = run_sweep(adapter, space, Path(tmp) / label, workers=workers, batch_size=batch,
                               plots=(workers == 2), progress=False)
            total = time.perf_counter() - t0
            if not quiet:
                print(f"{label}: {total:.1f} s in all, evaluation {report.stats.evaluate_s:.1f} s", file=sys.stderr)
            st = report.stats
            result[f"evaluate_s_{label}"] = st.evaluate_s
            result[f"cluster_start_s_{label}"] = st.cluster_start_s
            result[f"cpu_s_{label}"] = (st.driver_cpu_s + st.worker_cpu_s) if st.worker_cpu_s is not None else None
            result[f"load_average_1min_after_{label}"] = os.getloadavg()[0]
            result[f"seconds_{label}"] = total
            if workers == 2:
                result["status_counts"] = report.counts
    result["seconds_2_workers"] = result.pop("seconds_2_workers")
    e0, e1, e2 = (float(result[f"evaluate_s_{k}"]) for k in runs)  # type: ignore[arg-type]
    result["throughput_ratio_2_vs_1"] = e1 / e2
    result["dask_share"] = 1.0 - e0 / e1
    result["dask_share_2_workers"] = 1.0 - e0 / (2.0 * e2)
    result["designs_per_s_2_workers"] = designs / e2
    c0, c1, c2 = (result[f"cpu_s_{k}"] for k in runs)
    if c1 and c2:
        result["dask_share_cpu"] = 1.0 - float(c0) / float(c1)  # type: ignore[arg-type]
        result["dask_share_cpu_2_workers"] = 1.0 - float(c0) / float(c2)  # type: ignore[arg-type]
    result.setdefault("targets", {}).update(
        {"seconds_2_workers_max": 180.0, "throughput_ratio_2_vs_1_min": 1.7, "dask_share_max": 0.10})
    result.setdefault("targets_met", {}).update({
        "seconds_2_workers": float(result["seconds_2_workers"]) <= 180.0,  # type: ignore[arg-type]
        "throughput_ratio_2_vs_1": result["throughput_ratio_2_vs_1"] >= 1.7,
        "dask_share": result["dask_share"] <= 0.10,
    })


if __name__ == "__main__":
    main()
