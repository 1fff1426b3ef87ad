"""``pkmdyn import``: a closed-chain mechanism from MJCF, URDF (with its loop sidecar) or SDFormat
as a checked description (:mod:`pkmdyn.multibody.formats.importer`; ``docs/import.md``)."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path

from ..errors import ParameterError
from ..io import check_output_file
from ..multibody.formats.graph import TaskChoice
from ..multibody.formats.importer import import_description
from ._files import JobResult, write_texts

__all__ = ["job", "FORMATS"]

FORMATS = {".xml": "mjcf", ".mjcf": "mjcf", ".urdf": "urdf", ".sdf": "sdf"}


def _csv(text: str | None, kind=str) -> tuple | None:
    if text is None:
        return None
    return tuple(kind(x.strip()) for x in text.split(",") if x.strip())


def job(src: Path, out_path: Path, *, fmt: str | None = None, sidecar: Path | None = None, actuated: str | None = None,
        assemble: bool = False, keyframe: str | None = None, task_body: str | None = None, task_point: str | None = None,
        task_position: str | None = None, task_orientation: str | None = None, task_joints: str | None = None,
        announce: Callable[[Mapping[str, Path]], None] | None = None, weld_free: bool = False) -> JobResult:
    """The model file ``src`` (``fmt`` from its extension by default) as a description written to
    ``out_path``, checked by loading it as ``pkmdyn describe`` and ``run`` do; the options are those
    of ``pkmdyn import`` as text (``actuated``: joint names, comma-separated; ``task_point``: a
    site or frame name or ``x,y,z`` [m]; ``task_position``: ``x,y,z`` letters; ``task_orientation``:
    Euler angle numbers ``1,2,3``; ``task_joints``: joint names)."""
    fmt = fmt or FORMATS.get(Path(src).suffix.lower())
    if fmt is None:
        raise ParameterError(f"--from {Path(src).name}: unknown extension; give --format mjcf, urdf or sdf")
    inputs = {"--from": src, "--sidecar": sidecar}
    check_output_file(out_path, inputs)  # before anything is read: a bad --out costs nothing
    point = task_point
    if point is not None and "," in point:
        vals = _csv(point, float)
        if len(vals) != 3:
            raise ParameterError("--task-point: a site or frame name, or three numbers x,y,z")
        point = vals
    orient = None
    if task_orientation is not None:
        try:
            orient = _csv(task_orientation, int)
        except ValueError:
            raise ParameterError("--task-orientation: angle numbers 1, 2 or 3, comma-separated") from None
    pos = _csv(task_position)
    if pos is not None and any(c not in ("x", "y", "z") for c in pos):
        raise ParameterError("--task-position: letters x, y, z, comma-separated")
    if orient is not None and any(k not in (1, 2, 3) for k in orient):
        raise ParameterError("--task-orientation: angle numbers 1, 2 or 3, comma-separated")
    joints = _csv(task_joints)
    if joints is not None and not joints:
        raise ParameterError("--task-joints: joint names, comma-separated")
    given = pos is not None or orient is not None or joints is not None
    choice = TaskChoice(body=task_body, point=point, position=pos if pos is not None or not given else (),
                        orientation=orient if orient is not None or not given else (), joints=joints)
    text, notes = import_description(Path(src), fmt, sidecar=sidecar, actuated=_csv(actuated) or (),
                                     assemble=assemble, keyframe=keyframe, choice=choice, weld_free=weld_free)
    files = write_texts({"description": (Path(out_path), text)}, inputs, announce)
    return JobResult(files, notes=tuple(notes))
