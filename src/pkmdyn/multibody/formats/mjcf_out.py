"""Any described mechanism as a MuJoCo model (MJCF text).

The spanning tree becomes MuJoCo's kinematic tree; every cut joint that MuJoCo can express
becomes an equality constraint (MuJoCo closes loops softly, by its constraint solver):

* spherical cut joint: one ``connect`` at the joint centre (three translations);
* revolute cut joint: two ``connect`` at the joint centre and one axis length along the axis
  (six rows for the five constraints; one is redundant, which MuJoCo's solver tolerates);
* fixed cut joint: a ``weld``;
* prismatic, cylindrical, universal, planar cut joints: MuJoCo has no equality constraint for
  them; :func:`mechanism_mjcf` refuses such a mechanism naming the joint (cut another joint
  with ``[mechanism] cut_joints`` to export it).

Bodies: each body's frame is the description's body frame (its pose at the reference
configuration relative to its tree parent), with its mass, centre of mass and full inertia.
Each tree coordinate is a ``hinge`` or ``slide`` joint (named ``<joint>`` for one-coordinate
joints, ``<joint>_<k>`` otherwise) at the joint centre along its elementary-motion axis in the
body frame (a joint traversed from its child: reversed order, negated axes); MuJoCo applies a
body's joints in order, each axis turned by the previous ones, which is the product of
elementary motions of :mod:`pkmdyn.multibody.description.joint_types`, with its reference value
as the joint's ``ref`` (the value at which the body sits where the file places it). ``qpos`` is
therefore the tree coordinate vector ``q`` itself (a leg length stays a leg length through an
export and an import), ``qvel = qd``, ``qacc = qdd``, each in MuJoCo's joint order
(:func:`mujoco_order`); a limited revolute or prismatic joint is ``limited`` with its limits as
``range``.
Actuated joints get a ``motor`` (control = effort [N or N m]); a joint with a drive
(``[[actuators]]``) a motor named after the drive with ``gear`` = its transmission ratio k
(control = motor effort [N m]), its rotor as the joint's ``armature`` (``k^2 I_r``) and its
motor friction as ``damping`` (``k^2 b``) and ``frictionloss`` (``k C``, MuJoCo's dry friction,
not the regularised law). The task point is a site (:data:`TASK_SITE`) on the task body, and
what MJCF has no element for is a ``<custom>`` entry that ``pkmdyn import`` reads back: the task
coordinates (a ``text``) and each drive's stiffness (a ``numeric``). Not exported: joint
friction, loads, sections (MuJoCo has no load-dependent joint friction).

**Loop constraints.** MuJoCo closes loops softly; its defaults (``solref`` 0.02 s, ``solimp``
0.9 to 0.95) let a Stewart platform's accelerations under pkmdyn's efforts differ by several
hundred percent from the rigid mechanism's. The equalities are therefore written stiff
(:data:`SOLREF`, :data:`SOLIMP`: time constant 0.5 ms, critical damping, impedance 0.9999),
with ``refsafe`` off so that MuJoCo keeps a time constant below two time steps; both are
arguments of :func:`mechanism_mjcf` and options of ``pkmdyn export``. A body without mass is
refused, naming it (MuJoCo needs a mass on every moving body; pkmdyn does not silently add one),
unless a mass is given for it (``massless_kg``, ``pkmdyn export --massless-mass-kg``), said in a
comment of the file and on stderr.

"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ...errors import ParameterError
from ..description.joint_types import JOINT_TYPES
from ..model.compiler import MechanismModel, tree_task_joints

__all__ = ["mechanism_mjcf", "mujoco_qpos", "mujoco_order", "coordinate_names", "SOLREF", "SOLIMP", "TASK_SITE",
           "TASK_TEXT", "DRIVE_STIFFNESS"]

#: the equality constraints' ``solref`` (time constant [s], damping ratio): stiff (module docstring)
SOLREF = (0.0005, 1.0)
#: the equality constraints' ``solimp`` (d0, d_width, width [m], midpoint, power)
SOLIMP = (0.9999, 0.9999, 0.001, 0.5, 2.0)

Array = NDArray[np.float64]


def _v(a: Array) -> str:
    return " ".join(f"{float(x):.17g}" for x in np.ravel(a))


def _quat(R: Array) -> Array:
    """Unit quaternion (w, x, y, z) of a rotation matrix."""
    from scipy.spatial.transform import Rotation

    x, y, z, w = Rotation.from_matrix(R).as_quat()
    return np.array([w, x, y, z])


def coordinate_names(model: MechanismModel) -> list[str]:
    """MuJoCo joint name of every tree coordinate (order of ``q``)."""
    names = []
    for c, j in enumerate(model.coord_joint):
        k = c - int(model.joint_q0[j])
        names.append(model.joint_names[j] if model.joint_nq[j] == 1 else f"{model.joint_names[j]}_{k + 1}")
    return names


def mujoco_order(model: MechanismModel, mj_model) -> Array:
    """``idx (nq,)``: MuJoCo's ``qpos``/``qvel`` address of every tree coordinate (MuJoCo orders
    its joints depth first, the model in the order the tree reached its bodies)."""
    return np.array([int(mj_model.joint(nm).qposadr[0]) for nm in coordinate_names(model)], dtype=np.int64)


def mujoco_qpos(model: MechanismModel, q: Array, mj_model) -> Array:
    """MuJoCo ``qpos (nq,)`` of tree coordinates ``q (nq,)``: ``q`` itself (each joint's ``ref`` is
    its reference value) in MuJoCo's order (rates and accelerations: the same permutation,
    :func:`mujoco_order`)."""
    out = np.empty(model.nq)
    out[mujoco_order(model, mj_model)] = np.asarray(q, dtype=float)
    return out


def _coordinate_attrs(model: MechanismModel, j: int, c: int) -> str:
    """A tree joint coordinate's MJCF ``ref`` (its reference value) with ``limited`` and ``range``:
    the description's limits of a one-coordinate joint (``limits_m``, ``limits_rad``), unlimited
    otherwise. (A cut joint is an equality constraint in MuJoCo, with no place for its limits.)"""
    ref = f'ref="{float(model.coord_offset[c]):.17g}" '
    lim = model.joint_limits[j]
    if lim is None or int(model.joint_nq[j]) != 1:
        return ref + 'limited="false"'
    return ref + f'limited="true" range="{lim[0]:.17g} {lim[1]:.17g}"'


def massless_bodies(model: MechanismModel) -> list[str]:
    """The moving bodies without mass (MuJoCo needs one)."""
    return [model.body_names[b] for b in range(model.nb) if float(model.mass[b]) <= 0.0]


#: the site of the task point in an export, and the custom entries that carry what MJCF has no
#: element for (the task coordinates, the drives' stiffness): read back by ``pkmdyn import``
TASK_SITE = "pkmdyn_task_point"
TASK_TEXT = "pkmdyn_task"
DRIVE_STIFFNESS = "pkmdyn_drive_stiffness_"


def _custom(model: MechanismModel) -> list[str]:
    """``<custom>``: the task (``body=...;point=<site>;position=x,y;orientation=1,3;sequence=XYZ``,
    then ``;joints=a,b`` for a task with joint coordinates) and each actuated joint's drive
    stiffness (joint side, N/m or N m/rad)."""
    inv = {int(v): k for k, v in enumerate(model.euler_perm)}
    pos = ",".join("xyz"[int(i)] for kind, i in zip(model.task_kind, model.task_index) if kind == 0)
    ori = ",".join(str(inv[int(i)] + 1) for kind, i in zip(model.task_kind, model.task_index) if kind == 1)
    task = (f"body={model.body_names[model.task_body]};point={TASK_SITE};position={pos};orientation={ori};"
            f"sequence={model.euler_sequence}")
    if model.task_joints:
        task += f";joints={','.join(tree_task_joints(model))}"
    out = ["  <custom>", f'    <text name="{TASK_TEXT}" data="{task}"/>']
    for j in model.act_joint:
        st = model.joint_stiffness[j] or {}
        if st.get("drive"):
            out.append(f'    <numeric name="{DRIVE_STIFFNESS}{model.joint_names[j]}" data="{float(st["drive"]):.17g}"/>')
    return out + ["  </custom>"]


def mechanism_mjcf(model: MechanismModel, timestep: float = 1e-3, solref: tuple[float, float] = SOLREF,
                   solimp: tuple[float, ...] = SOLIMP, massless_kg: float | None = None) -> str:
    """The MJCF document of ``model`` (module docstring): the equality constraints with
    ``solref`` and ``solimp`` (MuJoCo's meaning). A body without mass is refused unless
    ``massless_kg`` [kg] is given: it then gets that mass, said in a comment of the file."""
    if len(solref) != 2 or not all(np.isfinite(solref)) or solref[0] <= 0 or solref[1] <= 0:
        raise ParameterError(f"solref {solref}: two positive numbers (time constant [s], damping ratio)")
    if len(solimp) != 5 or not all(np.isfinite(solimp)) or not (0 < solimp[0] < 1 and 0 < solimp[1] < 1) \
            or solimp[2] <= 0:
        raise ParameterError(f"solimp {solimp}: five numbers, the first two in (0, 1), the width > 0")
    light = massless_bodies(model)
    if light and massless_kg is None:
        raise ParameterError(f"[bodies] {light[0]}: no mass; MuJoCo needs a mass on every moving body "
                             "(give it one, fix it to a neighbour, or export with --massless-mass-kg)")
    if massless_kg is not None and not (np.isfinite(massless_kg) and massless_kg > 0):
        raise ParameterError(f"massless_kg {massless_kg}: a positive mass [kg]")
    for j in model.loop_joint:
        t = JOINT_TYPES[model.joint_type[j]].name
        if t not in ("spherical", "revolute", "fixed"):
            raise ParameterError(f"[joints] {model.joint_names[j]}: a cut {t} joint cannot be written as a MuJoCo "
                                 "equality constraint; cut another joint of its loop ([mechanism] cut_joints)")
    names = coordinate_names(model)
    children: dict[int, list[int]] = {}
    for b in range(model.nb):
        children.setdefault(int(model.body_parent[b]), []).append(b)
    lines = [f'<mujoco model="{model.name}">']
    if light:
        lines.append(f"  <!-- pkmdyn: bodies without mass given {massless_kg:g} kg (MuJoCo needs a mass): "
                     f"{', '.join(light)} -->")
    lines += [
             f'  <option timestep="{timestep:g}" gravity="{_v(model.gravity)}" integrator="RK4">',
             '    <flag refsafe="disable"/>', "  </option>",
             '  <compiler angle="radian" autolimits="true"/>',
             "  <default>", f'    <equality solref="{_v(solref)}" solimp="{_v(solimp)}"/>', "  </default>",
             "  <worldbody>"]

    # a drive on the joint (multibody.dynamics.actuators): its rotor reflected as armature k^2 I_r, its
    # motor's viscous friction as damping k^2 b and Coulomb friction as frictionloss k C
    drive_attrs: dict[int, str] = {}
    for i, j in enumerate(model.act_joint):
        if not model.drive_name or model.drive_name[i] is None:
            continue
        k = float(model.drive_ratio[i])
        parts = [("armature", k * k * float(model.drive_rotor[i])), ("damping", k * k * float(model.drive_viscous[i])),
                 ("frictionloss", k * float(model.drive_coulomb[i]))]
        drive_attrs[int(model.joint_q0[j])] = "".join(f' {key}="{v:.17g}"' for key, v in parts if v)

    def body(b: int, depth: int) -> None:
        ind = "  " * depth
        par = int(model.body_parent[b])
        Rp, pp = (np.eye(3), np.zeros(3)) if par < 0 else (model.R0[par], model.p0[par])
        pos = Rp.T @ (model.p0[b] - pp)
        quat = _quat(Rp.T @ model.R0[b])
        lines.append(f'{ind}<body name="{model.body_names[b]}" pos="{_v(pos)}" quat="{_v(quat)}">')
        I = model.inertia[b]
        mass = float(model.mass[b]) if float(model.mass[b]) > 0.0 else float(massless_kg)
        full = [I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]]
        lines.append(f'{ind}  <inertial pos="{_v(model.com[b])}" mass="{mass:.17g}" fullinertia="{_v(full)}"/>')
        if b == model.task_body:  # the task point, read back by pkmdyn import (TASK_SITE)
            lines.append(f'{ind}  <site name="{TASK_SITE}" pos="{_v(model.task_point)}"/>')
        k = int(model.body_joint[b])
        Rc, pc = model.tree_R_child[k], model.tree_p_child[k]
        for c in range(int(model.joint_q0[k]), int(model.joint_q0[k] + model.joint_nq[k])):
            mcode = int(model.coord_motion[c])
            axis = model.coord_sign[c] * Rc[:, mcode % 3]
            kind = "hinge" if mcode < 3 else "slide"
            sp = model.joint_spring[k] if model.joint_spring and model.joint_nq[k] == 1 else None
            spring = f' stiffness="{sp[0]:.17g}" springref="{sp[1]:.17g}"' if sp is not None else ""
            lines.append(f'{ind}  <joint name="{names[c]}" type="{kind}" pos="{_v(pc)}" axis="{_v(axis)}" '
                         f'{_coordinate_attrs(model, k, c)}{drive_attrs.get(c, "")}{spring}/>')
        for ch in children.get(b, []):
            body(ch, depth + 1)
        lines.append(f"{ind}</body>")

    for b in children.get(-1, []):
        body(b, 2)
    lines.append("  </worldbody>")
    eq = []
    for j in model.loop_joint:
        t = JOINT_TYPES[model.joint_type[j]].name
        a, c = int(model.joint_parent[j]), int(model.joint_child[j])
        if a < 0:  # MuJoCo's body1 must be a body; anchor in body1's frame
            a, c = c, a
            Ra, pa = model.joint_R_child[j], model.joint_p_child[j]
        else:
            Ra, pa = model.joint_R_parent[j], model.joint_p_parent[j]
        b1 = model.body_names[a]
        b2 = "world" if c < 0 else model.body_names[c]
        nm = model.joint_names[j]
        if t == "fixed":
            eq.append(f'    <weld name="{nm}" body1="{b1}" body2="{b2}"/>')
            continue
        eq.append(f'    <connect name="{nm}" body1="{b1}" body2="{b2}" anchor="{_v(pa)}"/>')
        if t == "revolute":
            eq.append(f'    <connect name="{nm}_axis" body1="{b1}" body2="{b2}" '
                      f'anchor="{_v(pa + Ra[:, 2] * model.length_scale)}"/>')
    if eq:
        lines += ["  <equality>", *eq, "  </equality>"]
    acts = []
    for i, j in enumerate(model.act_joint):
        name = model.drive_name[i] if model.drive_name and model.drive_name[i] is not None else model.joint_names[j]
        gear = float(model.drive_ratio[i]) if len(model.drive_ratio) else 1.0
        acts.append(f'    <motor name="{name}" joint="{names[int(model.joint_q0[j])]}" gear="{gear:.17g}"/>')
    lines += ["  <actuator>", *acts, "  </actuator>", *_custom(model), "</mujoco>"]
    return "\n".join(lines) + "\n"
