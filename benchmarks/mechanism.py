"""Speed and agreement of the generic kinematics of described mechanisms.

Runs in one process: the generic kinematics (every body, joint point, actuator rate and
Jacobian; ``pkmdyn.multibody.solve_kinematics``) of the built-in 6-UPS Stewart platform on a
smooth random motion, with its leg lengths, rates and accelerations compared with the
closed-form vector-loop solution (``tests/oracles/stewart.py``); the same for the Delta robot;
and the hip simulator's generic kinematics (its parameters turned into a description,
``hip_simulator/description.py``) beside its closed form (Eq. 1-6), timed and compared (slider
positions, rates, accelerations; every lever's centre motion and angular motion). Prints one JSON object;
with ``--json`` nothing else is printed.

    python benchmarks/mechanism.py --json [--samples 4000]

The PDM likewise (``pdm4/description.py``; every one of its 14 bodies' pose, velocity and
acceleration on the Eq. 84 motion).

Direct kinematics (``pkmdyn.multibody.kinematics.direct``) of the Stewart platform, the hip, the Delta and
the PDM: batched along a motion, the task motion alone (``bodies=False``, what ``pkmdyn run
--actuator-motion`` and identification from a measured log take: ``<machine>_dk_batched_us_per_sample``)
and with every body's coordinates (``<machine>_dk_batched_with_bodies_us_per_sample``), and one
sample at a time as a controller calls it (``direct_one``, warm-started), with the round trips
through the inverse kinematics (of each batched route); and the
Stewart platform's closed loop with exact encoders (``pkmdyn.simulate.track``, computed torque,
the pose from the encoders by the direct kinematics) beside MuJoCo simulating the exported
platform (``mj_step`` at 1 ms, actuator PD plus pkmdyn's feedforward) for the same seconds,
best of three each: ``stewart_exact_encoder_loop_over_mujoco`` times the whole pkmdyn run (its
reference's batched preparation included) against MuJoCo's loop alone;
``..._loop_alone_over_mujoco_loop`` the loops alone; ``..._loop_over_mujoco_with_preparation``
each with its reference's preparation (MuJoCo's kinematics and feedforward along its 1 ms
steps, by pkmdyn's batched verbs). The pkmdyn loop runs its cycles in one compiled call
(``pkmdyn.simulate._cycles``, compiled first: ``stewart_loop_kernel_compile_or_load_s``);
``..._python_cycles_...`` fields time the same run with its cycles in Python.

Single-state forward dynamics of the Stewart platform and the Delta beside two peers, in this
process on the same 2000 consecutive states of a 1 kHz loop and the same efforts, CPU time:
pkmdyn's compiled kernel, Pinocchio's exact closed-loop ``constraintDynamics`` (the URDF export
and its loop sidecar: the spanning tree, rigid 3D constraints at the cut joints) and MuJoCo's
``mj_forward`` on the exported MJCF (soft loop equalities), with the accelerations' agreement
in pkmdyn's tree coordinates (``<machine>_fd_*``, :func:`_forward_peers`). Only these:

    python benchmarks/mechanism.py --json --part fd
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from pkmdyn.multibody import load_mechanism, newton_only, reference_task, solve_kinematics

from _timing import best_time, best_times

ROOT = Path(__file__).resolve().parents[1]
MACHINES = ROOT / "src" / "pkmdyn" / "machines"


def _motion(x0: np.ndarray, amp: np.ndarray, n: int, seed: int = 0):
    """x0 + amp (sin(w t + ph) - sin ph) over 10 s, with exact rates and accelerations."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 10.0, n)
    w = rng.uniform(1.0, 3.0, x0.size)
    ph = rng.uniform(0, 2 * np.pi, x0.size)
    s, c = np.sin(w * t[:, None] + ph), np.cos(w * t[:, None] + ph)
    return t, x0 + amp * (s - np.sin(ph)), amp * w * c, -amp * w**2 * s


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a - b).max() / max(np.abs(b).max(), 1e-300))


def _dynamics(out: dict, n: int, repeat: int, m, hip, mh, pm) -> None:
    """Inverse dynamics, reactions and forward dynamics (issue 16), beside the closed forms and
    MuJoCo in this process."""
    from oracles import hip as hip_oracle  # the closed form of Eq. 1-16 beside the tests
    from pkmdyn.machines.hip_simulator import model_from_dict
    from pkmdyn.machines.hip_simulator.description import hip_description
    from pkmdyn.machines.hip_simulator.params import default_params_dict
    from pkmdyn.machines.pdm4 import inverse_kinematics as pdm_kinematics
    from pkmdyn.machines.pdm4.description import pdm_description
    from pkmdyn.machines.pdm4.paper import JOINTS
    from pkmdyn.multibody import load_mechanism
    from pkmdyn.multibody.dynamics.newton_euler import inverse_dynamics, joint_reactions
    from pkmdyn.multibody.dynamics.verbs import machine_verbs
    from pkmdyn.profiles.iso14242 import iso14242_motion
    from pkmdyn.profiles.pdm_motion import cycloidal_motion

    # hip, every friction family on (Table 2's S, U, slider and screw friction, Eq. 16 under the
    # ISO load): the generic efforts with friction (inverse_dynamics) against the closed form
    from pkmdyn.multibody.dynamics.friction import coulomb_viscous

    d = default_params_dict()
    for key, v in (("slider_coulomb_N", 5.0), ("slider_viscous_Ns_m", 20.0), ("screw_coulomb_Nm", 0.02),
                   ("screw_viscous_Nms_rad", 1e-4), ("spherical_coulomb_Nm", 0.1),
                   ("spherical_viscous_Nms_rad", 0.01), ("universal_coulomb_Nm", 0.1),
                   ("universal_viscous_Nms_rad", 0.01)):
        d["friction"][key] = v
    d["inertia"]["platform_mass_kg"] = 2.0
    hf = model_from_dict(d, "every friction family")
    motion = iso14242_motion(cycles=n / 1000.0, samples_per_cycle=1000)
    ref = hip_oracle.kinematics(hf, motion.angles, motion.rates, motion.accels)
    mf = load_mechanism(hip_description(hf))
    kin = solve_kinematics(mf, motion.angles, motion.rates, motion.accels, motion.t)
    named = {"hydraulic_N": motion.load}
    sec = best_time(lambda: hip_oracle.inverse_dynamics(hf, ref, motion.load), repeat)
    out["hip_id_closed_form_us_per_sample"] = sec / len(motion.t) * 1e6
    sec = best_time(lambda: inverse_dynamics(mf, kin, named=named), repeat)
    out["hip_id_generic_us_per_sample"] = sec / len(motion.t) * 1e6
    sec = best_time(lambda: inverse_dynamics(mf, kin, named=named, friction=False), repeat)
    out["hip_id_generic_without_friction_us_per_sample"] = sec / len(motion.t) * 1e6
    out["hip_id_generic_over_closed_form"] = out["hip_id_generic_us_per_sample"] / out["hip_id_closed_form_us_per_sample"]
    tau = hip_oracle.inverse_dynamics(hf, ref, motion.load).tau
    u = inverse_dynamics(mf, kin, named=named).u
    gear = hf.geometry.p / (2 * np.pi)
    sl = [mf.actuator_names.index(f"P_{i + 1}") for i in range(3)]
    f = hf.friction
    motor = (gear * u[:, sl] + hf.inertia.I_L * kin.act_qdd[:, sl] / gear
             + coulomb_viscous(kin.act_qd[:, sl] / gear, f.screw_coulomb, f.screw_viscous, f.eps_w, vector=False))
    out["hip_id_max_rel_diff"] = _rel(motor, tau)
    # hip single-sample forward dynamics: the engine's verb, and its compiled kernel as the plant
    # integrator calls it on consecutive ISO samples (1 kHz)
    Vh = machine_verbs(mf)
    kk = [0]
    k50 = slice(0, 50)
    uh = Vh.inverse_dynamics(mf, motion.angles[k50], motion.rates[k50], motion.accels[k50], motion.load[k50])

    def hip_verb() -> None:
        i = kk[0] % 50
        kk[0] += 1
        Vh.forward_dynamics_one(mf, motion.angles[i], motion.rates[i], uh[i], float(motion.load[i]))

    out["hip_fd_generic_single_verb_us"] = best_time(lambda: [hip_verb() for _ in range(200)], repeat) / 200 * 1e6
    pg, _, fg = Vh.one_sample_kernels(mf)
    mo = iso14242_motion(cycles=2.0, samples_per_cycle=1000)
    ug = Vh.inverse_dynamics(mf, mo.angles, mo.rates, mo.accels, mo.load)
    acc = np.empty(3)
    Vh.forward_dynamics_one(mf, mo.angles[0], mo.rates[0], ug[0], float(mo.load[0]))

    def kernel(f, p, u) -> None:
        for i in range(len(mo.t)):
            if f(p, mo.angles[i], mo.rates[i], u[i], float(mo.load[i]), acc):
                Vh.forward_dynamics_one(mf, mo.angles[i], mo.rates[i], u[i], float(mo.load[i]))

    out["hip_fd_generic_single_us"] = best_time(lambda: kernel(fg, pg, ug), repeat) / len(mo.t) * 1e6

    # PDM: efforts and all 19 joint wrenches (nine redundants by compliance) through its description,
    # against the hand-derived Newton-Euler oracle beside the tests (tests/oracles)
    try:
        from oracles.pdm_newton_euler import inverse_dynamics as pdm_closed_form
    except ImportError:
        pdm_closed_form = None
    mp = load_mechanism(pdm_description(pm))
    tr = pm.trajectory
    pmo = cycloidal_motion(tr.strokes, tr.period_s, min(n, 1000))
    out["pdm_id_max_rel_diff"] = None
    if pdm_closed_form is not None:
        R = pdm_closed_form(pm, pdm_kinematics(pm, pmo))
        r = joint_reactions(mp, solve_kinematics(mp, pmo.q, pmo.qd, pmo.qdd, pmo.t))
        limbs = [mp.actuator_names.index(nm) for nm in ("P11", "P12", "P23", "P24")]
        diffs = [_rel(r.u[:, limbs], R.force)]
        for j, (name, _, body_a, _) in enumerate(JOINTS):
            k = mp.joint_index(name)
            sg = 1.0 if (mp.body_names[mp.joint_parent[k]] if mp.joint_parent[k] >= 0 else "ground") == body_a else -1.0
            Mref = R.joint_moment[:, j] + np.cross(R.joint_point[:, j] - r.joint_point[:, k], R.joint_force[:, j])
            diffs += [float(np.abs(sg * r.joint_force[:, k] - R.joint_force[:, j]).max() / np.abs(R.joint_force).max()),
                      float(np.abs(sg * r.joint_moment[:, k] - Mref).max() / np.abs(R.joint_moment).max())]
        out["pdm_id_max_rel_diff"] = max(diffs)

    # Stewart: efforts and every joint reaction; single-sample forward dynamics beside MuJoCo's
    ns = min(n, 1000)
    t, x, xd, xdd = _motion(reference_task(m), np.array([0.05, 0.05, 0.05, 0.1, 0.1, 0.1]), ns, seed=2)
    ks = solve_kinematics(m, x, xd, xdd, t)
    sec = best_time(lambda: joint_reactions(m, ks), repeat)
    out["stewart_id_reactions_us_per_sample"] = sec / ns * 1e6
    V = machine_verbs(m)
    u = V.inverse_dynamics(m, x[:50], xd[:50], xdd[:50])
    a = V.forward_dynamics(m, x[:50], xd[:50], u)
    out["stewart_forward_of_inverse_max_rel_diff"] = _rel(a, xdd[:50])
    k = [0]

    def one() -> None:
        i = k[0] % 50
        k[0] += 1
        V.forward_dynamics_one(m, x[i], xd[i], u[i])

    sec = best_time(lambda: [one() for _ in range(200)], repeat)
    out["stewart_fd_single_verb_us"] = sec / 200 * 1e6


#: the forward-dynamics comparison's states: the first 2000 samples of ``_motion`` over 10 s
#: sampled every 1 ms (consecutive states of a 1 kHz loop), amplitude and seed per machine
FD_STATES = 2000
FD_MOTION = {"stewart": ([0.05, 0.05, 0.05, 0.1, 0.1, 0.1], 2), "delta": ([0.15, 0.15, 0.1], 1)}
#: Pinocchio's proximal settings for ``constraintDynamics``: absolute and relative accuracy,
#: proximal parameter mu, iterations at most (converged in 3 on both machines; a state that
#: reaches the limit is reported)
PIN_PROXIMAL = (1e-12, 1e-12, 1e-8, 100)


def pinocchio_closed_loop(m):
    """Pinocchio model of the described mechanism ``m`` from its URDF export and loop sidecar
    (``pkmdyn.multibody.formats.urdf_out.mechanism_urdf``, what ``pkmdyn export --format urdf``
    writes): Pinocchio's URDF parser builds the spanning tree (gravity from the sidecar), and
    each of the sidecar's frame pairs becomes a ``RigidConstraintModel`` (``3d``: CONTACT_3D,
    ``6d``: CONTACT_6D) between the two frames' joints at the frames' placements. Returns
    ``(model, constraints, frame_pairs, cmap, act_v)``: ``frame_pairs`` the pairs' frame ids
    and kinds; ``cmap`` for every tree coordinate of ``m``, (pkmdyn coordinate, Pinocchio q
    index, its nq, v index), the URDF joint position being ``q - coord_offset`` (a continuous
    joint's (cos, sin)); ``act_v`` the actuated joints' v indices (order of ``name_mot``, the
    description's actuators)."""
    import pinocchio as pin

    from pkmdyn.multibody.formats.urdf_out import mechanism_urdf

    text, side, _ = mechanism_urdf(m)
    model = pin.buildModelFromXML(text)
    model.gravity.linear = np.array(side["gravity_m_s2"], dtype=float)
    # Pinocchio's own vectors: a Python list is converted (copied) at every call, twice the time
    cms, pairs = pin.StdVec_RigidConstraintModel(), []
    for (fa, fb), kind in zip(side["closed_loop"], side["type"]):
        ia, ib = model.getFrameId(fa), model.getFrameId(fb)
        A, B = model.frames[ia], model.frames[ib]
        ct = pin.ContactType.CONTACT_3D if kind == "3d" else pin.ContactType.CONTACT_6D
        cms.append(pin.RigidConstraintModel(ct, model, A.parentJoint, A.placement, B.parentJoint, B.placement,
                                            pin.ReferenceFrame.LOCAL))
        pairs.append((ia, ib, kind))
    cmap = []
    for k, jn in enumerate(m.joint_names):
        nq = 0 if m.joint_cut[k] else int(m.joint_nq[k])
        for i in range(nq):
            jid = model.getJointId(jn if nq == 1 else f"{jn}_{i + 1}")
            cmap.append((int(m.joint_q0[k]) + i, int(model.idx_qs[jid]), int(model.nqs[jid]), int(model.idx_vs[jid])))
    act_v = [int(model.idx_vs[model.getJointId(nm)]) for nm in side["name_mot"]]
    return model, cms, pairs, cmap, act_v


def _pinocchio_state(m, model, cmap, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pinocchio's configuration and velocity of pkmdyn's tree coordinates ``q``, rates ``qd``."""
    import pinocchio as pin

    qp, vp = pin.neutral(model), np.zeros(model.nv)
    for c, iq, nq, iv in cmap:
        a = q[c] - m.coord_offset[c]
        if nq == 2:  # a continuous joint
            qp[iq], qp[iq + 1] = np.cos(a), np.sin(a)
        else:
            qp[iq] = a
        vp[iv] = qd[c]
    return qp, vp


def _forward_peers(out: dict, repeat: int, machines: dict) -> None:
    """Single-state forward dynamics of each machine: pkmdyn's compiled kernel (as the plant
    integrator and the controllers call it, no input checks), Pinocchio's exact closed-loop
    ``constraintDynamics`` (tree + rigid loop constraints, :func:`pinocchio_closed_loop`) and
    MuJoCo's ``mj_forward`` on the exported MJCF (soft loop equalities), in this process on
    the same 2000 consecutive states of a 1 kHz loop and the same efforts (pkmdyn's inverse
    dynamics of the motion), CPU time, best of ``repeat`` rounds that run the three in turn
    (``_timing.best_times``); the accelerations compared in pkmdyn's tree coordinates
    (pkmdyn's task accelerations mapped by its kinematics).

    Neither machine has drives (rotor inertia) or joint friction: the three engines solve the
    same rigid-body problem. pkmdyn holds idle freedoms (the Delta's six rod spins) by its
    rule ``n_k . (q - q_ref) = 0`` (``dynamics.idle_holding``), Pinocchio and MuJoCo let them
    spin freely: for the Delta the held case is also solved by Pinocchio
    (``pinocchio.forwardDynamics``: its mass matrix, bias forces and the loops' frame
    Jacobians and drifts, with the holding rows added), not timed."""
    from pkmdyn.multibody.dynamics.newton_euler import fr_any
    from pkmdyn.multibody.dynamics.verbs import machine_verbs

    try:
        import pinocchio as pin
    except ImportError:  # pragma: no cover - Pinocchio is optional (the validate extra)
        pin = None
    try:
        import mujoco

        from pkmdyn.multibody.formats.mjcf_out import mechanism_mjcf, mujoco_order, mujoco_qpos
    except ImportError:  # pragma: no cover - MuJoCo is optional
        mujoco = None
    for name, m in machines.items():
        if m.has_drives or fr_any(m):
            raise ValueError(f"{name}: drives or joint friction; the peers' models here are rigid bodies alone")
        V = machine_verbs(m)
        amp, seed = FD_MOTION[name]
        t1, x1, xd1, xdd1 = _motion(reference_task(m), np.array(amp), 10001, seed=seed)
        t1, x1, xd1, xdd1 = (a[:FD_STATES].copy() for a in (t1, x1, xd1, xdd1))
        n1 = len(x1)
        u1 = V.inverse_dynamics(m, x1, xd1, xdd1)
        kin = solve_kinematics(m, x1, xd1, xdd1, t1)  # the tree states every engine is given
        # pkmdyn: the compiled kernel on consecutive states (every 2000th call jumps back 2 s)
        p, _, forward = V.one_sample_kernels(m)
        acc = np.empty(m.nt)
        a1 = np.empty_like(x1)
        for i in range(n1):
            if forward(p, x1[i], xd1[i], u1[i], 0.0, acc):
                acc[:] = V.forward_dynamics_one(m, x1[i], xd1[i], u1[i])
            a1[i] = acc
        out[f"{name}_fd_single_max_rel_diff"] = _rel(a1, xdd1)  # forward(inverse) = identity

        def kernel() -> None:
            for i in range(n1):
                if forward(p, x1[i], xd1[i], u1[i], 0.0, acc):
                    V.forward_dynamics_one(m, x1[i], xd1[i], u1[i])

        runs = {"pkmdyn": kernel}
        tree = solve_kinematics(m, x1, xd1, a1, t1).qdd  # pkmdyn's accelerations in its tree coordinates
        act = m.act_coord
        if pin is not None:
            model, cms, pairs, cmap, act_v = pinocchio_closed_loop(m)
            data = model.createData()
            cds = pin.StdVec_RigidConstraintData()
            for c in cms:
                cds.append(c.createData())
            pin.initConstraintDynamics(model, data, cms, cds)
            prox = pin.ProximalSettings(*PIN_PROXIMAL)
            cidx = np.array([c for c, *_ in cmap])
            vidx = np.array([iv for *_, iv in cmap])
            qp = np.empty((n1, model.nq))
            vp = np.empty((n1, model.nv))
            tau = np.zeros((n1, model.nv))
            tau[:, act_v] = u1 * m.drive_ratio
            gap = 0.0
            for i in range(n1):
                qp[i], vp[i] = _pinocchio_state(m, model, cmap, kin.q[i], kin.qd[i])
                pin.framesForwardKinematics(model, data, qp[i])
                gap = max(gap, max(float(np.linalg.norm(data.oMf[a].translation - data.oMf[b].translation))
                                   for a, b, _ in pairs))
            out[f"{name}_fd_pinocchio_loop_gap_m"] = gap  # the loops closed at the given states
            ap = np.empty((n1, m.nq))
            iters = 0
            for i in range(n1):
                ddq = pin.constraintDynamics(model, data, qp[i], vp[i], tau[i], cms, cds, prox)
                ap[i, cidx] = ddq[vidx]
                iters = max(iters, prox.iter)
            out[f"{name}_fd_pinocchio_proximal_iterations"] = iters  # PIN_PROXIMAL's limit: not converged

            def pinocchio() -> None:
                for i in range(n1):
                    pin.constraintDynamics(model, data, qp[i], vp[i], tau[i], cms, cds, prox)

            runs["pinocchio"] = pinocchio
            out[f"{name}_fd_pinocchio_agreement"] = _rel(tree, ap)
            out[f"{name}_fd_pinocchio_actuated_agreement"] = _rel(tree[:, act], ap[:, act])
            if m.solver_idle.shape[0]:  # the idle freedoms held as pkmdyn holds them (docstring)
                W = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
                H = np.zeros((m.solver_idle.shape[0], model.nv))
                H[:, vidx] = np.asarray(m.solver_idle, dtype=float)[:, cidx]
                ah = np.empty((n1, m.nq))
                dh = model.createData()  # forwardDynamics resizes its data's multipliers
                for i in range(n1):
                    pin.computeJointJacobians(model, dh, qp[i])
                    pin.forwardKinematics(model, dh, qp[i], vp[i], np.zeros(model.nv))
                    pin.updateFramePlacements(model, dh)
                    rows, drift = [H], [np.zeros(len(H))]
                    for a, b, kind in pairs:
                        k = 3 if kind == "3d" else 6
                        Jab = pin.getFrameJacobian(model, dh, a, W) - pin.getFrameJacobian(model, dh, b, W)
                        rows.append(Jab[:k])
                        ca = pin.getFrameClassicalAcceleration(model, dh, a, W)
                        cb = pin.getFrameClassicalAcceleration(model, dh, b, W)
                        drift.append((ca - cb).vector[:k] if k == 6 else ca.linear - cb.linear)
                    ddq = pin.forwardDynamics(model, dh, qp[i], vp[i], tau[i], np.vstack(rows), np.concatenate(drift))
                    ah[i, cidx] = ddq[vidx]
                out[f"{name}_fd_pinocchio_idle_held_agreement"] = _rel(tree, ah)
        if mujoco is not None:
            mm = mujoco.MjModel.from_xml_string(mechanism_mjcf(m))
            md = mujoco.MjData(mm)
            o = mujoco_order(m, mm)
            qpos = np.array([mujoco_qpos(m, kin.q[i], mm) for i in range(n1)])
            qvel = np.zeros((n1, mm.nv))
            qvel[:, o] = kin.qd
            ctrl = np.ascontiguousarray(u1)
            am = np.empty((n1, m.nq))
            for i in range(n1):
                md.qpos[:], md.qvel[:], md.ctrl[:] = qpos[i], qvel[i], ctrl[i]
                mujoco.mj_forward(mm, md)
                am[i] = md.qacc[o]

            def mj() -> None:  # the inputs set, as a caller does, then mj_forward
                for i in range(n1):
                    md.qpos[:], md.qvel[:], md.ctrl[:] = qpos[i], qvel[i], ctrl[i]
                    mujoco.mj_forward(mm, md)

            runs["mujoco"] = mj
            out[f"{name}_fd_mujoco_soft_agreement"] = _rel(tree, am)  # soft loops: approximate
            out[f"{name}_fd_mujoco_soft_actuated_agreement"] = _rel(tree[:, act], am[:, act])
            if pin is not None:
                out[f"{name}_fd_mujoco_soft_vs_pinocchio_actuated_agreement"] = _rel(am[:, act], ap[:, act])
            if name == "stewart":  # the earlier figure: mj_forward alone, the first state repeated
                def mj_one_state() -> None:
                    md.qpos[:], md.qvel[:], md.ctrl[:] = qpos[0], qvel[0], ctrl[0]
                    for _ in range(n1):
                        mujoco.mj_forward(mm, md)

                runs["mujoco_one_state"] = mj_one_state
        best = best_times(runs, repeat)
        peers = {k: best[k] / n1 * 1e6 for k in ("pinocchio", "mujoco") if k in best}
        out[f"{name}_fd_pkmdyn_us"] = best["pkmdyn"] / n1 * 1e6
        if "mujoco_one_state" in best:
            out["mujoco_stewart_forward_us"] = best["mujoco_one_state"] / n1 * 1e6
        for peer in ("pinocchio", "mujoco"):
            out[f"{name}_fd_{peer}_us"] = peers.get(peer)
        out[f"{name}_fd_over_fastest_peer"] = (out[f"{name}_fd_pkmdyn_us"] / min(peers.values())
                                               if peers else None)
    if "stewart" in machines:  # the earlier keys
        out["stewart_fd_single_us"] = out["stewart_fd_pkmdyn_us"]
        mj = out.get("mujoco_stewart_forward_us")
        out["mujoco_stewart_forward_us"] = mj
        out["stewart_fd_over_mujoco"] = out["stewart_fd_single_us"] / mj if mj else float("inf")
        out["stewart_fd_over_mj_forward"] = out["stewart_fd_over_mujoco"]


def _direct(out: dict, n: int, repeat: int, machines: dict) -> None:
    """Direct kinematics: batched and single-sample timings, round trips (module docstring)."""
    from pkmdyn.multibody.kinematics.direct import direct_kinematics
    from pkmdyn.multibody.dynamics.verbs import machine_verbs

    for name, mech in machines.items():
        amp = np.where(mech.task_kind == 1, 0.05, 0.03 * mech.length_scale)
        t, x, xd, xdd = _motion(reference_task(mech), amp, n, seed=4)
        kin = solve_kinematics(mech, x, xd, xdd, t)
        q0 = kin.q[0]
        sc = np.where(mech.task_kind == 0, 1.0 / mech.length_scale, 1.0)
        act_sc = np.where(mech.coord_motion[mech.act_coord] >= 3, 1.0 / mech.length_scale, 1.0)
        for label, bodies in (("", False), ("_with_bodies", True)):
            def batched(bodies: bool = bodies):
                return direct_kinematics(mech, kin.act_q, kin.act_qd, kin.act_qdd, t, q_start=q0, bodies=bodies)

            sec = best_time(batched, repeat)
            out[f"{name}_dk_batched{label}_us_per_sample"] = sec / n * 1e6
            dk = batched()
            back = solve_kinematics(mech, dk.x, dk.xd, dk.xdd, t, q_start=q0)
            out[f"{name}_dk{label}_direct_of_inverse_max_err"] = float(np.abs((dk.x - x) * sc).max())
            out[f"{name}_dk{label}_inverse_of_direct_max_err"] = float(np.abs((back.act_q - kin.act_q) * act_sc).max())
        V = machine_verbs(mech)
        m1 = min(n, 2000)
        V.direct_one(mech, kin.act_q[0], kin.act_qd[0])

        def single() -> None:
            for i in range(m1):
                V.direct_one(mech, kin.act_q[i], kin.act_qd[i])

        sec = best_time(single, repeat)
        out[f"{name}_dk_single_us"] = sec / m1 * 1e6


def _stewart_loops(out: dict, m, seconds: float = 2.0) -> None:
    """The Stewart platform's closed loop with exact encoders beside MuJoCo's simulation of it."""
    import time

    from pkmdyn.jobs.control import described_control_settings
    from pkmdyn.control import gains, hermite_motion, loop_settings
    from pkmdyn.multibody import default_motion
    from pkmdyn.multibody.dynamics.verbs import machine_verbs
    from pkmdyn.simulate import track

    from dataclasses import replace

    from pkmdyn.simulate import _cycles
    from pkmdyn.simulate import _run

    settings = described_control_settings(m)
    settings["sensors"]["pose_feedback_from_sensor"] = 0  # the pose from the encoders, by the direct kinematics
    ls = loop_settings(settings)
    mo = default_motion(m, cycles=max(1.0, seconds / float(m.motion.period)))
    fn = hermite_motion(mo.t, mo.x, mo.xd, mo.xdd, None)
    V = machine_verbs(m)
    g = gains(settings, "computed-torque", m.nt)
    t0 = time.perf_counter()
    _cycles.compile_for_runs()  # the cycles in one compiled call (cached at install; else some 30 s, once)
    out["stewart_loop_kernel_compile_or_load_s"] = time.perf_counter() - t0
    real = _run.closed_loop
    loop_wall: list[float] = []

    def timed(*args, **kwargs):  # the closed loop alone, without the reference's preparation
        t = time.perf_counter()
        r = real(*args, **kwargs)
        loop_wall.append(time.perf_counter() - t)
        return r

    _run.closed_loop = timed
    try:
        for label, flag in (("_python_cycles", False), ("", True)):
            lsf = replace(ls, compiled_cycles=flag)
            track(V, m, m, fn, 0.1, "computed-torque", g, lsf, False)
            walls = []
            for _ in range(3):
                t0 = time.perf_counter()
                tr = track(V, m, m, fn, seconds, "computed-torque", g, lsf, False)
                walls.append((time.perf_counter() - t0, loop_wall[-1]))
            wall, alone = min(walls)
            out[f"stewart_exact_encoder_loop{label}_realtime_factor"] = seconds / wall
            out[f"stewart_exact_encoder_loop{label}_alone_realtime_factor"] = seconds / alone
    finally:
        _run.closed_loop = real
    ref = fn(tr.result.t)[0]
    out["stewart_exact_encoder_loop_max_error_mm"] = float(np.abs(tr.result.q - ref)[:, :3].max() * 1e3)
    try:
        import mujoco

        from pkmdyn.multibody.formats.mjcf_out import mechanism_mjcf, mujoco_order, mujoco_qpos
    except ImportError:  # pragma: no cover - MuJoCo is optional
        out["mujoco_stewart_loop_realtime_factor"] = None
        return
    mm = mujoco.MjModel.from_xml_string(mechanism_mjcf(m))
    md = mujoco.MjData(mm)
    T = mm.opt.timestep
    K = int(round(seconds / T))
    tt = np.arange(K) * T
    x, xd, xdd, _ = fn(tt)
    t0 = time.perf_counter()
    kin = solve_kinematics(m, x, xd, xdd, tt)
    ff = V.inverse_dynamics(m, x, xd, xdd)
    prep = time.perf_counter() - t0
    o = mujoco_order(m, mm)
    act = o[m.act_coord]
    s_ref = kin.act_q  # (the exported joints carry their reference values as ref: qpos = q)
    kp, kd = 2e4, 4e2  # [N/m, N s/m] on the legs
    walls = []
    for _ in range(3):  # the best of three, as pkmdyn's
        mujoco.mj_resetData(mm, md)
        md.qpos[:] = mujoco_qpos(m, kin.q[0], mm)
        md.qvel[o] = kin.qd[0]
        t0 = time.perf_counter()
        for k in range(K):
            md.ctrl[:] = ff[k] + kp * (s_ref[k] - md.qpos[act]) + kd * (kin.act_qd[k] - md.qvel[act])
            mujoco.mj_step(mm, md)
        walls.append(time.perf_counter() - t0)
    wall = min(walls)
    out["mujoco_stewart_loop_realtime_factor"] = seconds / wall
    out["mujoco_stewart_preparation_s"] = prep
    # the whole pkmdyn run (its reference's preparation included) against MuJoCo's loop alone
    out["stewart_exact_encoder_loop_over_mujoco"] = out["stewart_exact_encoder_loop_realtime_factor"] / out[
        "mujoco_stewart_loop_realtime_factor"]
    # like for like: each loop alone, or each with the preparation of its reference (MuJoCo's
    # kinematics and feedforward along the reference, by pkmdyn's batched verbs)
    out["stewart_exact_encoder_loop_alone_over_mujoco_loop"] = (
        out["stewart_exact_encoder_loop_alone_realtime_factor"] / out["mujoco_stewart_loop_realtime_factor"])
    out["stewart_exact_encoder_loop_over_mujoco_with_preparation"] = (
        out["stewart_exact_encoder_loop_realtime_factor"] * (wall + prep) / seconds)


def _hip_loops(out: dict, seconds: float = 2.0) -> None:
    """The hip's closed loop with exact encoders (computed torque, the default hip settings;
    ``benchmarks/control.py``, ``hip_project_loop``) beside MuJoCo's loop of the exported hip
    (``mujoco_part``), in this process."""
    import control as bc

    ex = bc.hip_project_loop(bc.load_params(), seconds, ("computed-torque-exact-encoders",))
    ex = ex["computed-torque-exact-encoders"]
    if "error" in ex:
        out["hip_exact_encoder_loop_error"] = ex["error"]
        return
    out["hip_exact_encoder_loop_realtime_factor"] = ex["realtime_factor"]
    out["hip_exact_encoder_loop_max_error_deg"] = ex["max_error_deg"]
    try:
        out["mujoco_hip_loop_realtime_factor"] = bc.mujoco_part(seconds)["realtime_factor"]
    except ImportError:  # pragma: no cover - MuJoCo is optional
        out["mujoco_hip_loop_realtime_factor"] = None
        return
    out["hip_exact_encoder_loop_over_mujoco"] = (out["hip_exact_encoder_loop_realtime_factor"]
                                                 / out["mujoco_hip_loop_realtime_factor"])


def _stiffness(out: dict, m, repeat: int, oracle) -> None:
    """The stiffness of the Stewart platform with its drives locked at 1,000 poses, batched
    (kinematics solved first, not timed), and its agreement with Gosselin's J^T diag(k) J from
    the closed-form oracle's Jacobian."""
    from pkmdyn.multibody.analyses.stiffness import stiffness

    rng = np.random.default_rng(7)
    x = reference_task(m) + rng.uniform(-1, 1, (1000, 6)) * np.array([0.08, 0.08, 0.08, 0.1, 0.1, 0.15])
    kin = solve_kinematics(m, x)
    stiffness(m, kin.rows(0, 2))  # the kernels compiled
    out["stiffness_1000_poses_s"] = best_time(lambda: stiffness(m, kin), repeat)
    if oracle is None:
        return
    st = stiffness(m, kin)
    a, b, _ = oracle.default_geometry()
    ref = oracle.inverse_kinematics(a, b, x[:, :3], x[:, 3:], "XYZ")
    E = np.stack([oracle.euler_kinematics(x[:, 3:], "XYZ", np.eye(3)[k][None].repeat(len(x), 0))["omega"]
                  for k in range(3)], axis=-1)
    J = np.concatenate([ref["J"][:, :, :3], np.einsum("nij,njk->nik", ref["J"][:, :, 3:], E)], axis=-1)
    legs = [m.actuator_names.index(f"P_{i + 1}") for i in range(6)]
    k = np.array([m.joint_stiffness[m.act_joint[a_]]["drive"] for a_ in legs])
    out["stiffness_gosselin_max_rel_diff"] = _rel(st.K_task, np.einsum("nat,a,nas->nts", J, k, J))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print only the JSON object")
    ap.add_argument("--samples", type=int, default=4000)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--part", choices=("all", "fd"), default="all",
                    help="fd: only the single-state forward dynamics beside Pinocchio and MuJoCo (Stewart, Delta)")
    args = ap.parse_args()
    if args.part == "fd":
        machines = {k: load_mechanism(MACHINES / k / f"{k}.toml") for k in ("stewart", "delta")}
        out = {"samples": FD_STATES}
        _forward_peers(out, args.repeat, machines)
        print(json.dumps(out, indent=None if args.json else 2))
        return
    sys.path.insert(0, str(ROOT / "tests"))
    try:
        from oracles import delta as delta_oracle
        from oracles import stewart as stewart_oracle
    except ImportError:  # the closed-form oracles live beside the tests; without them no agreement figures
        delta_oracle = stewart_oracle = None

    n = args.samples
    out: dict = {"samples": n}

    m = load_mechanism(MACHINES / "stewart" / "stewart.toml")
    t, x, xd, xdd = _motion(reference_task(m), np.array([0.05, 0.05, 0.05, 0.1, 0.1, 0.1]), n)
    sec = best_time(lambda: solve_kinematics(m, x, xd, xdd, t), args.repeat)
    kin = solve_kinematics(m, x, xd, xdd, t)
    out["stewart_kinematics_us_per_sample"] = sec / n * 1e6
    if stewart_oracle is not None:
        a, b, _ = stewart_oracle.default_geometry()
        ref = stewart_oracle.inverse_kinematics(a, b, x[:, :3], x[:, 3:], "XYZ", xd[:, :3], xd[:, 3:], xdd[:, :3],
                                                xdd[:, 3:])
        legs = [m.actuator_names.index(f"P_{i + 1}") for i in range(6)]
        out["stewart_max_rel_diff"] = max(_rel(kin.act_q[:, legs], ref["L"]), _rel(kin.act_qd[:, legs], ref["Ld"]),
                                          _rel(kin.act_qdd[:, legs], ref["Ldd"]))

    # the explicit legs (multibody/model/legs.py) against Newton on every block, same motion
    mn = newton_only(m)
    sec = best_time(lambda: solve_kinematics(mn, x, xd, xdd, t), args.repeat)
    out["stewart_kinematics_newton_us_per_sample"] = sec / n * 1e6
    kn = solve_kinematics(mn, x, xd, xdd, t)
    out["explicit_vs_newton_max_rel_diff"] = max(_rel(getattr(kin, k), getattr(kn, k)) for k in ("q", "qd", "qdd", "G"))

    md = load_mechanism(MACHINES / "delta" / "delta.toml")
    t, x, xd, xdd = _motion(reference_task(md), np.array([0.15, 0.15, 0.1]), n, seed=1)
    sec = best_time(lambda: solve_kinematics(md, x, xd, xdd, t), args.repeat)
    kin = solve_kinematics(md, x, xd, xdd, t)
    out["delta_kinematics_us_per_sample"] = sec / n * 1e6
    if delta_oracle is not None:
        g = delta_oracle.williams_irb360_geometry()
        ref = delta_oracle.kinematics(x, g["R_b"], g["R_p"], g["L_A"], g["L_B"], xd, xdd)
        legs = [md.actuator_names.index(f"R_{i + 1}") for i in range(3)]
        out["delta_max_rel_diff"] = max(_rel(kin.act_q[:, legs], ref["theta"]),
                                        _rel(kin.act_qd[:, legs], ref["thetad"]),
                                        _rel(kin.act_qdd[:, legs], ref["thetadd"]))

    from oracles import hip as hip_oracle  # the closed form of Eq. 1-6 beside the tests
    from pkmdyn.machines.hip_simulator import load_params
    from pkmdyn.machines.hip_simulator.description import hip_description
    from pkmdyn.profiles.iso14242 import iso14242_motion

    hip = load_params()
    motion = iso14242_motion(cycles=n / 1000.0, samples_per_cycle=1000)
    sec = best_time(lambda: hip_oracle.kinematics(hip, motion.angles, motion.rates, motion.accels), args.repeat)
    out["hip_kinematics_closed_form_us_per_sample"] = sec / len(motion.t) * 1e6
    mh = load_mechanism(hip_description(hip))
    sec = best_time(lambda: solve_kinematics(mh, motion.angles, motion.rates, motion.accels, motion.t), args.repeat)
    out["hip_kinematics_generic_us_per_sample"] = sec / len(motion.t) * 1e6
    ref = hip_oracle.kinematics(hip, motion.angles, motion.rates, motion.accels)
    kin = solve_kinematics(mh, motion.angles, motion.rates, motion.accels, motion.t)
    sl = [mh.actuator_names.index(f"P_{i + 1}") for i in range(3)]
    diffs = [_rel(kin.act_q[:, sl], ref.L[:, 1]), _rel(kin.act_qd[:, sl], ref.Ld[:, 1]),
             _rel(kin.act_qdd[:, sl], ref.Ldd[:, 1])]
    for i in range(3):
        for j, pname in enumerate(("upper", "lower")):
            b = mh.body_names.index(f"lever_{pname}_{i + 1}")
            diffs += [_rel(kin.p[:, b], ref.c_lever[:, j, i]), _rel(kin.v[:, b], ref.v_lever[:, i]),
                      _rel(kin.a[:, b], ref.a_lever[:, i]), _rel(kin.w[:, b], ref.omega_lever[:, i]),
                      _rel(kin.wd[:, b], ref.omega_lever_dot[:, i])]
    out["hip_max_rel_diff"] = max(diffs)
    out["hip_generic_over_closed_form"] = out["hip_kinematics_generic_us_per_sample"] / out[
        "hip_kinematics_closed_form_us_per_sample"]
    from pkmdyn.machines.pdm4 import BODY_NAMES
    from pkmdyn.machines.pdm4 import inverse_kinematics as pdm_kinematics
    from pkmdyn.machines.pdm4 import load_params as load_pdm
    from pkmdyn.machines.pdm4.description import pdm_description
    from pkmdyn.profiles.pdm_motion import cycloidal_motion

    pm = load_pdm()
    mp = load_mechanism(pdm_description(pm))
    tr = pm.trajectory
    motion = cycloidal_motion(tr.strokes, tr.period_s, n)
    sec = best_time(lambda: solve_kinematics(mp, motion.q, motion.qd, motion.qdd, motion.t), args.repeat)
    out["pdm_kinematics_generic_us_per_sample"] = sec / n * 1e6
    sec = best_time(lambda: pdm_kinematics(pm, motion), args.repeat)
    out["pdm_kinematics_closed_form_us_per_sample"] = sec / n * 1e6
    ref = pdm_kinematics(pm, motion)
    kin = solve_kinematics(mp, motion.q, motion.qd, motion.qdd, motion.t)
    diffs = []
    for b, name in enumerate(BODY_NAMES):
        k = mp.body_names.index(name)
        diffs += [_rel(getattr(kin, f)[:, k], getattr(ref.bodies[b], f)) for f in ("R", "p", "v", "a", "w", "wd")]
    out["pdm_max_rel_diff"] = max(diffs)
    _dynamics(out, n, args.repeat, m, hip, mh, pm)
    _forward_peers(out, args.repeat, {"stewart": m, "delta": md})
    _direct(out, n, args.repeat, {"stewart": m, "hip": mh, "delta": md, "pdm": mp})
    _stewart_loops(out, m)
    _hip_loops(out)
    _stiffness(out, m, args.repeat, stewart_oracle)
    out["targets"] = {"stewart_kinematics_us_per_sample<=20": out["stewart_kinematics_us_per_sample"] <= 20.0,
                      "hip_max_rel_diff<=1e-9": out["hip_max_rel_diff"] <= 1e-9,
                      "hip_generic_within_10x_of_closed_form": out["hip_generic_over_closed_form"] <= 10.0,
                      "pdm_max_rel_diff<=1e-9": out["pdm_max_rel_diff"] <= 1e-9,
                      "hip_id_max_rel_diff<=1e-8": out["hip_id_max_rel_diff"] <= 1e-8,
                      "pdm_id_max_rel_diff<=1e-8": out["pdm_id_max_rel_diff"] <= 1e-8,
                      "hip_id_generic_within_5x_of_closed_form": out["hip_id_generic_over_closed_form"] <= 5.0,
                      "stewart_id_reactions_us_per_sample<=20": out["stewart_id_reactions_us_per_sample"] <= 20.0,
                      "stewart_fd_single_faster_than_mujoco": out["stewart_fd_over_mujoco"] < 1.0,
                      "stewart_fd_over_mj_forward<=0.5": out["stewart_fd_over_mj_forward"] <= 0.5,
                      "stewart_id_reactions_us_per_sample<=10": out["stewart_id_reactions_us_per_sample"] <= 10.0,
                      "explicit_vs_newton_max_rel_diff<=1e-11": out["explicit_vs_newton_max_rel_diff"] <= 1e-11,
                      "stewart_dk_single_us<=5": out["stewart_dk_single_us"] <= 5.0,
                      "stewart_dk_batched_us_per_sample<=3": out["stewart_dk_batched_us_per_sample"] <= 3.0,
                      "stewart_dk_batched_with_bodies_us_per_sample<=3":
                          out["stewart_dk_batched_with_bodies_us_per_sample"] <= 3.0,
                      "dk_round_trips": all(out[f"{k}_dk{r}_direct_of_inverse_max_err"] <= 1e-10
                                            and out[f"{k}_dk{r}_inverse_of_direct_max_err"] <= 1e-12
                                            for k in ("stewart", "hip", "delta", "pdm") for r in ("", "_with_bodies")),
                      "stiffness_1000_poses_s<=1": out["stiffness_1000_poses_s"] <= 1.0,
                      "stiffness_gosselin_max_rel_diff<=1e-10": out.get("stiffness_gosselin_max_rel_diff", 0.0) <= 1e-10,
                      "stewart_exact_encoder_loop_at_least_mujoco":
                          out.get("stewart_exact_encoder_loop_over_mujoco", 0.0) >= 1.0,
                      "stewart_exact_encoder_loop_alone_at_least_mujoco_loop":
                          out.get("stewart_exact_encoder_loop_alone_over_mujoco_loop", 0.0) >= 1.0,
                      "stewart_exact_encoder_loop_at_least_mujoco_with_preparation":
                          out.get("stewart_exact_encoder_loop_over_mujoco_with_preparation", 0.0) >= 1.0,
                      "hip_exact_encoder_loop_at_least_mujoco": out.get("hip_exact_encoder_loop_over_mujoco", 0.0) >= 1.0}
    print(json.dumps(out, indent=None if args.json else 2))


if __name__ == "__main__":
    main()
