"""The description format: TOML (or a dict) to validated records: the schema and leg templates
(:mod:`.schema`), named design parameters and expressions (:mod:`.expressions`), the joint-type
table (:mod:`.joint_types`). Below every other part of the engine.

Every public name of these modules is importable from here; each is imported on first use."""

from __future__ import annotations

from ..._lazy import attach

__getattr__, __dir__ = attach(__name__, {
    **dict.fromkeys(("FUNCTIONS", "MAX_LENGTH", "evaluate", "parameter_bounds", "parameter_values",
                     "resolve_parameters"), ".expressions"),
    **dict.fromkeys(("JOINT_TYPES", "JointType", "MOTION_CODES", "joint_type", "type_code"), ".joint_types"),
    **dict.fromkeys(("ActuatorSpec", "BodySpec", "Description", "GROUND", "JointSpec", "LIMIT_KEYS", "LoadSpec",
                     "MAGNITUDES", "MotionSpec", "RESERVED_PARTS", "TaskSpec", "inertia_matrix",
                     "load_description"), ".schema"),
})
