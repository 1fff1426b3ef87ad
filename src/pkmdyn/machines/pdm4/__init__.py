"""The 4-DOF over-constrained parallel driving mechanism (PDM) of Huang et al. (2023).

Two RPR and two SPU limbs drive a planar six-bar that carries the moving platform through
the revolute joint R4. Data flows one way: TOML -> :class:`PdmModel` -> motion ->
:func:`inverse_kinematics` -> results and plots.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..._lazy import attach

if TYPE_CHECKING:
    from .kinematics import (
        BODY_NAMES,
        BodyState,
        PdmKinematics,
        PdmPositions,
        inverse_kinematics,
        inverse_position,
        reachable,
    )
    from .params import PdmModel, default_params_path, load_params

__all__ = [
    "PdmModel",
    "load_params",
    "default_params_path",
    "BODY_NAMES",
    "BodyState",
    "PdmPositions",
    "PdmKinematics",
    "inverse_position",
    "inverse_kinematics",
    "reachable",
]

#: the package's names and their modules, imported on first use (so that the registry and the
#: command line can read the machine's entry without loading its dynamics)
__getattr__, __dir__ = attach(__name__, {
    **dict.fromkeys(("PdmModel", "load_params", "default_params_path"), ".params"),
    **dict.fromkeys(("BODY_NAMES", "BodyState", "PdmPositions", "PdmKinematics", "inverse_position",
                     "inverse_kinematics", "reachable"), ".kinematics"),
})
