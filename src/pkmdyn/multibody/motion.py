"""Task motions of a described mechanism: the default motion and motion CSV files.

Motion CSV: ``t_s`` and one column per task coordinate, ``<name>_<unit>`` (``x_m``,
``euler3_rad``); optional rates ``<name>d_<unit>_s`` and accelerations ``<name>dd_<unit>_s2``
(each group all or none; missing derivatives from a quintic spline, as for the PDM's files);
optional: one column per named load of the description (``[[loads]]`` with a ``name`` such as
``push_N``), its magnitude [N] at each sample (the description's ``magnitude_N`` where the
column is absent).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..errors import MotionError
from ..io import read_csv_columns
from ..profiles._columns import column_group, derivatives, require_increasing
from .model import MechanismModel

__all__ = ["TaskMotion", "task_columns", "default_motion", "read_task_motion", "MAX_MOTION_ROWS"]

Array = NDArray[np.float64]

#: rows of a motion file for a described mechanism: every sample keeps the motion of every body
#: and joint (about 6 kB for a Stewart platform), so a run is held in memory whole
MAX_MOTION_ROWS = 200_000


@dataclass(frozen=True)
class TaskMotion:
    """``t`` (n,) [s]; ``x, xd, xdd`` (n, nt): task coordinates ([m], [rad]) in the model's
    ``task_names`` order and their first and second time derivatives; ``loads``: magnitudes
    (n,) [N] of named loads given by the motion (``{name: values}``)."""

    t: Array
    x: Array
    xd: Array
    xdd: Array
    loads: dict[str, Array] = field(default_factory=dict)

    def __len__(self) -> int:
        return int(self.t.shape[0])


def task_columns(model: MechanismModel) -> tuple[list[str], list[str], list[str]]:
    """Column names of the task coordinates, their rates and accelerations."""
    pos = [f"{n}_{u}" for n, u in zip(model.task_names, model.task_units)]
    vel = [f"{n}d_{u}_s" for n, u in zip(model.task_names, model.task_units)]
    acc = [f"{n}dd_{u}_s2" for n, u in zip(model.task_names, model.task_units)]
    return pos, vel, acc


def default_motion(model: MechanismModel) -> TaskMotion:
    """The description's ``[default_motion]``: ``x(t) = x_ref + offset + amplitude sin(2 pi t/T)``
    at ``samples`` times over one period ``T`` (x_ref: the task at the reference configuration)."""
    from .kinematics import reference_task

    spec = model.motion
    pos, _, _ = task_columns(model)
    off = np.array([spec.offset.get(c, 0.0) for c in pos])
    amp = np.array([spec.amplitude.get(c, 0.0) for c in pos])
    t = np.linspace(0.0, spec.period, spec.samples)
    w = 2.0 * np.pi / spec.period
    s = np.sin(w * t)[:, None]
    c = np.cos(w * t)[:, None]
    x = reference_task(model) + off + amp * s
    return TaskMotion(t, x, amp * w * c, -amp * w * w * s)


def read_task_motion(model: MechanismModel, path: str | Path, max_rows: int | None = MAX_MOTION_ROWS) -> TaskMotion:
    """Read a motion CSV for ``model`` (see the module docstring); errors name the file, row and column."""
    path = Path(path)
    pos, vel, acc = task_columns(model)
    cols = read_csv_columns(path, ("t_s", *pos), (*vel, *acc, *model.named_loads), max_rows=max_rows)
    t = cols["t_s"]
    require_increasing(path, t)
    x = column_group(path, cols, pos)
    if x is None:  # pragma: no cover - required columns
        raise MotionError(f"{path}: no task columns")
    xd, xdd = derivatives(path, t, x, column_group(path, cols, vel), column_group(path, cols, acc), vel)
    loads = {nm: np.asarray(cols[nm], dtype=float) for nm in model.named_loads if cols.get(nm) is not None}
    return TaskMotion(t, np.ascontiguousarray(x), np.ascontiguousarray(xd), np.ascontiguousarray(xdd), loads)
