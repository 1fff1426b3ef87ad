"""The U-joint study of the paper's Fig. 23: constraint torque at U23, U24 and the error of the
actuator forces when it is neglected, for motions of increasing peak y acceleration.

The Eq. 84 motion of the model's ``[trajectory]`` amplitudes is run with the period that makes
``|y_ddot|max = 2 pi |S_y| / T^2`` equal to each requested peak, through the generic engine on
the PDM's description (the route of ``pkmdyn pdm run``, :func:`.run.compute`): the U-joint
torque is the reaction moment of U23, U24 along ``U_j3 = U_j1 x U_j2`` (Eq. 28, 58).
"Neglected" is the same description with both U joints made spherical: a joint that transmits
no torque, the SPU limb free to spin about its own axis, so that its spin equation (Eq. 58)
drops out. (The hand-derived route of the paper, Eq. 60/62 with ``M_uj = 0``, keeps the limb's
spin rate of the U joint; the two agree to about 1 % of the SPU limbs' errors, docs/pdm4.md.)
``python -m pkmdyn.machines.pdm4.ujoint`` prints the table as JSON for the default parameters.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

from ...multibody import load_mechanism, solve_kinematics
from ...multibody.dynamics.newton_euler import joint_reactions
from ...profiles.pdm_motion import cycloidal_motion
from .description import pdm_description
from .paper import LIMBS
from .params import PdmModel, load_params
from .run import compute

__all__ = ["u_joint_study", "PAPER_PEAKS_M_S2"]

#: the paper's three levels of peak y acceleration: 50, 500 and 1000 mm/s^2
PAPER_PEAKS_M_S2 = (0.05, 0.5, 1.0)


def _without_u_joint_torque(model: PdmModel) -> Any:
    """The PDM's compiled description with U23 and U24 spherical."""
    d = pdm_description(model)
    for joint in d["joints"]:
        if joint["name"] in ("U23", "U24"):
            joint["type"] = "spherical"
            del joint["axes"]
    return load_mechanism(d)


def u_joint_study(model: PdmModel, peaks_m_s2: tuple[float, ...] = PAPER_PEAKS_M_S2, samples: int = 401
                  ) -> list[dict[str, Any]]:
    """One row per peak acceleration [m/s^2]: ``period_s``, ``max_abs_u_joint_torque_Nm``
    (U23, U24), ``max_abs_force_N`` (four limbs) and ``max_force_error_percent``: the largest
    ``|f_neglected - f|`` over the motion, in percent of that limb's largest ``|f|``."""

    free = _without_u_joint_torque(model)
    limbs = [free.actuator_names.index(n) for n in LIMBS]
    rows = []
    S = model.trajectory.strokes
    for peak in peaks_m_s2:
        T = math.sqrt(2.0 * math.pi * abs(S[1]) / peak)
        motion = cycloidal_motion(S, T, samples)
        cols = compute(model, motion, progress=False).cols
        f = np.stack([cols[f"f{k}_N"] for k in range(1, 5)], axis=-1)
        torque = np.stack([cols["U23_torque_Nm"], cols["U24_torque_Nm"]], axis=-1)
        kin = solve_kinematics(free, motion.q, motion.qd, motion.qdd, motion.t)
        f0 = joint_reactions(free, kin).u[:, limbs]
        big = np.abs(f).max(axis=0)
        rows.append({
            "peak_y_accel_m_s2": peak,
            "period_s": T,
            "max_abs_u_joint_torque_Nm": np.abs(torque).max(axis=0).tolist(),
            "max_abs_force_N": big.tolist(),
            "max_force_error_percent": (100.0 * np.abs(f0 - f).max(axis=0) / big).tolist(),
        })
    return rows


if __name__ == "__main__":  # pragma: no cover
    print(json.dumps(u_joint_study(load_params()), indent=2))
