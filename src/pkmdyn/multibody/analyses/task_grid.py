"""Task poses and grids of poses named on the command line: ``--pose "x=0.02,euler3_rad=0.1"``,
``--grid "x=-0.1:0.1:21,z=0.9:1.1:11"`` (task coordinates by name, with or without unit; the
reference pose's value for every coordinate not named)."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
from numpy.typing import NDArray

from ...errors import ParameterError
from ..kinematics.inverse import reference_task
from ..model.compiler import MechanismModel

__all__ = ["parse_pose", "parse_grid", "parse_ranges", "grid_poses", "MAX_GRID_POINTS"]

Array = NDArray[np.float64]

#: the most poses a grid may hold
MAX_GRID_POINTS = 100_000


def _coordinate(model: MechanismModel, key: str, what: str) -> int:
    """The task coordinate named ``key`` (``x`` or ``x_m``)."""
    for i, (n, u) in enumerate(zip(model.task_names, model.task_units)):
        if key in (n, f"{n}_{u}"):
            return i
    names = ", ".join(f"{n}_{u}" for n, u in zip(model.task_names, model.task_units))
    raise ParameterError(f"{what}: {key!r} is not a task coordinate of {model.name} ({names})")


def _number(text: str, what: str, model: MechanismModel | None = None, i: int = 0,
            limits: Mapping[str, float] | None = None) -> float:
    """The number ``text``; with ``model``, task coordinate ``i``'s value, within the magnitude
    limit of its unit (``[limits] max_length_m`` or ``max_angle_rad``: ``limits``, the
    description's with ``--limit`` laid over them, else the description's own)."""
    try:
        v = float(text)
    except ValueError:
        raise ParameterError(f"{what}: {text!r} is not a number") from None
    if not math.isfinite(v):
        raise ParameterError(f"{what}: {text!r} is not finite")
    if model is not None:
        key = "max_length_m" if model.task_units[i] == "m" else "max_angle_rad"
        bound = float((limits if limits is not None else model.limits).get(key, math.inf))
        if abs(v) > bound:
            raise ParameterError(f"{what}: {v:g} {model.task_units[i]} is beyond the limit {key} = {bound:g} (raise "
                                 f"it with [limits] {key} in the description or --limit {key}=VALUE)")
    return v


def parse_pose(model: MechanismModel, text: str, limits: Mapping[str, float] | None = None) -> Array:
    """``"x=0.01,euler1_rad=0.02"`` -> the task pose (nt,), the reference pose's value for every
    coordinate not named; each value within ``limits``' magnitudes (:func:`_number`)."""
    x = reference_task(model).copy()
    seen: set[int] = set()
    for item in filter(None, (s.strip() for s in text.split(","))):
        key, sep, val = item.partition("=")
        if not sep:
            raise ParameterError(f"--pose: {item!r} is not NAME=VALUE")
        i = _coordinate(model, key.strip(), "--pose")
        if i in seen:
            raise ParameterError(f"--pose: {key.strip()!r} given twice")
        seen.add(i)
        x[i] = _number(val.strip(), f"--pose {key.strip()}", model, i, limits)
    return x


def parse_grid(model: MechanismModel, text: str, max_axes: int = 2, max_points: int = MAX_GRID_POINTS,
               what: str = "--grid", limit_key: str | None = None,
               limits: Mapping[str, float] | None = None) -> list[tuple[int, Array]]:
    """``"x=-0.1:0.1:21,y=-0.1:0.1:21"`` -> up to ``max_axes`` (task coordinate, values) axes,
    each ``lo:hi:count`` (count 2 to 1,000), about the reference pose; at most ``max_points``
    poses in all (``limit_key``: the ``[limits]`` key that sets it, named in the refusal);
    ``what``: the option named in messages."""
    axes: list[tuple[int, Array]] = []
    for item in filter(None, (s.strip() for s in text.split(","))):
        key, sep, val = item.partition("=")
        parts = val.split(":")
        if not sep or len(parts) != 3:
            raise ParameterError(f"{what}: {item!r} is not NAME=LOW:HIGH:COUNT")
        i = _coordinate(model, key.strip(), what)
        if any(i == a for a, _ in axes):
            raise ParameterError(f"{what}: {key.strip()!r} given twice")
        lo, hi = (_number(p.strip(), f"{what} {key.strip()}", model, i, limits) for p in parts[:2])
        try:
            count = int(parts[2])
        except ValueError:
            raise ParameterError(f"{what} {key.strip()}: count {parts[2]!r} is not an integer") from None
        if not 2 <= count <= 1000 or not lo < hi:
            raise ParameterError(f"{what} {key.strip()}: expected LOW < HIGH and a count from 2 to 1,000")
        axes.append((i, np.linspace(lo, hi, count)))
    if not 1 <= len(axes) <= max_axes:
        raise ParameterError(f"{what}: give one to {max_axes} task coordinates")
    if math.prod(len(v) for _, v in axes) > max_points:
        raise ParameterError(f"{what}: more than {max_points:,} poses"
                             + (f" (the limit {limit_key}; raise it with --limit {limit_key}=N)" if limit_key else ""))
    return axes


def parse_ranges(model: MechanismModel, text: str, limits: Mapping[str, float] | None = None
                 ) -> list[tuple[int, Array]]:
    """``--orientation-range "euler1=-0.1:0.1:3,..."``: held task coordinates over ranges (the
    grid syntax, at most three coordinates and 1,000 combinations)."""
    return parse_grid(model, text, max_axes=3, max_points=1000, what="--orientation-range", limits=limits)


def grid_poses(model: MechanismModel, axes: list[tuple[int, Array]], base: Array | None = None) -> Array:
    """Every pose of the grid (n, nt), the first axis slowest."""
    base = reference_task(model) if base is None else base
    mesh = np.meshgrid(*[v for _, v in axes], indexing="ij")
    x = np.tile(base, (mesh[0].size, 1))
    for (i, _), m in zip(axes, mesh):
        x[:, i] = m.reshape(-1)
    return x
