"""Any closed-chain mechanism from a description file: format, topology, kinematics.

Description (TOML) -> :func:`load_description` -> :func:`compile_model` (spanning tree, cut
joints, loop records, flat arrays) -> :func:`solve_kinematics` (batched, compiled kernels)
-> :class:`MechanismKinematics`. :func:`load_mechanism` does the first two steps.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

if TYPE_CHECKING:
    from .description import Description, load_description
    from .joint_types import JOINT_TYPES, JointType, joint_type
    from .kinematics import (
        MechanismKinematics,
        SingularityMeasures,
        loop_residuals,
        reachable,
        reference_task,
        singularity_measures,
        solve_kinematics,
    )
    from .legs import LegTable, newton_only
    from .model import LoopRecord, MechanismModel, compile_model, load_mechanism
    from .motion import TaskMotion, default_motion, read_task_motion, task_columns
    from .topology import TopologyReport, analyse_topology, constraint_jacobian

__all__ = [
    "Description", "load_description", "JOINT_TYPES", "JointType", "joint_type",
    "MechanismModel", "LoopRecord", "compile_model", "load_mechanism",
    "TopologyReport", "analyse_topology", "constraint_jacobian",
    "MechanismKinematics", "solve_kinematics", "reference_task", "loop_residuals", "reachable",
    "SingularityMeasures", "singularity_measures",
    "TaskMotion", "default_motion", "read_task_motion", "task_columns", "LegTable", "newton_only",
]

#: where each public name lives, imported on first use: ``import pkmdyn.multibody`` loads
#: neither Numba's kernels nor SciPy until a function is looked up
__getattr__, __dir__ = attach(__name__, {
    **dict.fromkeys(("Description", "load_description"), ".description"),
    **dict.fromkeys(("JOINT_TYPES", "JointType", "joint_type"), ".joint_types"),
    **dict.fromkeys(("MechanismKinematics", "SingularityMeasures", "loop_residuals", "reachable", "reference_task",
                     "singularity_measures", "solve_kinematics"), ".kinematics"),
    **dict.fromkeys(("LegTable", "newton_only"), ".legs"),
    **dict.fromkeys(("LoopRecord", "MechanismModel", "compile_model", "load_mechanism"), ".model"),
    **dict.fromkeys(("TaskMotion", "default_motion", "read_task_motion", "task_columns"), ".motion"),
    **dict.fromkeys(("TopologyReport", "analyse_topology", "constraint_jacobian"), ".topology"),
})
