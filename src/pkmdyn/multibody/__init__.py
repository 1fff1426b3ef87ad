"""The engine: any closed-chain mechanism from a description, in layers that import one way.

Description (TOML) -> :func:`load_description` (:mod:`pkmdyn.multibody.description.schema`) -> :func:`compile_model`
(spanning tree, cut joints, loop records, flat arrays: :mod:`pkmdyn.multibody.model.compiler`) -> :func:`solve_kinematics`
(batched, compiled kernels: :mod:`pkmdyn.multibody.kinematics.inverse`) -> :class:`MechanismKinematics` -> inverse and
forward dynamics, reactions, friction, drives (:mod:`pkmdyn.multibody.dynamics.newton_euler`) -> stiffness, workspace, wear,
identification's regressor, design metrics (:mod:`.analyses`); other file formats at the edge
(:mod:`.formats`); the results as the files' columns (:mod:`.columns`) and as a 3D scene
(:mod:`.scene`). :func:`load_mechanism` does the first two steps. The engine writes no files and
starts no processes.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

if TYPE_CHECKING:
    from .description.schema import Description, load_description
    from .description.joint_types import JOINT_TYPES, JointType, joint_type
    from .kinematics.inverse import (
        MechanismKinematics,
        loop_residuals,
        reachable,
        reference_task,
        solve_kinematics,
    )
    from .kinematics.singularity.measures import SingularityMeasures, singularity_measures
    from .model.legs import LegTable, newton_only
    from .model.compiler import LoopRecord, MechanismModel, compile_model, load_mechanism
    from .kinematics.motion import TaskMotion, default_motion, read_task_motion, task_columns
    from .model.topology import TopologyReport, analyse_topology, constraint_jacobian

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
    **dict.fromkeys(("Description", "load_description"), ".description.schema"),
    **dict.fromkeys(("JOINT_TYPES", "JointType", "joint_type"), ".description.joint_types"),
    **dict.fromkeys(("MechanismKinematics", "loop_residuals", "reachable", "reference_task", "solve_kinematics"),
                    ".kinematics.inverse"),
    **dict.fromkeys(("SingularityMeasures", "singularity_measures"), ".kinematics.singularity.measures"),
    **dict.fromkeys(("LegTable", "newton_only"), ".model.legs"),
    **dict.fromkeys(("LoopRecord", "MechanismModel", "compile_model", "load_mechanism"), ".model.compiler"),
    **dict.fromkeys(("TaskMotion", "default_motion", "read_task_motion", "task_columns"), ".kinematics.motion"),
    **dict.fromkeys(("TopologyReport", "analyse_topology", "constraint_jacobian"), ".model.topology"),
})
