"""The engine's results as the files' columns and records: ``results.csv``'s columns, ``model.json``'s
record, ``bodies.npz``'s arrays (formats: ``docs/mechanism_format.md``, "Outputs"); the jobs write them.

``model.json`` is enough to rebuild the mechanism without pkmdyn: every body (mass, centre of
mass and inertia in its own frame, its frame at the reference configuration), every joint
(type, parent and child, its frame on both bodies, its elementary motions, actuated and cut
flags), the loops, the task coordinates and gravity.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import PkmdynError
from .analyses.stiffness import deflection
from .description.joint_types import JOINT_TYPES
from .description.schema import MOTOR_KEYS
from .dynamics.actuators import motor_effort_column, motor_efforts
from .dynamics.newton_euler import effort_unit, named_magnitudes
from .kinematics.inverse import MechanismKinematics
from .kinematics.motion import motion_columns, task_columns
from .model.compiler import MechanismModel

__all__ = ["results_columns", "pose_columns", "pose_column_names", "motion_columns", "joint_effort_column",
           "actuator_effort_column", "model_summary", "bodies_arrays", "effort_columns", "results_column_names", "deflection_columns"]

Array = NDArray[np.float64]
_MOTION_NAMES = ("RX", "RY", "RZ", "TX", "TY", "TZ")


def joint_effort_column(model: MechanismModel, i: int, part: str | None = None) -> str:
    """Actuated joint i's effort column ``<joint>_effort_<N|Nm>``, or one part of it
    (``<joint>_effort_<part>_<N|Nm>``)."""
    name, unit = model.actuator_names[i], effort_unit(model, i)
    return f"{name}_effort_{unit}" if part is None else f"{name}_effort_{part}_{unit}"


def actuator_effort_column(model: MechanismModel, i: int, part: str | None = None) -> str:
    """Actuator i's effort column as its machine is driven, or one part of its split: at the
    motor for a drive (:func:`pkmdyn.multibody.dynamics.actuators.motor_effort_column`), else at the joint."""
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


def pose_column_names(model: MechanismModel) -> list[str]:
    """The pose columns of :func:`pose_columns`: ``task_body_x_m`` ... ``task_body_euler3_rad``,
    then the same six for every ``[[outputs]]`` entry under its name."""
    out: list[str] = []
    for prefix in ("task_body", *model.output_names):
        out += [f"{prefix}_{c}_m" for c in "xyz"] + [f"{prefix}_euler{k}_rad" for k in (1, 2, 3)]
    return out


def _euler_angles(model: MechanismModel, R: Array) -> Array:
    """The three Euler angles (n, 3) [rad] of the rotations ``R`` (n, 3, 3) in the task's sequence,
    as written (``XYZ`` intrinsic, ``xyz`` extrinsic: scipy's convention), each in its principal
    range; a proper sequence at its singular pose gives one of its equivalent triples."""
    from scipy.spatial.transform import Rotation  # scipy: loaded by the first run, not by the import

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # gimbal lock: still a valid triple
        return Rotation.from_matrix(R).as_euler(model.euler_sequence)


def pose_columns(model: MechanismModel, kin: MechanismKinematics) -> dict[str, Array]:
    """The whole pose of the task body, whatever the task coordinates are, and of every
    ``[[outputs]]`` body (a lower-mobility mechanism's parasitic motions among them): the point's
    base-frame position ``o_b + R_b r`` (``r`` the point in the body frame: the task point, the
    output's point) and the Euler angles of ``R_b`` in the task's sequence (the body frame's
    rotation to the base frame, as the task's angles). A task angle keeps the motion's own value
    (not wrapped) where it is the same angle up to whole turns; where the task's middle angle
    leaves scipy's principal range the columns are scipy's equivalent triple."""
    cols: dict[str, Array] = {}
    bodies = [(int(model.task_body), model.task_point, "task_body")]
    bodies += [(int(b), pt, name) for b, pt, name in zip(model.output_body, model.output_point, model.output_names)]
    inv = {int(v): k for k, v in enumerate(model.euler_perm)}
    for b, pt, prefix in bodies:
        R = kin.R[:, b]
        p = kin.origin[:, b] + R @ pt
        ang = _euler_angles(model, R)
        if b == model.task_body:
            for j, (kind, i) in enumerate(zip(model.task_kind, model.task_index)):
                if kind == 1:
                    k = inv[int(i)]
                    turns = (kin.x[:, j] - ang[:, k]) / (2.0 * np.pi)
                    same = np.abs(turns - np.round(turns)) < 1e-9
                    ang[same, k] = kin.x[same, j]
        for c, v in zip("xyz", p.T):
            cols[f"{prefix}_{c}_m"] = v
        for k in range(3):
            cols[f"{prefix}_euler{k + 1}_rad"] = ang[:, k]
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
        if model.joint_spring and model.joint_spring[k] is not None:
            u = jt.units[0]
            entry["spring"] = {f"stiffness_{'Nm_rad' if u == 'rad' else 'N_m'}": model.joint_spring[k][0],
                               f"reference_{u}": model.joint_spring[k][1]}
        if len(model.joint_bearing) and model.joint_bearing[k] >= 0:
            entry["bearing"] = parent if model.joint_bearing[k] == 0 else child
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
        "outputs": [{"name": n, "body": model.body_names[b], "point_m": pt}
                    for n, b, pt in zip(model.output_names, model.output_body, model.output_point)],
        "actuators": list(model.actuator_names),
        "drives": [_drive_entry(model, i) for i, d in enumerate(model.drive_name) if d is not None],
        "groups": {g: [model.body_names[b] for b in np.flatnonzero(model.body_group == k)]
                   for k, g in enumerate(model.group_names)},
        "loads": [_load_entry(model, k) for k in range(len(model.load_body))],
        "topology": model.topology.as_dict() if model.topology is not None else None,
    }


def _drive_entry(model: MechanismModel, i: int) -> dict[str, Any]:
    """One drive of model.json (multibody.dynamics.actuators, Eq. A1), its keys in the motor's units:
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
            ("encoder_resolution_rad" if rot else "encoder_resolution_m"): float(model.drive_encoder[i]) or None,
            "winding_resistance_ohm": spec.resistance if spec.constant else None,
            keys["constant"]: spec.constant or None}


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
    """Each task coordinate: its column, and the base-frame component (0-2) of the task point,
    the place (1-3) of the Euler angle in ``euler_sequence`` as written, or the joint."""
    out = []
    inv = {int(v): k for k, v in enumerate(model.euler_perm)}
    joints = iter(model.task_joints)  # the joint rows' entries, in the rows' order
    for c, kind, i in zip(pos, model.task_kind, model.task_index):
        if kind == 0:
            out.append({"column": c, "kind": "position", "component": int(i)})
        elif kind == 2:
            out.append({"column": c, "kind": "joint", "joint": next(joints)})
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


#: an under-actuated mechanism's column of ``results.csv``: the share of each sample's
#: generalised force along freedoms no actuator moves (dimensionless,
#: :func:`pkmdyn.multibody.dynamics.newton_euler.unactuated_share`)
UNACTUATED_COLUMN = "unactuated_force_ratio"


def effort_columns(model: MechanismModel, kin: MechanismKinematics, reac: Any, named: Mapping | None) -> dict[str, Array]:
    """The dynamics' columns of ``results.csv``: per actuated joint ``<joint>_effort_<N|Nm>``;
    per drive its motor ``<actuator>_pos_rad``, ``_vel_rad_s``, ``_acc_rad_s2`` (``m`` for a
    linear motor) and ``<actuator>_torque_Nm`` (``_force_N``); then the effort split
    (:class:`~pkmdyn.multibody.dynamics.newton_euler.EffortShares`): per actuator and part (each body group, ``rotor`` for a
    drive, ``friction``: every joint's and the motor's) ``<actuator>_torque_<part>_Nm`` (a
    drive, motor side) or ``<joint>_effort_<part>_<N|Nm>`` (a joint without one); the named
    loads' magnitudes; an under-actuated mechanism's :data:`UNACTUATED_COLUMN`."""
    cols: dict[str, Array] = {}
    u = reac.u
    for i in range(model.na):
        cols[joint_effort_column(model, i)] = u[:, i]
    mot = motor_efforts(model, kin.act_q, kin.act_qd, kin.act_qdd, u)
    for i, name in enumerate(model.drive_name):
        if name is None:
            continue
        for c, v in zip(motion_columns(name, model.motor_units[i]), (mot.theta, mot.theta_dot, mot.theta_ddot)):
            cols[c] = v[:, i]
        cols[motor_effort_column(model, i)] = mot.effort[:, i]
    sh = reac.shares
    if sh is not None:
        k = model.drive_ratio
        fr_joint = sh.friction.sum(axis=2)
        for i in range(model.na):
            for g, gname in enumerate(model.group_names):
                cols[actuator_effort_column(model, i, gname)] = sh.groups[:, i, g] / k[i]
            if model.drive_name[i] is not None:
                cols[actuator_effort_column(model, i, "rotor")] = mot.rotor[:, i]
            cols[actuator_effort_column(model, i, "friction")] = fr_joint[:, i] / k[i] + mot.friction[:, i]
            if model.na > model.nt:  # redundant actuation: the distribution's internal force
                cols[actuator_effort_column(model, i, "internal")] = sh.internal[:, i] / k[i]
    if model.named_loads:
        cols.update(named_magnitudes(model, len(kin), named))
    if model.na < model.nt:  # under-actuated: how far from dynamically inconsistent each sample is
        cols[UNACTUATED_COLUMN] = reac.unactuated
    return cols


def results_column_names(model: MechanismModel, deflection: bool = False) -> list[str]:
    """Every column of a run's results table, in order (:func:`results_columns`, then
    :func:`effort_columns`; with ``deflection`` the task coordinates' elastic deflection last,
    :func:`deflection_columns`)."""
    

    pos, _, _ = task_columns(model)
    out = ["t_s", *pos]
    for name, unit in zip(model.actuator_names, model.actuator_units):
        out += motion_columns(name, unit)
    out += [joint_effort_column(model, i) for i in range(model.na)]
    for i, name in enumerate(model.drive_name):
        if name is not None:
            out += [*motion_columns(name, model.motor_units[i]), motor_effort_column(model, i)]
    for i in range(model.na):
        parts = [*model.group_names, *(["rotor"] if model.drive_name[i] is not None else []), "friction",
                 *(["internal"] if model.na > model.nt else [])]
        out += [actuator_effort_column(model, i, p) for p in parts]
    out += list(model.named_loads)
    if model.na < model.nt:
        out.append(UNACTUATED_COLUMN)
    if deflection:
        out += [f"{n}_deflection_{u}" for n, u in zip(model.task_names, model.task_units)]
    return out + pose_column_names(model)


def deflection_columns(model: MechanismModel, kin: MechanismKinematics, reac: Any, named: Mapping | None,
                       sample_offset: int = 0) -> dict[str, Array]:
    """``<coordinate>_deflection_<unit>``: the task coordinates' elastic deflection with the
    actuators locked under the motion's own loads (:func:`pkmdyn.multibody.analyses.stiffness.deflection`)."""
    dx = deflection(model, kin, reac, named=named, sample_offset=sample_offset)
    return {f"{n}_deflection_{u}": dx[:, i] for i, (n, u) in enumerate(zip(model.task_names, model.task_units))}
