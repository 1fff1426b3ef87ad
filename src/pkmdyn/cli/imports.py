"""``pkmdyn import``: a mechanism from MJCF, URDF (+ loop sidecar) or SDFormat as a description."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

from .._lazy import lazy_module
from ..errors import ParameterError
from ..io import atomic_file, check_output_file
from ._groups import PATH_IN, cli

if TYPE_CHECKING:
    from ..multibody.formats import graph as _graph
    from ..multibody.formats import importer as _importer
else:  # loaded when a command runs, not on import (nor for --help)
    _graph = lazy_module("pkmdyn.multibody.formats.graph")
    _importer = lazy_module("pkmdyn.multibody.formats.importer")

FORMATS = {".xml": "mjcf", ".mjcf": "mjcf", ".urdf": "urdf", ".sdf": "sdf"}


def _csv(text: str | None, kind=str) -> tuple | None:
    if text is None:
        return None
    return tuple(kind(x.strip()) for x in text.split(",") if x.strip())


@cli.command("import")
@click.option("--from", "src", type=PATH_IN, required=True,
              help="The model file: MJCF (.xml, .mjcf), URDF (.urdf) or SDFormat (.sdf).")
@click.option("--format", "fmt", type=click.Choice(["mjcf", "urdf", "sdf"]), default=None,
              help="The file's format (default: from its extension).")
@click.option("--sidecar", "sidecar", type=PATH_IN, default=None,
              help="URDF: the loop closures and actuated joints (YAML: closed_loop, type, name_mot; docs/import.md).")
@click.option("--actuated", default=None, help="URDF, SDFormat: the actuated joints, comma-separated.")
@click.option("--assemble", is_flag=True,
              help="URDF, SDFormat: close the loops from the zero configuration (least change of the joint "
                   "positions) where the file is not assembled there.")
@click.option("--keyframe", default=None, help="MJCF: the reference configuration from this keyframe (default qpos0).")
@click.option("--task-body", default=None, help="The task body (default: an end-effector frame's body, docs/import.md).")
@click.option("--task-point", default=None, help="The task point: a site or frame name, or x,y,z [m] in the base frame.")
@click.option("--task-position", default=None, help="Task position components, e.g. x,y,z (default: chosen).")
@click.option("--task-orientation", default=None, help="Task Euler angles of XYZ, e.g. 1,2,3 (default: chosen).")
@click.option("--out", "out_path", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="The description to write (e.g. mechanism.toml).")
def import_(src, fmt, sidecar, actuated, assemble, keyframe, task_body, task_point, task_position,
            task_orientation, out_path) -> None:
    """Read a closed-chain mechanism from another format and write its description, checked by
    loading it as `pkmdyn describe` and `run` do. Nothing is written when an element has no
    equivalent (one line naming it)."""

    fmt = fmt or FORMATS.get(Path(src).suffix.lower())
    if fmt is None:
        raise ParameterError(f"--from {Path(src).name}: unknown extension; give --format mjcf, urdf or sdf")
    inputs = {"--from": src, "--sidecar": sidecar}
    check_output_file(out_path, inputs)
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
    choice = _graph.TaskChoice(body=task_body, point=point, position=pos if pos is not None or orient is None else (),
                        orientation=orient if orient is not None or pos is None else ())
    text, notes = _importer.import_description(Path(src), fmt, sidecar=sidecar, actuated=_csv(actuated) or (),
                                     assemble=assemble, keyframe=keyframe, choice=choice)
    with atomic_file(out_path, inputs=inputs) as tmp:
        tmp.write_text(text, encoding="utf-8")
    for line in notes:
        click.echo(f"note: {line}", err=True)
    click.echo(f"description: {out_path}")
