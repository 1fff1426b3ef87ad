"""MJCF (MuJoCo) files read by MuJoCo's own compiler, as a :class:`~pkmdyn.multibody.formats.graph.Graph`.

The reference configuration is the model's ``qpos0`` (or a keyframe's ``qpos``); every
quantity is read from the compiled model after ``mj_kinematics`` there, so that MuJoCo's
defaults, classes, frames and inertia from geoms are resolved as MuJoCo resolves them:

* bodies: ``body_mass``, the centre of mass ``xipos`` and the inertia
  ``ximat diag(body_inertia) ximat^T``; a body without joints is fixed to its parent;
* joints: ``hinge`` and ``slide`` at ``xanchor`` along ``xaxis`` with their coordinate
  ``qpos`` (the description's reference value, so that its coordinates are MuJoCo's
  ``qpos``), ``range`` where limited, ``damping``, ``frictionloss`` and ``armature``; ``ball``
  (its ``range`` not kept, said);
  several joints of one body are a chain through massless links; a ``free`` joint is refused;
* equality constraints: ``connect`` (3D closure) and ``weld`` (6D closure), between bodies
  or sites; ``joint``, ``tendon``, ``flex`` and ``distance`` equalities are refused by name,
  an inactive one (``active="false"``) is left out and said so in the notes;
* actuators with a joint transmission and their ``gear`` (a servo's gain, bias or dynamics,
  and ``ctrlrange``/``forcerange``, are not kept: said in the notes); other transmissions, and
  tendons with a spring, damping or limit, are refused;
* sites: task points (``--task-point SITE``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...errors import ParameterError
from ..description.schema import GROUND
from .graph import Actuator, Closure, Frame, Graph, Joint, Link, safe_name


def _mujoco():
    try:
        import mujoco
    except ImportError as exc:  # pragma: no cover - the extra is in the test dependencies
        raise ParameterError("reading MJCF needs MuJoCo, in the import extra: pip install 'pkmdyn[import]' (from a "
                             "source checkout: pip install '.[import]')") from exc
    return mujoco


def name_of(mujoco, m, obj, i: int, kind: str) -> str:
    """A MuJoCo element's name as a description name (``<kind>_<i>`` for an unnamed one)."""
    return safe_name(mujoco.mj_id2name(m, obj, i) or "", f"{kind}_{i}")


def mjcf_graph(path: str | Path, keyframe: str | None = None) -> Graph:
    """The mechanism of an MJCF file (module docstring)."""
    mujoco = _mujoco()
    src = Path(path).name
    try:
        m = mujoco.MjModel.from_xml_path(str(path))
    except Exception as exc:  # MuJoCo's own message names the element and line
        raise ParameterError(f"{src}: MuJoCo cannot read it: {' '.join(str(exc).split())[:300]}") from None
    # the equalities' residuals are read from MuJoCo's constraint rows: computed even where disabled
    m.opt.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_EQUALITY)
    for t in range(m.ntendon):
        if m.tendon_stiffness[t] or m.tendon_damping[t] or m.tendon_limited[t]:
            raise ParameterError(f"{src}: tendon {name_of(mujoco, m, mujoco.mjtObj.mjOBJ_TENDON, t, 'tendon')}: "
                                 "a tendon's spring, damping or limit has no equivalent in a description")
    d = mujoco.MjData(m)
    if keyframe is None:
        d.qpos[:] = m.qpos0
    else:
        k = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_KEY, keyframe)
        if k < 0:
            raise ParameterError(f"{src}: keyframe {keyframe!r}: no keyframe of that name")
        d.qpos[:] = m.key_qpos[k]
    mujoco.mj_forward(m, d)  # the poses, and the equality constraints' residuals (efc_pos)

    def name(obj, i: int, kind: str) -> str:
        return name_of(mujoco, m, obj, i, kind)

    # a body called ground (pkmdyn's exports hang the tree from one) is not the world itself
    bname = [GROUND] + [nm if nm != GROUND else "ground_body"
                        for nm in (name(mujoco.mjtObj.mjOBJ_BODY, b, "body") for b in range(1, m.nbody))]
    links = []
    for b in range(1, m.nbody):
        if hasattr(m, "body_gravcomp") and m.body_gravcomp[b]:
            raise ParameterError(f"{src}: body {bname[b]}: gravity compensation (gravcomp) has no equivalent")
        R = d.ximat[b].reshape(3, 3)
        links.append(Link(bname[b], float(m.body_mass[b]), d.xipos[b].copy(), R @ np.diag(m.body_inertia[b]) @ R.T))
    joints: list[Joint] = []
    notes: list[str] = []
    jname = [name(mujoco.mjtObj.mjOBJ_JOINT, j, "joint") for j in range(m.njnt)]
    for b in range(1, m.nbody):
        ids = [j for j in range(m.njnt) if m.jnt_bodyid[j] == b]
        parent = bname[int(m.body_parentid[b])]
        if not ids:
            joints.append(Joint(f"{bname[b]}_weld", "fixed", parent, bname[b], d.xpos[b].copy(), np.array([0, 0, 1.0])))
            continue
        for n, j in enumerate(ids):
            t = int(m.jnt_type[j])
            if t == mujoco.mjtJoint.mjJNT_FREE:
                raise ParameterError(f"{src}: joint {jname[j]}: a free joint; pkmdyn describes mechanisms whose "
                                     "base is the ground (remove it, or weld the body)")
            kind = {int(mujoco.mjtJoint.mjJNT_HINGE): "hinge", int(mujoco.mjtJoint.mjJNT_SLIDE): "slide",
                    int(mujoco.mjtJoint.mjJNT_BALL): "ball"}[t]
            child = bname[b] if n == len(ids) - 1 else f"{bname[b]}__{n + 1}"
            if n < len(ids) - 1:  # an intermediate massless link between two joints of one body
                links.append(Link(child, 0.0, d.xpos[b].copy(), np.zeros((3, 3))))
            dof = int(m.jnt_dofadr[j])
            if m.jnt_stiffness[j]:
                raise ParameterError(f"{src}: joint {jname[j]}: a joint spring (stiffness {m.jnt_stiffness[j]:g}) has no "
                                     "equivalent in a description's dynamics")
            lim = (float(m.jnt_range[j, 0]), float(m.jnt_range[j, 1])) if m.jnt_limited[j] and kind != "ball" else None
            joints.append(Joint(
                jname[j], kind, parent, child, d.xanchor[j].copy(), d.xaxis[j].copy(),
                value=float(d.qpos[m.jnt_qposadr[j]]) if kind != "ball" else 0.0, limits=lim,
                damping=float(m.dof_damping[dof]), frictionloss=float(m.dof_frictionloss[dof]),
                armature=float(m.dof_armature[dof])))
            if kind == "ball" and m.jnt_limited[j]:
                notes.append(f"joint {jname[j]}: a ball joint's range is not kept (a spherical joint has no limits)")
            if kind == "ball" and (m.dof_damping[dof] or m.dof_frictionloss[dof] or m.dof_armature[dof]):
                raise ParameterError(f"{src}: joint {jname[j]}: damping, frictionloss or armature on a ball joint has "
                                     "no equivalent in a description")
            parent = child
    closures = []
    for e in range(m.neq):
        ename = name(mujoco.mjtObj.mjOBJ_EQUALITY, e, "equality")
        t = int(m.eq_type[e])
        kinds = {int(mujoco.mjtEq.mjEQ_CONNECT): "3d", int(mujoco.mjtEq.mjEQ_WELD): "6d"}
        if t not in kinds:
            tn = mujoco.mjtEq(t).name.removeprefix("mjEQ_").lower()
            raise ParameterError(f"{src}: equality {ename}: a {tn} equality has no equivalent in a description "
                                 "(only connect and weld close loops)")
        if not m.eq_active0[e]:
            notes.append(f"equality {ename} is inactive in the file and left out")
            continue
        a, b2 = int(m.eq_obj1id[e]), int(m.eq_obj2id[e])
        data = m.eq_data[e]
        rows = (d.efc_id[:d.nefc] == e) & (d.efc_type[:d.nefc] == int(mujoco.mjtConstraint.mjCNSTR_EQUALITY))
        res = d.efc_pos[:d.nefc][rows]
        gap = (float(np.linalg.norm(res[:3])), float(np.linalg.norm(res[3:6])) if t != int(mujoco.mjtEq.mjEQ_CONNECT) else 0.0)
        if int(m.eq_objtype[e]) == int(mujoco.mjtObj.mjOBJ_SITE):
            l1, l2 = bname[int(m.site_bodyid[a])], bname[int(m.site_bodyid[b2])]
            p2, R2 = d.site_xpos[b2].copy(), d.site_xmat[b2].reshape(3, 3).copy()
        else:
            l1, l2 = bname[a], bname[b2]
            R2 = d.xmat[b2].reshape(3, 3).copy()
            # connect: body2's anchor (data[3:6]); weld: its anchor in body2 (data[0:3])
            p2 = d.xpos[b2] + R2 @ (data[3:6] if t == int(mujoco.mjtEq.mjEQ_CONNECT) else data[0:3])
        closures.append(Closure(ename, kinds[t], l1, l2, np.asarray(p2, float), np.asarray(p2, float), R2, R2, gap=gap))
    actuators = []
    for i in range(m.nu):
        aname = name(mujoco.mjtObj.mjOBJ_ACTUATOR, i, "actuator")
        if int(m.actuator_trntype[i]) != int(mujoco.mjtTrn.mjTRN_JOINT):
            raise ParameterError(f"{src}: actuator {aname}: only actuators on a joint have an equivalent "
                                 "(not tendons, sites or bodies)")
        g = m.actuator_gear[i]
        if np.any(g[1:] != 0):
            raise ParameterError(f"{src}: actuator {aname}: a gear with more than one entry")
        plain = (int(m.actuator_dyntype[i]) == int(mujoco.mjtDyn.mjDYN_NONE)
                 and int(m.actuator_gaintype[i]) == int(mujoco.mjtGain.mjGAIN_FIXED) and m.actuator_gainprm[i, 0] == 1.0
                 and int(m.actuator_biastype[i]) == int(mujoco.mjtBias.mjBIAS_NONE))
        if not plain:
            notes.append(f"actuator {aname}: not a plain motor (gain, bias or dynamics): pkmdyn's effort is the force "
                         "it must apply, not its control")
        if m.actuator_ctrllimited[i] or m.actuator_forcelimited[i]:
            notes.append(f"actuator {aname}: its ctrlrange and forcerange are not kept")
        actuators.append(Actuator(aname, jname[int(m.actuator_trnid[i, 0])], float(g[0])))
    frames = [Frame(name(mujoco.mjtObj.mjOBJ_SITE, s, "site"), bname[int(m.site_bodyid[s])], d.site_xpos[s].copy())
              for s in range(m.nsite)]
    frames += [Frame(bname[b], bname[b], d.xpos[b].copy()) for b in range(1, m.nbody)]
    model_name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_MODEL, 0) if hasattr(mujoco.mjtObj, "mjOBJ_MODEL") else None
    return Graph(name=model_name or Path(path).stem, source=src, gravity=np.array(m.opt.gravity, dtype=float),
                 links=links, joints=joints, closures=closures, actuators=actuators, frames=frames, notes=notes)
