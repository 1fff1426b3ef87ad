"""Actuator efforts of a closed-chain mechanism by projected inverse dynamics in another engine.

Independent of pkmdyn's engine: the tree's generalised forces come from the other engine's
own dynamics (Pinocchio's RNEA, MuJoCo's mass matrix and bias forces), the loop constraints'
Jacobians from its own frame Jacobians (Pinocchio) or constraint rows (MuJoCo), and the
efforts from the balance of the tree coordinates

    tau = S^T u + J_c^T lambda,

solved in least squares (``u``: the actuated coordinates' efforts, ``lambda``: the loops'
constraint forces; an over-constrained loop leaves ``lambda`` non-unique but ``u`` unique,
checked). Featherstone, Rigid Body Dynamics Algorithms (2008), ch. 8.
"""

from __future__ import annotations

import numpy as np


def _null(a: np.ndarray, n: int) -> np.ndarray:
    if a.shape[0] == 0:
        return np.eye(n)
    _, sv, vh = np.linalg.svd(a)
    r = int(np.sum(sv > 1e-10 * max(sv.max(initial=0.0), 1e-300)))
    return vh[r:].T


def projected_efforts(tau: np.ndarray, S: np.ndarray, Jc: np.ndarray,
                      held: np.ndarray | None = None) -> tuple[np.ndarray, float, float]:
    """``u`` from ``tau (nv,) = S^T u + Jc^T lambda + N_i mu``, ``S (na, nv)``, ``Jc (nc, nv)``;
    returns ``(u, residual, spread)``: the balance's residual and how much of the solution
    set's freedom reaches ``u`` (0: ``u`` unique).

    ``N_i``: the idle motions (allowed by the loops, moving no actuator, e.g. a rod's spin
    between two ball joints). A motion prescribes their accelerations kinematically, so their
    balance is left out: by virtual power, ``n . tau = (S n) . u`` for every motion ``n`` the
    loops allow, and those with ``S n = 0`` say nothing of ``u``. Where the motion's idle
    accelerations come from a holding rule (pkmdyn's ``n_k . (q - q_ref) = 0``), ``held (nv, k)``
    gives the rule's force directions instead, and ``u`` is that of the held motion."""
    if held is not None:
        idle = held
    else:
        N = _null(Jc, S.shape[1])
        idle = N @ _null(S @ N, N.shape[1]) if N.size else np.zeros((S.shape[1], 0))
    A = np.hstack([S.T, Jc.T, idle])
    sol, *_ = np.linalg.lstsq(A, tau, rcond=None)
    res = float(np.abs(A @ sol - tau).max())
    _, sv, vh = np.linalg.svd(A)
    rank = int(np.sum(sv > 1e-10 * sv.max()))
    N = vh[rank:]
    spread = float(np.abs(N[:, :S.shape[0]]).max()) if N.size else 0.0
    return sol[:S.shape[0]], res, spread


def pinocchio_efforts(urdf: str, closures: list[tuple[str, str, str]], actuated: list[str], q_of: dict,
                      qd_of: dict, qdd_of: dict, gravity=(0.0, 0.0, -9.81),
                      held: dict | None = None) -> tuple[np.ndarray, float, float]:
    """Efforts of the joints ``actuated`` of the URDF file ``urdf`` closed by the frame pairs
    ``closures`` ((frame_A, frame_B, '3d' | '6d')), at the joint positions, rates and
    accelerations ``q_of``, ``qd_of``, ``qdd_of`` (joint name -> value; one-coordinate joints);
    ``held``: joint name -> the idle holding rules' force directions on it ((k,) each)."""
    import pinocchio as pin

    model = pin.buildModelFromUrdf(urdf)
    model.gravity.linear = np.array(gravity, dtype=float)
    data = model.createData()
    q, v, a = pin.neutral(model), np.zeros(model.nv), np.zeros(model.nv)
    for j in range(1, model.njoints):
        nm = model.names[j]
        iq, iv = model.idx_qs[j], model.idx_vs[j]
        if model.nqs[j] == 2:  # a continuous joint: (cos, sin)
            q[iq:iq + 2] = np.cos(q_of[nm]), np.sin(q_of[nm])
        else:
            q[iq] = q_of[nm]
        v[iv], a[iv] = qd_of[nm], qdd_of[nm]
    tau = pin.rnea(model, data, q, v, a)
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    rows = []
    for fa, fb, kind in closures:
        ia, ib = model.getFrameId(fa), model.getFrameId(fb)
        J = (pin.getFrameJacobian(model, data, ia, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
             - pin.getFrameJacobian(model, data, ib, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED))
        rows.append(J if kind == "6d" else J[:3])
    S = np.zeros((len(actuated), model.nv))
    for i, nm in enumerate(actuated):
        S[i, model.idx_vs[model.getJointId(nm)]] = 1.0
    H = None
    if held is not None:
        H = np.zeros((model.nv, len(next(iter(held.values())))))
        for nm, row in held.items():
            H[model.idx_vs[model.getJointId(nm)]] = row
    return projected_efforts(tau, S, np.vstack(rows), H)


def mujoco_efforts(xml: str, q_of: dict, qd_of: dict, qdd_of: dict) -> tuple[np.ndarray, float, float]:
    """Controls of every actuator (each ``gear`` times its control acts on its joint) of the MJCF
    file ``xml`` at the joint positions, rates and accelerations given by joint name (hinge
    and slide joints): MuJoCo's ``M qacc + bias - passive`` balanced by the actuators and the
    equality constraints' rows."""
    import mujoco

    m = mujoco.MjModel.from_xml_path(xml)
    m.opt.jacobian = mujoco.mjtJacobian.mjJAC_DENSE  # efc_J as a dense (nefc, nv) matrix
    d = mujoco.MjData(m)
    for j in range(m.njnt):
        nm = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j)
        d.qpos[m.jnt_qposadr[j]] = q_of[nm]
        d.qvel[m.jnt_dofadr[j]] = qd_of[nm]
    qacc = np.zeros(m.nv)
    for j in range(m.njnt):
        qacc[m.jnt_dofadr[j]] = qdd_of[mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j)]
    mujoco.mj_forward(m, d)
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M)
    tau = M @ qacc + d.qfrc_bias - d.qfrc_passive
    eq = d.efc_type[:d.nefc] == int(mujoco.mjtConstraint.mjCNSTR_EQUALITY)
    Jc = d.efc_J.reshape(d.nefc, m.nv)[eq] if d.nefc else np.zeros((0, m.nv))
    S = np.zeros((m.nu, m.nv))
    for i in range(m.nu):
        S[i, m.jnt_dofadr[m.actuator_trnid[i, 0]]] = m.actuator_gear[i, 0]
    return projected_efforts(tau, S, Jc)
