"""Result files of a described mechanism's run: ``results.csv``, ``model.json``,
``bodies.npz``, ``summary.json`` (formats: ``docs/mechanism_format.md``, "Outputs").

``model.json`` is enough to rebuild the mechanism without pkmdyn: every body (mass, centre of
mass and inertia in its own frame, its frame at the reference configuration), every joint
(type, parent and child, its frame on both bodies, its elementary motions, actuated and cut
flags), the loops, the task coordinates and gravity.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import PkmdynError
from ..io import output_dir, write_csv, write_json
from .joint_types import JOINT_TYPES
from .kinematics import MechanismKinematics, limit_message, singularity_measures, solve_kinematics
from .model import MechanismModel
from .motion import TaskMotion, task_columns

__all__ = ["results_columns", "model_summary", "bodies_arrays", "run_mechanism"]

Array = NDArray[np.float64]
_MOTION_NAMES = ("RX", "RY", "RZ", "TX", "TY", "TZ")


def results_columns(model: MechanismModel, kin: MechanismKinematics) -> dict[str, Array]:
    """``t_s``, the task coordinates, and per actuated joint ``<joint>_pos_<u>``,
    ``<joint>_vel_<u>_s``, ``<joint>_acc_<u>_s2`` (u = m or rad)."""
    cols: dict[str, Array] = {}
    cols["t_s"] = kin.t if kin.t is not None else np.arange(len(kin), dtype=float)
    pos, _, _ = task_columns(model)
    for k, c in enumerate(pos):
        cols[c] = kin.x[:, k]
    for i, (name, unit) in enumerate(zip(model.actuator_names, model.actuator_units)):
        cols[f"{name}_pos_{unit}"] = kin.act_q[:, i]
        cols[f"{name}_vel_{unit}_s"] = kin.act_qd[:, i]
        cols[f"{name}_acc_{unit}_s2"] = kin.act_qdd[:, i]
    return cols


def _frame(R: Array, p: Array) -> dict[str, Any]:
    return {"origin_m": p, "x_axis": R[:, 0], "y_axis": R[:, 1], "z_axis": R[:, 2]}


def model_summary(model: MechanismModel) -> dict[str, Any]:
    """The ``model.json`` document (see the module docstring)."""
    bodies = []
    for b, name in enumerate(model.body_names):
        extra = model.body_extra[b]
        bodies.append({
            "name": name, "mass_kg": float(model.mass[b]), "com_m": model.com[b], "inertia_kgm2": model.inertia[b],
            "reference_frame": _frame(model.R0[b], model.p0[b]),
            **{k: v for k, v in extra.items() if v is not None},
        })
    joints = []
    for k, name in enumerate(model.joint_names):
        jt = JOINT_TYPES[model.joint_type[k]]
        parent = "ground" if model.joint_parent[k] < 0 else model.body_names[model.joint_parent[k]]
        child = "ground" if model.joint_child[k] < 0 else model.body_names[model.joint_child[k]]
        entry: dict[str, Any] = {
            "name": name, "type": jt.name, "letter": jt.letter, "parent": parent, "child": child,
            "body_a": parent, "body_b": child,
            "parent_frame": _frame(model.joint_R_parent[k], model.joint_p_parent[k]),
            "child_frame": _frame(model.joint_R_child[k], model.joint_p_child[k]),
            "motions": [m for m in jt.motions], "coordinate_units": list(jt.units),
            "actuated": bool(model.joint_actuated[k]), "cut": bool(model.joint_cut[k]),
            "traversed_backwards": bool(model.joint_flipped[k]),
            "position_at_reference": float(model.joint_offset[k]),
        }
        if model.joint_cut[k]:
            entry["constrained_directions"] = list(jt.directions)
        if model.joint_limits[k] is not None:
            entry["limits"] = list(model.joint_limits[k])
        if model.joint_friction[k] is not None:
            entry["friction"] = model.joint_friction[k]
        joints.append(entry)
    pos, _, _ = task_columns(model)
    return {
        "format": "pkmdyn mechanism model 1",
        "name": model.name, "source": model.source, "gravity_m_s2": model.gravity,
        "frames": ("every point and frame of a body is in that body's frame; reference_frame is the body frame in "
                   "the base frame at the reference configuration, where every joint coordinate equals "
                   "position_at_reference and each joint's parent_frame and child_frame coincide; a joint's "
                   "relative motion is the product of its elementary motions (RX: rotation about the joint "
                   "frame's x axis, TZ: translation along z, ...) applied to the child frame"),
        "bodies": bodies, "joints": joints,
        "loops": [{"cut_joint": lp.joint, "body_a": lp.body_a, "body_b": lp.body_b,
                   "constrained_directions": list(lp.directions), "tree_path": list(lp.path)} for lp in model.loops],
        "task": {"body": model.body_names[model.task_body], "point_m": model.task_point,
                 "euler_sequence": model.euler_sequence,
                 "coordinates": _task_coordinates(model, pos)},
        "actuators": list(model.actuator_names),
        "loads": [_load_entry(model, k) for k in range(len(model.load_body))],
        "topology": model.topology.as_dict() if model.topology is not None else None,
    }


def _load_entry(model: MechanismModel, k: int) -> dict[str, Any]:
    """One ``[[loads]]`` entry of model.json: body, force and moment (base frame) and point (body
    frame); a named load adds its name and direction, its force being the one at the
    description's magnitude (a run's per-sample forces are in bodies.npz, ``load_force``)."""
    entry: dict[str, Any] = {"body": model.body_names[model.load_body[k]], "force_N": model.load_force[k],
                             "moment_Nm": model.load_moment[k], "point_m": model.load_point[k]}
    if model.load_name[k] is not None:
        entry.update(name=model.load_name[k], direction=model.load_direction[k])
    return entry


def _task_coordinates(model: MechanismModel, pos: list[str]) -> list[dict[str, Any]]:
    """Each task coordinate: its column, and the base-frame component (0-2) of the task point
    or the place (1-3) of the Euler angle in ``euler_sequence`` as written."""
    out = []
    inv = {int(v): k for k, v in enumerate(model.euler_perm)}
    for c, kind, i in zip(pos, model.task_kind, model.task_index):
        if kind == 0:
            out.append({"column": c, "kind": "position", "component": int(i)})
        else:
            out.append({"column": c, "kind": "euler_angle", "angle": inv[int(i)] + 1})
    return out


def bodies_arrays(model: MechanismModel, kin: MechanismKinematics) -> dict[str, Array]:
    """``bodies.npz`` arrays (base frame, SI): per body ``R``, ``p``/``v``/``a`` (centre of
    mass), ``w``, ``wd``, ``origin``/``origin_v``/``origin_a`` (body frame origin); per joint
    ``joint_point``/``joint_point_v``/``joint_point_a``; ``q, qd, qdd`` (tree coordinates),
    ``x, xd, xdd`` (task), ``t``; ``body_names``, ``joint_names``, ``coordinate_joints``."""
    out = {f: getattr(kin, f) for f in ("R", "p", "v", "a", "w", "wd", "origin", "origin_v", "origin_a",
                                         "joint_point", "joint_point_v", "joint_point_a", "q", "qd", "qdd",
                                         "x", "xd", "xdd")}
    out["t"] = kin.t if kin.t is not None else np.arange(len(kin), dtype=float)
    for k, v in out.items():
        if not np.all(np.isfinite(v)):
            raise PkmdynError(f"bodies.npz: {k} has a non-finite value; refusing to write it")
    return out


def _write_report(out: Path, model: MechanismModel, files: dict[str, Path], cols: dict[str, Array],
                  summary: dict[str, Any], description_text: str) -> Path:
    """``report.html`` of a run (:mod:`pkmdyn.report`): the mechanism drawn from the files just
    written (``model.json``, ``bodies.npz``), the task and actuator coordinates against time."""
    from ..report import Curve, TimePlot, scene_from_files, write_report

    t = cols["t_s"]
    pos, _, _ = task_columns(model)
    plots = [TimePlot("Task coordinates", "task coordinate [m or rad]", t, tuple(Curve(c, cols[c]) for c in pos))]
    for kind, label in (("pos", "actuator coordinates"), ("vel", "actuator rates"), ("effort", "actuator efforts")):
        names = [c for c in cols if f"_{kind}_" in c]
        if names:
            plots.append(TimePlot(label.capitalize(), f"{label} [SI]", t, tuple(Curve(c, cols[c]) for c in names)))
    efforts = {}
    for name in model.actuator_names:
        col = next((c for c in cols if c.startswith(f"{name}_effort_")), None)
        if col is not None:
            efforts[name] = (cols[col], f"{name} effort", col.rsplit("_effort_", 1)[1])
    scene = scene_from_files(files["model"], files["bodies"], actuated=efforts or None)
    return write_report(out, title=f"{model.name}: pkmdyn run", scene=scene,
                        plots=plots, summary=summary, parameters=description_text,
                        notes=[f"mechanism: {model.name}" + (f" ({model.source})" if model.source else "")],
                        scene_note="Joint centres as in bodies.npz (joint_point); actuated joints drawn as chains.")


def run_mechanism(model: MechanismModel, motion: TaskMotion, out_dir: str | Path, inputs: Any = (),
                  report: Callable[[dict[str, Path]], None] | None = None, description_text: str = "",
                  unique_reactions: bool = False) -> dict[str, Any]:
    """Kinematics of ``model`` along ``motion``, written into ``out_dir`` (through
    :func:`pkmdyn.io.output_dir` under the output rule, ``inputs`` the files the run read:
    nothing is written when anything fails), with ``report.html`` (``description_text``: the
    description file's text, shown on the page). ``report`` is called with the files' final
    paths before they move into place. An over-constrained mechanism needs the section and
    material that make its reactions unique: without them its run writes the minimum-norm
    reactions flagged ``"unique": false`` (kinematics and efforts are unique all the same), or,
    with ``unique_reactions``, is refused (:func:`pkmdyn.multibody.dynamics.dynamics_outputs`). Returns the summary with ``files`` as
    ``{label: path}``."""
    from .dynamics import dynamics_outputs

    kin = solve_kinematics(model, motion.x, motion.xd, motion.xdd, motion.t)
    sm = singularity_measures(model, kin.q)
    beyond = limit_message(model, kin)
    cols = results_columns(model, kin)
    npz = bodies_arrays(model, kin)
    dyn_cols, dyn_npz, dyn_summary = dynamics_outputs(model, kin, minimum_norm=not unique_reactions,
                                                      named=motion.loads)
    cols.update(dyn_cols)
    npz.update(dyn_npz)
    summary = {
        "mechanism": model.name, "samples": len(kin), "max_residual": float(kin.residual.max()),
        "min_inverse_singularity_measure": float(sm.inverse.min()),
        "min_direct_singularity_measure": None if np.isnan(sm.direct).all() else float(np.nanmin(sm.direct)),
        "min_constraint_singularity_measure": float(sm.constraint.min()),
        # the motion against the joints' limits (stored in the description; the run goes on beyond them)
        "joint_limits": {"kept": beyond is None, "first_beyond": beyond},
        "topology": model.topology.as_dict() if model.topology is not None else None,
        **dyn_summary,
    }
    final = Path(out_dir)
    with output_dir(out_dir, inputs=inputs) as out:
        files = {"results": out / "results.csv", "model": out / "model.json", "bodies": out / "bodies.npz",
                 "summary": out / "summary.json"}
        write_csv(files["results"], cols)
        write_json(files["model"], model_summary(model))
        try:
            np.savez_compressed(files["bodies"], body_names=np.array(model.body_names),
                                joint_names=np.array(model.joint_names),
                                coordinate_joints=np.array([model.joint_names[j] for j in model.coord_joint]), **npz)
        except OSError as exc:
            raise PkmdynError(f"{files['bodies']}: cannot write file ({exc.strerror or type(exc).__name__})") from None
        files["report"] = _write_report(out, model, files, cols, summary, description_text)
        summary["files"] = sorted(p.name for p in files.values())
        write_json(files["summary"], summary)
        if report is not None:
            report({k: final / v.name for k, v in files.items()})
    return {**summary, "files": {k: final / v.name for k, v in files.items()}}
