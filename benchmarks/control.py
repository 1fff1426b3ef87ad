"""Speed of the real-time model path and of closed-loop simulation: pkmdyn beside MuJoCo.

Runs in one process, on one core, on the same inputs:

- ``hip``: the machine as ``pkmdyn hip control`` runs it, the generic engine's verbs on its
  description (``control_job.verbs``): one sample of inverse and forward dynamics on the
  single-sample path (``inverse_dynamics_one`` / ``forward_dynamics_one``, every friction term
  on) and on the batched verbs at ``n = 1``, over 1000 states of the ISO 14242-1 cycle model; a
  10 s closed loop at 1 kHz through the project's closed-loop simulator
  (``pkmdyn.simulate.track``: sensors, controller, ROS2 plant on the fast path), and the same
  10 s through a minimal loop (computed torque on the fast path, one linearly implicit Euler
  step per cycle), each with its tracking accuracy; and that minimal loop compiled whole with
  Numba around the engine's single-sample kernels (``one_sample_kernels``), the floor the model
  path allows.
- ``pdm``: the PDM's single-sample verbs and its closed loop through ``pkmdyn.simulate.track``
  (PID at the PDM's 2 ms cycle) on a raised-cosine swing of all four coordinates.
- ``mujoco``: the hip machine exported to MJCF (``pkmdyn hip export``: the engine's writer on
  its description, :mod:`pkmdyn.multibody.formats.mjcf_out`; no friction) - one ``mj_inverse``,
  ``mj_forward`` and RK4 ``mj_step`` (1 ms) at consistent states of the same cycle, and a 10 s
  closed loop at 1 kHz (joint-space PD on the motor angles plus pkmdyn's friction-free
  feedforward, one ``mj_step`` per cycle; the best of three runs, as the engine's loops) with its
  tracking accuracy.
- ``ratios``: ``hip_engine_loop_over_mujoco``, the real-time factor of the hip's closed loop on
  the engine (``pkmdyn.simulate.track``, computed torque, default settings) over that of
  MuJoCo's loop (target: at least 1).

    python benchmarks/control.py --json [--seconds 10]

Prints one JSON object. Times are the best of several repeats (per-call times: best mean of
batches of calls); ``realtime_factor`` = simulated seconds / wall seconds of the whole loop.
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import json
import os
import sys
import time
from typing import Any

import numba
import numpy as np

from pkmdyn.machines.hip_simulator import control_job
from pkmdyn.machines.hip_simulator.params import load_params
from pkmdyn.multibody.dynamics._sample_kernels import FORWARD, INVERSE, _dynamics
from pkmdyn.profiles.iso14242 import iso14242_motion
from pkmdyn.spatial import euler_kinematics

TARGET_SINGLE_US = 10.0
TARGET_REALTIME = 30.0


def _per_call_us(fn, args_list, repeat: int = 5) -> float:
    """Best mean time of one call [us] over ``repeat`` passes through ``args_list``."""
    for a in args_list[:20]:
        fn(*a)
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        for a in args_list:
            fn(*a)
        best = min(best, (time.perf_counter() - t0) / len(args_list))
    return best * 1e6


def _solve3(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``A^-1 b`` for a 3 x 3 system by cofactors (no per-call overhead of LAPACK)."""
    (a, b_, c), (d, e, f), (g, h, i) = A.tolist()
    x, y, z = b.tolist()
    c0, c1, c2 = e * i - f * h, f * g - d * i, d * h - e * g
    det = a * c0 + b_ * c1 + c * c2
    return np.array([
        (x * c0 + y * (c * h - b_ * i) + z * (b_ * f - c * e)) / det,
        (x * c1 + y * (a * i - c * g) + z * (c * d - a * f)) / det,
        (x * c2 + y * (b_ * g - a * h) + z * (a * e - b_ * d)) / det,
    ])


def _angle_error_deg(R_ref: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Rotation angle of ``R_ref^T R`` [deg], per sample."""
    c = (np.einsum("nij,nij->n", R_ref, R) - 1.0) / 2.0
    return np.rad2deg(np.arccos(np.clip(c, -1.0, 1.0)))


def _hip_inputs(n: int) -> tuple[Any, ...]:
    model = load_params()
    mo = iso14242_motion(cycles=1.0, samples_per_cycle=n)
    return model, mo


def _engine(model: Any) -> tuple[Any, Any]:
    """``(control model, verbs)``: what ``pkmdyn hip control`` runs for the parameters ``model``,
    the engine's verbs on its description compiled."""
    cm = control_job.control_model(model)
    return cm, control_job.verbs(cm)


def hip_single(model: Any, mo: Any) -> dict[str, float]:
    q, qd, qdd, load = mo.angles, mo.rates, mo.accels, mo.load
    model, verbs = _engine(model)
    u = verbs.inverse_dynamics(model, q, qd, qdd, load)
    n = len(q)
    args_id = [(model, q[k], qd[k], qdd[k], float(load[k])) for k in range(n)]
    args_fd = [(model, q[k], qd[k], u[k], float(load[k])) for k in range(n)]
    out = {
        "id_single_us": _per_call_us(verbs.inverse_dynamics_one, args_id),
        "fd_single_us": _per_call_us(verbs.forward_dynamics_one, args_fd),
    }
    sub = slice(0, n, 10)
    args_id_b = [(model, q[k : k + 1], qd[k : k + 1], qdd[k : k + 1], load[k : k + 1]) for k in range(n)[sub]]
    args_fd_b = [(model, q[k : k + 1], qd[k : k + 1], u[k : k + 1], load[k : k + 1]) for k in range(n)[sub]]
    out["id_batched_n1_us"] = _per_call_us(verbs.inverse_dynamics, args_id_b, repeat=3)
    out["fd_batched_n1_us"] = _per_call_us(verbs.forward_dynamics, args_fd_b, repeat=3)
    # agreement of the two paths on these samples
    u1 = np.array([verbs.inverse_dynamics_one(*a) for a in args_id])
    f1 = np.array([verbs.forward_dynamics_one(*a) for a in args_fd])
    out["max_rel_diff_fast_vs_batched"] = float(
        max(np.abs(u1 - u).max() / np.abs(u).max(), np.abs(f1 - qdd).max() / np.abs(qdd).max())
    )
    out["id_speedup_vs_batched"] = out["id_batched_n1_us"] / out["id_single_us"]
    out["fd_speedup_vs_batched"] = out["fd_batched_n1_us"] / out["fd_single_us"]
    return out


def hip_minimal_loop(model: Any, seconds: float) -> dict[str, float]:
    """Computed torque on the fast path (exact model, friction included) and one linearly
    implicit Euler step per 1 ms cycle: ``(I - h A) dqd = h f(q, qd)``, ``A = d f / d qd`` by
    forward differences, ``q += h (qd + dqd)``."""
    T = 1e-3
    K = int(round(seconds / T))
    mo = iso14242_motion(cycles=seconds, samples_per_cycle=1000)
    q_ref, qd_ref, qdd_ref, load = mo.angles, mo.rates, mo.accels, mo.load
    kp, kd = (2 * np.pi * 20.0) ** 2, 2 * 0.7 * 2 * np.pi * 20.0
    seq = model.geometry.euler_sequence
    model, verbs = _engine(model)
    fd, idd = verbs.forward_dynamics_one, verbs.inverse_dynamics_one
    q, qd = q_ref[0].copy(), qd_ref[0].copy()
    fd(model, q, qd, idd(model, q, qd, qdd_ref[0], load[0]), load[0])  # compile and warm up
    qs = np.empty((K, 3))
    A = np.empty((3, 3))
    eye = np.eye(3)
    t0 = time.perf_counter()
    for k in range(K):
        qs[k] = q
        a_cmd = qdd_ref[k] + kp * (q_ref[k] - q) + kd * (qd_ref[k] - qd)
        u = idd(model, q, qd, a_cmd, load[k])
        f0 = fd(model, q, qd, u, load[k])
        for c in range(3):
            v = qd.copy()
            dv = 1e-7 * (1.0 + abs(qd[c]))
            v[c] += dv
            A[:, c] = (fd(model, q, v, u, load[k]) - f0) / dv
        dqd = _solve3(eye - T * A, T * f0)
        qd = qd + dqd
        q = q + T * qd
    wall = time.perf_counter() - t0
    R_ref = euler_kinematics(seq, q_ref[:K], qd_ref[:K], qdd_ref[:K])[0]
    R = euler_kinematics(seq, qs, qd_ref[:K], qdd_ref[:K])[0]
    err = _angle_error_deg(R_ref, R)
    return {
        "realtime_factor_minimal_loop": seconds / wall,
        "minimal_loop_us_per_cycle": wall / K * 1e6,
        "minimal_loop_rms_error_deg": float(np.sqrt(np.mean(err**2))),
        "minimal_loop_max_error_deg": float(err.max()),
    }


@numba.njit(cache=True)
def _compiled_loop(p, modes, q_ref, qd_ref, qdd_ref, load, T, kp, kd, qs):  # pragma: no cover
    """The minimal loop of :func:`hip_minimal_loop`, compiled whole, calling the engine's
    single-sample kernel (``multibody._one``; ``modes``: its inverse and forward modes, as
    values)."""
    inv, fwd = modes[0], modes[1]
    q = q_ref[0].copy()
    qd = qd_ref[0].copy()
    a_cmd = np.empty(3)
    u = np.empty(3)
    f0 = np.empty(3)
    f1 = np.empty(3)
    v = np.empty(3)
    W = np.empty((3, 3))
    for k in range(qs.shape[0]):
        qs[k] = q
        for i in range(3):
            a_cmd[i] = qdd_ref[k, i] + kp * (q_ref[k, i] - q[i]) + kd * (qd_ref[k, i] - qd[i])
        if _dynamics(p, q, qd, a_cmd, load[k], inv, u) != 0 or _dynamics(p, q, qd, u, load[k], fwd, f0) != 0:
            return k
        for c in range(3):
            v[:] = qd
            dv = 1e-7 * (1.0 + abs(qd[c]))
            v[c] += dv
            _dynamics(p, q, v, u, load[k], fwd, f1)
            for r in range(3):
                W[r, c] = -T * (f1[r] - f0[r]) / dv
            W[c, c] += 1.0
        dqd = np.linalg.solve(W, T * f0)
        for i in range(3):
            qd[i] += dqd[i]
            q[i] += T * qd[i]
    return qs.shape[0]


def hip_compiled_loop(model: Any, seconds: float) -> dict[str, float]:
    """The same minimal loop compiled whole around the engine's single-sample kernels
    (``one_sample_kernels``): the floor the model path allows."""
    T = 1e-3
    K = int(round(seconds / T))
    mo = iso14242_motion(cycles=seconds, samples_per_cycle=1000)
    seq = model.geometry.euler_sequence
    cm, verbs = _engine(model)
    p = verbs.one_sample_kernels(cm)[0]
    kp, kd = (2 * np.pi * 20.0) ** 2, 2 * 0.7 * 2 * np.pi * 20.0
    args = (p, np.array([INVERSE, FORWARD], dtype=np.int64), mo.angles, mo.rates, mo.accels, mo.load, T, kp, kd)

    def prime() -> None:  # the kernels start from the last solved sample: the run's first one
        verbs.inverse_dynamics(cm, mo.angles[:1], mo.rates[:1], mo.accels[:1], mo.load[:1])

    prime()
    _compiled_loop(*args, np.empty((10, 3)))  # compile and warm up
    best = np.inf
    for _ in range(3):
        qs = np.empty((K, 3))
        prime()
        t0 = time.perf_counter()
        done = _compiled_loop(*args, qs)
        best = min(best, time.perf_counter() - t0)
    if done != K:
        raise RuntimeError(f"compiled loop stopped at cycle {done}")
    err = _angle_error_deg(euler_kinematics(seq, mo.angles[:K], qs, qs)[0], euler_kinematics(seq, qs, qs, qs)[0])
    return {
        "realtime_factor_compiled_loop": seconds / best,
        "compiled_loop_us_per_cycle": best / K * 1e6,
        "compiled_loop_max_error_deg": float(err.max()),
    }


def hip_project_loop(model: Any, seconds: float,
                     kinds: tuple[str, ...] = ("computed-torque", "augmented-pd", "computed-torque-exact-encoders"),
                     generic: bool = False) -> dict[str, Any]:
    """The project's closed-loop simulator on the default settings, exact plant: each of
    ``kinds`` (a control law, ``-exact-encoders``: with ``exact_encoders = 1``), on the engine's
    verbs of the hip's description (:func:`_project_loop_run`)."""
    from pkmdyn.control import hermite_motion, load_settings, loop_settings
    from pkmdyn.simulate import track  # noqa: F401  (raises if the simulator is absent)
    from pkmdyn.simulate._cycles import compile_for_runs

    compile_for_runs()  # the cycles in one compiled call, as an install has them (pkmdyn compile)

    st = load_settings("hip")
    ls = loop_settings(st)
    mo = iso14242_motion(cycles=seconds + 1.0, samples_per_cycle=2000)
    motion = hermite_motion(mo.t, mo.angles, mo.rates, mo.accels, mo.load)
    out: dict[str, Any] = {"loop_settings": {"control_cycle_s": ls.cycle_s, "integration_step_s": ls.step_s}}
    exact = copy.deepcopy(st)
    exact["sensors"]["exact_encoders"] = 1  # the encoders through the kinematics, the pose by the direct kinematics
    for kind in kinds:
        if kind.endswith("-exact-encoders"):  # its own failure leaves the other loops' figures
            try:
                out[kind] = _project_loop_run(model, motion, st, exact, kind, seconds, generic)
            except Exception as exc:
                out[kind] = {"error": f"{type(exc).__name__}: {exc}"}
            continue
        out[kind] = _project_loop_run(model, motion, st, st, kind, seconds, generic)
    return out


def _project_loop_run(model: Any, motion: Any, st: dict, settings: dict, kind: str, seconds: float,
                      generic: bool = False) -> dict[str, Any]:
    """One closed loop of :func:`hip_project_loop`: the law of ``kind`` (its gains from ``st``)
    under the loop ``settings``, on the engine's verbs of the hip's description: under the
    paper's names as ``pkmdyn hip control`` runs them (``control_job.verbs``), or with
    ``generic`` the described mechanism's own (``machine_verbs``, the description's names)."""
    from pkmdyn.control import gains, loop_settings
    from pkmdyn.simulate._run import track as _track

    plant, verbs = _engine(model)
    if generic:
        from pkmdyn.machines.hip_simulator.description import hip_description
        from pkmdyn.multibody import load_mechanism
        from pkmdyn.multibody.dynamics.verbs import machine_verbs

        plant = load_mechanism(hip_description(model))
        verbs = machine_verbs(plant)
    kind_law = kind.replace("-exact-encoders", "")
    ls = loop_settings(settings)
    g = gains(st, kind_law, 3)
    _track(verbs, plant, plant, motion, 0.05, kind_law, g, ls, True)  # compile and warm up
    wall = np.inf
    for _ in range(3):  # the best of three
        t0 = time.perf_counter()
        tr = _track(verbs, plant, plant, motion, seconds, kind_law, g, ls, True)
        wall = min(wall, time.perf_counter() - t0)
    res = tr.result
    K = res.q.shape[0]
    seq = model.geometry.euler_sequence
    R_ref = euler_kinematics(seq, tr.reference.q[:K], res.qd, res.qd)[0]
    R = euler_kinematics(seq, res.q, res.qd, res.qd)[0]
    err = _angle_error_deg(R_ref, R)
    return {
        "realtime_factor": seconds / wall,
        "us_per_cycle": wall / K * 1e6,
        "rms_error_deg": float(np.sqrt(np.mean(err**2))),
        "max_error_deg": float(err.max()),
        "fast_path": bool(tr.fast_path),
    }


def pdm_part(seconds: float) -> dict[str, Any]:
    from pkmdyn.machines.pdm4 import control_job
    from pkmdyn.machines.pdm4.params import load_params as load_pdm
    from pkmdyn.profiles.pdm_motion import cycloidal_motion

    model = control_job.control_model(load_pdm())  # what pkmdyn pdm control runs: the engine on the description
    pdm = control_job.verbs(model)
    mo = cycloidal_motion((0.02, 0.02, np.deg2rad(5.0), np.deg2rad(5.0)), 1.0, 200)
    q, qd, qdd = mo.q, mo.qd, mo.qdd
    u = pdm.inverse_dynamics(model, q, qd, qdd, None)
    out: dict[str, Any] = {"single_sample_path": "the engine's inverse_dynamics_one / forward_dynamics_one on the "
                                                 "PDM's description"}
    out["id_single_us"] = _per_call_us(pdm.inverse_dynamics_one, [(model, q[k], qd[k], qdd[k], None) for k in range(len(q))])
    out["fd_single_us"] = _per_call_us(pdm.forward_dynamics_one, [(model, q[k], qd[k], u[k], None) for k in range(len(q))])
    try:
        from pkmdyn.control import gains, load_settings, loop_settings
        from pkmdyn.simulate._run import track

        st = load_settings("pdm")
        ls = loop_settings(st)
        amp = np.array([0.02, 0.02, np.deg2rad(5.0), np.deg2rad(5.0)])
        wn = 2 * np.pi / 2.0  # a 2 s raised-cosine swing from the home pose and back

        def motion(t):
            t = np.asarray(t, dtype=float)[:, None]
            return (amp * (1 - np.cos(wn * t)) / 2, amp * wn * np.sin(wn * t) / 2, amp * wn**2 * np.cos(wn * t) / 2, None)

        g = gains(st, "pid", 4)
        track(pdm, model, model, motion, 0.05, "pid", g, ls, False)
        t0 = time.perf_counter()
        tr = track(pdm, model, model, motion, seconds, "pid", g, ls, False)
        wall = time.perf_counter() - t0
        e = tr.result.q - tr.reference.q[: tr.result.q.shape[0]]
        out["realtime_factor"] = seconds / wall
        out["loop"] = f"pkmdyn.simulate.track, PID, control cycle {ls.cycle_s:g} s, step {ls.step_s:g} s"
        out["max_error_mm"] = float(np.abs(e[:, :2]).max() * 1e3)
        out["max_error_deg"] = float(np.rad2deg(np.abs(e[:, 2:]).max()))
    except Exception as exc:  # the closed-loop simulator may be absent or fail on this motion
        out["realtime_factor"] = None
        out["loop_error"] = f"{type(exc).__name__}: {exc}"
    return out


def mujoco_part(seconds: float) -> dict[str, Any]:
    import mujoco

    import pkmdyn.cli  # noqa: F401  (the command line first: the hip's commands module is one of its groups)
    from pkmdyn.machines.hip_simulator.job import PLATFORM_MASS_KG  # what pkmdyn hip export writes
    from pkmdyn.multibody import solve_kinematics
    from pkmdyn.multibody.formats.mjcf_out import mechanism_mjcf, mujoco_order, mujoco_qpos

    base = load_params()
    model = dataclasses.replace(base, friction=dataclasses.replace(base.friction, mu_h=0.0, mu_t=0.0))
    cm, verbs = _engine(model)
    mech = cm.mechanism
    mj = mujoco.MjModel.from_xml_string(mechanism_mjcf(mech, massless_kg=PLATFORM_MASS_KG))  # pkmdyn hip export
    data = mujoco.MjData(mj)
    seq = model.geometry.euler_sequence
    order = mujoco_order(mech, mj)

    def mujoco_state(q, qd, qdd):
        """MuJoCo's ``qpos, qvel, qacc (n, nv)`` at the platforms' angles, rates and
        accelerations (the tree coordinates of the engine's kinematics) and that kinematics."""
        kin = solve_kinematics(mech, q, qd, qdd)
        qpos = np.array([mujoco_qpos(mech, kin.q[k], mj) for k in range(len(q))])
        qvel, qacc = np.empty((len(q), mj.nv)), np.empty((len(q), mj.nv))
        qvel[:, order], qacc[:, order] = kin.qd, kin.qdd
        return qpos, qvel, qacc, kin

    mo = iso14242_motion(cycles=1.0, samples_per_cycle=1000)
    qpos, qvel, qacc, kin0 = mujoco_state(mo.angles, mo.rates, mo.accels)
    tau = verbs.inverse_dynamics(cm, mo.angles, mo.rates, mo.accels, np.zeros(len(mo.t)))
    n = len(mo.t)

    def setter(k: int) -> None:
        data.qpos[:] = qpos[k]
        data.qvel[:] = qvel[k]
        data.qacc[:] = qacc[k]
        data.ctrl[:] = tau[k]

    def timed(fn) -> float:
        best = np.inf
        for _ in range(5):
            total = 0.0
            for k in range(n):
                setter(k)
                t0 = time.perf_counter()
                fn(mj, data)
                total += time.perf_counter() - t0
            best = min(best, total / n)
        return best * 1e6

    out: dict[str, Any] = {
        "version": mujoco.__version__,
        "model": f"pkmdyn hip export (no friction): nq {mj.nq}, nv {mj.nv}, {mj.neq} connect loops, RK4, 1 ms",
        "mj_inverse_us": timed(mujoco.mj_inverse),
        "mj_forward_us": timed(mujoco.mj_forward),
        "mj_step_us": timed(mujoco.mj_step),
    }
    # forward accuracy: pkmdyn torques in MuJoCo -> the upper platform's coordinate accelerations
    upper = [c for c, j in enumerate(mech.coord_joint) if mech.joint_names[j] == "S0_upper"]
    dof = order[upper]
    errs = []
    for k in range(0, n, 10):
        setter(k)
        mujoco.mj_forward(mj, data)
        errs.append(np.abs(data.qacc[dof] - kin0.qdd[k, upper]).max() / np.abs(kin0.qdd[k, upper]).max())
    out["forward_rel_error_vs_pkmdyn_max"] = float(np.max(errs))
    # closed loop: motor-angle PD + friction-free feedforward, one mj_step per 1 ms cycle
    T = mj.opt.timestep
    K = int(round(seconds / T))
    long = iso14242_motion(cycles=seconds, samples_per_cycle=int(round(1.0 / T)))
    Rr = euler_kinematics(seq, long.angles[:K], long.rates[:K], long.accels[:K])[0]
    ff = verbs.inverse_dynamics(cm, long.angles[:K], long.rates[:K], long.accels[:K], np.zeros(K))
    qpos_r, qvel_r, _, kin = mujoco_state(long.angles[:K], long.rates[:K], long.accels[:K])
    # the motors' angles: the slide joints' qpos (the sliders' positions, each joint's ref its
    # reference value) times their gear, the drives' ratio 2 pi / p
    gear = np.asarray(mech.drive_ratio, dtype=float)
    slide = order[np.asarray(mech.act_coord)]
    theta_ref = qpos_r[:, slide] * gear
    thetad_ref = qvel_r[:, slide] * gear
    upper_body = mj.body("upper").id  # its frame is the base frame at the zero pose
    kp, kd = 2.0, 0.02  # [N m/rad, N m s/rad] on the motor angles
    Rm = np.empty((K, 9))
    wall = np.inf
    for _ in range(3):  # the best of three, as the engine's loops
        mujoco.mj_resetData(mj, data)
        data.qpos[:] = qpos_r[0]
        data.qvel[:] = qvel_r[0]
        mujoco.mj_forward(mj, data)
        t0 = time.perf_counter()
        for k in range(K):
            Rm[k] = data.xmat[upper_body]
            th = data.qpos[slide] * gear
            thd = data.qvel[slide] * gear
            data.ctrl[:] = ff[k] + kp * (theta_ref[k] - th) + kd * (thetad_ref[k] - thd)
            mujoco.mj_step(mj, data)
        wall = min(wall, time.perf_counter() - t0)
    err = _angle_error_deg(Rr, Rm.reshape(K, 3, 3))
    out["realtime_factor"] = seconds / wall
    out["loop"] = "motor-angle PD (2 N m/rad, 0.02 N m s/rad) + pkmdyn friction-free feedforward, mj_step RK4 1 ms"
    out["rms_error_deg"] = float(np.sqrt(np.mean(err**2)))
    out["max_error_deg"] = float(err.max())
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print only the JSON object")
    ap.add_argument("--seconds", type=float, default=10.0, help="simulated seconds of each closed loop")
    args = ap.parse_args(argv)
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})  # one core
    model, mo = _hip_inputs(1000)
    hip: dict[str, Any] = hip_single(model, mo)
    hip.update(hip_minimal_loop(model, args.seconds))
    hip.update(hip_compiled_loop(model, args.seconds))
    try:
        proj = hip_project_loop(model, args.seconds)
        hip["closed_loop"] = proj
        hip["realtime_factor"] = proj["computed-torque"]["realtime_factor"]
        hip["realtime_factor_loop"] = "pkmdyn.simulate.track, computed torque, default hip settings"
    except Exception as exc:  # the project's simulator absent or failing: the minimal loop stands in
        hip["closed_loop_error"] = f"{type(exc).__name__}: {exc}"
        hip["realtime_factor"] = hip["realtime_factor_minimal_loop"]
        hip["realtime_factor_loop"] = "minimal loop (computed torque + linearly implicit Euler)"
    hip["targets_met"] = {
        "id_single_us": hip["id_single_us"] <= TARGET_SINGLE_US,
        "fd_single_us": hip["fd_single_us"] <= TARGET_SINGLE_US,
        "realtime_factor": hip["realtime_factor"] >= TARGET_REALTIME,
    }
    result: dict[str, Any] = {"hip": hip}
    try:
        result["pdm"] = pdm_part(args.seconds)
    except Exception as exc:
        result["pdm"] = {"error": f"{type(exc).__name__}: {exc}"}
    try:
        result["mujoco"] = mujoco_part(args.seconds)
        m = result["mujoco"]
        result["ratios"] = {
            "hip_id_single_vs_mj_inverse": hip["id_single_us"] / m["mj_inverse_us"],
            "hip_fd_single_vs_mj_forward": hip["fd_single_us"] / m["mj_forward_us"],
            "hip_realtime_vs_mujoco": hip["realtime_factor"] / m["realtime_factor"],
        }
        loop = hip.get("closed_loop", {}).get("computed-torque", {})
        if "realtime_factor" in loop:  # the hip's loop on the engine, same 1 ms cycle, same seconds
            r = loop["realtime_factor"] / m["realtime_factor"]
            result["ratios"]["hip_engine_loop_over_mujoco"] = r
            result.setdefault("ratios_targets_met", {})["hip_engine_loop_over_mujoco"] = r >= 1.0
        ex = hip.get("closed_loop", {}).get("computed-torque-exact-encoders", {})
        if "realtime_factor" in ex:  # at least MuJoCo's real-time factor with exact encoders
            r = ex["realtime_factor"] / m["realtime_factor"]
            result["ratios"]["hip_exact_encoder_realtime_vs_mujoco"] = r
            result.setdefault("ratios_targets_met", {})["hip_exact_encoder_realtime_vs_mujoco"] = r >= 1.0
    except ImportError:
        result["mujoco"] = {"error": "MuJoCo not installed (pip install 'pkmdyn[validate]')"}
    result["python"] = sys.version.split()[0]
    if hasattr(os, "getloadavg"):
        result["load_average_1min"] = os.getloadavg()[0]  # other work on the machine inflates every time
    print(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
