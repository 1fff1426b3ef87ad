"""The compiled single-sample dynamics of described mechanisms (``pkmdyn.multibody.dynamics._sample_kernels``):
one call per sample, equal to the batched verbs, falling back where it cannot answer."""

from __future__ import annotations

import numpy as np
import pytest

import multibody_examples as ex
from pkmdyn.multibody import load_mechanism, reference_task
from pkmdyn.multibody.dynamics import _sample_kernels as _one
from pkmdyn.multibody.dynamics.verbs import machine_verbs

CASES = {"stewart": lambda: ex.builtin_dict("stewart"), "delta": lambda: ex.builtin_dict("delta"),
         "bennett": lambda: ex.builtin_dict("bennett"), "rrr3": lambda: ex.builtin_dict("rrr3"),
         "four_bar": ex.four_bar, "stewart_sps": ex.stewart_sps, "stewart_with_tool": ex.stewart_with_tool}


def _motion(m, n=40, seed=4):
    t = np.linspace(0.0, 1.0, n)
    amp = np.where(m.task_kind == 1, 0.05, 0.03 * m.length_scale)
    return ex.smooth_motion(reference_task(m), amp, t, seed)


def _with_load(d):
    d = ex.deep(d)
    body = d["task"]["body"]
    d["loads"] = [{"body": body, "force_N": [3.0, -2.0, -40.0], "moment_Nm": [0.5, 0.2, -0.3]}]
    return d


@pytest.mark.parametrize("name", sorted(CASES))
def test_the_compiled_sample_equals_the_batched_verbs(name):
    """Along a motion, sample after sample (each call starting from the previous solution), the
    compiled forward and inverse dynamics equal the batched verbs (a constant load on the task
    body included); the first call has no previous solution and takes the general route."""
    m = load_mechanism(_with_load(CASES[name]()))
    assert _one.supported(m)
    x, xd, xdd = _motion(m)
    ref = machine_verbs(m)
    u = ref.inverse_dynamics(m, x, xd, xdd)
    a_ref = ref.forward_dynamics(m, x, xd, u)
    V = machine_verbs(m)
    p, inverse, forward = V.one_sample_kernels(m)
    out = np.empty(m.nt)
    assert forward(p, x[0], xd[0], u[0], 0.0, out) == _one.COLD  # nothing solved yet
    scale_a = max(np.abs(a_ref).max(), 1e-9)
    scale_u = max(np.abs(u).max(), 1e-9)
    a = V.forward_dynamics_one(m, x[0], xd[0], u[0])  # the general route, which primes the kernel
    assert np.abs(a - a_ref[0]).max() <= 1e-9 * scale_a
    for i in range(1, len(x)):
        # the kernel itself, from the previous sample's solution (predictor and Newton)
        assert forward(p, x[i], xd[i], u[i], 0.0, out) == 0, (name, i)
        assert np.abs(out - a_ref[i]).max() <= 1e-9 * scale_a, (name, i)
        assert inverse(p, x[i], xd[i], xdd[i], 0.0, out) == 0
        assert np.abs(out - u[i]).max() <= 1e-9 * scale_u, (name, i)
        a = V.forward_dynamics_one(m, x[i], xd[i], u[i])
        assert np.abs(a - a_ref[i]).max() <= 1e-9 * scale_a, (name, i)
    assert np.abs(a_ref - xdd).max() <= 1e-8 * max(np.abs(xdd).max(), 1e-9)


def test_a_far_jump_and_a_failed_solve_fall_back():
    """A pose far from the last one still comes out exact (Newton from a poor start, or the
    general route); a pose the mechanism cannot reach gives the general route's error."""
    from pkmdyn.errors import PkmdynError

    m = load_mechanism(ex.builtin_dict("stewart"))
    x, xd, xdd = _motion(m)
    V = machine_verbs(m)
    u = V.inverse_dynamics(m, x, xd, xdd)
    V.forward_dynamics_one(m, x[0], xd[0], u[0])
    far = x[-1].copy()
    far[2] += 0.5 * m.length_scale
    far[3] += 0.2
    ref = machine_verbs(m).forward_dynamics(m, far[None], xd[-1:], u[-1:])[0]
    a = V.forward_dynamics_one(m, far, xd[-1], u[-1])
    assert np.abs(a - ref).max() <= 1e-9 * np.abs(ref).max()
    md = load_mechanism(ex.builtin_dict("delta"))
    x, xd, xdd = _motion(md)
    Vd = machine_verbs(md)
    u = Vd.inverse_dynamics(md, x, xd, xdd)
    Vd.forward_dynamics_one(md, x[0], xd[0], u[0])
    out_of_reach = x[0] + 10.0 * md.length_scale
    with pytest.raises(PkmdynError):
        Vd.forward_dynamics_one(md, out_of_reach, xd[0], u[0])
    a = Vd.forward_dynamics_one(md, x[1], xd[1], u[1])  # and it goes on from there
    assert np.abs(a - xdd[1]).max() <= 1e-8 * np.abs(xdd).max()


def test_friction_that_depends_on_the_reactions_takes_the_general_route():
    d = ex.builtin_dict("stewart")
    d["legs"][0]["joints"][1]["friction"] = {"coefficient": 0.1}
    m = load_mechanism(d)
    assert not _one.supported(m)
    V = machine_verbs(m)
    assert V.one_sample_kernels(m) is None
    x, xd, xdd = _motion(m, n=5)
    u = V.inverse_dynamics(m, x, xd, xdd)
    a = V.forward_dynamics_one(m, x[2], xd[2], u[2])
    assert np.abs(a - xdd[2]).max() <= 1e-8 * np.abs(xdd).max()


def test_the_compiled_sample_with_friction_and_a_named_load():
    """Coulomb and viscous friction on every joint, friction driven by a named load and the
    load itself, varying along the motion: the compiled sample equals the batched verbs; the
    hip's description (every friction family, the ISO load) likewise."""
    from pkmdyn.machines.hip_simulator import model_from_dict
    from pkmdyn.machines.hip_simulator.description import hip_description
    from pkmdyn.machines.hip_simulator.params import default_params_dict
    from pkmdyn.profiles.iso14242 import iso14242_motion

    d = _every_joint_with_friction(ex.builtin_dict("stewart"))
    plat = next(b for b in d["bodies"] if b["name"] == "platform")
    d["loads"] = [{"name": "push_N", "body": "platform", "direction": [0.2, 0.1, -1.0],
                   "point_m": (np.array(plat["com_m"]) + [0.03, 0.0, 0.0]).tolist()}]
    d["legs"][0]["joints"][-1]["friction"]["external"] = [{"load": "push_N", "coefficient": 0.1, "radius_m": 0.02,
                                                           "offset_N": -50.0}]
    m = load_mechanism(d)
    x, xd, xdd = _motion(m)
    F = 300.0 + 200.0 * np.sin(np.linspace(0.0, 6.0, len(x)))
    hd = default_params_dict()
    for key, v in (("slider_coulomb_N", 5.0), ("slider_viscous_Ns_m", 20.0), ("spherical_coulomb_Nm", 0.1),
                   ("spherical_viscous_Nms_rad", 0.01), ("universal_coulomb_Nm", 0.1),
                   ("universal_viscous_Nms_rad", 0.01)):
        hd["friction"][key] = v
    hd["inertia"]["platform_mass_kg"] = 2.0
    mh = load_mechanism(hip_description(model_from_dict(hd, "friction")))
    mo = iso14242_motion(cycles=0.1, samples_per_cycle=400)
    for mech, (x, xd, xdd, F) in ((m, (x, xd, xdd, F)), (mh, (mo.angles, mo.rates, mo.accels, mo.load))):
        assert _one.supported(mech)
        ref = machine_verbs(mech)
        u = ref.inverse_dynamics(mech, x, xd, xdd, F)
        a_ref = ref.forward_dynamics(mech, x, xd, u, F)
        V = machine_verbs(mech)
        p, inverse, forward = V._state(mech).pk, _one.inverse_one, _one.forward_one
        out = np.empty(mech.nt)
        V.forward_dynamics_one(mech, x[0], xd[0], u[0], float(F[0]))  # primes the kernel
        for i in range(1, len(x)):
            assert forward(p, x[i], xd[i], u[i], float(F[i]), out) == 0
            assert np.abs(out - a_ref[i]).max() <= 1e-9 * np.abs(a_ref).max(), (mech.name, i)
            assert inverse(p, x[i], xd[i], xdd[i], float(F[i]), out) == 0
            assert np.abs(out - u[i]).max() <= 1e-9 * np.abs(u).max(), (mech.name, i)
            a = V.forward_dynamics_one(mech, x[i], xd[i], u[i], float(F[i]))
            assert np.abs(a - a_ref[i]).max() <= 1e-9 * np.abs(a_ref).max()
        assert np.abs(a_ref - xdd).max() <= 1e-8 * np.abs(xdd).max()


def _every_joint_with_friction(d):
    d = ex.deep(d)
    joints = list(d.get("joints", []))
    for leg in d.get("legs", []):
        joints += leg["joints"]
    for k, j in enumerate(joints):
        if j["type"] != "fixed":
            j["friction"] = {"coulomb_torque_Nm": 0.1 + 0.01 * k, "viscous_Nm_s_rad": 0.05 + 0.002 * k,
                             "coulomb_force_N": 2.0 + 0.1 * k, "viscous_N_s_m": 3.0}
    return d


FRICTION_CASES = {**CASES, "four_bar_cut_b": ex.four_bar_cut_b, "cylindrical": lambda: ex.slider_crank("cylindrical"),
                  "sarrus": ex.sarrus, "flipped": ex.stewart_flipped_spheres, "rssr": ex.rssr}


@pytest.mark.parametrize("name", sorted(FRICTION_CASES))
def test_compiled_friction_equals_the_joint_by_joint_route(name):
    """The compiled friction of every joint (tree and cut; revolute, prismatic, cylindrical,
    universal, spherical): its generalised forces projected on the task rates (``G^T Q``, what
    the efforts see) equal those of the joint-by-joint route of JointFriction, and the efforts
    of inverse_dynamics equal those of the reaction solver (which balances each joint's
    friction along its free twists)."""
    from pkmdyn.multibody import solve_kinematics
    from pkmdyn.multibody.dynamics.newton_euler import coordinate_twists, free_blocks, inverse_dynamics, joint_reactions
    from pkmdyn.multibody.dynamics.friction import JointFriction, known_friction

    m = load_mechanism(_every_joint_with_friction(FRICTION_CASES[name]()))
    x, xd, xdd = _motion(m, n=25)
    kin = solve_kinematics(m, x, xd, xdd, np.linspace(0.0, 1.0, 25))
    S = coordinate_twists(m, kin.q, kin)
    jf = JointFriction(m, kin, S, free_blocks(m, kin, S))
    a = np.einsum("nct,nc->nt", kin.G, jf.generalised(jf.initial()))
    b = np.einsum("nct,nc->nt", kin.G, known_friction(m, kin, S))
    assert np.abs(a).max() > 0.05
    assert np.abs(a - b).max() <= 1e-12 * np.abs(a).max()
    u = inverse_dynamics(m, kin).u
    r = joint_reactions(m, kin, overconstrained="minimum-norm").u
    assert np.abs(u - r).max() <= 1e-10 * np.abs(r).max()


def test_the_general_route_starts_where_the_kernel_left_off():
    """After a run of compiled samples, a batched verb solves the same assembly branch as a
    fresh set of verbs that followed the motion itself (the kernel's solution is the start)."""
    m = load_mechanism(ex.builtin_dict("rrr3"))
    x0 = reference_task(m)
    steps = np.linspace(0.0, 1.0, 200)[:, None]
    amp = np.where(m.task_kind == 1, 0.3, 0.15 * m.length_scale)
    x = x0 + steps * amp
    zero = np.zeros(m.nt)
    V = machine_verbs(m)
    for xi in x:
        V.forward_dynamics_one(m, xi, zero, zero)
    from pkmdyn.multibody.dynamics import _sample_kernels as _one

    assert _one.solution(V._state(m).pk) is not None
    ref = machine_verbs(m)
    from pkmdyn.multibody import solve_kinematics

    q_ref = solve_kinematics(m, x).q[-1]
    assert np.abs(V._state(m).last_q() - q_ref).max() <= 1e-8
    assert np.allclose(V.mass_matrix(m, x[-1:]), ref.mass_matrix(m, solve_kinematics(m, x).x[-1:]), rtol=1e-9)


def test_non_finite_input_goes_to_the_checked_verb():
    from pkmdyn.errors import MotionError

    m = load_mechanism(ex.builtin_dict("stewart"))
    x, xd, xdd = _motion(m, n=5)
    V = machine_verbs(m)
    u = V.inverse_dynamics(m, x, xd, xdd)
    V.forward_dynamics_one(m, x[0], xd[0], u[0])
    p, _, forward = V.one_sample_kernels(m)
    bad = xd[1].copy()
    bad[2] = np.nan
    out = np.empty(m.nt)
    assert forward(p, x[1], bad, u[1], 0.0, out) != 0
    with pytest.raises(MotionError):
        V.forward_dynamics_one(m, x[1], bad, u[1])


def test_no_kernels_for_a_plant_that_would_pass_a_wrong_load():
    """A caller without a load passes 0.0: with a named load whose default magnitude is not
    zero the kernels are withheld (the verbs still answer, with the default)."""
    d = ex.builtin_dict("stewart")
    d["loads"] = [{"name": "push_N", "body": "platform", "direction": [0.0, 0.0, -1.0], "magnitude_N": 100.0}]
    m = load_mechanism(d)
    V = machine_verbs(m)
    assert V.one_sample_kernels(m) is None
    x, xd, xdd = _motion(m, n=3)
    u = V.inverse_dynamics(m, x, xd, xdd)
    assert np.allclose(V.forward_dynamics_one(m, x[1], xd[1], u[1]), xdd[1], rtol=1e-8, atol=1e-10)
    d["loads"][0]["magnitude_N"] = 0.0
    m0 = load_mechanism(d)
    assert machine_verbs(m0).one_sample_kernels(m0) is not None


@pytest.mark.parametrize("name", sorted(CASES))
def test_consecutive_samples_need_no_newton_step_after_the_simplified_step(name):
    """On the consecutive samples of a 1 kHz loop, the second-order predictor and one
    simplified Newton step with the previous sample's factors close the loops to the solver's
    tolerance: with the Newton steps limited to none (header entry 3 of the packed integers),
    every call after the kernel's first still converges, and equals the batched verbs."""
    m = load_mechanism(CASES[name]())
    t = np.arange(0.0, 0.3, 1e-3)
    amp = np.where(m.task_kind == 1, 0.05, 0.03 * m.length_scale)
    x, xd, xdd = ex.smooth_motion(reference_task(m), amp, t, 7)
    ref = machine_verbs(m)
    u = ref.inverse_dynamics(m, x, xd, xdd)
    V = machine_verbs(m)
    V.forward_dynamics_one(m, x[0], xd[0], u[0])  # primes the kernel (no factors yet)
    p, _, forward = V.one_sample_kernels(m)
    out = np.empty(m.nt)
    assert forward(p, x[1], xd[1], u[1], 0.0, out) == 0  # Newton from the first-order predictor
    assert p[3] > 0  # the Newton step limit (header entry 3 of the packed buffer)
    p[3] = 0
    scale = max(np.abs(xdd).max(), 1e-9)
    for i in range(2, len(x)):
        assert forward(p, x[i], xd[i], u[i], 0.0, out) == 0, (name, i)
        assert np.abs(out - xdd[i]).max() <= 1e-8 * scale, (name, i)


def test_sines_and_cosines_from_a_nearby_angle_are_exact_to_rounding():
    """The pass after the simplified Newton step takes each turning coordinate's sine and cosine
    from the previous pass by angle addition (``_kernels._cos_sin``): within 1e-3 rad of the
    kept angle they equal the library's to a few units of rounding; farther, or without
    ``reuse``, they are the library's own, and the kept angle moves on."""
    from pkmdyn.multibody.model._tree_kernels import (_cos_sin)

    rng = np.random.default_rng(3)
    trig = np.zeros((1, 3))
    worst = 0.0
    for q0 in rng.uniform(-7.0, 7.0, 200):
        _cos_sin(trig, 0, q0, False)
        assert (trig[0, 0], trig[0, 1], trig[0, 2]) == (np.cos(q0), np.sin(q0), q0)
        for d in (1e-12, -3e-9, 2e-6, -4e-5, 9.9e-4):
            trig[0] = (np.cos(q0), np.sin(q0), q0)
            c, s = _cos_sin(trig, 0, q0 + d, True)
            worst = max(worst, abs(c - np.cos(q0 + d)), abs(s - np.sin(q0 + d)))
            assert trig[0, 2] == q0 + d
        trig[0] = (0.25, 0.5, q0)  # not the sine and cosine of q0: a far angle must not use them
        assert _cos_sin(trig, 0, q0 + 2e-3, True) == (np.cos(q0 + 2e-3), np.sin(q0 + 2e-3))
    assert worst < 1e-15


@pytest.mark.parametrize("name", sorted(CASES))
def test_a_sample_at_rest_after_moving_ones_equals_the_full_passes(name):
    """A sample at rest (the task's rates zero), taken after moving samples whose velocities and
    accelerations fill the kernel's buffers, skips the passes of the rates: its efforts and
    accelerations equal those of the same sample at a velocity of 1e-200 (which takes every pass,
    its velocity terms below any rounding), and forward(inverse) is the identity."""
    m = load_mechanism(_with_load(CASES[name]()))
    x, xd, xdd = _motion(m)
    tiny = np.full(m.nt, 1e-200)
    out = {}
    for label, v in (("rest", np.zeros(m.nt)), ("tiny", tiny)):
        V = machine_verbs(m)
        for i in range(12):  # moving samples first
            V.forward_dynamics_one(m, x[i], xd[i], V.inverse_dynamics_one(m, x[i], xd[i], xdd[i]))
        u = V.inverse_dynamics_one(m, x[12], v, xdd[12])
        out[label] = (u, V.forward_dynamics_one(m, x[12], v, u))
    (u0, a0), (u1, a1) = out["rest"], out["tiny"]
    assert np.abs(u0 - u1).max() <= 1e-12 * max(np.abs(u1).max(), 1e-9), name
    assert np.abs(a0 - a1).max() <= 1e-10 * max(np.abs(a1).max(), 1e-9), name
    assert np.abs(a0 - xdd[12]).max() <= 1e-8 * max(np.abs(xdd[12]).max(), 1e-9), name
