"""Any closed-chain mechanism from a description file: format, topology, kinematics.

Description (TOML) -> :func:`load_description` -> :func:`compile_model` (spanning tree, cut
joints, loop records, flat arrays) -> :func:`solve_kinematics` (batched, compiled kernels)
-> :class:`MechanismKinematics`. :func:`load_mechanism` does the first two steps.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

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
from .model import LoopRecord, MechanismModel, compile_model
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


def load_mechanism(source: str | Path | dict[str, Any], limits: dict[str, Any] | None = None) -> MechanismModel:
    """Read, validate and compile a description (a TOML path or a dict); ``limits`` lay over its
    ``[limits]`` for the plausibility of its numbers (:func:`load_description`)."""
    return compile_model(load_description(source, limits))
