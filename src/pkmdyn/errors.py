"""One exception family for every user error pkmdyn can report.

Every message names what is wrong (the key, the row, the leg, the sample time) so that
the command line can print it as one line and exit with status 2.
"""

from __future__ import annotations

__all__ = [
    "PkmdynError",
    "ParameterError",
    "MotionError",
    "UnreachablePoseError",
    "SingularityError",
    "SingularityWarning",
]


class PkmdynError(Exception):
    """Base class of every error caused by user input."""


class ParameterError(PkmdynError):
    """A parameter file or value breaks a rule; the message names the key."""


class MotionError(PkmdynError):
    """A motion or load file or array is malformed; the message names the row or column."""


class UnreachablePoseError(PkmdynError):
    """A pose that no lever or limb can reach; the message names the sample time and leg."""


class SingularityError(PkmdynError):
    """A configuration at which a Jacobian cannot be inverted."""


class SingularityWarning(UserWarning):
    """A sample closer to a singularity than the configured threshold."""
