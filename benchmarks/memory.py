"""Peak memory and throughput of long runs as a function of the sample count: ``pkmdyn hip run
--no-plots`` and ``pkmdyn run --machine NAME`` (the generic engine, streamed in chunks: every
body's kinematics, efforts, motor torques, effort split and joint reactions).

Each measurement runs the command in a fresh subprocess (so the peak resident set size is the
run's own, read from ``resource.getrusage`` in the child): the hip job on the built-in ISO
14242-1 cycle at 1000 samples per cycle; ``--machine stewart`` on its default motion at 1000
samples per cycle, ``--machine hip`` (the hip's description) on its ISO cycle (1000 samples)
repeated. The bound: 10,000,000 samples within 500 MiB.

    python benchmarks/memory.py --json                      # hip run: 1e5, 1e6, 1e7 samples, parquet + csv
    python benchmarks/memory.py --json --samples 1000000 --formats csv
    python benchmarks/memory.py --json --machine stewart hip --formats csv   # run --machine
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

from _timing import cli_peak_memory

BOUND_MIB = 500.0
SAMPLES_PER_CYCLE = 1000


def _measure(args: list[str], fmt: str, out: Path, **extra) -> dict:
    """Run ``pkmdyn ARGS`` (writing into ``out``) in a subprocess: peak RSS, speed, output size."""
    peak, run_s, wall = cli_peak_memory(args)
    summary = json.loads((out / "summary.json").read_text())
    size = sum(p.stat().st_size for p in out.iterdir())
    return {
        **extra,
        "samples": summary["samples"],
        **({"bodies_samples": summary["bodies_samples"]} if "bodies_samples" in summary else {}),
        "format": fmt,
        "peak_rss_mib": round(peak, 1),
        "samples_per_s": round(summary["samples"] / float(run_s)),
        "run_s": round(float(run_s), 2),
        "process_wall_s": round(wall, 2),
        "output_mib": round(size / 2**20, 1),
        "within_bound": peak <= BOUND_MIB,
    }


def measure(samples: int, fmt: str) -> dict:
    """One ``hip run --no-plots`` of ``samples`` samples in a subprocess: peak RSS and speed."""
    cycles = (samples - 1) / SAMPLES_PER_CYCLE
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        return _measure(["hip", "run", "--no-plots", "--cycles", repr(cycles), "--samples-per-cycle",
                         str(SAMPLES_PER_CYCLE), "--format", fmt, "--limit", f"max_samples={max(samples, 1)}",
                         "--out", str(out)], fmt, out)


def measure_described(machine: str, samples: int, fmt: str) -> dict:
    """One ``run --machine MACHINE`` of ``samples`` samples in a subprocess: peak RSS and speed."""
    cycles = (samples - 1) / SAMPLES_PER_CYCLE
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        args = ["run", "--machine", machine, "--cycles", repr(cycles), "--format", fmt, "--out", str(out)]
        if machine != "hip":  # the hip's description repeats its 1000-sample ISO cycle
            args[5:5] = ["--samples-per-cycle", str(SAMPLES_PER_CYCLE)]
        return _measure(args, fmt, out, machine=machine)


def baseline() -> float:
    """Peak RSS [MiB] of a process that only imports the command line (the fixed cost)."""
    code = ("import resource; import pkmdyn.cli, pkmdyn.machines.hip_simulator.job; "
            "print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return round(int(out.stdout.strip()) / 1024.0, 1)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--samples", type=int, nargs="+", default=[100_001, 1_000_001, 10_000_001])
    ap.add_argument("--formats", nargs="+", default=["parquet", "csv"], choices=["csv", "parquet"])
    ap.add_argument("--machine", nargs="+", default=None,
                    help="measure pkmdyn run --machine NAME (e.g. stewart hip) instead of pkmdyn hip run")
    args = ap.parse_args()
    if args.machine:
        runs = [measure_described(mach, n, fmt) for mach in args.machine for fmt in args.formats for n in args.samples]
        result = {"bound_mib": BOUND_MIB, "runs": runs,
                  "largest": {mach: max((r for r in runs if r["machine"] == mach), key=lambda r: r["samples"])
                              for mach in args.machine},
                  "all_within_bound": all(r["within_bound"] for r in runs)}
        if args.json:
            print(json.dumps(result, indent=2))
        else:
            for r in runs:
                print(f"{r['machine']:8s} {r['format']:8s} {r['samples']:>10d} samples: {r['peak_rss_mib']:7.1f} MiB, "
                      f"{r['samples_per_s']:>9d} samples/s")
        return
    runs = [measure(n, fmt) for fmt in args.formats for n in args.samples]
    base = baseline()
    largest = {fmt: max((r for r in runs if r["format"] == fmt), key=lambda r: r["samples"]) for fmt in args.formats}
    smallest = {fmt: min((r for r in runs if r["format"] == fmt), key=lambda r: r["samples"]) for fmt in args.formats}
    result = {
        "bound_mib": BOUND_MIB,
        "import_only_peak_rss_mib": base,
        "runs": runs,
        # the headline figures: the largest run of the first format
        "samples": largest[args.formats[0]]["samples"],
        "peak_rss_mib": largest[args.formats[0]]["peak_rss_mib"],
        "samples_per_s": largest[args.formats[0]]["samples_per_s"],
        "rss_growth_ratio": {fmt: round(largest[fmt]["peak_rss_mib"] / smallest[fmt]["peak_rss_mib"], 3)
                             for fmt in args.formats},
        "all_within_bound": all(r["within_bound"] for r in runs),
    }
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        for r in runs:
            print(f"{r['format']:8s} {r['samples']:>10d} samples: {r['peak_rss_mib']:7.1f} MiB, "
                  f"{r['samples_per_s']:>9d} samples/s")


if __name__ == "__main__":
    main()
