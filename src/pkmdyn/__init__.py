"""pkmdyn: kinematics, dynamics and trajectory-tracking control of parallel manipulators."""

from .errors import (
    MotionError,
    ParameterError,
    PkmdynError,
    SingularityError,
    SingularityWarning,
    UnreachablePoseError,
)

__all__ = [
    "PkmdynError",
    "ParameterError",
    "MotionError",
    "UnreachablePoseError",
    "SingularityError",
    "SingularityWarning",
]
