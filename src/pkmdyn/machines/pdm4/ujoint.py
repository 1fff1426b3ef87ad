"""The U-joint study of the paper's Fig. 23: constraint torque at U23, U24 and the error of the
actuator forces when it is neglected, for motions of increasing peak y acceleration.

The Eq. 84 motion of the model's ``[trajectory]`` amplitudes is run with the period that makes
``|y_ddot|max = 2 pi |S_y| / T^2`` equal to each requested peak. "Neglected" means the paper's
Eq. 60/62 with ``M_uj = 0``: the U joint is treated as transmitting no torque, and the limb's
spin equation about its own axis (Eq. 58) is dropped. ``python -m pkmdyn.machines.pdm4.ujoint``
prints the table as JSON for the default parameters.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

from ...profiles.pdm_motion import cycloidal_motion
from .dynamics import actuator_forces, inverse_dynamics
from .kinematics import inverse_kinematics
from .params import PdmModel, load_params

__all__ = ["u_joint_study", "PAPER_PEAKS_M_S2"]

#: the paper's three levels of peak y acceleration: 50, 500 and 1000 mm/s^2
PAPER_PEAKS_M_S2 = (0.05, 0.5, 1.0)


def u_joint_study(model: PdmModel, peaks_m_s2: tuple[float, ...] = PAPER_PEAKS_M_S2, samples: int = 401
                  ) -> list[dict[str, Any]]:
    """One row per peak acceleration [m/s^2]: ``period_s``, ``max_abs_u_joint_torque_Nm``
    (U23, U24), ``max_abs_force_N`` (four limbs) and ``max_force_error_percent``: the largest
    ``|f_neglected - f|`` over the motion, in percent of that limb's largest ``|f|``."""
    rows = []
    S = model.trajectory.strokes
    for peak in peaks_m_s2:
        T = math.sqrt(2.0 * math.pi * abs(S[1]) / peak)
        kin = inverse_kinematics(model, cycloidal_motion(S, T, samples))
        reac = inverse_dynamics(model, kin)
        f0 = actuator_forces(model, kin, u_joint_torque=False)
        big = np.abs(reac.force).max(axis=0)
        rows.append({
            "peak_y_accel_m_s2": peak,
            "period_s": T,
            "max_abs_u_joint_torque_Nm": np.abs(reac.u_joint_torque).max(axis=0).tolist(),
            "max_abs_force_N": big.tolist(),
            "max_force_error_percent": (100.0 * np.abs(f0 - reac.force).max(axis=0) / big).tolist(),
        })
    return rows


if __name__ == "__main__":  # pragma: no cover
    print(json.dumps(u_joint_study(load_params()), indent=2))
