"""One conformance suite for every built-in machine: the four described mechanisms (Stewart,
Delta, 3-RRR, Bennett) and the two papers' machines as descriptions (the hip simulator, the
PDM), each run through the same checks on a smooth random motion about its reference pose:

* the task-space mass matrix symmetric positive definite;
* forward dynamics of the inverse dynamics gives the accelerations back;
* the single-sample verbs give the batched ones;
* power balance: the actuators' power is the rate of the kinetic and potential energy
  (the machine without drives, friction and external loads, whose work this check leaves out);
* the actuator Jacobian and the tree-rate map by central finite differences of the kinematics;
* the actuator coordinates against the machine's own closed form (tests/oracles for the four
  described mechanisms and the hip, Eq. 1-6 of the hip paper; the hand-derived kinematics of
  Eq. 2-48 of the PDM paper);
* the hip against its closed-form oracle (tests/oracles/hip.py) in full, to 1e-9: every body's
  kinematics, ``M``, ``h``, ``B``, and the motor torques and their parts with every friction
  family and the hydraulic load (Eq. 7-16), batched and single-sample.

The thresholds are fixed by the arithmetic of each check (rounding for identities, the
finite-difference truncation for derivatives), far from what a wrong formula gives.
"""

from __future__ import annotations

import copy
from types import SimpleNamespace

import numpy as np
import pytest

import multibody_examples as ex
from oracles import bennett, delta, rrr3, stewart
from pkmdyn.multibody import load_mechanism, reference_task, solve_kinematics
from pkmdyn.multibody.dynamics.newton_euler import energies
from pkmdyn.multibody.dynamics.verbs import machine_verbs


def _hip():
    from pkmdyn.machines.hip_simulator import load_params
    from pkmdyn.machines.hip_simulator.description import hip_description

    return hip_description(load_params())


def _pdm():
    from pkmdyn.machines.pdm4 import load_params
    from pkmdyn.machines.pdm4.description import pdm_description

    return pdm_description(load_params())


#: name -> the description; the amplitude of the motion per task coordinate (lengths, angles)
MACHINES = {
    "stewart": (lambda: ex.builtin_dict("stewart"), (0.05, 0.08)),
    "delta": (lambda: ex.builtin_dict("delta"), (0.15, 0.0)),
    "rrr3": (lambda: ex.builtin_dict("rrr3"), (0.04, 0.2)),
    "bennett": (lambda: ex.builtin_dict("bennett"), (0.0, 0.4)),
    "hip": (_hip, (0.0, 0.3)),
    "pdm": (_pdm, (0.03, 0.15)),
}

_CACHE: dict = {}


def _model(name, rigid=False):
    """The machine (``rigid``: without drives, joint friction and external loads)."""
    key = (name, rigid)
    if key not in _CACHE:
        d = copy.deepcopy(MACHINES[name][0]())
        if rigid:
            d.pop("actuators", None)
            d.pop("loads", None)
            for group in [d, *d.get("legs", [])]:
                for j in group.get("joints", []):
                    j.pop("friction", None)
        _CACHE[key] = load_mechanism(d)
    return _CACHE[key]


def _motion(m, name, n=40, period=1.0, seed=3):
    """x0 + a smooth sum of two sinusoids per task coordinate, with its exact derivatives
    (``at(t)`` gives them at any time)."""
    rng = np.random.default_rng(seed)
    lin, ang = MACHINES[name][1]
    amp = np.where(m.task_kind == 1, ang, lin) * rng.uniform(0.5, 1.0, m.nt)
    w = rng.uniform(3.0, 7.0, (2, m.nt))
    ph = rng.uniform(0.0, 2 * np.pi, (2, m.nt))
    x0 = reference_task(m)

    def at(t):
        t = np.asarray(t, dtype=float)[:, None]
        s = [np.sin(w[k] * t + ph[k]) for k in range(2)]
        c = [np.cos(w[k] * t + ph[k]) for k in range(2)]
        x = x0 + 0.5 * amp * (s[0] - np.sin(ph[0]) + s[1] - np.sin(ph[1]))
        xd = 0.5 * amp * (w[0] * c[0] + w[1] * c[1])
        xdd = -0.5 * amp * (w[0] ** 2 * s[0] + w[1] ** 2 * s[1])
        return x, xd, xdd

    t = np.linspace(0.0, period, n)
    return (t, *at(t)), at


def _rel(a, b):
    return float(np.abs(np.asarray(a) - np.asarray(b)).max() / max(float(np.abs(b).max()), 1e-300))


@pytest.mark.parametrize("name", sorted(MACHINES))
def test_mass_matrix_is_symmetric_positive_definite(name):
    m = _model(name)
    (t, x, xd, xdd), _ = _motion(m, name, n=8)
    M = machine_verbs(m).mass_matrix(m, x)
    assert _rel(M, np.swapaxes(M, 1, 2)) < 1e-12
    ev = np.linalg.eigvalsh(0.5 * (M + np.swapaxes(M, 1, 2)))
    assert np.all(ev[:, 0] > 1e-9 * ev[:, -1])


@pytest.mark.parametrize("name", sorted(MACHINES))
def test_forward_of_inverse_and_single_sample_equal_batched(name):
    m = _model(name)
    V = machine_verbs(m)
    (t, x, xd, xdd), _ = _motion(m, name, n=12)
    u = V.inverse_dynamics(m, x, xd, xdd)
    a = V.forward_dynamics(m, x, xd, u)
    assert _rel(a, xdd) < 1e-9
    for k in (0, 7):
        assert _rel(V.inverse_dynamics_one(m, x[k], xd[k], xdd[k]), u[k]) < 1e-9
        assert _rel(V.forward_dynamics_one(m, x[k], xd[k], u[k]), a[k]) < 1e-9


@pytest.mark.parametrize("name", sorted(MACHINES))
def test_power_balance(name):
    """sum_k u_k sd_k = d(T + V)/dt (no friction, drives or external loads), the rate by central
    differences of the energies at t +- h on the exact motion (truncation ~ h^2)."""
    m = _model(name, rigid=True)
    V = machine_verbs(m)
    (t, x, xd, xdd), at = _motion(m, name, n=10)
    kin = solve_kinematics(m, x, xd, xdd, t)
    u = V.inverse_dynamics(m, x, xd, xdd)
    power = np.einsum("na,na->n", u, kin.act_qd)
    h = 1e-5
    E = []
    for sign in (-1.0, 1.0):
        xs, xds, xdds = at(t + sign * h)
        T, P = energies(m, solve_kinematics(m, xs, xds, xdds, t + sign * h, q_start=kin.q[0]))
        E.append(T + P)
    rate = (E[1] - E[0]) / (2 * h)
    assert np.abs(power).max() > 0
    assert np.abs(power - rate).max() < 1e-6 * np.abs(power).max()


@pytest.mark.parametrize("name", sorted(MACHINES))
def test_jacobians_by_finite_differences(name):
    """``J_ax = dq_a/dx`` and ``G = dq/dx`` against central differences of the kinematics in each
    task coordinate (step 1e-6 of the length scale or 1e-6 rad; truncation and rounding ~1e-10)."""
    m = _model(name)
    (t, x, xd, xdd), _ = _motion(m, name, n=4)
    kin = solve_kinematics(m, x, xd, xdd, t)
    for k in range(len(t)):
        for j in range(m.nt):
            h = 1e-6 * (1.0 if m.task_kind[j] == 1 else m.length_scale)
            q = []
            for sign in (-1.0, 1.0):
                xp = x[k:k + 1].copy()
                xp[0, j] += sign * h
                q.append(solve_kinematics(m, xp, q_start=kin.q[k]).q[0])
            dq = (q[1] - q[0]) / (2 * h)
            assert np.abs(dq - kin.G[k, :, j]).max() < 1e-6 * max(np.abs(kin.G[k]).max(), 1.0)
            assert np.abs(dq[m.act_coord] - kin.J_ax[k, :, j]).max() < 1e-6 * max(np.abs(kin.J_ax[k]).max(), 1.0)


def _wrap(a):
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def _oracle(name, m, t, x, xd, xdd):
    """(the engine's columns of ``kin.q``, the closed form's values) for the machine's actuator
    coordinates (the Bennett linkage: its follower joint J2; angles compared wrapped)."""
    acts = m.act_coord
    if name == "stewart":
        a, b, _ = stewart.default_geometry()
        return [acts[m.actuator_names.index(f"P_{i + 1}")] for i in range(6)], \
            stewart.inverse_kinematics(a, b, x[:, :3], x[:, 3:], "XYZ")["L"]
    if name == "delta":
        g = delta.williams_irb360_geometry()
        return [acts[m.actuator_names.index(f"R_{i + 1}")] for i in range(3)], \
            delta.kinematics(x, g["R_b"], g["R_p"], g["L_A"], g["L_B"], xd, xdd)["theta"]
    if name == "rrr3":
        g = rrr3.symmetric_geometry()
        ref = rrr3.inverse_kinematics(x, g["A"], g["c"], g["l1"], g["l2"], (1, 1, 1), xd, xdd)["theta"]
        return [acts[m.actuator_names.index(f"RA_{i + 1}")] for i in range(3)], \
            ref - np.radians([0.0, 120.0, 240.0])  # each leg's angle in its own turned frame
    if name == "bennett":
        ref = bennett.input_output(x[:, 0], np.radians(30.0), np.radians(60.0), xd[:, 0], xdd[:, 0])
        return [int(m.joint_q0[m.joint_index("J2")])], ref["theta2"][:, None]
    if name == "hip":
        from oracles import hip
        from pkmdyn.machines.hip_simulator import load_params

        ref = hip.kinematics(load_params(), x, xd, xdd)
        return [acts[m.actuator_names.index(f"P_{i + 1}")] for i in range(3)], ref.L[:, 1]
    from pkmdyn.machines.pdm4 import inverse_kinematics, load_params

    ref = inverse_kinematics(load_params(), SimpleNamespace(t=t, q=x, qd=xd, qdd=xdd))
    return [acts[m.actuator_names.index(nm)] for nm in ("P11", "P12", "P23", "P24")], ref.pos.l


@pytest.mark.parametrize("name", sorted(MACHINES))
def test_actuator_coordinates_against_the_closed_form(name):
    m = _model(name)
    (t, x, xd, xdd), _ = _motion(m, name, n=30)
    kin = solve_kinematics(m, x, xd, xdd, t)
    cols, ref = _oracle(name, m, t, x, xd, xdd)
    got = kin.q[:, cols]
    angular = [m.coord_motion[c] < 3 for c in cols]  # rotation coordinates: compare wrapped
    diff = np.where(angular, _wrap(got - ref), got - ref)
    assert np.abs(diff).max() < 1e-9 * max(float(np.abs(ref).max()), 1.0)


def _hip_with_every_friction():
    """The built-in hip with every friction family of Table 2 on and a platform mass (so that
    the thrust bearing's offset m_m g of Eq. 16 counts)."""
    from pkmdyn.machines.hip_simulator import model_from_dict
    from pkmdyn.machines.hip_simulator.params import default_params_dict

    d = default_params_dict()
    d["friction"].update(slider_coulomb_N=8.0, slider_viscous_Ns_m=30.0, screw_coulomb_Nm=0.02,
                         screw_viscous_Nms_rad=2e-4, spherical_coulomb_Nm=0.2, spherical_viscous_Nms_rad=0.02,
                         universal_coulomb_Nm=0.15, universal_viscous_Nms_rad=0.03)
    d["inertia"]["platform_mass_kg"] = 2.5
    return model_from_dict(d, "every friction")


@pytest.mark.parametrize("variant", ["built-in", "every friction"])
def test_hip_against_its_closed_form_oracle(variant):
    """The hip's description through the engine against Eq. 1-16 (tests/oracles/hip.py) on the
    conformance motion with a varying hydraulic load, 1e-9 of each quantity's largest value:
    every body's kinematics and J_ax; M, h, B and the inverse and forward dynamics of the verbs;
    the motor torques from the joint reactions and every part of their split (platform, lever,
    slider, screw rotor, friction, the Eq. 16 share); the single-sample verbs."""
    from hip_helpers import engine, engine_torques, kinematics_against_oracle
    from oracles import hip
    from pkmdyn.machines.hip_simulator import load_params

    model = load_params() if variant == "built-in" else _hip_with_every_friction()
    m = engine(model)
    (t, x, xd, xdd), _ = _motion(m, "hip", n=30)
    load = 800.0 + 600.0 * np.sin(3.0 * t) ** 2
    assert kinematics_against_oracle(model, x, xd, xdd, t) < 1e-9
    ref = hip.inverse_dynamics(model, hip.kinematics(model, x, xd, xdd), load)
    eng = engine_torques(model, x, xd, xdd, load, t)
    for part in ("tau", *hip.PARTS, "hip_friction", "power"):
        assert _rel(getattr(eng, part), getattr(ref, part)) < 1e-9, part
    assert np.abs(ref.hip_friction).max() > 1e-4 * np.abs(ref.tau).max()
    if variant == "every friction":
        assert np.abs(ref.friction - ref.hip_friction).max() > 1e-2 * np.abs(ref.tau).max()
    V = machine_verbs(m)
    assert _rel(V.mass_matrix(m, x), hip.mass_matrix(model, x)) < 1e-9
    assert _rel(V.bias_forces(m, x, xd, load), hip.bias_forces(model, x, xd, load)) < 1e-9
    assert _rel(V.actuator_map(m, x), hip.actuator_map(model, x)) < 1e-9
    u = V.inverse_dynamics(m, x, xd, xdd, load)
    assert _rel(u, ref.tau) < 1e-9
    assert _rel(V.forward_dynamics(m, x, xd, ref.tau, load), xdd) < 1e-9
    for k in (0, 7, 29):
        assert _rel(V.inverse_dynamics_one(m, x[k], xd[k], xdd[k], load[k]), ref.tau[k]) < 1e-9
        assert _rel(V.forward_dynamics_one(m, x[k], xd[k], ref.tau[k], load[k]), xdd[k]) < 1e-9
