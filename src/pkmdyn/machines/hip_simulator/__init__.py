"""The 2(3PUS+S) dual-platform hip-joint wear simulator (Chen, Cheng & Pang 2022)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..._lazy import attach

if TYPE_CHECKING:
    from .dynamics import HipTorques, inverse_dynamics
    from .forward import forward_dynamics
    from .kinematics import HipKinematics, inverse_kinematics, platform_kinematics
    from .params import HipModel, load_params, model_from_dict

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

#: the package's names and their modules, imported on first use (so that the registry and the
#: command line can read the machine's entry without loading its dynamics)
__getattr__, __dir__ = attach(__name__, {
    **dict.fromkeys(("HipModel", "load_params", "model_from_dict"), ".params"),
    **dict.fromkeys(("HipKinematics", "inverse_kinematics", "platform_kinematics"), ".kinematics"),
    **dict.fromkeys(("HipTorques", "inverse_dynamics"), ".dynamics"),
    "forward_dynamics": ".forward",
})
