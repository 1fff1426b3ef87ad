"""MJCF (MuJoCo) files read by MuJoCo's own compiler, as a :class:`~pkmdyn.multibody.formats.graph.Graph`.

The reference configuration is the model's ``qpos0`` (or a keyframe's ``qpos``); every
quantity is read from the compiled model after ``mj_kinematics`` there, so that MuJoCo's
defaults, classes, frames and inertia from geoms are resolved as MuJoCo resolves them:

* bodies: ``body_mass``, the centre of mass ``xipos`` and the inertia
  ``ximat diag(body_inertia) ximat^T``; a body without joints is fixed to its parent;
* joints: ``hinge`` and ``slide`` at ``xanchor`` along ``xaxis`` with their coordinate
  ``qpos`` (the description's reference value, so that its coordinates are MuJoCo's
  ``qpos``), ``range`` where limited, ``damping``, ``frictionloss``, ``armature``, and
  ``stiffness`` with ``springref`` as the joint's spring; ``ball``
  (its ``range`` not kept, said);
  several joints of one body are a chain through massless links; a ``ball`` joint's damping
  and dry friction are its viscous and Coulomb friction; a ``free`` joint whose body an
  active equality joins to a body outside its subtree hangs the body from that equality (a
  spherical or fixed tree joint), a floating one is refused or, with ``weld_free``, welded;
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
from .graph import Actuator, Closure, Frame, Graph, Joint, Link, TaskChoice, safe_name
from .mjcf_out import DRIVE_STIFFNESS, TASK_TEXT
from .prescan import prescan_mjcf


def _mujoco():
    try:
        import mujoco
    except ImportError as exc:  # pragma: no cover - the extra is in the test dependencies
        raise ParameterError("reading MJCF needs MuJoCo, in the import extra: pip install 'pkmdyn[import]' (from a "
                             "source checkout: pip install '.[import]')") from exc
    return mujoco


def _refusals(src: str, problems: list[str]) -> str:
    """One line naming every refusal of the file (at most :data:`MAX_LISTED`, the rest counted)."""
    more = f"; and {len(problems) - MAX_LISTED} more" if len(problems) > MAX_LISTED else ""
    return f"{src}: {len(problems)} refusal{'s' if len(problems) > 1 else ''}: " + "; ".join(problems[:MAX_LISTED]) + more


def _compiled(mujoco, path: Path, src: str, notes: list[str], problems: list[str]):
    """MuJoCo's model of the file. Where mesh files are missing (a model published without its
    assets), the geoms that use them are left out of MuJoCo's specification and it compiles
    without them, said in a note, where each such body gives its inertia explicitly
    (``<inertial>``: the geoms decide nothing then); a body whose inertia those meshes would
    give is refused by name."""
    try:
        return mujoco.MjModel.from_xml_path(str(path))
    except Exception as exc:  # MuJoCo's own message names the element and line
        why = f"{src}: MuJoCo cannot read it: {' '.join(str(exc).split())[:300]}"
    try:
        spec = mujoco.MjSpec.from_file(str(path))
    except Exception:
        raise ParameterError(why) from None
    folder = path.parent / (spec.meshdir or "")
    missing = {mesh.name: mesh for mesh in spec.meshes if mesh.file and not (folder / mesh.file).is_file()}
    tex_folder = path.parent / (spec.texturedir or "")
    # a texture's image, or a cube's or skybox's six (``fileright`` ...): those missing
    textures = [(t, absent) for t in spec.textures
                if (absent := [f for f in (t.file, *t.cubefiles) if f and not (tex_folder / f).is_file()])]
    if not missing and not textures:
        raise ParameterError(why)
    gone = {t.name for t, _ in textures if t.name}
    for mat in spec.materials:  # a texture only colours: its material keeps its colour without it
        mat.textures = ["" if name in gone else name for name in mat.textures]
    for t, _ in textures:
        spec.delete(t)
    # with inertiafromgeom="true" MuJoCo takes every body's inertia from its geoms, <inertial> or not
    from_geoms = int(spec.compiler.inertiafromgeom) == int(mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_TRUE)
    hint = ' and drop inertiafromgeom="true"' if from_geoms else ""
    left = []
    for body in spec.bodies:
        for g in list(body.geoms):
            if int(g.type) == int(mujoco.mjtGeom.mjGEOM_MESH) and g.meshname in missing:
                if body.name != "world" and (from_geoms or not body.explicitinertial):
                    problems.append(f"body {body.name}: its inertia would come from mesh {g.meshname}, whose file "
                                    f"{missing[g.meshname].file} is missing (give the body an <inertial>{hint}, "
                                    "or the file)")
                spec.delete(g)  # (a refused body's too: the file's other refusals are still listed)
                left.append(body.name)
    for mesh in missing.values():
        spec.delete(mesh)
    try:
        m = spec.compile()
    except Exception:  # a refused body left without mass: the refusals say why
        if problems:
            raise ParameterError(_refusals(src, problems)) from None
        raise ParameterError(why) from None
    files = sorted({mesh.file for mesh in missing.values()})
    if files:
        notes.append(f"mesh files missing ({', '.join(files[:5])}{' ...' if len(files) > 5 else ''}): their geoms "
                     f"left out of bodies {', '.join(sorted(set(left))[:8])}, whose inertia the file gives explicitly"
                     " (the world's geoms carry none)")
    if textures:
        tex = sorted({f for _, absent in textures for f in absent})
        notes.append(f"texture files missing ({', '.join(tex[:5])}{' ...' if len(tex) > 5 else ''}): left out "
                     "(a texture only colours the geoms)")
    return m


#: the loop closure's residual at which --assemble stops, relative to the model's size, and its
#: most Newton steps
ASSEMBLE_TOL = 1e-12
ASSEMBLE_STEPS = 100


def _assemble(mujoco, m, d, src: str) -> list[str]:
    """Close the active equality constraints from ``d.qpos`` by Gauss-Newton steps of least
    change (the minimum-norm step ``dq = -J^+ r`` on MuJoCo's own equality rows and Jacobian,
    integrated on the configuration manifold), to :data:`ASSEMBLE_TOL`; refused where they do not
    close. Returns the note saying how far the file's configuration was from closing."""
    m.opt.jacobian = mujoco.mjtJacobian.mjJAC_DENSE
    eq = int(mujoco.mjtConstraint.mjCNSTR_EQUALITY)
    tol = ASSEMBLE_TOL * max(1.0, float(m.stat.extent))  # the model's size: metres or millimetres alike
    first = None
    for _ in range(ASSEMBLE_STEPS + 1):
        mujoco.mj_forward(m, d)
        rows = np.flatnonzero(d.efc_type[:d.nefc] == eq)
        if rows.size == 0:
            return []
        r = d.efc_pos[:d.nefc][rows]
        gap = float(np.abs(r).max())
        first = gap if first is None else first
        if gap <= tol:
            return [f"reference configuration: the loops closed from the file's configuration (--assemble; they "
                    f"were {first:.3g} m or rad open)"] if first > tol else []
        J = np.asarray(d.efc_J[:d.nefc * m.nv]).reshape(d.nefc, m.nv)[rows]
        dq = -np.linalg.lstsq(J, r, rcond=None)[0]
        mujoco.mj_integratePos(m, d.qpos, dq, 1.0)
    raise ParameterError(f"{src}: --assemble: the loops do not close from the file's configuration (still "
                         f"{gap:.3g} m or rad open after {ASSEMBLE_STEPS} steps)")


def _custom(mujoco, m, problems: list[str]) -> tuple[TaskChoice | None, dict[str, float]]:
    """What pkmdyn's own export keeps in ``<custom>`` (:mod:`pkmdyn.multibody.formats.mjcf_out`): the
    task (a ``text``) and each drive's stiffness by joint name (``numeric`` entries)."""
    task = None
    stiff: dict[str, float] = {}
    for i in range(m.ntext):
        if mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_TEXT, i) != TASK_TEXT:
            continue
        adr, size = int(m.text_adr[i]), int(m.text_size[i])
        text = bytes(m.text_data[adr:adr + size]).split(b"\0", 1)[0].decode("utf-8", "replace")
        fields = dict(part.partition("=")[::2] for part in text.split(";") if "=" in part)
        try:
            task = TaskChoice(body=safe_name(fields["body"], "body"), point=fields.get("point") or None,
                              position=tuple(c for c in fields.get("position", "").split(",") if c),
                              orientation=tuple(int(c) for c in fields.get("orientation", "").split(",") if c),
                              sequence=fields.get("sequence") or None,
                              joints=tuple(c for c in fields.get("joints", "").split(",") if c) or None)
        except (KeyError, ValueError):
            problems.append(f"custom text {TASK_TEXT}: {text[:80]!r} is not body=...;position=...;orientation=...")
    for i in range(m.nnumeric):
        name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_NUMERIC, i) or ""
        if not name.startswith(DRIVE_STIFFNESS):
            continue
        adr, size = int(m.numeric_adr[i]), int(m.numeric_size[i])
        v = float(m.numeric_data[adr]) if size >= 1 else float("nan")
        if not (np.isfinite(v) and v > 0):
            problems.append(f"custom numeric {name}: a drive stiffness must be a finite number > 0")
            continue
        stiff[safe_name(name[len(DRIVE_STIFFNESS):], "joint")] = v
    return task, stiff


def _held_free_bodies(mujoco, m) -> dict[int, int]:
    """Each body with a free joint that an active connect or weld joins directly to a body on the
    world's own tree (inside no free body's subtree; a platform closed by the loops): the first
    such equality. Free bodies held only by one another are floating."""
    parent = [int(v) for v in m.body_parentid]

    def inside(b: int, root: int) -> bool:
        while b > 0:
            if b == root:
                return True
            b = parent[b]
        return False

    def body_of(e: int, k: int) -> int:
        i = int(m.eq_obj1id[e] if k == 0 else m.eq_obj2id[e])
        return int(m.site_bodyid[i]) if int(m.eq_objtype[e]) == int(mujoco.mjtObj.mjOBJ_SITE) else i

    kinds = (int(mujoco.mjtEq.mjEQ_CONNECT), int(mujoco.mjtEq.mjEQ_WELD))
    free = [int(m.jnt_bodyid[j]) for j in range(m.njnt) if int(m.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_FREE)]

    def grounded(b: int) -> bool:  # on the world's tree, inside no free body's subtree
        return not any(inside(b, f) for f in free)

    out: dict[int, int] = {}
    for b in free:
        for e in range(m.neq):
            if int(m.eq_type[e]) not in kinds or not m.eq_active0[e]:
                continue
            a, c = body_of(e, 0), body_of(e, 1)
            if (a == b and grounded(c)) or (c == b and grounded(a)):
                out[b] = e
                break
    return out


def name_of(mujoco, m, obj, i: int, kind: str) -> str:
    """A MuJoCo element's name as a description name (``<kind>_<i>`` for an unnamed one)."""
    return safe_name(mujoco.mj_id2name(m, obj, i) or "", f"{kind}_{i}")


#: at most this many refusals of one file are listed (the rest counted)
MAX_LISTED = 12


def mjcf_graph(path: str | Path, keyframe: str | None = None, weld_free: bool = False,
               assemble: bool = False) -> Graph:
    """The mechanism of an MJCF file (module docstring). MuJoCo's warnings are taken as notes
    (its default handler would append them to ``MUJOCO_LOG.TXT`` in the working folder); every
    element without an equivalent is named in one refusal. ``weld_free``: a free joint whose
    body no loop closure holds is welded to the ground at its reference pose; ``assemble``: the
    loops closed from the file's configuration (``qpos0`` or the keyframe) first (:func:`_assemble`)."""
    mujoco = _mujoco()
    heard: list[str] = []
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(lambda msg: heard.append(" ".join(str(msg).split())[:200]))
    try:
        return _graph(mujoco, Path(path), keyframe, weld_free, heard, assemble)
    finally:
        mujoco.set_mju_user_warning(previous)


def _graph(mujoco, path: Path, keyframe: str | None, weld_free: bool, heard: list[str],
           assemble: bool = False) -> Graph:
    src = path.name
    problems: list[str] = []
    notes: list[str] = []
    prescan_mjcf(path, src)  # bounded before MuJoCo reads it: FIFOs, replicates, includes
    m = _compiled(mujoco, path, src, notes, problems)
    # the equalities' residuals are read from MuJoCo's constraint rows: computed even where disabled
    m.opt.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_EQUALITY)
    for t in range(m.ntendon):
        if m.tendon_stiffness[t] or m.tendon_damping[t] or m.tendon_limited[t]:
            problems.append(f"tendon {name_of(mujoco, m, mujoco.mjtObj.mjOBJ_TENDON, t, 'tendon')}: a tendon's spring, "
                            "damping or limit has no equivalent in a description")
    d = mujoco.MjData(m)
    if keyframe is None:
        d.qpos[:] = m.qpos0
    else:
        k = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_KEY, keyframe)
        if k < 0:
            raise ParameterError(f"{src}: keyframe {keyframe!r}: no keyframe of that name")
        d.qpos[:] = m.key_qpos[k]
    mujoco.mj_forward(m, d)  # the poses, and the equality constraints' residuals (efc_pos)
    if assemble:
        notes.extend(_assemble(mujoco, m, d, src))

    def name(obj, i: int, kind: str) -> str:
        return name_of(mujoco, m, obj, i, kind)

    # a body called ground (pkmdyn's exports hang the tree from one) is not the world itself
    bname = [GROUND] + [nm if nm != GROUND else "ground_body"
                        for nm in (name(mujoco.mjtObj.mjOBJ_BODY, b, "body") for b in range(1, m.nbody))]
    links = []
    for b in range(1, m.nbody):
        if hasattr(m, "body_gravcomp") and m.body_gravcomp[b]:
            problems.append(f"body {bname[b]}: gravity compensation (gravcomp) has no equivalent")
        R = d.ximat[b].reshape(3, 3)
        links.append(Link(bname[b], float(m.body_mass[b]), d.xipos[b].copy(), R @ np.diag(m.body_inertia[b]) @ R.T))
    joints: list[Joint] = []
    notes += [f"MuJoCo: {w}" for w in dict.fromkeys(heard)]
    jname = [name(mujoco.mjtObj.mjOBJ_JOINT, j, "joint") for j in range(m.njnt)]
    held = _held_free_bodies(mujoco, m)
    task, drive_k = _custom(mujoco, m, problems)
    free_by: dict[int, int] = {}  # a free body held by a loop -> the equality that becomes its tree joint
    for b in range(1, m.nbody):
        ids = [j for j in range(m.njnt) if m.jnt_bodyid[j] == b]
        parent = bname[int(m.body_parentid[b])]
        if not ids:
            joints.append(Joint(f"{bname[b]}_weld", "fixed", parent, bname[b], d.xpos[b].copy(), np.array([0, 0, 1.0])))
            continue
        for n, j in enumerate(ids):
            t = int(m.jnt_type[j])
            if t == mujoco.mjtJoint.mjJNT_FREE:
                if b in held:  # a platform closed by the loops: one of them becomes its tree joint
                    free_by[b] = held[b]
                    notes.append(f"joint {jname[j]}: a free joint whose body the loops hold; body {bname[b]} hangs from "
                                 f"equality {name(mujoco.mjtObj.mjOBJ_EQUALITY, held[b], 'equality')} instead")
                elif weld_free:
                    joints.append(Joint(f"{bname[b]}_weld", "fixed", GROUND, bname[b], d.xpos[b].copy(),
                                        np.array([0, 0, 1.0])))
                    notes.append(f"joint {jname[j]}: a free joint, welded to the ground at its reference pose "
                                 "(--weld-free)")
                else:
                    problems.append(f"joint {jname[j]}: a free joint whose body no loop closure holds (a floating "
                                    "base); pkmdyn describes mechanisms on the ground: weld it at its reference pose "
                                    "with --weld-free")
                break
            kind = {int(mujoco.mjtJoint.mjJNT_HINGE): "hinge", int(mujoco.mjtJoint.mjJNT_SLIDE): "slide",
                    int(mujoco.mjtJoint.mjJNT_BALL): "ball"}[t]
            child = bname[b] if n == len(ids) - 1 else f"{bname[b]}__{n + 1}"
            if n < len(ids) - 1:  # an intermediate massless link between two joints of one body
                links.append(Link(child, 0.0, d.xpos[b].copy(), np.zeros((3, 3))))
            dof = int(m.jnt_dofadr[j])
            spring = None
            if m.jnt_stiffness[j]:
                if kind == "ball":
                    problems.append(f"joint {jname[j]}: a ball joint's spring (stiffness {m.jnt_stiffness[j]:g}) has "
                                    "no equivalent in a description (a spring takes one coordinate)")
                else:  # MuJoCo's passive force -k (qpos - qpos_spring): the description's spring
                    spring = (float(m.jnt_stiffness[j]), float(m.qpos_spring[m.jnt_qposadr[j]]))
            lim = (float(m.jnt_range[j, 0]), float(m.jnt_range[j, 1])) if m.jnt_limited[j] and kind != "ball" else None
            st = drive_k.pop(jname[j], None)
            joints.append(Joint(
                jname[j], kind, parent, child, d.xanchor[j].copy(), d.xaxis[j].copy(),
                value=float(d.qpos[m.jnt_qposadr[j]]) if kind != "ball" else 0.0, limits=lim,
                damping=float(m.dof_damping[dof]), frictionloss=float(m.dof_frictionloss[dof]),
                armature=float(m.dof_armature[dof]),
                stiffness=None if st is None else {("drive_Nm_rad" if kind == "hinge" else "drive_N_m"): st},
                spring=spring))
            if kind == "ball" and m.jnt_limited[j]:
                notes.append(f"joint {jname[j]}: a ball joint's range is not kept (a spherical joint has no limits)")
            if kind == "ball" and m.dof_armature[dof]:
                problems.append(f"joint {jname[j]}: armature on a ball joint has no equivalent in a description")
            parent = child
    closures = []
    for e in range(m.neq):
        ename = name(mujoco.mjtObj.mjOBJ_EQUALITY, e, "equality")
        t = int(m.eq_type[e])
        kinds = {int(mujoco.mjtEq.mjEQ_CONNECT): "3d", int(mujoco.mjtEq.mjEQ_WELD): "6d"}
        if t not in kinds:
            tn = mujoco.mjtEq(t).name.removeprefix("mjEQ_").lower()
            problems.append(f"equality {ename}: a {tn} equality has no equivalent in a description "
                            "(only connect and weld close loops)")
            continue
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
        free = next((f for f, q in free_by.items() if q == e), None)
        if free is not None:  # the tree joint of a held free body: a ball (connect) or a weld
            other = l1 if l2 == bname[free] else l2
            if gap[0] > 1e-9 * max(1.0, float(np.linalg.norm(p2))) or gap[1] > 1e-9:
                apart = f"{gap[0]:.3g} m" + (f" and {gap[1]:.3g} rad" if kinds[t] == "6d" else "")
                problems.append(f"equality {ename}: holds the free body {bname[free]} but is {apart} apart at the "
                                "reference configuration (--assemble closes it)")
            joints.append(Joint(ename, "ball" if kinds[t] == "3d" else "fixed", other, bname[free], np.asarray(p2, float),
                                R2[:, 2].copy()))
            continue
        closures.append(Closure(ename, kinds[t], l1, l2, np.asarray(p2, float), np.asarray(p2, float), R2, R2, gap=gap))
    actuators = []
    for i in range(m.nu):
        aname = name(mujoco.mjtObj.mjOBJ_ACTUATOR, i, "actuator")
        if int(m.actuator_trntype[i]) != int(mujoco.mjtTrn.mjTRN_JOINT):
            problems.append(f"actuator {aname}: only actuators on a joint have an equivalent "
                            "(not tendons, sites or bodies)")
            continue
        g = m.actuator_gear[i]
        if np.any(g[1:] != 0):
            problems.append(f"actuator {aname}: a gear with more than one entry")
            continue
        if not (np.isfinite(g[0]) and abs(g[0]) >= 1e-12):
            problems.append(f"actuator {aname}: gear {g[0]:g} (a gear must be a finite number, not near 0)")
            continue
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
    for jn in drive_k:
        problems.append(f"custom numeric {DRIVE_STIFFNESS}{jn}: no joint {jn!r}")
    if problems:
        raise ParameterError(_refusals(src, problems))
    model_name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_MODEL, 0) if hasattr(mujoco.mjtObj, "mjOBJ_MODEL") else None
    if not model_name:  # the model's name heads MuJoCo's name buffer
        model_name = bytes(m.names).split(b"\0", 1)[0].decode("utf-8", "replace")
    model_name = safe_name(model_name, "") if model_name and model_name != "MuJoCo Model" else ""
    return Graph(name=model_name or path.stem, source=src, gravity=np.array(m.opt.gravity, dtype=float),
                 links=links, joints=joints, closures=closures, actuators=actuators, frames=frames, notes=notes,
                 task=task)
