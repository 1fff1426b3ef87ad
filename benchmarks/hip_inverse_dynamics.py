"""Speed of the hip simulator's closed-chain inverse dynamics with friction on the engine.

Runs, in one process and on the same samples (the ISO 14242-1 cycle model and its load): the
engine on the hip's description (kinematics of every body, the motor torques with every joint's
friction and the load-driven bearing friction, ``machines/hip_simulator/paper.PaperView``,
batched), the Pinocchio reference path (spanning tree + loop closures, one sample at a time,
``tests/oracles/hip_pinocchio.py``), and one bare ``pinocchio.rnea`` call on the machine's
spanning tree. Prints one JSON object; with ``--json`` nothing else is printed.

    python benchmarks/hip_inverse_dynamics.py --json [--samples 10000]

Fields: samples, engine_us_per_sample, reference_us_per_sample (timed on
``--reference-samples`` samples), rnea_us, speedup (reference / engine), single_sample_us (one
sample through the engine's single-sample verb, as a controller would call it),
peak_rss_mib_1e6 (peak resident memory of a fresh process that computes 1,000,000 samples in
blocks), targets met.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from pkmdyn.machines.hip_simulator import load_params
from pkmdyn.machines.hip_simulator.paper import PaperView
from pkmdyn.profiles.iso14242 import iso14242_motion
from pkmdyn.spatial import euler_kinematics

from _timing import best_time


def _inputs(n: int):
    model = load_params()
    motion = iso14242_motion(cycles=max(n / 1000.0, 0.002), samples_per_cycle=1000)
    sl = slice(0, n)
    motion = type(motion)(motion.t[sl], motion.angles[sl], motion.rates[sl], motion.accels[sl], motion.load[sl])
    R, w, wd = euler_kinematics(model.geometry.euler_sequence, motion.angles, motion.rates, motion.accels)
    return model, motion, R, w, wd


def _peak_rss_child(n: int) -> None:
    """Child-process mode: compute ``n`` samples in blocks and print the peak RSS in MiB."""
    view = PaperView(load_params())
    chunk = 4096
    cycle_samples = 1000
    total = 0.0
    q = None
    for start in range(0, n, chunk):
        m = min(chunk, n - start)
        motion = iso14242_motion(cycles=m / cycle_samples, samples_per_cycle=cycle_samples)
        b = view.solve(motion, start, q)
        q = b.kin.q[-1].copy()
        total += float(np.abs(b.tau).sum())
    assert np.isfinite(total)
    print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print only the JSON object")
    ap.add_argument("--samples", type=int, default=10_000)
    ap.add_argument("--reference-samples", type=int, default=200)
    ap.add_argument("--rss-samples", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--_rss_child", type=int, default=0, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args._rss_child:
        _peak_rss_child(args._rss_child)
        return

    import pinocchio

    # the independent Pinocchio spanning-tree reference lives beside the tests (tests/oracles)
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from oracles.hip_pinocchio import reference_torques, spanning_tree_rnea_inputs

    model, motion, R, w, wd = _inputs(args.samples)
    t, load = motion.t, motion.load
    n = t.shape[0]
    view = PaperView(model)
    engine = best_time(lambda: view.solve(motion), args.repeat) / n * 1e6

    nr = min(args.reference_samples, n)
    ref_time = best_time(lambda: reference_torques(model, t[:nr], R[:nr], w[:nr], wd[:nr], load[:nr]), 1) / nr * 1e6
    tau_engine = view.solve(motion).tau[:nr]
    tau_ref = reference_torques(model, t[:nr], R[:nr], w[:nr], wd[:nr], load[:nr])["tau"]
    agreement = float(np.abs(tau_engine - tau_ref).max() / np.abs(tau_ref).max())

    pm, pd, q, v, a = spanning_tree_rnea_inputs(model)
    reps = 20_000
    rnea = np.inf
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        for _ in range(reps):
            pinocchio.rnea(pm, pd, q, v, a)
        rnea = min(rnea, (time.perf_counter() - t0) / reps * 1e6)

    from pkmdyn.multibody.dynamics.verbs import machine_verbs

    verbs = machine_verbs(view.mech)
    q0, qd0, qdd0, f0 = motion.angles[0], motion.rates[0], motion.accels[0], float(load[0])
    verbs.inverse_dynamics_one(view.mech, q0, qd0, qdd0, f0)

    def one_sample() -> None:
        verbs.inverse_dynamics_one(view.mech, q0, qd0, qdd0, f0)

    single = np.inf
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        for _ in range(200):
            one_sample()
        single = min(single, (time.perf_counter() - t0) / 200 * 1e6)

    child = subprocess.run(
        [sys.executable, __file__, "--_rss_child", str(args.rss_samples)], capture_output=True, text=True, check=True
    )
    rss = float(child.stdout.strip().splitlines()[-1])

    result = {
        "samples": n,
        "engine_us_per_sample": round(engine, 4),
        "reference_us_per_sample": round(ref_time, 2),
        "reference_samples": nr,
        "rnea_us": round(rnea, 4),
        "speedup": round(ref_time / engine, 1),
        "single_sample_us": round(single, 2),
        "peak_rss_mib_1e6": round(rss, 1),
        "rss_samples": args.rss_samples,
        "max_rel_difference_vs_reference": agreement,
        "targets": {
            "speedup_ge_100": ref_time / engine >= 100,
            "peak_rss_le_1024_mib": rss <= 1024,
        },
    }
    if not args.json:
        print("hip inverse dynamics benchmark (ISO 14242-1 cycle model, built-in parameters)")
    print(json.dumps(result, indent=None if args.json else 2))


if __name__ == "__main__":
    main()
