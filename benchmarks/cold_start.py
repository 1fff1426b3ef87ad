"""Cold and warm start of the commands: the wall time from the command to its files.

Each command runs in a child process (``python -m pkmdyn.cli ...``), first with an empty
numba cache (``NUMBA_CACHE_DIR`` a fresh folder: what a fresh install has, every kernel
compiled), then again with the cache that run left (what every later run has). ``run`` and
``control`` are timed cold each in a cache of its own, so that neither profits from the
other's compilation. Prints one JSON object with ``cold_run_s``, ``cold_control_s``,
``warm_run_s``, ``warm_control_s`` per machine and the targets of the cold start (30 s cold,
3 s warm); with ``--json`` nothing else is printed.

    python benchmarks/cold_start.py --json [--machines stewart delta hip]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def _timed(args: list[str], cache: Path, out: Path) -> float:
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "-m", "pkmdyn.cli", *args, "--out", str(out)], env=env,
                       capture_output=True, text=True)
    dt = time.perf_counter() - t0
    if r.returncode != 0:
        raise SystemExit(f"pkmdyn {' '.join(args)} failed: {r.stderr.strip()}")
    return dt


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print only the JSON object")
    ap.add_argument("--machines", nargs="+", default=["stewart", "delta", "hip"])
    args = ap.parse_args()
    out: dict = {"cpus": os.cpu_count()}
    commands = {"run": ["run"], "control": ["control", "--controller", "computed-torque"]}
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        for m in args.machines:
            res = {}
            for name, cmd in commands.items():
                cache = root / f"cache-{m}-{name}"
                cache.mkdir()
                res[f"cold_{name}_s"] = _timed([*cmd, "--machine", m], cache, root / f"{m}-{name}-cold")
                res[f"warm_{name}_s"] = _timed([*cmd, "--machine", m], cache, root / f"{m}-{name}-warm")
                if not args.json:
                    print(m, name, res, file=sys.stderr)
            out[m] = res
    out["targets"] = {f"{m}_cold_{c}_s<=30": out[m][f"cold_{c}_s"] <= 30.0 for m in args.machines
                      for c in ("run", "control")}
    out["targets"].update({f"{m}_warm_{c}_s<=3": out[m][f"warm_{c}_s"] <= 3.0 for m in args.machines
                           for c in ("run", "control")})
    print(json.dumps(out))


if __name__ == "__main__":
    main()
