"""Kinematics on a compiled model: loop closure and task by batched Newton, velocities,
accelerations and Jacobians (:mod:`.inverse`), the singularity measures (:mod:`.singularity`),
direct kinematics and assembly modes (:mod:`.direct`), task and actuator motions
(:mod:`.motion`); their compiled kernels beside them.

Every public name of these modules is importable from here; each is imported on first use."""

from __future__ import annotations

from ..._lazy import attach

__getattr__, __dir__ = attach(__name__, {
    **dict.fromkeys(("Assembly", "AssemblyModes", "DirectKinematics", "ROUND_TRIP_TOLERANCE", "actuator_reference",
                     "assembly_modes", "direct_kinematics", "parse_actuators", "task_motion"), ".direct"),
    **dict.fromkeys(("MechanismKinematics", "TOLERANCE", "joint_coordinates", "joint_frame", "limit_bounds",
                     "limit_hit", "limit_line", "limit_message", "limit_violation", "limited_joints", "loop_residuals",
                     "neighbour_pairs", "reachable", "reference_task", "solve_graph", "solve_kinematics"), ".inverse"),
    **dict.fromkeys(("SCREEN_STRIDE", "SingularityMeasures", "least_measure_bounds", "least_measures",
                     "singularity_measures"), ".singularity.measures"),
    **dict.fromkeys(("ActuatorMotion", "MAX_MOTION_ROWS", "PeriodicMotion", "RepeatedMotion", "TaskMotion",
                     "actuator_columns", "actuator_rates", "default_motion", "motion_columns", "periodic_motion",
                     "read_actuator_motion", "read_task_motion", "repeated_motion", "task_columns"), ".motion"),
})
