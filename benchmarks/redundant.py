"""Redundant actuation: what the distribution of the efforts costs per sample.

The inverse dynamics (efforts and every joint's reaction, ``joint_reactions``) of a redundantly
actuated mechanism against the same mechanism with one drive fewer (square), on the same
motion, warm: ``rrr4`` and ``stewart7``, each against itself with its last leg's drive passive
(square); each distribution of ``[actuation]``
(minimum norm, weighted, minimax, a preload). Prints one JSON object; the issue's target is the
minimum-norm route within 2x of the square one per sample.

    python benchmarks/redundant.py [--samples 400]
"""

from __future__ import annotations

import argparse
import copy
import json
import sys
import time
from pathlib import Path

import numpy as np

import pkmdyn
from pkmdyn.machines.registry import builtin_names
from pkmdyn.multibody import load_mechanism, reference_task, solve_kinematics
from pkmdyn.multibody.dynamics.newton_euler import joint_reactions

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import multibody_examples as ex  # noqa: E402  (the built-ins as dicts, their square variants)


def _per_sample(model, kin, repeats: int = 3) -> float:
    joint_reactions(model, kin)  # warm
    best = np.inf
    for _ in range(repeats):
        w0 = time.perf_counter()
        joint_reactions(model, kin)
        best = min(best, time.perf_counter() - w0)
    return best / len(kin)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=400)
    a = ap.parse_args()
    assert "rrr4" in builtin_names() and "stewart7" in builtin_names()
    out: dict = {}
    for red in ("rrr4", "stewart7"):
        m = pkmdyn.load(red)
        t = np.linspace(0.0, 2.0, a.samples)
        amp = np.where(m.task_kind == 1, 0.05, 0.02)
        x = reference_task(m) + amp * np.sin(2 * np.pi * t[:, None] / 2.0)
        xd = amp * 2 * np.pi / 2.0 * np.cos(2 * np.pi * t[:, None] / 2.0)
        xdd = -amp * (2 * np.pi / 2.0) ** 2 * np.sin(2 * np.pi * t[:, None] / 2.0)
        row = {}
        sq = load_mechanism(ex.passive_last_drive(ex.builtin_dict(red)))
        assert sq.na == sq.nt
        row["square_us"] = 1e6 * _per_sample(sq, solve_kinematics(sq, x, xd, xdd, t))
        for label, act in (("minimum_norm", {}), ("weighted", {"distribution": "weighted"}),
                           ("minimax", {"distribution": "minimax"}), ("preload", {"preload_min_effort_SI": 1.0})):
            d = copy.deepcopy(ex.builtin_dict(red))
            d["actuation"] = {**d.get("actuation", {}), **act}
            mm = load_mechanism(d)
            row[f"{red}_{label}_us"] = 1e6 * _per_sample(mm, solve_kinematics(mm, x, xd, xdd, t), 1)
        row["minimum_norm_over_square"] = row[f"{red}_minimum_norm_us"] / row["square_us"]
        out[red] = row
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
