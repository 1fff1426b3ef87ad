"""The first command after an install against the same command warm, and the install itself.

1. A fresh virtual environment and ``python -m pip install .`` of this checkout, timed (the
   wheel's build compiles the kernels, ``pkmdyn compile``; pip's own cache of downloaded
   packages is used where it has them: say so beside the figure).
2. Each command of :data:`COMMANDS` run twice in that environment, each in a folder of its
   own, with numba's default cache location (inside the installed package): ``first_s``, the
   first run after the install, and ``warm_s``, the second; ``first_over_warm`` their ratio
   (target: at most 1.5).
3. With ``--fallback``, each command again with ``NUMBA_CACHE_DIR`` a fresh empty folder: what a
   command costs where the installed cache cannot serve (another CPU, another numba), compiling
   what it needs (``fallback_first_s``).

Wall times of whole commands (``pkmdyn ...`` as a user types it). Prints one JSON object; with
``--json`` nothing else.

    python benchmarks/cold_start.py --json [--fallback] [--venv DIR (reuse an installed one)]
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

ROOT = Path(__file__).resolve().parent.parent

#: the commands timed, by name: their arguments without ``--out`` (``@stewart-actuators``: the
#: Stewart platform's actuators a little off their reference, computed in the environment)
COMMANDS = {
    "run_stewart": ["run", "--machine", "stewart"],
    "control_stewart": ["control", "--machine", "stewart"],
    "hip_run": ["hip", "run"],
    "assemble_stewart": ["assemble", "--machine", "stewart", "--actuators", "@stewart-actuators"],
    "stiffness_delta": ["stiffness", "--machine", "delta"],
}


def _timed(cmd: list[str], env: dict[str, str]) -> float:
    t0 = time.perf_counter()
    r = subprocess.run(cmd, env=env, capture_output=True, text=True)
    dt = time.perf_counter() - t0
    if r.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({r.returncode}): {r.stderr.strip()[-2000:]}")
    return dt


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print only the JSON object")
    ap.add_argument("--fallback", action="store_true", help="also each command with an empty numba cache")
    ap.add_argument("--venv", type=Path, help="an environment pkmdyn is installed in (no install timed)")
    args = ap.parse_args()
    say = (lambda *a: None) if args.json else (lambda *a: print(*a, file=sys.stderr, flush=True))
    out: dict = {"cpus": os.cpu_count()}
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "PYTHONPATH", "VIRTUAL_ENV")}
    with tempfile.TemporaryDirectory(prefix="pkmdyn-cold-") as tmp:
        root = Path(tmp)
        venv = args.venv
        if venv is None:
            venv = root / "venv"
            subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
            subprocess.run([str(venv / "bin" / "python"), "-m", "pip", "install", "-q", "--upgrade", "pip"], check=True,
                           env=env)
            t0 = time.perf_counter()
            subprocess.run([str(venv / "bin" / "python"), "-m", "pip", "install", "-q", str(ROOT)], check=True, env=env)
            out["install_s"] = time.perf_counter() - t0
            say("install", out["install_s"])
        py = str(venv / "bin" / "python")
        act = subprocess.run([py, "-c", "from pkmdyn.cli.compile import _reference_actuators as a; print(a('stewart'))"],
                             env=env, capture_output=True, text=True, check=True).stdout.strip()
        for name, cmd in COMMANDS.items():
            line = [py, "-m", "pkmdyn.cli", *[act if a == "@stewart-actuators" else a for a in cmd]]
            res = {"first_s": _timed([*line, "--out", str(root / f"{name}-1")], env),
                   "warm_s": _timed([*line, "--out", str(root / f"{name}-2")], env)}
            res["first_over_warm"] = res["first_s"] / res["warm_s"]
            if args.fallback:
                cache = root / f"cache-{name}"
                cache.mkdir()
                res["fallback_first_s"] = _timed([*line, "--out", str(root / f"{name}-3")],
                                                 {**env, "NUMBA_CACHE_DIR": str(cache)})
            out[name] = res
            say(name, res)
    out["targets"] = {f"{n}_first_over_warm<=1.5": out[n]["first_over_warm"] <= 1.5 for n in COMMANDS}
    if "install_s" in out:
        out["targets"]["install_s<=300"] = out["install_s"] <= 300.0
    print(json.dumps(out))


if __name__ == "__main__":
    main()
