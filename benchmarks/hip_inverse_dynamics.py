"""Speed of the hip simulator's closed-chain inverse dynamics with friction.

Runs, in one process and on the same samples (the ISO 14242-1 cycle model, inputs R, omega,
omega_dot and load): the closed-form batched model, the Pinocchio reference path (spanning
tree + loop closures, one sample at a time), and one bare ``pinocchio.rnea`` call on the
machine's spanning tree. Prints one JSON object; with ``--json`` nothing else is printed.

    python benchmarks/hip_inverse_dynamics.py --json [--samples 10000]

Fields: samples, closed_form_us_per_sample, reference_us_per_sample (timed on
``--reference-samples`` samples), rnea_us, speedup (reference / closed form),
single_sample_us (one sample, one call, as a controller would call it), peak_rss_mib_1e6 (peak
resident memory of a fresh process that computes 1,000,000 samples in chunks), targets met.
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

from pkmdyn.machines.hip_simulator import inverse_dynamics, load_params, platform_kinematics
from pkmdyn.machines.hip_simulator.run import torques_batched
from pkmdyn.profiles.iso14242 import iso14242_motion
from pkmdyn.spatial import euler_kinematics

from _timing import best_time


def _inputs(n: int):
    model = load_params()
    motion = iso14242_motion(cycles=max(n / 1000.0, 0.002), samples_per_cycle=1000)
    motion_t = motion.t[:n]
    R, w, wd = euler_kinematics(model.geometry.euler_sequence, motion.angles[:n], motion.rates[:n], motion.accels[:n])
    return model, motion_t, R, w, wd, motion.load[:n]


def _peak_rss_child(n: int) -> None:
    """Child-process mode: compute ``n`` samples in chunks and print the peak RSS in MiB."""
    model = load_params()
    chunk = 100_000
    cycle_samples = 1000
    total = 0.0
    for start in range(0, n, chunk):
        m = min(chunk, n - start)
        motion = iso14242_motion(cycles=m / cycle_samples, samples_per_cycle=cycle_samples)
        R, w, wd = euler_kinematics(model.geometry.euler_sequence, motion.angles[:m], motion.rates[:m], motion.accels[:m])
        tau = torques_batched(model, motion.t[:m], R, w, wd, motion.load[:m])
        total += float(np.abs(tau).sum())
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

    model, t, R, w, wd, load = _inputs(args.samples)
    n = t.shape[0]
    closed = best_time(lambda: torques_batched(model, t, R, w, wd, load), args.repeat) / n * 1e6

    nr = min(args.reference_samples, n)
    ref_time = best_time(lambda: reference_torques(model, t[:nr], R[:nr], w[:nr], wd[:nr], load[:nr]), 1) / nr * 1e6
    tau_closed = torques_batched(model, t[:nr], R[:nr], w[:nr], wd[:nr], load[:nr])
    tau_ref = reference_torques(model, t[:nr], R[:nr], w[:nr], wd[:nr], load[:nr])["tau"]
    agreement = float(np.abs(tau_closed - tau_ref).max() / np.abs(tau_ref).max())

    pm, pd, q, v, a = spanning_tree_rnea_inputs(model)
    reps = 20_000
    rnea = np.inf
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        for _ in range(reps):
            pinocchio.rnea(pm, pd, q, v, a)
        rnea = min(rnea, (time.perf_counter() - t0) / reps * 1e6)

    def one_sample() -> None:
        kin = platform_kinematics(model, t[:1], R[:1], w[:1], wd[:1], check_conditioning=False)
        inverse_dynamics(model, kin, load[:1])

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
        "closed_form_us_per_sample": round(closed, 4),
        "reference_us_per_sample": round(ref_time, 2),
        "reference_samples": nr,
        "rnea_us": round(rnea, 4),
        "speedup": round(ref_time / closed, 1),
        "single_sample_us": round(single, 2),
        "peak_rss_mib_1e6": round(rss, 1),
        "rss_samples": args.rss_samples,
        "max_rel_difference_vs_reference": agreement,
        "targets": {
            "closed_form_le_rnea": closed <= rnea,
            "speedup_ge_100": ref_time / closed >= 100,
            "peak_rss_le_1024_mib": rss <= 1024,
        },
    }
    if not args.json:
        print("hip inverse dynamics benchmark (ISO 14242-1 cycle model, built-in parameters)")
    print(json.dumps(result, indent=None if args.json else 2))


if __name__ == "__main__":
    main()
