"""``pkmdyn view``: a page for any machine without running a motion."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

from .._lazy import lazy_module
from ..io import check_output_file
from ..machines.registry import resolve
from ..report import scene_from_joints, topology_from_model, write_view
from ._groups import PATH_IN, cli, echo

if TYPE_CHECKING:
    from .. import multibody as _multibody
    from ..multibody import columns as _columns
else:  # loaded when a command runs, not on import (nor for --help)
    _multibody = lazy_module("pkmdyn.multibody")
    _columns = lazy_module("pkmdyn.multibody.columns")


def _listing(path: Path) -> None:
    echo(f"view: {path}")


def _described_page(path: Path | None, out: Path, description: dict | None = None, parameters: str = "",
                    notes: tuple[str, ...] = (), inputs: dict | None = None) -> Path:
    """A described mechanism (the file ``path``, or a machine's generated ``description`` with
    its parameter file's text ``parameters``) at its reference configuration: the scene from its
    joint points, the topology from its model document, mobility and over-constraints by rank."""
    import numpy as np

    model = _multibody.load_mechanism(path if description is None else description)
    x = _multibody.reference_task(model)[None]
    kin = _multibody.solve_kinematics(model, x, np.zeros_like(x), np.zeros_like(x), np.zeros(1))
    doc = _columns.model_summary(model)
    joints = [(j["name"], j["type"], j["body_a"], j["body_b"]) for j in doc["joints"]]
    zero = np.zeros(1)
    actuated = {j["name"]: (zero, f"{j['name']} (actuated)", "-") for j in doc["joints"] if j.get("actuated")}
    scene = scene_from_joints(np.zeros(1), kin.joint_point, joints, actuated)
    rep = model.topology
    mobility = {"Kutzbach-Gruebler mobility": rep.kutzbach, "mobility (rank, reference configuration)": rep.mobility,
                "idle freedoms": rep.idle, "degrees of freedom": rep.dof, "over-constraints": rep.overconstraints}
    return write_view(out, title=f"{model.name}: machine view", scene=scene, topology=topology_from_model(doc),
                      mobility=mobility,
                      parameters=parameters if description is not None else Path(path).read_text(encoding="utf-8",
                                                                                                  errors="replace"),
                      notes=[*(notes or [f"description: {path}"]),
                             "reference configuration (every joint coordinate at its reference)"],
                      inputs=inputs if inputs is not None else {"--machine": path}, listing=_listing)


@cli.command("view")
@click.option("--machine", required=True, help="A built-in machine (see pkmdyn machines) or a description FILE.toml.")
@click.option("--params", "params_path", type=PATH_IN,
              help="Parameter file (TOML) of a generated machine (see pkmdyn machines); default: the built-in one.")
@click.option("--out", "out_path", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="HTML file to write (atomically; only a page pkmdyn wrote is replaced).")
def view(machine: str, params_path: Path | None, out_path: Path) -> None:
    """A self-contained HTML page of a machine: home pose in 3D, topology graph, mobility and
    over-constraint counts."""

    entry, path = resolve(machine)
    check_output_file(out_path, {"--params": params_path, "--machine": path})  # the output rule, before any work
    if entry is not None and not hasattr(entry, "view_page"):  # a machine that generates its description
        _described_page(None, out_path, entry.description(params_path), entry.parameters_text(params_path),
                        (f"machine: {entry.TITLE}", f"parameters: {params_path or 'built-in'}"), {"--params": params_path})
    elif entry is not None:
        entry.view_page(params_path, out_path, _listing)
    elif params_path is not None:
        raise click.UsageError("--params applies to the generated machines (see pkmdyn machines); a described mechanism is its file")
    else:
        _described_page(path, out_path)
