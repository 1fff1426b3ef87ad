"""Kinematics on a compiled model: loop closure and task by batched Newton, velocities,
accelerations, Jacobians and singularity measures (:mod:`.inverse`), direct kinematics and
assembly modes (:mod:`.direct`), task and actuator motions (:mod:`.motion`); their compiled
kernels beside them.

Every public name of these modules is importable from here; each is imported on first use."""

from __future__ import annotations

from ..._lazy import attach

__getattr__, __dir__ = attach(__name__, {
    **dict.fromkeys(("Assembly", "AssemblyModes", "DirectKinematics", "ROUND_TRIP_TOLERANCE", "actuator_reference",
                     "assembly_modes", "direct_kinematics", "parse_actuators", "task_motion"), ".direct"),
    **dict.fromkeys(("MechanismKinematics", "SingularityMeasures", "TOLERANCE", "joint_coordinates", "joint_frame",
                     "least_measure_bounds", "least_measures", "limit_bounds", "limit_hit", "limit_line",
                     "limit_message", "limit_violation", "limited_joints", "loop_residuals", "neighbour_pairs",
                     "reachable", "reference_task", "singularity_measures", "solve_graph", "solve_kinematics"),
                     ".inverse"),
    **dict.fromkeys(("ActuatorMotion", "MAX_MOTION_ROWS", "PeriodicMotion", "RepeatedMotion", "TaskMotion",
                     "actuator_columns", "actuator_rates", "default_motion", "motion_columns", "periodic_motion",
                     "read_actuator_motion", "read_task_motion", "repeated_motion", "task_columns"), ".motion"),
})
