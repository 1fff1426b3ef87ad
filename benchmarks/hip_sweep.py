"""Speed of the hip simulator's sweep designs, in this process: designs per second of the
sweep's evaluation (the adapter's ``evaluate`` on a batch, the sweep's files excluded) and where
a design's time goes. Prints one JSON object.

    python benchmarks/hip_sweep.py [--designs 256] [--samples-per-cycle 500] [--workspace-points 256]
        [--engine-measures] [--repeat 3] [--old FILE]

The designs: Sobol over the five geometry keys of ``benchmarks/sweep.py`` (base and platform
radii, lever length, lower platform height, screw lead), one ISO 14242-1 cycle of
``--samples-per-cycle`` samples each; ``--engine-measures``: the sweep's ``[motion]
engine_measures = true`` (the engine's least singularity measures, off by default). Fields:
``designs``, ``samples``, ``engine_measures``; ``ms_per_design`` and ``designs_per_s`` (the
whole evaluation of a design: parameters, description, model, engine, the hip's metrics; the
best of ``--repeat`` passes over the designs, so that a pass slowed by other work on the
machine does not count); ``stages_ms``: a design's stages, each the median over the designs
(``params_and_description``: the parameter file validated and turned into a description;
``model``: the description read and compiled on the base structure; ``kinematics``: along the
cycle; ``singularity_measures``: the least of each measure, only with ``--engine-measures``;
``reactions``: efforts with every joint reaction and the friction; ``hip_metrics``: the hip's
metrics from these, the orientation workspace included) and ``engine_part_ms`` = model +
kinematics + reactions (the target: about 2 ms). ``--old FILE``: also the evaluation of an
earlier hip sweep adapter module (a copy of the hand-built ``machines/hip_simulator/sweep.py``
of an earlier commit, e.g. ``git show COMMIT:src/pkmdyn/machines/hip_simulator/sweep.py >
old.py``), loaded in this process, on the same designs, timed the same way:
``old_ms_per_design``, ``old_designs_per_s``, ``ratio`` (new over old time per design).
``load_average_1min``: the machine's load when the script ends.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import statistics
import sys
import time
from pathlib import Path


def _designs(base: dict, n: int) -> list[dict]:
    import copy

    from scipy.stats import qmc

    u = qmc.Sobol(5, scramble=True, rng=17).random_base2(max(0, (n - 1).bit_length()))[:n]
    leads = [0.005, 0.010, 0.016, 0.020]
    out = []
    for row in u:
        d = copy.deepcopy(base)
        g = d["geometry"]
        g["base_radius_m"] = 0.22 + 0.10 * row[0]
        g["platform_radius_m"] = 0.11 + 0.07 * row[1]
        g["lever_length_m"] = 0.26 + 0.14 * row[2]
        g["platform_heights_m"][1] = 0.44 + 0.10 * row[3]
        g["screw_lead_m"] = leads[min(3, int(4 * row[4]))]
        out.append(d)
    return out


def _old_adapter(path: str):
    name = "pkmdyn.machines.hip_simulator._earlier_sweep"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def _stages(ad, designs: list[dict], ctx) -> dict[str, float]:
    """Each stage of each design timed alone (the same calls as the adapter's evaluation)."""
    import numpy as np

    from pkmdyn.multibody.dynamics.newton_euler import joint_reactions
    from pkmdyn.multibody.kinematics.inverse import solve_kinematics
    from pkmdyn.multibody.kinematics.singularity.measures import least_measures
    from pkmdyn.multibody.description.schema import load_description
    from pkmdyn.multibody.model.compiler import compile_with
    from pkmdyn.multibody.analyses.designs import evaluate_model

    hooks = ad.hooks
    eng = ctx.engine
    measures = getattr(eng, "measures", True)  # (a tree before the option computed them always)
    mo = eng.motion
    times: dict[str, list[float]] = {k: [] for k in ("params_and_description", "model", "kinematics",
                                                     "singularity_measures", "reactions", "hip_metrics")}
    with np.errstate(all="ignore"):
        for d in designs:
            t0 = time.perf_counter()
            desc = hooks.description(d)
            t1 = time.perf_counter()
            model = compile_with(eng.template, load_description(desc))
            t2 = time.perf_counter()
            try:
                kin = solve_kinematics(model, mo.x, mo.xd, mo.xdd, mo.t)
            except Exception:  # noqa: BLE001  (a design that does not reach: not timed further)
                continue
            t3 = time.perf_counter()
            if measures:
                least_measures(model, kin.q)
            t4 = time.perf_counter()
            joint_reactions(model, kin, named=mo.loads)
            t5 = time.perf_counter()
            outcome, state = evaluate_model(model, mo, eng)
            t6 = time.perf_counter()
            hooks.design_metrics(d, outcome, state, ctx.data)
            t7 = time.perf_counter()
            for k, v in zip(times, (t1 - t0, t2 - t1, t3 - t2, t4 - t3, t5 - t4, t7 - t6)):
                if k != "singularity_measures" or measures:
                    times[k].append(1e3 * v)
    return {k: round(statistics.median(v), 3) for k, v in times.items() if v}


def _best(run, repeat: int):
    """The shortest of ``repeat`` runs of ``run()`` [s] and the last run's result."""
    best, result = float("inf"), None
    for _ in range(max(1, repeat)):
        t0 = time.perf_counter()
        result = run()
        best = min(best, time.perf_counter() - t0)
    return best, result


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--designs", type=int, default=256)
    ap.add_argument("--samples-per-cycle", type=int, default=500)
    ap.add_argument("--workspace-points", type=int, default=256)
    ap.add_argument("--engine-measures", action="store_true")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--old", default=None)
    a = ap.parse_args()
    from pkmdyn.machines.registry import sweep_adapter

    ad = sweep_adapter("hip")
    base = ad.base_description(None)
    options = {"samples_per_cycle": a.samples_per_cycle, "workspace_points": a.workspace_points}
    designs = _designs(base, a.designs)
    # (the option given only when asked for: the script then runs on a tree before it as well)
    ctx = ad.prepare(base, {**options, **({"engine_measures": True} if a.engine_measures else {})}, Path("."))
    ad.evaluate(designs[:3], ctx)  # compilations and caches before timing
    new_s, outcomes = _best(lambda: ad.evaluate(designs, ctx), a.repeat)
    out = {"designs": a.designs, "samples": len(ctx.engine.motion),
           "workspace_points": a.workspace_points,
           "engine_measures": bool(getattr(ctx.engine, "measures", True)), "repeat": a.repeat,
           "ms_per_design": round(1e3 * new_s / a.designs, 3), "designs_per_s": round(a.designs / new_s, 1),
           "statuses": {s: sum(o.status == s for o in outcomes) for s in sorted({o.status for o in outcomes})}}
    stages = _stages(ad, designs, ctx)
    out["stages_ms"] = stages
    out["engine_part_ms"] = round(sum(stages.get(k, 0.0) for k in ("model", "kinematics", "reactions")), 3)
    if a.old:
        old = _old_adapter(a.old)
        octx = old.prepare(base, options, Path("."))
        old.evaluate(designs[:3], octx)
        old_s, _ = _best(lambda: old.evaluate(designs, octx), a.repeat)
        out["old_ms_per_design"] = round(1e3 * old_s / a.designs, 3)
        out["old_designs_per_s"] = round(a.designs / old_s, 1)
        out["ratio"] = round(new_s / old_s, 2)
    import os

    out["load_average_1min"] = round(os.getloadavg()[0], 2)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
