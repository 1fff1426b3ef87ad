"""``pkmdyn assemble``: a machine and one actuator configuration in; every assembly mode found, and
``assemblies.json`` and ``report.html`` out (docs/mechanism_format.md, "Direct kinematics"). The
numbers come from :func:`pkmdyn.multibody.kinematics.direct.assembly_modes`."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from ..io import write_json
from ..multibody.columns import model_summary
from ..multibody.kinematics.direct import PATIENCE, assembly_modes, parse_actuators
from ..multibody.kinematics.inverse import solve_kinematics
from ..report import Output, Report, scene_from_joints, write_output
from ._files import JobResult, prepare

__all__ = ["job"]


def _document(model: Any, modes: Any) -> dict[str, Any]:
    """``assemblies.json`` (docs/mechanism_format.md, "Direct kinematics")."""
    units = list(model.task_units)
    return {
        "mechanism": model.name,
        "actuators": {a: {"value": float(v), "unit": "m" if model.coord_motion[c] >= 3 else "rad"}
                      for a, c, v in zip(model.actuator_names, model.act_coord, modes.s)},
        "method": modes.method,
        "starts": modes.starts,
        "converged_starts": modes.converged,
        "stopping_rule": ({"kind": "fixed", "starts": modes.starts} if modes.patience is None else
                          {"kind": "no new mode in consecutive starts", "patience": modes.patience}),
        "last_new_mode_at_start": modes.last_new_mode_at,
        "modes": [{
            "mode": k + 1,
            "task": {f"{n}_{u}": float(v) for n, u, v in zip(model.task_names, units, a.x)},
            "residual": a.residual,
            "round_trip": a.round_trip,
            "det_sign": a.det_sign,
            "singularity_measures": {"inverse": a.inverse, "direct": a.direct, "constraint": a.constraint},
            "starts_reaching_it": a.hits,
            "tree_coordinates": {name: float(v) for name, v in zip(_coordinate_names(model), a.q)},
        } for k, a in enumerate(modes.modes)],
    }


def _coordinate_names(model: Any) -> list[str]:
    out = []
    for c in range(model.nq):
        j = int(model.coord_joint[c])
        k = c - int(model.joint_q0[j])
        out.append(f"{model.joint_names[j]}[{k}]" if model.joint_nq[j] > 1 else model.joint_names[j])
    return out


def _report(model: Any, modes: Any, text: str) -> Report:
    """``report.html``'s content: one frame per assembly mode."""
    points = []
    for a in modes.modes:
        kin = solve_kinematics(model, a.x[None], q_start=a.q)
        points.append(kin.joint_point[0])
    jp = np.stack(points)
    summ = model_summary(model)
    joints = [(j["name"], j["type"], j["body_a"], j["body_b"]) for j in summ["joints"]]
    zero = np.zeros(len(modes.modes))
    actuated = {j["name"]: (zero, f"{j['name']} (actuated)", "-") for j in summ["joints"] if j.get("actuated")}
    scene = replace(scene_from_joints(np.arange(1, len(modes.modes) + 1, dtype=float), jp, joints, actuated),
                    frame_label="mode", frame_unit="")
    return Report(f"{model.name}: assembly modes", scene=scene, parameters=text,
                  notes=[f"{len(modes.modes)} assembly mode(s) at " + ", ".join(
                      f"{a} = {v + 0.0:.6g}" for a, v in zip(model.actuator_names, modes.s))],
                  scene_note="One frame per assembly mode, numbered as in the table.")


def job(machine: str, actuators: str, starts: int | None, seed: int, out_dir: Path | None,
        announce: Callable[[Mapping[str, Path]], None] | None = None, patience: int = PATIENCE) -> JobResult:
    """Every assembly mode of ``machine`` found at the actuator configuration ``actuators``
    (``NAME=VALUE,...``) from ``starts`` starts (``seed``; None: until ``patience`` consecutive
    starts found no new mode), each verified by the inverse kinematics; ``assemblies.json`` and
    ``report.html`` in ``out_dir`` where given."""
    p = prepare(machine, out_dir)
    model = p.model
    s = parse_actuators(model, actuators)
    modes = assembly_modes(model, s, starts=starts, seed=seed, patience=patience)
    rule = ("a fixed count" if modes.patience is None else
            f"until {modes.patience:,} starts in a row found no new mode")
    doc = _document(model, modes)
    lines = [f"mechanism: {model.name}",
             "actuators: " + ", ".join(f"{a} = {v['value'] + 0.0:.9g} {v['unit']}" for a, v in doc["actuators"].items()),
             f"method: {modes.method}",
             f"starts: {modes.starts:,} ({rule}; the last new mode at start {modes.last_new_mode_at:,}); "
             f"converged: {modes.converged:,}; assembly modes found: {len(modes.modes)}"]
    for m in doc["modes"]:
        task = ", ".join(f"{k} = {v + 0.0:.9g}" for k, v in m["task"].items())
        sm = m["singularity_measures"]
        lines.append(f"mode {m['mode']}: {task}; residual {m['residual']:.2g}; round trip {m['round_trip']:.2g}; "
                     f"det sign {m['det_sign']:+d}; singularity measures inverse {sm['inverse']:.4g}, direct "
                     f"{sm['direct']:.4g}, constraint {sm['constraint']:.4g}; starts reaching it "
                     f"{m['starts_reaching_it']}")
    files: dict[str, Path] = {}
    report = None
    if out_dir is not None:  # (the report's frames: one kinematics solve per mode)
        report = replace(_report(model, modes, p.text), summary=doc)

        def make(out: Path) -> Output:
            written = {"assemblies": out / "assemblies.json"}
            write_json(written["assemblies"], doc)
            return Output(written, report=report)

        files, _ = write_output(out_dir, p.inputs, make, announce)
    return JobResult(files, doc, tuple(lines), report=report)
