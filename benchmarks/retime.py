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

- **Least energy** on the Delta's cycle within 1.1 to 2 times the fastest cycle time: the energy
  (Eq. E1: copper losses, with ``R / k_t^2 = 1`` as the Delta's description gives no motor
  constants, and friction dissipation) against the fastest timing slowed down uniformly to the
  same cycle time, and the Pareto curve on 8 cycle times up to 3 times the fastest.

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
    Retiming,
    limit_use,
    retime,
    task_path,
    timing_energy,
)
from pkmdyn.multibody.analyses.retime_energy import pareto_front, retime_energy


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
    # the least energy within longer cycles, against the fastest timing slowed down uniformly to
    # the same cycle (same path, same cycle time), both measured through run's inverse dynamics
    path = task_path(delta, rows)
    energy = []
    for f in (1.1, 1.25, 1.5, 2.0):
        w0 = time.perf_counter()
        least = retime_energy(delta, path, f * ret.cycle_time, a.points, lim, fastest=ret)
        took = time.perf_counter() - w0
        k = f * ret.cycle_time / ret.cycle_time
        slow = Retiming(ret.s, ret.t * k, ret.sd / k, ret.sdd / k ** 2, ret.x, ret.xd / k, ret.xdd / k ** 2,
                        ret.sd_limit, ret.sd_reach, ret.iterations, ret.bounds)
        e_least, e_slow = _checked(delta, least.timing, lim), _checked(delta, slow, lim)
        energy.append({"cycle_time_bound_s": f * ret.cycle_time, "cycle_time_s": least.timing.cycle_time,
                       "energy_J": e_least["energy_J"], "program_energy_J": least.energy_J,
                       "fastest_slowed_down_energy_J": e_slow["energy_J"],
                       "energy_over_slowed_down": e_least["energy_J"] / e_slow["energy_J"],
                       "largest_use_ratio": e_least["largest_use_ratio"], "passes": least.passes, "seconds": took})
    out["delta_least_energy"] = energy
    w0 = time.perf_counter()
    front = pareto_front(delta, path, ret.cycle_time * np.linspace(1.0, 3.0, 8), a.points, lim, fastest=ret)
    out["delta_pareto"] = {"seconds": time.perf_counter() - w0, "points": len(front),
                           "cycle_time_s": [f.timing.cycle_time for f in front],
                           "program_energy_J": [f.energy_J for f in front]}
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
