"""Orientation motions with a load (a platform's Euler angles and an axial test load) and their CSV
file format.

CSV columns (spec, "Motion file"): ``t_s, alpha_deg, beta_deg, gamma_deg``; optional
Euler-angle rates ``alpha_dot_deg_s, beta_dot_deg_s, gamma_dot_deg_s`` and accelerations
``alpha_ddot_deg_s2, beta_ddot_deg_s2, gamma_ddot_deg_s2`` (all three of a kind or none);
optional ``load_N``. Given derivative columns are used as they are; missing ones are derived
by an interpolating quintic B-spline (``scipy.interpolate.make_interp_spline``, k = 5,
not-a-knot ends) through the angles, or through the rates when only the accelerations are
missing; its first and second derivatives are continuous. Give the derivative columns
whenever they are known exactly.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..errors import MotionError, as_array
from ..io import DEFAULT_MAX_SAMPLES, read_csv_columns, write_csv
from ._columns import column_group, derivatives, require_increasing

__all__ = ["OrientationMotion", "check_load", "make_motion", "read_motion_csv", "write_motion_csv", "MOTION_COLUMNS"]

Array = NDArray[np.float64]

_ANG = ("alpha_deg", "beta_deg", "gamma_deg")
_RATE = ("alpha_dot_deg_s", "beta_dot_deg_s", "gamma_dot_deg_s")
_ACC = ("alpha_ddot_deg_s2", "beta_ddot_deg_s2", "gamma_ddot_deg_s2")
MOTION_COLUMNS = ("t_s", *_ANG, *_RATE, *_ACC, "load_N")


@dataclass(frozen=True)
class OrientationMotion:
    """Euler angles of the platforms over time, with the hydraulic load.

    ``t (n,)`` [s]; ``angles, rates, accels (n, 3)`` [rad, rad/s, rad/s^2] in the order of the
    model's Euler sequence (alpha FE, beta AA, gamma IER); ``load (n,)`` [N], >= 0.
    """

    t: Array
    angles: Array
    rates: Array
    accels: Array
    load: Array

    def __len__(self) -> int:
        return int(self.t.shape[0])


def check_load(t: Array, load: Array) -> Array:
    """The hydraulic load ``(n,)`` [N] as floats; a wrong shape, a NaN, an infinity or a negative
    value is a :class:`MotionError` naming the row and its time."""
    load = as_array(load, np.shape(t), "load", MotionError)
    bad = np.flatnonzero(~(np.isfinite(load) & (load >= 0.0)))
    if bad.size:
        r = int(bad[0])
        what = "not finite" if not np.isfinite(load[r]) else "negative"
        raise MotionError(f"load row {r + 1} (t = {t[r]:g} s): {load[r]:g} N is {what}")
    return load


def make_motion(t: Array, angles: Array, rates: Array, accels: Array, load: Array | None = None) -> OrientationMotion:
    """Check shapes and values and build a motion; errors name the row and the quantity.

    ``t (n,)`` [s] strictly increasing; ``angles, rates, accels (n, 3)`` [rad, rad/s, rad/s^2],
    one row per sample (a transposed ``(3, n)`` or flattened array is refused with the expected
    shape); ``load (n,)`` [N] >= 0 or ``None`` (zero).
    """
    t = as_array(t, (None,), "motion t", MotionError)
    n = t.shape[0]
    arrays = {name: as_array(a, (n, 3), f"motion {name}", MotionError)
              for name, a in (("angles", angles), ("rates", rates), ("accels", accels))}
    for name, a in (("t", t), *arrays.items()):
        bad = ~np.isfinite(a)
        if bad.any():
            row = int(np.flatnonzero(bad.reshape(n, -1).any(axis=1))[0])
            when = f"t = {t[row]:g} s" if np.isfinite(t[row]) else "t not finite"
            raise MotionError(f"motion row {row + 1} ({when}): {name} is not finite")
    ld = np.zeros(n) if load is None else check_load(t, as_array(load, (n,), "motion load", MotionError))
    if n > 1 and np.any(np.diff(t) <= 0):
        r = int(np.flatnonzero(np.diff(t) <= 0)[0]) + 1
        raise MotionError(f"motion row {r + 1}: time {t[r]:g} s does not increase")
    return OrientationMotion(t, arrays["angles"], arrays["rates"], arrays["accels"], ld)


def read_motion_csv(path: str | Path, max_rows: int | None = DEFAULT_MAX_SAMPLES) -> OrientationMotion:
    """Read the spec's motion CSV (degrees on file, radians inside); at most ``max_rows`` rows."""
    cols = read_csv_columns(path, ("t_s", *_ANG), (*_RATE, *_ACC, "load_N"), max_rows=max_rows)
    t = cols["t_s"]
    require_increasing(path, t)
    load = cols.get("load_N")
    if load is not None:
        neg = np.flatnonzero(load < 0)
        if neg.size:
            raise MotionError(f"{path}: row {neg[0] + 1}, column 'load_N': {load[neg[0]]:g} N is negative")
    angles = np.deg2rad(column_group(path, cols, _ANG))
    groups = [column_group(path, cols, names) for names in (_RATE, _ACC)]
    rates, accels = (None if g is None else np.deg2rad(g) for g in groups)
    rates, accels = derivatives(path, t, angles, rates, accels, _RATE)
    return make_motion(t, angles, rates, accels, load)


def write_motion_csv(path: str | Path, motion: OrientationMotion) -> None:
    """Write a motion with all derivative columns and the load (degrees on file)."""
    cols = {"t_s": motion.t}
    for names, arr in ((_ANG, motion.angles), (_RATE, motion.rates), (_ACC, motion.accels)):
        for k, name in enumerate(names):
            cols[name] = np.rad2deg(arr[:, k])
    cols["load_N"] = motion.load
    write_csv(path, cols)
