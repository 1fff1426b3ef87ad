"""Checks and fits shared by the motion-file readers (orientation motions, the PDM's, described mechanisms).

Errors name the file, the 1-based data row and the column.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from .._lazy import lazy_module
from ..errors import MotionError

if TYPE_CHECKING:
    from scipy import interpolate, signal
else:  # imported by the first derivatives taken (scipy.signal alone costs a third of a second)
    interpolate, signal = lazy_module("scipy.interpolate"), lazy_module("scipy.signal")

__all__ = ["require_increasing", "require_rows", "column_group", "derivatives", "savgol_derivatives",
           "check_smoothing"]

Array = NDArray[np.float64]


def require_increasing(path: str | Path, t: Array) -> None:
    """Time ``t_s`` must increase strictly from row to row."""
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        r = int(bad[0]) + 2
        raise MotionError(
            f"{path}: row {r}, column 't_s': time must increase strictly ({t[r - 1]:g} s after {t[r - 2]:g} s)"
        )


def require_rows(path: str | Path, t: Array) -> None:
    """A motion has at least two rows (one sample has no duration)."""
    if t.shape[0] < 2:
        raise MotionError(f"{path}: a motion needs at least 2 data rows, found {t.shape[0]} (one sample has no "
                          "duration)")


def column_group(path: str | Path, cols: Mapping[str, Array], names: Sequence[str]) -> Array | None:
    """The columns ``names`` stacked as ``(n, len(names))``, or ``None`` when none is present.

    A group is all or nothing: a partial group is an error naming the first missing column.
    """
    present = [c for c in names if c in cols]
    if not present:
        return None
    if len(present) != len(names):
        missing = next(c for c in names if c not in cols)
        raise MotionError(f"{path}: missing column {missing!r} (give all of {', '.join(names)} or none)")
    return np.stack([cols[c] for c in names], axis=-1)


def derivatives(
    path: str | Path, t: Array, q: Array, qd: Array | None, qdd: Array | None, rate_names: Sequence[str]
) -> tuple[Array, Array]:
    """Rates and accelerations of ``q (n, k)``: given columns are used as they are; missing ones
    come from an interpolating quintic B-spline (``make_interp_spline``, k = 5, not-a-knot ends)
    through the angles (both missing) or through the given rates (accelerations missing)."""
    if qd is None and qdd is not None:
        raise MotionError(f"{path}: acceleration columns need the rate columns ({', '.join(rate_names)})")
    require_rows(path, t)
    if qd is not None and qdd is not None:
        return qd, qdd
    if t.shape[0] < 6:
        raise MotionError(
            f"{path}: at least 6 rows are needed to derive missing derivative columns by a quintic spline, "
            f"found {t.shape[0]}"
        )
    try:
        with np.errstate(all="ignore"):
            if qd is None:
                spline = interpolate.make_interp_spline(t, q, k=5, axis=0)
                qd, qdd = spline.derivative(1)(t), spline.derivative(2)(t)
            else:
                qdd = interpolate.make_interp_spline(t, qd, k=5, axis=0).derivative(1)(t)
    except (ValueError, np.linalg.LinAlgError):  # e.g. times so far apart that the spline is singular
        qdd = None
    if qdd is None or not (np.all(np.isfinite(qd)) and np.all(np.isfinite(qdd))):
        raise MotionError(f"{path}: the spline through the rows gives no finite derivatives (column 't_s' from "
                          f"{t[0]:g} to {t[-1]:g} s); give the derivative columns or check the times")
    return qd, qdd


def check_smoothing(window: int, order: int) -> None:
    """The Savitzky-Golay differentiator's window (odd, >= 3) and degree (>= 2, below the
    window); errors name the option."""
    if window % 2 == 0 or window < 3:
        raise MotionError(f"--sg-window: must be an odd number >= 3, got {window}")
    if not 2 <= order < window:
        raise MotionError(f"--sg-order: must be >= 2 and less than the window ({window}), got {order}")


def savgol_derivatives(t: Array, x: Array, window: int, order: int, source: str) -> tuple[Array, Array]:
    """First and second time derivatives of ``x (n, k)`` by a Savitzky-Golay filter.

    A polynomial of degree ``order`` is fitted by least squares to each ``window`` samples
    (``scipy.signal.savgol_filter``, ends by a fit to the first/last window) and
    differentiated; sampling must be uniform. Errors name ``source``.
    """
    n = t.shape[0]
    check_smoothing(window, order)
    if n < window:
        raise MotionError(f"{source}: {n} rows are fewer than the smoothing window of {window} samples")
    dt = np.diff(t)
    h = (t[-1] - t[0]) / (n - 1)
    if np.max(np.abs(dt - h)) > 1e-6 * h:
        r = int(np.argmax(np.abs(dt - h))) + 2
        raise MotionError(
            f"{source}: row {r}, column 't_s': sampling is not uniform (step {dt[r - 2]:g} s, mean {h:g} s); "
            "the smoothing differentiator needs a uniform time step, or give the derivative columns"
        )
    try:
        with np.errstate(all="ignore"):
            d1 = signal.savgol_filter(x, window, order, deriv=1, delta=h, axis=0, mode="interp")
            d2 = signal.savgol_filter(x, window, order, deriv=2, delta=h, axis=0, mode="interp")
    except (ValueError, np.linalg.LinAlgError):
        d1 = d2 = np.full_like(x, np.nan)
    if not (np.all(np.isfinite(d1)) and np.all(np.isfinite(d2))):
        raise MotionError(f"{source}: the derivatives overflow (time step {h:g} s); check the column 't_s'")
    return d1, d2
