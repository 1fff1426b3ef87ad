"""Timing shared by the benchmark scripts (run as ``python benchmarks/NAME.py``, so this folder is
on the import path)."""

from __future__ import annotations

import subprocess
import sys
import time
from collections.abc import Callable

__all__ = ["best_time", "best_times", "cli_peak_memory"]

_CHILD = """
import resource, sys, time
from pkmdyn.cli import main
t0 = time.perf_counter()
rc = main(sys.argv[1:])
dt = time.perf_counter() - t0
print(f"{rc} {dt} {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss}")
"""


def best_time(fn: Callable[[], object], repeat: int) -> float:
    """Best wall time [s] of ``repeat`` calls of ``fn`` after one warm-up call."""
    fn()
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def best_times(fns: dict[str, Callable[[], object]], repeat: int,
               clock: Callable[[], float] = time.process_time) -> dict[str, float]:
    """Best time [s] of each of ``fns`` over ``repeat`` rounds, each round calling every one in
    turn (after one warm-up call each), so that a change of a shared machine's load falls on
    all of them; CPU time of the process by default (what other jobs take from it is then not
    counted), wall time with ``clock=time.perf_counter``."""
    for fn in fns.values():
        fn()
    best = dict.fromkeys(fns, float("inf"))
    for _ in range(repeat):
        for k, fn in fns.items():
            t0 = clock()
            fn()
            best[k] = min(best[k], clock() - t0)
    return best


def cli_peak_memory(args: list[str]) -> tuple[float, float, float]:
    """Run ``pkmdyn ARGS`` in a fresh Python process; its own peak resident set size [MiB] (from
    ``resource.getrusage`` inside the child), the command's run time [s] and the process's
    wall time [s]. Exits with the command's error if it fails."""
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", _CHILD, *args], capture_output=True, text=True)
    wall = time.perf_counter() - t0
    lines = proc.stdout.strip().splitlines()
    if proc.returncode != 0 or not lines or lines[-1].split()[0] != "0":
        raise SystemExit(f"run failed: {proc.stderr.strip()}")
    _, run_s, maxrss_kib = lines[-1].split()
    return int(maxrss_kib) / 1024.0, float(run_s), wall
