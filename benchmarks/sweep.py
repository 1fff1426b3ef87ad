"""Speed of a design sweep of the hip simulator: in this process, on 1 and on 2 Dask workers.

The same space (``--designs`` designs, Sobol over five geometry keys, one ISO 14242-1 cycle of
500 samples; every design: validation, kinematics and conditioning along the cycle, the
orientation workspace, inverse dynamics with friction, every metric) is run three times with
the same batches: in this process (``--workers 0``), on a local cluster of 1 worker and of 2
workers. Prints one JSON object; with ``--json`` nothing else is printed.

    python benchmarks/sweep.py --json [--designs 10000]

Fields: designs; seconds_2_workers (the whole library call on 2 workers: cluster start,
evaluation, part files, designs.parquet, Pareto set, best design, plots); evaluate_s_* (the
evaluation phase alone: batches dispatched, computed, part files written; cluster start
excluded) for in_process, 1_worker, 2_workers; cluster_start_s_*; throughput_ratio_2_vs_1 =
evaluate_s_1_worker / evaluate_s_2_workers; dask_share = 1 - evaluate_s_in_process /
evaluate_s_1_worker (the share of a 1-worker run's evaluation time that the same batches do not
need in-process: scheduling, serialisation, transfer); dask_share_2_workers = 1 -
evaluate_s_in_process / (2 x evaluate_s_2_workers) (also counts any imbalance or contention of
the two workers); designs_per_s_2_workers; cpu_s_* (CPU seconds of the evaluation: the
calling process, scheduler included, plus every worker process) and dask_share_cpu = 1 -
cpu_s_in_process / cpu_s_1_worker, dask_share_cpu_2_workers likewise: the same shares by CPU
time, which the other load of a shared machine does not inflate; the 1-minute load average
before and after each run; targets and whether each is met.
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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print only the JSON object")
    ap.add_argument("--designs", type=int, default=10_000)
    args = ap.parse_args()

    from pkmdyn.machines.registry import sweep_adapter
    from pkmdyn.sweep import run_sweep
    from pkmdyn.sweep.execute import default_batch_size

    adapter = sweep_adapter("hip")
    batch = default_batch_size(args.designs, 2)
    result: dict[str, object] = {"designs": args.designs, "samples_per_design": 501, "batch_size": batch,
                                 "cpu_count": os.cpu_count(), "load_average_1min_before": os.getloadavg()[0]}
    with tempfile.TemporaryDirectory() as tmp:
        space = Path(tmp) / "space.toml"
        space.write_text(SPACE.format(designs=args.designs), encoding="utf-8")
        runs = {"in_process": 0, "1_worker": 1, "2_workers": 2}
        for label, workers in runs.items():
            t0 = time.perf_counter()
            report = run_sweep(adapter, space, Path(tmp) / label, workers=workers, batch_size=batch,
                               plots=(workers == 2), progress=False)
            total = time.perf_counter() - t0
            if not args.json:
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
    result["designs_per_s_2_workers"] = args.designs / e2
    c0, c1, c2 = (result[f"cpu_s_{k}"] for k in runs)
    if c1 and c2:
        result["dask_share_cpu"] = 1.0 - float(c0) / float(c1)  # type: ignore[arg-type]
        result["dask_share_cpu_2_workers"] = 1.0 - float(c0) / float(c2)  # type: ignore[arg-type]
    result["targets"] = {"seconds_2_workers_max": 180.0, "throughput_ratio_2_vs_1_min": 1.7, "dask_share_max": 0.10}
    result["targets_met"] = {
        "seconds_2_workers": float(result["seconds_2_workers"]) <= 180.0,  # type: ignore[arg-type]
        "throughput_ratio_2_vs_1": result["throughput_ratio_2_vs_1"] >= 1.7,
        "dask_share": result["dask_share"] <= 0.10,
    }
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
