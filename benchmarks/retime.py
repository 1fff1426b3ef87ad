"""The fastest timing of a path (``pkmdyn retime``): its cycle times, energies and the time it
takes, on the papers' kind of cycles.

- **Delta pick-and-place** (the Delta benchmark's cycle of ``sweep.py``: 305 mm across along a
  25 mm arch at z = -1 m and back), every arm's torque within ``--delta-effort`` N m: the cycle
  time, the friction dissipation and effort integrals, the largest use of a bound through the
  same inverse dynamics as ``pkmdyn run``, and the share of grid points where a bound is used at
  99 % or more (time-optimality's signature; the issue's target 95 %).
- **Stewart platform**, its default motion's path on 1,000 grid points with every limit: each
  leg's force, every joint's reaction force and moment, the description's speed and
  acceleration limits; the wall-clock time of a warm call (target: within 10 s on 2 cores).

The original timing of each path is given beside the retimed one. Prints one JSON object; with
``--json`` nothing else.

    python benchmarks/retime.py --json [--points 1000] [--delta-effort 30]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

import pkmdyn
from pkmdyn.multibody.analyses.retime import (
    RetimeLimits,
    limit_use,
    retime,
    task_path,
    timing_energy,
)


def _pick_and_place() -> tuple[np.ndarray, np.ndarray]:
    t = np.linspace(0.0, 0.5, 201)
    u = np.where(t <= 0.25, t / 0.25, 2.0 - t / 0.25)
    w = u ** 3 * (10.0 - 15.0 * u + 6.0 * u ** 2)
    return t, np.column_stack([-0.1525 + 0.305 * w, 0.0 * t, -1.0 + 0.025 * np.sin(np.pi * w)])


def _checked(model, ret, limits) -> dict:
    kin = pkmdyn.kinematics(model, ret.motion())
    dyn = pkmdyn.dynamics(model, kin)
    use = limit_use(model, kin, dyn.reactions, limits)
    most = use.use.max(axis=1)
    return {"cycle_time_s": ret.cycle_time, "passes": ret.iterations, "largest_use_ratio": float(most.max()),
            "share_at_99_percent": float(np.mean(most >= 0.99)), **timing_energy(model, kin, dyn.reactions)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--points", type=int, default=1000)
    ap.add_argument("--delta-effort", type=float, default=30.0)
    a = ap.parse_args()
    out: dict = {}
    delta = pkmdyn.load("delta")
    t, rows = _pick_and_place()
    nj = len(delta.joint_names)
    lim = RetimeLimits(np.full(delta.na, a.delta_effort), np.full(nj, np.inf), np.full(nj, np.inf), {})
    w0 = time.perf_counter()
    ret = retime(delta, task_path(delta, rows), a.points, lim)
    out["delta_retime_s"] = time.perf_counter() - w0
    out["delta_pick_and_place"] = {"original_cycle_s": float(t[-1]), "effort_bound_Nm": a.delta_effort,
                                   **_checked(delta, ret, lim)}
    st = pkmdyn.load("stewart")
    nj = len(st.joint_names)
    path = task_path(st, pkmdyn.default_motion(st).x)
    lim = RetimeLimits(np.full(st.na, 2000.0), np.full(nj, 3000.0), np.full(nj, 500.0), {})
    retime(st, path, 50, lim)  # warm: the kernels compiled
    w0 = time.perf_counter()
    ret = retime(st, path, a.points, lim)
    out["stewart_retime_every_limit_s"] = time.perf_counter() - w0
    out["stewart_default_path"] = {"original_cycle_s": float(pkmdyn.default_motion(st).t[-1]),
                                   "bounds": "leg force 2000 N, reaction force 3000 N, reaction moment 500 N m, "
                                             "the description's speed and acceleration limits",
                                   "grid_points": a.points, **_checked(st, ret, lim)}
    print(json.dumps(out, indent=None if a.json else 2))


if __name__ == "__main__":
    main()
