"""Task motions of a described mechanism: the default motion and motion CSV files.

Motion CSV: ``t_s`` and one column per task coordinate, ``<name>_<unit>`` (``x_m``,
``euler3_rad``); optional rates ``<name>d_<unit>_s`` and accelerations ``<name>dd_<unit>_s2``
(each group all or none; missing derivatives from a quintic spline, as for the PDM's files);
optional: one column per named load of the description (``[[loads]]`` with a ``name`` such as
``push_N``), its magnitude [N] at each sample (the description's ``magnitude_N`` where the
column is absent).

Actuator motion CSV (:func:`read_actuator_motion`; the pose then follows by the direct
kinematics, :mod:`pkmdyn.multibody.kinematics.direct`): ``t_s`` and one column per actuated joint,
``<joint>_pos_<unit>`` (``m`` or ``rad``, the columns of a run's ``results.csv``); optional rates
``<joint>_vel_<unit>_s`` and accelerations ``<joint>_acc_<unit>_s2`` (each group all or
none) and the named loads' columns. Missing derivatives come from a Savitzky-Golay smoothing
differentiator (a polynomial of degree ``sg_order`` fitted to each ``sg_window`` samples,
uniform sampling; for measured positions) or, with ``sg_window = 0``, from the interpolating
quintic spline of a task motion file (for exact, planned positions).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ...errors import MotionError
from ...io import read_csv_columns
from ...params_util import check_limit
from ...profiles._columns import column_group, derivatives, require_increasing, require_rows, savgol_derivatives
from ..model.compiler import MechanismModel
from .inverse import reference_task

__all__ = ["TaskMotion", "PeriodicMotion", "RepeatedMotion", "ActuatorMotion", "task_columns", "motion_columns",
           "actuator_columns", "default_motion", "periodic_motion", "repeated_motion", "read_task_motion",
           "read_actuator_motion", "actuator_rates", "MAX_MOTION_ROWS"]

Array = NDArray[np.float64]

#: rows of a motion file for a described mechanism: the file is read whole (its rows, not the
#: bodies' motion, are held in memory; a run computes and writes them chunk by chunk); longer
#: runs repeat the default motion (``pkmdyn run --cycles``)
MAX_MOTION_ROWS = 200_000
#: what the row limit of a motion file is (:func:`pkmdyn.io.read_csv_columns`)
_BEYOND = ("the most a motion file of a described mechanism holds (it is read whole); a longer run repeats the "
           "default motion (pkmdyn run --cycles)")


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

    def chunk(self, start: int, stop: int) -> "TaskMotion":
        """Samples ``start .. stop - 1`` (views)."""
        sl = slice(start, stop)
        return TaskMotion(self.t[sl], self.x[sl], self.xd[sl], self.xdd[sl],
                          {k: v[sl] for k, v in self.loads.items()})


@dataclass(frozen=True)
class PeriodicMotion:
    """The default motion ``x(t) = x_ref + offset + amplitude sin(2 pi t / T)`` over ``cycles``
    periods at ``samples_per_cycle`` samples per period (``n = round(cycles samples_per_cycle)
    + 1`` samples, ``t_i = i T / samples_per_cycle``), made chunk by chunk (:meth:`chunk`), so
    that a long run never holds the whole motion. Its rates are exact."""

    x_ref: Array
    offset: Array
    amplitude: Array
    period: float
    samples_per_cycle: int
    n: int

    def __len__(self) -> int:
        return self.n

    def chunk(self, start: int, stop: int) -> TaskMotion:
        """Samples ``start .. stop - 1`` of the motion."""
        stop = min(stop, self.n)
        t = np.arange(start, stop, dtype=float) * (self.period / self.samples_per_cycle)
        w = 2.0 * np.pi / self.period
        s = np.sin(w * t)[:, None]
        c = np.cos(w * t)[:, None]
        x = self.x_ref + self.offset + self.amplitude * s
        return TaskMotion(t, np.ascontiguousarray(x), np.ascontiguousarray(self.amplitude * w * c),
                          np.ascontiguousarray(-self.amplitude * w * w * s))


def motion_columns(name: str, unit: str) -> tuple[str, str, str]:
    """The columns of a coordinate ``name`` in ``unit`` (an actuated joint's or a motor's):
    ``<name>_pos_<u>``, ``<name>_vel_<u>_s``, ``<name>_acc_<u>_s2``."""
    return f"{name}_pos_{unit}", f"{name}_vel_{unit}_s", f"{name}_acc_{unit}_s2"


def actuator_columns(model: MechanismModel) -> tuple[list[str], list[str], list[str]]:
    """Column names of the actuated joints' coordinates, rates and accelerations."""
    cols = [motion_columns(a, u) for a, u in zip(model.actuator_names, model.actuator_units)]
    return [c[0] for c in cols], [c[1] for c in cols], [c[2] for c in cols]


@dataclass(frozen=True)
class ActuatorMotion:
    """``t`` (n,) [s]; ``s, sd, sdd`` (n, na): the actuated joints' coordinates ([m], [rad]) in
    the model's ``actuator_names`` order and their first and second time derivatives;
    ``loads``: magnitudes (n,) [N] of named loads given by the motion."""

    t: Array
    s: Array
    sd: Array
    sdd: Array
    loads: dict[str, Array] = field(default_factory=dict)

    def __len__(self) -> int:
        return int(self.t.shape[0])


def task_columns(model: MechanismModel) -> tuple[list[str], list[str], list[str]]:
    """Column names of the task coordinates, their rates and accelerations."""
    pos = [f"{n}_{u}" for n, u in zip(model.task_names, model.task_units)]
    vel = [f"{n}d_{u}_s" for n, u in zip(model.task_names, model.task_units)]
    acc = [f"{n}dd_{u}_s2" for n, u in zip(model.task_names, model.task_units)]
    return pos, vel, acc


@dataclass(frozen=True)
class RepeatedMotion:
    """A one-cycle motion ``cycle`` (a :class:`TaskMotion` whose last sample is its first one
    period later) repeated ``cycles`` times: sample ``i`` is the cycle's sample ``i mod m``
    (``m = len(cycle) - 1``) shifted by whole periods, ``n = round(cycles m) + 1`` samples, made
    chunk by chunk (:meth:`chunk`)."""

    cycle: TaskMotion
    n: int

    def __len__(self) -> int:
        return self.n

    def chunk(self, start: int, stop: int) -> TaskMotion:
        stop = min(stop, self.n)
        m = len(self.cycle) - 1
        i = np.arange(start, stop)
        c, r = np.divmod(i, m)
        c = c.astype(float)
        period = float(self.cycle.t[m] - self.cycle.t[0])
        t = self.cycle.t[r] + c * period
        return TaskMotion(t, self.cycle.x[r], self.cycle.xd[r], self.cycle.xdd[r],
                          {k: v[r] for k, v in self.cycle.loads.items()})


def repeated_motion(cycle: TaskMotion, cycles: float, what: str = "the default motion",
                    max_samples: int | None = None) -> TaskMotion | RepeatedMotion:
    """``cycle`` repeated ``cycles`` times (:class:`RepeatedMotion`; ``cycle`` itself for one
    cycle, its first samples for less). To repeat, the cycle must be periodic: its last sample
    equal to its first (positions, rates, accelerations, loads) to 1e-9 of their size, else a
    :class:`~pkmdyn.errors.MotionError`."""
    if not (np.isfinite(cycles) and cycles > 0):
        raise MotionError(f"--cycles: must be a finite number > 0, got {cycles!r}")
    m = len(cycle) - 1
    n = int(round(float(cycles) * m)) + 1
    if n <= len(cycle):  # a part of one cycle (or all of it): no repetition, no periodicity needed
        return cycle if n == len(cycle) else cycle.chunk(0, n)
    if m < 1:
        raise MotionError(f"--cycles: {what} has one sample; nothing to repeat")
    for name, a in (("position", cycle.x), ("rate", cycle.xd), ("acceleration", cycle.xdd),
                    *((f"load {k}", v[:, None]) for k, v in cycle.loads.items())):
        scale = max(float(np.abs(a).max()), 1e-12)
        if not np.abs(a[-1] - a[0]).max() <= 1e-9 * scale:
            raise MotionError(f"--cycles: {what} is not periodic (its last sample's {name} differs from its first); "
                              "only a periodic motion repeats")
    if max_samples is not None and not n <= max_samples:
        check_limit(n, max_samples, "motion: samples (cycles x samples per cycle + 1)", "max_samples",
                    file="the description")
    return RepeatedMotion(cycle, n)


def default_motion(model: MechanismModel, cycles: float = 1.0, samples_per_cycle: int | None = None
                   ) -> TaskMotion:
    """The description's ``[default_motion]``: ``x(t) = x_ref + offset + amplitude sin(2 pi t/T)``
    at ``samples`` times over one period ``T`` (x_ref: the task at the reference configuration);
    over ``cycles`` periods at ``samples_per_cycle`` samples each when given
    (:func:`periodic_motion`), in memory."""
    m = periodic_motion(model, cycles, samples_per_cycle)
    return m.chunk(0, len(m))


def periodic_motion(model: MechanismModel, cycles: float = 1.0, samples_per_cycle: int | None = None,
                    max_samples: int | None = None) -> PeriodicMotion:
    """The default motion as a :class:`PeriodicMotion`: ``cycles`` periods (default 1) at
    ``samples_per_cycle`` samples per period (default the description's ``samples - 1``, so that
    one cycle has ``samples`` samples, both ends included). More than ``max_samples`` samples is
    a :class:`~pkmdyn.errors.LimitError` naming the limit."""
    spec = model.motion
    if not (np.isfinite(cycles) and cycles > 0):
        raise MotionError(f"--cycles: must be a finite number > 0, got {cycles!r}")
    spc = spec.samples - 1 if samples_per_cycle is None else int(samples_per_cycle)
    if spc < 1:
        raise MotionError(f"--samples-per-cycle: must be at least 1, got {samples_per_cycle!r}")
    total = float(cycles) * spc
    n = int(round(total)) + 1
    if max_samples is not None and not n <= max_samples:
        check_limit(n, max_samples, "default motion: samples (cycles x samples per cycle + 1)", "max_samples",
                    file="the description")
    pos, _, _ = task_columns(model)
    off = np.array([spec.offset.get(c, 0.0) for c in pos])
    amp = np.array([spec.amplitude.get(c, 0.0) for c in pos])
    return PeriodicMotion(reference_task(model), off, amp, float(spec.period), spc, n)


def read_task_motion(model: MechanismModel, path: str | Path, max_rows: int | None = MAX_MOTION_ROWS) -> TaskMotion:
    """Read a motion CSV for ``model`` (see the module docstring); errors name the file, row and column."""
    path = Path(path)
    pos, vel, acc = task_columns(model)
    cols = read_csv_columns(path, ("t_s", *pos), (*vel, *acc, *model.named_loads), max_rows=max_rows, beyond=_BEYOND)
    t = cols["t_s"]
    require_increasing(path, t)
    x = column_group(path, cols, pos)
    if x is None:  # pragma: no cover - required columns
        raise MotionError(f"{path}: no task columns")
    xd, xdd = derivatives(path, t, x, column_group(path, cols, vel), column_group(path, cols, acc), vel)
    loads = {nm: np.asarray(cols[nm], dtype=float) for nm in model.named_loads if cols.get(nm) is not None}
    return TaskMotion(t, np.ascontiguousarray(x), np.ascontiguousarray(xd), np.ascontiguousarray(xdd), loads)


def actuator_rates(path: str | Path, t: Array, s: Array, sd: Array | None, sdd: Array | None, rate_names: list[str],
                   sg_window: int = 15, sg_order: int = 5) -> tuple[Array, Array]:
    """Rates and accelerations of actuator positions ``s (n, na)`` (module docstring): given
    columns as they are, missing ones by the Savitzky-Golay differentiator (``sg_window`` > 0)
    or the quintic spline (``sg_window = 0``)."""
    if sd is None and sdd is not None:
        raise MotionError(f"{path}: acceleration columns need the rate columns ({', '.join(rate_names)})")
    if sg_window == 0:
        return derivatives(path, t, s, sd, sdd, rate_names)
    if sd is None:
        return savgol_derivatives(t, s, sg_window, sg_order, str(path))
    if sdd is None:
        return sd, savgol_derivatives(t, sd, sg_window, sg_order, str(path))[0]
    return sd, sdd


def read_actuator_motion(model: MechanismModel, path: str | Path, sg_window: int = 15, sg_order: int = 5,
                         max_rows: int | None = MAX_MOTION_ROWS) -> ActuatorMotion:
    """Read an actuator motion CSV for ``model`` (module docstring): missing rates and
    accelerations by the Savitzky-Golay differentiator (``sg_window`` odd >= 3 samples, degree
    ``sg_order``), or by the quintic spline with ``sg_window = 0``. Errors name the file, row and
    column."""
    path = Path(path)
    pos, vel, acc = actuator_columns(model)
    cols = read_csv_columns(path, ("t_s", *pos), (*vel, *acc, *model.named_loads), max_rows=max_rows, beyond=_BEYOND)
    t = cols["t_s"]
    require_rows(path, t)
    require_increasing(path, t)
    s = column_group(path, cols, pos)
    if s is None:  # pragma: no cover - required columns
        raise MotionError(f"{path}: no actuator columns")
    sd, sdd = actuator_rates(path, t, s, column_group(path, cols, vel), column_group(path, cols, acc), vel, sg_window,
                             sg_order)
    loads = {nm: np.asarray(cols[nm], dtype=float) for nm in model.named_loads if cols.get(nm) is not None}
    return ActuatorMotion(t, np.ascontiguousarray(s), np.ascontiguousarray(sd), np.ascontiguousarray(sdd), loads)
