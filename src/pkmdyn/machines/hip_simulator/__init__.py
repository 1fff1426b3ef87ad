"""The 2(3PUS+S) dual-platform hip-joint wear simulator (Chen, Cheng & Pang 2022)."""

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
