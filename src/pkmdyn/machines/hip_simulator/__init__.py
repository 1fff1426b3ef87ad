"""The 2(3PUS+S) dual-platform hip-joint wear simulator (Chen, Cheng & Pang 2022)."""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .dynamics import HipTorques, inverse_dynamics
    from .forward import forward_dynamics
    from .kinematics import HipKinematics, inverse_kinematics, platform_kinematics
    from .params import HipModel, load_params, model_from_dict

#: the package's names and their modules, imported on first use (so that the registry and the
#: command line can read the machine's entry without loading its dynamics)
_LAZY = {"HipModel": "params", "load_params": "params", "model_from_dict": "params",
         "HipKinematics": "kinematics", "inverse_kinematics": "kinematics", "platform_kinematics": "kinematics",
         "HipTorques": "dynamics", "inverse_dynamics": "dynamics", "forward_dynamics": "forward"}

__all__ = [
    "HipModel",
    "load_params",
    "model_from_dict",
    "HipKinematics",
    "inverse_kinematics",
    "platform_kinematics",
    "HipTorques",
    "inverse_dynamics",
    "forward_dynamics",
]


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
