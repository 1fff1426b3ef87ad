"""Any described mechanism as URDF plus a loop sidecar (YAML): the pair that Pinocchio's URDF
parser and Gepetto's Extended-URDF loader read, and that ``pkmdyn import`` reads back.

* **Tree.** The spanning tree becomes the URDF tree, rooted at a link ``ground``. Every link
  frame is parallel to the base frame at the reference configuration and sits at the joint
  centre, so that URDF's zero joint position is the description's reference configuration:
  the URDF joint position is the tree coordinate less its reference value
  (``q - coord_offset``, as in the MJCF export). A joint of several coordinates is a chain of
  one-coordinate URDF joints through massless links ``<child>__<k>`` (a universal joint two
  revolute joints, a spherical joint three), named ``<joint>_<k>``; a one-coordinate joint
  keeps its name. A revolute joint without limits is ``continuous``; a prismatic one without
  limits gets ``lower = -1e9``, ``upper = 1e9`` [m] (URDF requires a range; import leaves out a
  range a million or more wide).
* **Loops.** Each cut joint gets two frames, fixed links ``<joint>_A`` on its parent body and
  ``<joint>_B`` on its child body at the joint centre, turned as the joint frame; the sidecar
  closes a spherical cut joint with a ``3d`` pair and a fixed one with a ``6d`` pair, and a
  revolute cut joint with two ``3d`` pairs, the second (``<joint>_axis_A/B``) one length scale
  along the axis. Prismatic, cylindrical, universal and planar cut joints are refused, naming
  the joint (cut another joint with ``[mechanism] cut_joints``).
* **Sidecar.** ``gravity_m_s2`` (URDF holds none), ``closed_loop``, ``type``, ``name_mot`` (the actuated joints), pkmdyn's
  ``task`` (body, point, position, orientation, euler_sequence) and ``actuators`` (each drive's ratio, rotor
  and motor friction, as ``[[actuators]]`` entries).
* **Friction.** A one-coordinate joint's Coulomb and viscous friction become
  ``<dynamics friction damping>``; load-dependent and external friction, loads, sections and
  stiffness have no URDF equivalent and are listed in the returned notes.
"""

from __future__ import annotations

from xml.sax.saxutils import quoteattr

import numpy as np

from ...errors import ParameterError
from ..description.schema import MOTOR_KEYS
from ..description.joint_types import JOINT_TYPES
from ..model.compiler import MechanismModel, tree_task_joints

__all__ = ["mechanism_urdf"]

#: the range written for a prismatic joint without limits [m] (URDF requires one); pkmdyn import
#: leaves out any range a million or more wide
NO_RANGE_M = 1e9


def _v(a) -> str:
    return " ".join(f"{float(x):.17g}" for x in np.ravel(a))


def _rpy(R) -> str:
    from scipy.spatial.transform import Rotation

    return _v(Rotation.from_matrix(R).as_euler("xyz"))  # URDF: fixed-axis roll, pitch, yaw


def _inertial(mass: float, com, inertia) -> str:
    I = inertia
    return (f'    <inertial><origin xyz="{_v(com)}" rpy="0 0 0"/><mass value="{mass:.17g}"/>'
            f'<inertia ixx="{I[0, 0]:.17g}" ixy="{I[0, 1]:.17g}" ixz="{I[0, 2]:.17g}" iyy="{I[1, 1]:.17g}" '
            f'iyz="{I[1, 2]:.17g}" izz="{I[2, 2]:.17g}"/></inertial>')


def _drives(model: MechanismModel) -> list[dict]:
    out = []
    for spec in model.drive_specs or ():
        if spec is None:
            continue
        d = {"joint": spec.joint, "name": spec.name}
        if spec.lead is not None:
            d["screw_lead_m"] = float(spec.lead)
        if spec.kind == "rotary":
            d["gear_ratio"] = float(spec.gear_ratio)
        for role, v in (("rotor", spec.rotor), ("coulomb", spec.coulomb), ("viscous", spec.viscous)):
            if v:
                d[MOTOR_KEYS[spec.kind][role]] = float(v)
        if spec.constant:
            d["winding_resistance_ohm"] = float(spec.resistance)
            d[MOTOR_KEYS[spec.kind]["constant"]] = float(spec.constant)
        out.append(d)
    return out


def mechanism_urdf(model: MechanismModel) -> tuple[str, dict, list[str]]:
    """``(urdf_text, sidecar, notes)`` of ``model`` (module docstring); ``sidecar`` is the
    YAML's mapping."""
    for j in model.loop_joint:
        t = JOINT_TYPES[model.joint_type[j]].name
        if t not in ("spherical", "revolute", "fixed"):
            raise ParameterError(f"[joints] {model.joint_names[j]}: a cut {t} joint cannot be written as a URDF loop "
                                 "closure; cut another joint of its loop ([mechanism] cut_joints)")
    notes = []
    lines = [f'<robot name={quoteattr(model.name)}>', '  <link name="ground"/>']
    frame_at: dict[int, np.ndarray] = {-1: np.zeros(3)}  # each body's URDF link origin (base frame)

    def link(name: str, mass: float, com, inertia, origin) -> None:
        lines.append(f"  <link name={quoteattr(name)}>")
        lines.append(_inertial(mass, com - origin, inertia))  # a body's inertia even without mass
        lines.append("  </link>")

    for b in range(model.nb):  # the model's body order is the tree's: parents first
        k = int(model.body_joint[b])
        par = int(model.body_parent[b])
        parent_link = "ground" if par < 0 else model.body_names[par]
        Rb, pb = model.R0[b], model.p0[b]
        point = pb + Rb @ model.tree_p_child[k]
        Ic = Rb @ model.inertia[b] @ Rb.T
        com = pb + Rb @ model.com[b]
        nq = int(model.joint_nq[k])
        jname = model.joint_names[k]
        prev, prev_origin = parent_link, frame_at[par]
        if nq == 0:
            lines.append(f'  <joint name={quoteattr(jname)} type="fixed"><parent link={quoteattr(prev)}/>'
                         f'<child link={quoteattr(model.body_names[b])}/><origin xyz="{_v(point - prev_origin)}" '
                         'rpy="0 0 0"/></joint>')
        for i, c in enumerate(range(int(model.joint_q0[k]), int(model.joint_q0[k]) + nq)):
            last = i == nq - 1
            child = model.body_names[b] if last else f"{model.body_names[b]}__{i + 1}"
            name = jname if nq == 1 else f"{jname}_{i + 1}"
            mcode = int(model.coord_motion[c])
            axis = Rb @ (model.coord_sign[c] * model.tree_R_child[k][:, mcode % 3])
            lim = model.joint_limits[k] if nq == 1 else None
            off = float(model.coord_offset[c])
            if mcode < 3:
                kind = "revolute" if lim is not None else "continuous"
            else:
                kind = "prismatic"
            text = (f'  <joint name={quoteattr(name)} type="{kind}"><parent link={quoteattr(prev)}/>'
                    f'<child link={quoteattr(child)}/><origin xyz="{_v(point - prev_origin)}" rpy="0 0 0"/>'
                    f'<axis xyz="{_v(axis)}"/>')
            if lim is not None:
                text += f'<limit lower="{lim[0] - off:.17g}" upper="{lim[1] - off:.17g}" effort="0" velocity="0"/>'
            elif kind == "prismatic":  # URDF needs a range: one no mechanism reaches (import drops it)
                text += f'<limit lower="{-NO_RANGE_M:g}" upper="{NO_RANGE_M:g}" effort="0" velocity="0"/>'
            fr = model.joint_friction[k] or {}
            if nq == 1 and fr:
                rot = mcode < 3
                dry = fr.get("coulomb_torque_Nm" if rot else "coulomb_force_N", 0.0)
                visc = fr.get("viscous_Nm_s_rad" if rot else "viscous_N_s_m", 0.0)
                if dry or visc:
                    text += f'<dynamics damping="{visc:.17g}" friction="{dry:.17g}"/>'
                rest = [key for key, v in fr.items() if v and key not in (
                    "coulomb_torque_Nm", "coulomb_force_N", "viscous_Nm_s_rad", "viscous_N_s_m")]
                if rest:
                    notes.append(f"joint {jname}: friction {', '.join(rest)} not written (no URDF equivalent)")
            elif i == 0 and fr and any(v for v in fr.values()):
                notes.append(f"joint {jname}: friction not written (a joint of several coordinates)")
            lines.append(text + "</joint>")
            if last:
                link(child, float(model.mass[b]), com, Ic, point)
            else:
                lines.append(f"  <link name={quoteattr(child)}/>")
            prev, prev_origin = child, point
        if nq == 0:
            link(model.body_names[b], float(model.mass[b]), com, Ic, point)
        frame_at[b] = point
    closed, types = [], []
    for j in model.loop_joint:
        t = JOINT_TYPES[model.joint_type[j]].name
        a, c = int(model.joint_parent[j]), int(model.joint_child[j])
        nm = model.joint_names[j]
        # the joint frame on each side, base frame at the reference configuration
        Ra = model.joint_R_parent[j] if a < 0 else model.R0[a] @ model.joint_R_parent[j]
        pa = model.joint_p_parent[j] if a < 0 else model.p0[a] + model.R0[a] @ model.joint_p_parent[j]
        pairs = [(f"{nm}_A", f"{nm}_B", pa)]
        if t == "revolute":
            pairs.append((f"{nm}_axis_A", f"{nm}_axis_B", pa + Ra[:, 2] * model.length_scale))
        for fa, fb, p in pairs:
            for fname, body in ((fa, a), (fb, c)):
                host = "ground" if body < 0 else model.body_names[body]
                lines.append(f'  <joint name={quoteattr(fname + "_fixed")} type="fixed"><parent link={quoteattr(host)}/>'
                             f'<child link={quoteattr(fname)}/><origin xyz="{_v(p - frame_at[body])}" '
                             f'rpy="{_rpy(Ra)}"/></joint>')
                lines.append(f"  <link name={quoteattr(fname)}/>")
            closed.append([fa, fb])
            types.append("6d" if t == "fixed" else "3d")
    lines.append("</robot>")
    task = {"body": model.body_names[model.task_body],
            "point": [float(x) for x in model.p0[model.task_body] + model.R0[model.task_body] @ model.task_point],
            "position": [model.task_names[i] for i in range(model.nt) if model.task_kind[i] == 0],
            "orientation": [int(model.task_names[i][5:]) for i in range(model.nt) if model.task_kind[i] == 1],
            "euler_sequence": model.euler_sequence,
            **({"joints": list(tree_task_joints(model))} if model.task_joints else {})}
    sidecar = {"gravity_m_s2": [float(x) for x in model.gravity], "closed_loop": closed, "type": types,
               "name_mot": [model.joint_names[j] for j in model.act_joint], "task": task}
    drives = _drives(model)
    if drives:
        sidecar["actuators"] = drives
    # URDF's joint position is the coordinate less its reference value: the sidecar keeps that value
    refs = {model.joint_names[k]: float(model.coord_offset[int(model.joint_q0[k])]) for k in range(len(model.joint_names))
            if not model.joint_cut[k] and model.joint_nq[k] == 1 and model.coord_offset[int(model.joint_q0[k])] != 0.0}
    if refs:
        sidecar["reference"] = refs
    stiff = {model.joint_names[j]: float(model.joint_stiffness[j]["drive"]) for j in model.act_joint
             if (model.joint_stiffness[j] or {}).get("drive")}
    if stiff:  # URDF has no place for it: the sidecar keeps it (joint side, N/m or N m/rad)
        sidecar["drive_stiffness"] = stiff
    for k, f in enumerate(model.joint_friction):
        if f and any(f.get(x) for x in ("coefficient", "external")):
            notes.append(f"joint {model.joint_names[k]}: load-dependent friction not written")
    if len(model.load_body):
        notes.append("loads ([[loads]]) not written (URDF has none)")
    springs = [model.joint_names[k] for k, sp in enumerate(model.joint_spring) if sp is not None]
    if springs:
        notes.append(f"joint springs not written (URDF has none): {', '.join(springs)}")
    return "\n".join(lines) + "\n", sidecar, notes
