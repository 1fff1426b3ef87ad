"""Timing shared by the benchmark scripts (run as ``python benchmarks/NAME.py``, so this folder is
on the import path)."""

from __future__ import annotations

import subprocess
import sys
import time
from collections.abc import Callable

__all__ = ["best_time", "cli_peak_memory"]

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
