"""``pkmdyn view``: one self-contained HTML page of a machine without running a motion: its home
pose in 3D, the topology graph, mobility and over-constraint counts (:func:`pkmdyn.report.write_view`)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..errors import ParameterError
from ..io import check_output_file
from ..machines.registry import resolve
from ..multibody.columns import model_summary
from ..multibody.kinematics.inverse import reference_task, solve_kinematics
from ..multibody.model.compiler import load_mechanism
from ..report import scene_from_joints, topology_from_model, write_view
from ._files import JobResult

__all__ = ["job"]


def job(machine: str, out_path: Path, *, params_path: Path | None = None,
        announce: Callable[[Path], None] | None = None) -> JobResult:
    """The page of ``machine`` (a built-in name or a description file; a generated machine's
    description from ``params_path``) into ``out_path``; ``announce`` is given the page's path
    before it moves into place."""
    entry, path = resolve(machine)
    check_output_file(out_path, {"--params": params_path, "--machine": path})  # the output rule, before any work
    if entry is not None and not hasattr(entry, "view_page"):  # a machine that generates its description
        page = _described_page(None, out_path, entry.description(params_path), entry.parameters_text(params_path),
                               (f"machine: {entry.TITLE}", f"parameters: {params_path or 'built-in'}"),
                               {"--params": params_path}, announce)
    elif entry is not None:
        page = entry.view_page(params_path, out_path, announce)
    elif params_path is not None:
        raise ParameterError("--params applies to the generated machines (see pkmdyn machines); a described "
                             "mechanism is its file")
    else:
        page = _described_page(path, out_path, announce=announce)
    return JobResult({"view": Path(page) if page is not None else Path(out_path)})


def _described_page(path: Path | None, out: Path, description: dict | None = None, parameters: str = "",
                    notes: tuple[str, ...] = (), inputs: dict | None = None,
                    announce: Callable[[Path], None] | None = None) -> Path:
    """A described mechanism (the file ``path``, or a machine's generated ``description`` with
    its parameter file's text ``parameters``) at its reference configuration: the scene from its
    joint points, the topology from its model document, mobility and over-constraints by rank."""
    model = load_mechanism(path if description is None else description)
    x = reference_task(model)[None]
    kin = solve_kinematics(model, x, np.zeros_like(x), np.zeros_like(x), np.zeros(1))
    doc = model_summary(model)
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
                      inputs=inputs if inputs is not None else {"--machine": path}, listing=announce)
