"""Platform motions of the 4-DOF PDM: the motion object, Eq. 84 profiles and CSV files.

Motion CSV (``docs/pdm4.md``): required columns ``t_s, x_m, y_m, alpha_rad, gamma_rad``;
optional first derivatives ``xd_m_s, yd_m_s, alphad_rad_s, gammad_rad_s`` and second
derivatives ``xdd_m_s2, ydd_m_s2, alphadd_rad_s2, gammadd_rad_s2`` (each group all or none;
second derivatives only together with first ones). Missing derivatives are taken from an
interpolating quintic B-spline through the samples (``scipy.interpolate.make_interp_spline``,
``k = 5``, default not-a-knot end conditions): first and second derivatives of the spline
through the poses when both groups are absent, the first derivative of the spline through
the given velocities when only the second group is absent.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..errors import MotionError
from ..io import read_csv_columns, write_csv
from ._columns import column_group, derivatives, require_increasing
from .cycloidal import cycloidal

__all__ = ["PdmMotion", "POSE_COLUMNS", "RATE_COLUMNS", "ACCEL_COLUMNS", "cycloidal_motion",
           "read_pdm_motion", "write_pdm_motion"]

Array = NDArray[np.float64]
POSE_COLUMNS = ("x_m", "y_m", "alpha_rad", "gamma_rad")
RATE_COLUMNS = ("xd_m_s", "yd_m_s", "alphad_rad_s", "gammad_rad_s")
ACCEL_COLUMNS = ("xdd_m_s2", "ydd_m_s2", "alphadd_rad_s2", "gammadd_rad_s2")


@dataclass(frozen=True)
class PdmMotion:
    """Platform motion: ``t`` (n,) [s]; ``q, qd, qdd`` (n, 4) = (x [m], y [m], alpha [rad],
    gamma [rad]) and their first and second time derivatives. x, y locate the platform point
    P in the base frame; alpha is about the base z axis, gamma about the platform x axis."""

    t: Array
    q: Array
    qd: Array
    qdd: Array

    def __post_init__(self) -> None:
        n = self.t.shape[0]
        for name in ("q", "qd", "qdd"):
            a = getattr(self, name)
            if a.shape != (n, 4):
                raise MotionError(f"motion: {name} has shape {a.shape}, expected ({n}, 4)")
        for name in ("t", "q", "qd", "qdd"):
            a = getattr(self, name)
            if not np.all(np.isfinite(a)):
                raise MotionError(f"motion: {name} contains a non-finite value")

    def __len__(self) -> int:
        return int(self.t.shape[0])

    def slice(self, start: int, stop: int) -> "PdmMotion":
        """Samples ``start:stop`` as a new motion."""
        return PdmMotion(self.t[start:stop], self.q[start:stop], self.qd[start:stop], self.qdd[start:stop])


def cycloidal_motion(strokes: tuple[float, float, float, float], period: float, samples: int) -> PdmMotion:
    """Eq. 84 for all four coordinates: ``S = (S_x [m], S_y [m], S_alpha [rad], S_gamma [rad])``,
    ``samples`` equally spaced times over ``[0, T]``."""
    if samples < 2:
        raise MotionError(f"cycloidal motion: samples must be >= 2, got {samples}")
    t = np.linspace(0.0, period, samples)
    q, qd, qdd = cycloidal(t, np.asarray(strokes, dtype=float), period)
    return PdmMotion(t, q, qd, qdd)


#: default cap on the rows of a PDM motion file (the PDM's ``[limits] max_samples`` default)
PDM_MAX_ROWS = 200_000


def read_pdm_motion(path: str | Path, max_rows: int | None = PDM_MAX_ROWS) -> PdmMotion:
    """Read a PDM motion CSV (see the module docstring); errors name the file, row and column.
    More than ``max_rows`` data rows is a :class:`~pkmdyn.errors.LimitError`."""
    path = Path(path)
    cols = read_csv_columns(path, ("t_s", *POSE_COLUMNS), (*RATE_COLUMNS, *ACCEL_COLUMNS), max_rows=max_rows)
    t = cols["t_s"]
    require_increasing(path, t)
    q = column_group(path, cols, POSE_COLUMNS)
    rates, accels = column_group(path, cols, RATE_COLUMNS), column_group(path, cols, ACCEL_COLUMNS)
    qd, qdd = derivatives(path, t, q, rates, accels, RATE_COLUMNS)
    return PdmMotion(t, q, qd, qdd)


def write_pdm_motion(path: str | Path, motion: PdmMotion, derivatives: bool = True) -> None:
    """Write a motion CSV with the pose columns and, with ``derivatives``, both rate groups."""
    cols = {"t_s": motion.t}
    cols.update({c: motion.q[:, k] for k, c in enumerate(POSE_COLUMNS)})
    if derivatives:
        cols.update({c: motion.qd[:, k] for k, c in enumerate(RATE_COLUMNS)})
        cols.update({c: motion.qdd[:, k] for k, c in enumerate(ACCEL_COLUMNS)})
    write_csv(path, cols, precision=15)
