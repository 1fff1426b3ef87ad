"""``pkmdyn import``: a mechanism from MJCF, URDF (+ loop sidecar) or SDFormat as a description."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

from .._lazy import lazy_module
from ._groups import PATH_IN, cli, list_files, show

if TYPE_CHECKING:
    from ..jobs import imports as import_job
else:  # the readers and the engine load when the command runs, not for --help
    import_job = lazy_module("pkmdyn.jobs.imports")


@cli.command("import")
@click.option("--from", "src", type=PATH_IN, required=True,
              help="The model file: MJCF (.xml, .mjcf), URDF (.urdf) or SDFormat (.sdf).")
@click.option("--format", "fmt", type=click.Choice(["mjcf", "urdf", "sdf"]), default=None,
              help="The file's format (default: from its extension).")
@click.option("--sidecar", "sidecar", type=PATH_IN, default=None,
              help="URDF: the loop closures and actuated joints (YAML: closed_loop, type, name_mot; docs/import.md).")
@click.option("--actuated", default=None, help="URDF, SDFormat: the actuated joints, comma-separated.")
@click.option("--assemble", is_flag=True,
              help="Close the loops where the file is not assembled: URDF from the zero configuration, MJCF from "
                   "qpos0 or the keyframe (least change of the joint positions); not for SDFormat.")
@click.option("--keyframe", default=None, help="MJCF: the reference configuration from this keyframe (default qpos0).")
@click.option("--weld-free", is_flag=True,
              help="MJCF: weld a free joint's body that no loop closure holds (a floating base) to the ground at its "
                   "reference pose (default: refused). A free body the loops hold hangs from one of them.")
@click.option("--task-body", default=None, help="The task body (default: an end-effector frame's body, docs/import.md).")
@click.option("--task-point", default=None, help="The task point: a site or frame name, or x,y,z [m] in the base frame.")
@click.option("--task-position", default=None, help="Task position components, e.g. x,y,z (default: chosen).")
@click.option("--task-orientation", default=None, help="Task Euler angles of XYZ, e.g. 1,2,3 (default: chosen).")
@click.option("--task-joints", default=None,
              help="Joints whose coordinates are task coordinates, comma-separated (a mechanism whose freedoms no "
                   "single body carries; default: chosen where no body's coordinates do).")
@click.option("--out", "out_path", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="The description to write (e.g. mechanism.toml).")
def import_(src, fmt, sidecar, actuated, assemble, keyframe, weld_free, task_body, task_point, task_position,
            task_orientation, task_joints, out_path) -> None:
    """Read a closed-chain mechanism from another format and write its description, checked by
    loading it as `pkmdyn describe` and `run` do. Nothing is written when an element has no
    equivalent (one line naming it)."""
    show(import_job.job(src, out_path, fmt=fmt, sidecar=sidecar, actuated=actuated, assemble=assemble, keyframe=keyframe,
                        task_body=task_body, task_point=task_point, task_position=task_position,
                        task_orientation=task_orientation, task_joints=task_joints, announce=list_files,
                        weld_free=weld_free))
