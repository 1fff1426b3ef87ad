"""The 4-DOF over-constrained parallel driving mechanism (PDM) of Huang et al. (2023).

Two RPR and two SPU limbs drive a planar six-bar that carries the moving platform through
the revolute joint R4. Data flows one way: TOML -> :class:`PdmModel` -> motion ->
:func:`inverse_kinematics` -> results and plots.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

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

#: the package's names and their modules, imported on first use (so that the registry and the
#: command line can read the machine's entry without loading its dynamics)
_LAZY = {"PdmModel": "params", "load_params": "params", "default_params_path": "params",
         **dict.fromkeys(("BODY_NAMES", "BodyState", "PdmPositions", "PdmKinematics", "inverse_position",
                          "inverse_kinematics", "reachable"), "kinematics")}

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


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
