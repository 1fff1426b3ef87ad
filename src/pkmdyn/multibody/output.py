"""Result files of a described mechanism's run: ``results.csv``, ``model.json``,
``bodies.npz``, ``summary.json`` (formats: ``docs/mechanism_format.md``, "Outputs").

``model.json`` is enough to rebuild the mechanism without pkmdyn: every body (mass, centre of
mass and inertia in its own frame, its frame at the reference configuration), every joint
(type, parent and child, its frame on both bodies, its elementary motions, actuated and cut
flags), the loops, the task coordinates and gravity.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import PkmdynError
from .actuators import motor_effort_column
from .description import MOTOR_KEYS
from .dynamics import effort_unit
from .joint_types import JOINT_TYPES
from .kinematics import MechanismKinematics
from .model import MechanismModel
from .motion import motion_columns, task_columns

__all__ = ["results_columns", "motion_columns", "joint_effort_column", "actuator_effort_column", "model_summary", "bodies_arrays",
           "report_columns", "write_run_report", "mechanism_scene"]

Array = NDArray[np.float64]
_MOTION_NAMES = ("RX", "RY", "RZ", "TX", "TY", "TZ")


def joint_effort_column(model: MechanismModel, i: int, part: str | None = None) -> str:
    """Actuated joint i's effort column ``<joint>_effort_<N|Nm>``, or one part of it
    (``<joint>_effort_<part>_<N|Nm>``)."""
    name, unit = model.actuator_names[i], effort_unit(model, i)
    return f"{name}_effort_{unit}" if part is None else f"{name}_effort_{part}_{unit}"


def actuator_effort_column(model: MechanismModel, i: int, part: str | None = None) -> str:
    """Actuator i's effort column as its machine is driven, or one part of its split: at the
    motor for a drive (:func:`.actuators.motor_effort_column`), else at the joint."""
    return motor_effort_column(model, i, part) if model.drive_name[i] is not None else \
        joint_effort_column(model, i, part)


def results_columns(model: MechanismModel, kin: MechanismKinematics) -> dict[str, Array]:
    """``t_s``, the task coordinates, and per actuated joint ``<joint>_pos_<u>``,
    ``<joint>_vel_<u>_s``, ``<joint>_acc_<u>_s2`` (u = m or rad)."""
    cols: dict[str, Array] = {}
    cols["t_s"] = kin.t if kin.t is not None else np.arange(len(kin), dtype=float)
    pos, _, _ = task_columns(model)
    for k, c in enumerate(pos):
        cols[c] = kin.x[:, k]
    for i, (name, unit) in enumerate(zip(model.actuator_names, model.actuator_units)):
        for c, v in zip(motion_columns(name, unit), (kin.act_q, kin.act_qd, kin.act_qdd)):
            cols[c] = v[:, i]
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
        if model.joint_stiffness[k] is not None:  # drive_N_m|drive_Nm_rad, force_N_m, moment_Nm_rad
            st = model.joint_stiffness[k]
            unit = ("drive_N_m" if jt.units[0] == "m" else "drive_Nm_rad") if "drive" in st else ""
            entry["stiffness"] = {(unit if key == "drive" else key): v for key, v in st.items()}
        joints.append(entry)
    pos, _, _ = task_columns(model)
    return {
        "format": "pkmdyn mechanism model 1",
        "name": model.name, "source": model.source, "gravity_m_s2": model.gravity,
        "parameters": dict(model.parameters),
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
        "drives": [_drive_entry(model, i) for i, d in enumerate(model.drive_name) if d is not None],
        "groups": {g: [model.body_names[b] for b in np.flatnonzero(model.body_group == k)]
                   for k, g in enumerate(model.group_names)},
        "loads": [_load_entry(model, k) for k in range(len(model.load_body))],
        "topology": model.topology.as_dict() if model.topology is not None else None,
    }


def _drive_entry(model: MechanismModel, i: int) -> dict[str, Any]:
    """One drive of model.json (multibody.actuators, Eq. A1), its keys in the motor's units:
    ``name``, ``joint``, ``kind`` (``rotary`` or ``linear``), ``ratio`` (motor coordinate per
    joint coordinate, ``theta = ratio q``), ``screw_lead_m`` and ``gear_ratio`` as given, the
    rotor, friction and limits (null when not given), ``encoder_resolution`` (motor travel per
    count, null when not given)."""
    rot = model.motor_units[i] == "rad"
    spec = model.drive_specs[i]

    def val(v: float) -> float | None:
        return float(v) if np.isfinite(v) else None

    keys = MOTOR_KEYS["rotary" if rot else "linear"]
    return {"name": model.drive_name[i], "joint": model.actuator_names[i], "kind": model.drive_kind[i],
            "ratio": float(model.drive_ratio[i]), "screw_lead_m": spec.lead, "gear_ratio": spec.gear_ratio,
            keys["rotor"]: float(model.drive_rotor[i]), keys["coulomb"]: float(model.drive_coulomb[i]),
            keys["viscous"]: float(model.drive_viscous[i]), keys["max_effort"]: val(model.drive_max_effort[i]),
            keys["max_speed"]: val(model.drive_max_speed[i]),
            keys["max_acceleration"]: val(model.drive_max_acceleration[i]),
            ("encoder_resolution_rad" if rot else "encoder_resolution_m"): float(model.drive_encoder[i]) or None}


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


def _report_groups(model: MechanismModel) -> list[tuple[str, str, list[str]]]:
    """The report's plots of the actuators: ``(title, y label, columns)``."""
    joints = [motion_columns(a, u) for a, u in zip(model.actuator_names, model.actuator_units)]
    groups = [("Actuator coordinates", "actuator coordinates [SI]", [c[0] for c in joints]),
              ("Actuator rates", "actuator rates [SI]", [c[1] for c in joints]),
              ("Actuator efforts", "actuator efforts [SI]", [joint_effort_column(model, i) for i in range(model.na)])]
    motors = [motor_effort_column(model, i) for i, d in enumerate(model.drive_name) if d is not None]
    if motors:
        groups.append(("Motor efforts", "motor effort [N m or N]", motors))
    return groups


def report_columns(model: MechanismModel) -> list[str]:
    """The results columns a run's report plots (:func:`write_run_report`)."""
    pos, _, _ = task_columns(model)
    return ["t_s", *pos, *(c for _, _, cols in _report_groups(model) for c in cols)]


def write_run_report(out: Path, model: MechanismModel, cols: dict[str, Array], frames: dict[str, Array],
                     summary: dict[str, Any], description_text: str, samples: int | None = None) -> Path:
    """``report.html`` of a run (:mod:`pkmdyn.report`): the mechanism drawn at the animation's
    samples ``frames`` (``t``, ``joint_point``: each body through its joint centres, actuated
    joints as chains coloured by effort), the task and actuator coordinates, rates and efforts
    against time from the results columns ``cols`` (the plots' window of the run; ``samples``:
    the run's length when the window is shorter)."""
    from ..report import Curve, TimePlot, write_report

    t = cols["t_s"]
    pos, _, _ = task_columns(model)
    plots = [TimePlot("Task coordinates", "task coordinate [m or rad]", t, tuple(Curve(c, cols[c]) for c in pos))]
    for title, label, group in _report_groups(model):
        plots.append(TimePlot(title, label, t, tuple(Curve(c, cols[c]) for c in group)))
    idx = frame_indices_of(t, frames["t"])
    efforts = {}
    for i, name in enumerate(model.actuator_names):
        efforts[name] = (cols[joint_effort_column(model, i)][idx], f"{name} effort", effort_unit(model, i))
    scene = mechanism_scene(model, frames["t"], frames["joint_point"], efforts)
    notes = [f"mechanism: {model.name}" + (f" ({model.source})" if model.source else "")]
    if samples is not None and samples > t.shape[0]:
        notes.append(f"plots and animation: the first {t.shape[0]} of {samples} samples (results hold every sample)")
    return write_report(out, title=f"{model.name}: pkmdyn run", scene=scene,
                        plots=plots, summary=summary, parameters=description_text, notes=notes,
                        scene_note="Joint centres as in bodies.npz (joint_point); actuated joints drawn as chains.",
                        samples=t.shape[0])


def mechanism_scene(model: MechanismModel, t: Array, joint_point: Array,
                    efforts: dict[str, tuple[Array, str, str]] | None = None) -> Any:
    """The report's 3D scene of ``model`` (:func:`pkmdyn.report.scene_from_joints`): every body
    through its joint centres ``joint_point (n, nj, 3)`` [m] at the times ``t (n,)`` [s];
    ``efforts``: ``{actuated joint: (effort (n,), label, unit)}``, those joints drawn as chains
    coloured by their effort."""
    from ..report import scene_from_joints

    joints = [(nm, JOINT_TYPES[model.joint_type[k]].name,
               "ground" if model.joint_parent[k] < 0 else model.body_names[model.joint_parent[k]],
               "ground" if model.joint_child[k] < 0 else model.body_names[model.joint_child[k]])
              for k, nm in enumerate(model.joint_names)]
    return scene_from_joints(t, joint_point, joints, efforts)


def frame_indices_of(t: Array, frame_t: Array) -> Array:
    """Indices into ``t`` (increasing) of the animation's sample times ``frame_t``."""
    return np.clip(np.searchsorted(t, frame_t), 0, t.shape[0] - 1)
