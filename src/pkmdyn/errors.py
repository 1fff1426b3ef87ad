"""One exception family for every user error pkmdyn can report.

Every message names what is wrong (the key, the row, the leg, the sample time) so that
the command line can print it as one line and exit with status 2. The entry checks of the
library's public functions (:func:`as_array`, :func:`check_type`) live here too, so that a
wrong shape or type becomes one of these errors with the expected shape.
"""

from __future__ import annotations

__all__ = [
    "at_sample",
    "PkmdynError",
    "ParameterError",
    "MotionError",
    "UnreachablePoseError",
    "SingularityError",
    "SingularityWarning",
    "LimitError",
    "as_array",
    "check_type",
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


class LimitError(PkmdynError):
    """A value beyond a configurable plausibility limit; the message names the limit and how to raise it."""


class SingularityWarning(UserWarning):
    """A sample closer to a singularity than the configured threshold."""


def at_sample(i: int, t: object = None, offset: int = 0) -> str:
    """How messages name sample ``i`` of a run's window that starts at sample ``offset``:
    ``sample N`` and, where the times ``t`` are known, ``(t = ... s)``."""
    return f"sample {i + offset}" + (f" (t = {t[i]:.6g} s)" if t is not None else "")  # type: ignore[index]


def as_array(value: object, shape: tuple[int | None, ...], name: str, error: type[PkmdynError] = PkmdynError):
    """``value`` as a float array of ``shape`` (``None`` = any length), or ``error`` naming ``name``.

    The entry check of the library's public functions: a wrong type, a transposed or flattened
    array, or a wrong number of dimensions is reported with the expected shape, e.g.
    ``"angles: expected shape (n, 3), got (3, 100)"``, instead of a numpy error deep inside.
    """
    import numpy as np  # deferred: `import pkmdyn` (its errors) loads no numpy

    want = "(" + ", ".join("n" if s is None else str(s) for s in shape) + (",)" if len(shape) == 1 else ")")
    if isinstance(value, (str, bytes)) or value is None:
        raise error(f"{name}: expected a float array of shape {want}, got {type(value).__name__}")
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise error(f"{name}: expected a float array of shape {want}, got {type(value).__name__}") from None
    if arr.ndim != len(shape) or any(s is not None and a != s for a, s in zip(arr.shape, shape)):
        raise error(f"{name}: expected shape {want}, got {arr.shape}")
    return arr


def check_type(value: object, cls: type, name: str, error: type[PkmdynError] = PkmdynError) -> None:
    """Raise ``error`` naming ``name`` unless ``value`` is an instance of ``cls``."""
    if not isinstance(value, cls):
        raise error(f"{name}: expected a {cls.__name__}, got {type(value).__name__}")
