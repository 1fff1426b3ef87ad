"""Compare the hip model on the built-in ISO 14242-1 cycle with the values reported in the paper.

Prints Markdown tables (used in ``docs/hip_simulator.md``). The paper's figures below are the
values *reported* in Chen, Cheng & Pang (2022), §5.1-5.2, kept here only to be compared with;
nothing computed by pkmdyn depends on them.

    python examples/hip_paper_comparison.py
"""

from __future__ import annotations

import copy

import numpy as np

from pkmdyn.machines.hip_simulator import inverse_dynamics, inverse_kinematics, load_params, model_from_dict
from pkmdyn.machines.hip_simulator.params import default_params_dict
from pkmdyn.profiles.iso14242 import iso14242_motion

PAPER_KINEMATICS = {  # §5.1, mm, mm/s, mm/s^2
    "max L, platform 1 [mm]": (665.58, 660.47, 624.42),
    "max L, platform 2 [mm]": (256.58, 251.47, 215.42),
    "max |Ld| [mm/s]": (275.15, 267.80, 143.97),
    "max |Ldd| [mm/s^2]": (2152.40, 2100.80, 1270.90),
}
PAPER_TORQUES = {  # §5.2, N mm
    "platform": (300.18, 289.79, 267.69),
    "lever": (26.22, 30.97, 26.38),
    "slider": (118.41, 119.30, 115.11),
    "screw": (74.261, 72.69, 44.12),
    "total (measured, Fig. 11)": (850.0, 806.0, 743.0),
}


def _row(name: str, ours, paper) -> str:
    cells = []
    for o, p in zip(ours, paper):
        cells.append(f"{o:.2f} / {p:.2f} ({100 * (o - p) / p:+.1f} %)")
    return f"| {name} | " + " | ".join(cells) + " |"


def main() -> None:
    model = load_params()
    motion = iso14242_motion(1, 2000)
    kin = inverse_kinematics(model, motion)
    tq = inverse_dynamics(model, kin, motion.load)
    print("Kinematics on the ISO 14242-1 model: pkmdyn / paper (relative difference)\n")
    print("| quantity | slider 1 | slider 2 | slider 3 |\n|---|---|---|---|")
    ours = {
        "max L, platform 1 [mm]": 1e3 * kin.L[:, 0].max(axis=0),
        "max L, platform 2 [mm]": 1e3 * kin.L[:, 1].max(axis=0),
        "max |Ld| [mm/s]": 1e3 * np.abs(kin.Ld[:, 1]).max(axis=0),
        "max |Ldd| [mm/s^2]": 1e3 * np.abs(kin.Ldd[:, 1]).max(axis=0),
    }
    for name, paper in PAPER_KINEMATICS.items():
        print(_row(name, ours[name], paper))
    print("\nMaximum |torque| per motor [N mm]: pkmdyn / paper (relative difference)\n")
    print("| part | motor 1 | motor 2 | motor 3 |\n|---|---|---|---|")
    for part, paper in PAPER_TORQUES.items():
        key = part.split()[0]
        value = tq.tau if key == "total" else getattr(tq, key)
        print(_row(part, 1e3 * np.abs(value).max(axis=0), paper))
    fr = 1e3 * np.abs(tq.friction).max(axis=0)
    print("| friction (not split out in the paper) | " + " | ".join(f"{v:.2f} / -" for v in fr) + " |")
    print(_row("platform + friction", 1e3 * np.abs(tq.platform + tq.friction).max(axis=0), PAPER_TORQUES["platform"]))

    # the paper's perpendicular-lever assumption against the U-joint default
    d = copy.deepcopy(default_params_dict())
    d["geometry"]["lever_spin"] = "perpendicular"
    perp = model_from_dict(d)
    kin_p = inverse_kinematics(perp, motion)
    tq_p = inverse_dynamics(perp, kin_p, motion.load)
    print("\nLever spin: perpendicular (paper Eq. 4) against U joint (default), ISO cycle\n")
    print(f"- max lever spin about its own axis: {np.abs(kin.spin).max():.4f} rad/s "
          f"(max |omega_lever| {np.abs(kin.omega_lever).max():.4f} rad/s)")
    for part in ("lever", "tau"):
        diff = np.abs(getattr(tq_p, part) - getattr(tq, part)).max()
        label = "the total torque" if part == "tau" else f"tau_{part}"
        print(f"- max |difference| in {label}: {1e3 * diff:.4f} N mm "
              f"({100 * diff / np.abs(getattr(tq, part)).max():.3f} % of its max)")
    # the platform mass only enters the thrust-bearing friction
    d = copy.deepcopy(default_params_dict())
    d["inertia"]["platform_mass_kg"] = 10.0
    heavy = model_from_dict(d)
    tq_h = inverse_dynamics(heavy, inverse_kinematics(heavy, motion), motion.load)
    print(f"\nA 10 kg platform (instead of 0) raises the max friction torque by "
          f"{1e3 * (np.abs(tq_h.friction).max() - np.abs(tq.friction).max()):.3f} N mm.")
    rise = 1e3 * (np.abs(tq_h.friction).max(axis=0) - np.abs(tq.friction).max(axis=0))
    print("Per motor: " + ", ".join(f"motor {i + 1} +{r:.2f} N mm" for i, r in enumerate(rise)) + ".")


if __name__ == "__main__":
    main()
