"""Peak memory of ``pkmdyn hip control`` as a function of the run's length (streamed in spans).

Each measurement runs the command in a fresh subprocess (so the peak resident set size is the
run's own, read from ``resource.getrusage``) with the augmented PD on the built-in ISO 14242-1
cycle, 1000 control cycles per motion cycle. The bound of issue 14: flat in the run length, a
few hundred MiB at the ``--cycles`` cap (1000).

    python benchmarks/control_memory.py --json                      # 3, 30, 300, 1000 cycles, parquet
    python benchmarks/control_memory.py --json --cycles 3 300 --formats csv
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

from _timing import cli_peak_memory

BOUND_MIB = 500.0


def measure(cycles: float, fmt: str, plots: bool) -> dict:
    """One ``hip control`` run of ``cycles`` motion cycles in a subprocess: peak RSS and speed."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        args = ["hip", "control", "--controller", "augmented-pd", "--cycles", repr(cycles), "--format", fmt,
                "--out", str(out)] + ([] if plots else ["--no-plots"])
        peak, run_s, wall = cli_peak_memory(args)
        summary = json.loads((out / "summary.json").read_text())
        size = sum(p.stat().st_size for p in out.iterdir())
    return {"cycles": cycles, "control_cycles": summary["cycles"], "format": fmt, "plots": plots,
            "peak_rss_mib": round(peak, 1), "control_cycles_per_s": round(summary["cycles"] / float(run_s)),
            "run_s": round(float(run_s), 2), "process_wall_s": round(wall, 2), "output_mib": round(size / 2**20, 1),
            "within_bound": peak <= BOUND_MIB}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--cycles", type=float, nargs="+", default=[3.0, 30.0, 300.0, 1000.0])
    ap.add_argument("--formats", nargs="+", default=["parquet"], choices=["csv", "parquet"])
    ap.add_argument("--no-plots", action="store_true", help="measure without the plots")
    args = ap.parse_args()
    runs = [measure(c, fmt, not args.no_plots) for fmt in args.formats for c in args.cycles]
    first = [r for r in runs if r["format"] == args.formats[0]]
    result = {
        "bound_mib": BOUND_MIB,
        "runs": runs,
        "peak_rss_mib": max(r["peak_rss_mib"] for r in first),
        "rss_growth_ratio": round(first[-1]["peak_rss_mib"] / first[0]["peak_rss_mib"], 3),
        "all_within_bound": all(r["within_bound"] for r in runs),
    }
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        for r in runs:
            print(f"{r['format']:8s} {r['control_cycles']:>9d} control cycles: {r['peak_rss_mib']:7.1f} MiB, "
                  f"{r['run_s']:7.2f} s")


if __name__ == "__main__":
    main()
