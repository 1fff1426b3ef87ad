"""Described mechanisms as machines: the verbs of pkmdyn.machine_protocol in task coordinates, and
closed-loop control from the command line."""

from __future__ import annotations

import json

import numpy as np
import pytest

import multibody_examples as ex
from pkmdyn.errors import ParameterError
from pkmdyn.multibody import load_mechanism, reference_task, solve_kinematics
from pkmdyn.multibody.dynamics.newton_euler import energies, joint_reactions
from pkmdyn.multibody.dynamics.verbs import machine_verbs


def _friction(d):
    for leg in d.get("legs", []):
        for j in leg["joints"]:
            if j["type"] == "spherical":
                j["friction"] = {"coulomb_torque_Nm": 0.1, "viscous_Nm_s_rad": 0.05}
            if j["type"] in ("prismatic", "revolute"):
                j["friction"] = {"coulomb_force_N": 5.0, "viscous_N_s_m": 20.0, "coulomb_torque_Nm": 0.2,
                                 "viscous_Nm_s_rad": 0.1}
    return d


CASES = {
    "stewart": lambda: ex.builtin_dict("stewart"),
    "stewart_friction": lambda: _friction(ex.builtin_dict("stewart")),
    "delta_friction": lambda: _friction(ex.builtin_dict("delta")),
    "bennett": lambda: ex.builtin_dict("bennett"),
    "four_bar_cut_b": ex.four_bar_cut_b,
}


def _state(m, n=12, seed=0):
    t = np.linspace(0.0, 0.8, n)
    amp = np.where(m.task_kind == 1, 0.04, 0.02 * m.length_scale)
    return t, *ex.smooth_motion(reference_task(m), amp, t, seed)


@pytest.mark.parametrize("name", sorted(CASES))
def test_forward_of_inverse_is_identity(name):
    m = load_mechanism(CASES[name]())
    V = machine_verbs(m)
    t, x, xd, xdd = _state(m)
    u = V.inverse_dynamics(m, x, xd, xdd, None)
    a = V.forward_dynamics(m, x, xd, u, None)
    assert np.abs(a - xdd).max() <= 1e-10 * np.abs(xdd).max()
    for k in (0, 5):
        assert np.allclose(V.forward_dynamics_one(m, x[k], xd[k], u[k], None), a[k], rtol=0, atol=1e-10 * np.abs(a).max())
        assert np.allclose(V.inverse_dynamics_one(m, x[k], xd[k], xdd[k], None), u[k], rtol=0,
                           atol=1e-10 * np.abs(u).max())


@pytest.mark.parametrize("name", ["stewart", "delta_friction", "four_bar_cut_b"])
def test_actuator_accelerations_are_the_time_derivative_of_the_actuator_rates(name):
    """``actuator_accelerations`` against a central difference in time of ``B^T xd`` along a
    smooth motion (step 1e-4 s: truncation ~1e-8 relative, round-off ~1e-16 / 1e-4 ~ 1e-12
    relative; allowed 1e-6 of the largest acceleration)."""
    m = load_mechanism(CASES[name]())
    V = machine_verbs(m)
    amp = np.where(m.task_kind == 1, 0.04, 0.02 * m.length_scale)
    t = np.linspace(0.1, 0.7, 7)
    x, xd, xdd = ex.smooth_motion(reference_task(m), amp, t, 3)
    sdd = V.actuator_accelerations(m, x, xd, xdd)
    h = 1e-4

    def rates(s):
        xs, xds, _ = ex.smooth_motion(reference_task(m), amp, t + s, 3)
        return np.einsum("nij,ni->nj", V.actuator_map(m, xs), xds)

    fd = (rates(h) - rates(-h)) / (2 * h)
    assert np.abs(sdd).max() > 1e-3
    assert np.abs(sdd - fd).max() <= 1e-6 * np.abs(sdd).max()


@pytest.mark.parametrize("name", sorted(set(CASES) - {"delta_friction"}))
def test_verbs_agree_with_the_reactions_route(name):
    """B u = M xdd + h gives the efforts of the Newton-Euler route with its friction (no
    load-dependent friction here, so the two must agree exactly). Not the Delta: the verbs hold
    its idle rod spins as the kinematics do, the reactions route gives them their own dynamics."""
    m = load_mechanism(CASES[name]())
    V = machine_verbs(m)
    t, x, xd, xdd = _state(m)
    u = V.inverse_dynamics(m, x, xd, xdd, None)
    kin = solve_kinematics(m, x, xd, xdd, t)
    d = CASES[name]()
    if m.topology.overconstraints:
        import test_multibody_dynamics as td

        d = td._with_sections(d)
    r = joint_reactions(load_mechanism(d), kin)
    assert np.abs(u - r.u).max() <= 1e-9 * np.abs(r.u).max()


@pytest.mark.parametrize("name", ["stewart", "bennett", "four_bar_cut_b"])
def test_mass_matrix_is_the_kinetic_energy(name):
    """1/2 xd^T M xd equals the bodies' kinetic energy; M symmetric positive definite; B = J_ax^T."""
    m = load_mechanism(CASES[name]())
    V = machine_verbs(m)
    t, x, xd, xdd = _state(m)
    M = V.mass_matrix(m, x)
    T, _ = energies(m, solve_kinematics(m, x, xd, None, t))
    assert np.abs(0.5 * np.einsum("ni,nij,nj->n", xd, M, xd) - T).max() <= 1e-12 * T.max()
    assert np.abs(M - np.swapaxes(M, 1, 2)).max() == 0.0
    assert np.linalg.eigvalsh(M).min() > 0.0
    B = V.actuator_map(m, x)
    assert B.shape == (len(x), m.nt, m.na)


def test_bias_forces_by_finite_differences_of_the_energy():
    """With gravity only (xd = 0), h = dV/dx by central differences."""
    m = load_mechanism(ex.builtin_dict("stewart"))
    V = machine_verbs(m)
    x0 = reference_task(m) + np.array([0.01, -0.02, 0.015, 0.03, -0.02, 0.05])
    h = V.bias_forces(m, x0[None], np.zeros((1, m.nt)), None)[0]
    dV = np.empty(m.nt)
    for k in range(m.nt):
        e = np.zeros(m.nt)
        e[k] = 1e-5
        Vp = energies(m, solve_kinematics(m, (x0 + e)[None]))[1][0]
        Vm = energies(m, solve_kinematics(m, (x0 - e)[None]))[1][0]
        dV[k] = (Vp - Vm) / 2e-5
    assert np.abs(h - dV).max() <= 1e-6 * np.abs(dV).max()


def test_a_load_argument_is_refused_without_named_loads():
    m = load_mechanism(ex.builtin_dict("stewart"))
    V = machine_verbs(m)
    with pytest.raises(ParameterError, match="has no named load"):
        V.bias_forces(m, reference_task(m)[None], np.zeros((1, m.nt)), np.ones(1))


@pytest.mark.parametrize("machine", ["stewart", "delta"])
def test_closed_loop_computed_torque_from_the_command_line(tmp_path, machine):
    from pkmdyn.cli import main

    out = tmp_path / "out"
    assert main(["control", "--machine", machine, "--controller", "computed-torque", "--duration", "0.1",
                 "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["controller"] == "computed-torque" and s["cycles"] == 50
    # the plant is the controller's own model: tracking errors are tiny
    for c, v in s["coordinates"].items():
        key = next(k for k in v if k.startswith("max_abs_err"))
        assert v[key] < (0.05 if key.endswith("deg") else 1.0), (c, v)
    # a described mechanism's control run reports like every other command
    assert {p.name for p in out.iterdir()} >= {"control.csv", "summary.json", "report.html", "tracking_errors.png",
                                               "efforts.png"}
    page = (out / "report.html").read_text()
    assert "Tracking errors (reference - measured)" in page and "Actuator efforts" in page
    assert main(["control", "--machine", machine, "--duration", "0.02", "--no-plots", "--out", str(tmp_path / "np")]) == 0
    assert not list((tmp_path / "np").glob("*.png")) and (tmp_path / "np" / "report.html").is_file()


def _max_err(s, coordinate):
    v = s["coordinates"][coordinate]
    return v[next(k for k in v if k.startswith("max_abs_err"))]


def test_every_controller_tracks_a_described_mechanism(tmp_path):
    """Every controller on the Stewart platform from the command line, its gains tuned from the
    mechanism's inertia (5 Hz, damping 0.7). With the plant equal to the model, the model-based
    laws track to far below a millimetre; the PD without gravity compensation sags by about
    g / wn^2 (9.9 mm) along the vertical; a stiffer PD from --gains sags less by its gain ratio."""
    from pkmdyn.cli import main

    sag = 9.80665 / (2 * np.pi * 5.0) ** 2 * 1e3  # [mm]
    res = {}
    for c in ("computed-torque", "augmented-pd", "feedforward", "pd", "pid"):
        out = tmp_path / c
        assert main(["control", "--machine", "stewart", "--controller", c, "--duration", "0.4",
                     "--out", str(out)]) == 0
        res[c] = json.loads((out / "summary.json").read_text())
        assert res[c]["controller"] == c
    for c in ("computed-torque", "augmented-pd", "feedforward"):
        assert max(_max_err(res[c], k) for k in ("x", "y", "z")) < 0.2, c
    assert 0.5 * sag < _max_err(res["pd"], "z") < 1.5 * sag
    assert max(_max_err(res["pid"], k) for k in ("x", "y", "z")) < 2 * sag
    gains = tmp_path / "stiff.toml"
    from pkmdyn.jobs.control import described_control_settings

    m = load_mechanism(ex.builtin_dict("stewart"))
    pd = described_control_settings(m)["pd"]
    gains.write_text("[pd]\nkp_si = [%s]\nkd_si = [%s]\n" % (", ".join(str(4 * v) for v in pd["kp_si"]),
                                                            ", ".join(str(2 * v) for v in pd["kd_si"])))
    out = tmp_path / "stiff"
    assert main(["control", "--machine", "stewart", "--controller", "pd", "--duration", "0.4", "--gains", str(gains),
                 "--out", str(out)]) == 0
    ratio = _max_err(res["pd"], "z") / _max_err(json.loads((out / "summary.json").read_text()), "z")
    assert 2.5 < ratio < 6.0


def test_described_control_refuses_bad_settings_by_key(tmp_path, capsys):
    from pkmdyn.cli import main

    for text, word in (("[pd]\nkp_N_m = [1.0]\n", "kp_N_m"), ("[pd]\nkp_si = [1.0]\n", "kp_si"),
                       ("[mismatch]\nmass_factor = 2.0\n", "mismatch"),  # the plant is the model itself
                       # the limits of the papers' machines' loops hold here too: cycles, steps, filters
                       ("[timing]\ncontrol_cycle_s = 1e-8\nintegration_step_s = 1e-8\n", "control cycles"),
                       ("[timing]\ncontrol_cycle_s = 0.002\nintegration_step_s = 1e-6\n", "steps per control cycle"),
                       ("[sensors]\nvelocity_cutoff_Hz = 400.0\n", "Nyquist"),
                       ("[sensors]\nexact_encoders = 2\n", "exact_encoders")):
        bad = tmp_path / "bad.toml"
        bad.write_text(text)
        code = main(["control", "--machine", "stewart", "--controller", "pd", "--gains", str(bad),
                     "--out", str(tmp_path / "o")])
        err = capsys.readouterr().err.strip()
        assert code == 2 and word in err and len(err.splitlines()) == 1 and not (tmp_path / "o").exists(), err


@pytest.mark.parametrize("name", ["hip", "pdm"])
def test_a_described_mechanism_named_like_a_hand_built_machine_controls_as_itself(tmp_path, name):
    """The control job takes a described mechanism's columns from its description, whatever its
    name: a copy of rrr3 renamed after a hand-built machine writes the same control.csv as rrr3
    (before, the name routed it to that machine's columns and the run failed)."""
    from pkmdyn.cli import main

    text = (ex.MACHINES / "rrr3" / "rrr3.toml").read_text(encoding="utf-8")
    assert 'name = "rrr3"' in text
    renamed = tmp_path / "renamed.toml"
    renamed.write_text(text.replace('name = "rrr3"', f'name = "{name}"', 1), encoding="utf-8")
    for machine, out in (("rrr3", tmp_path / "a"), (str(renamed), tmp_path / "b")):
        assert main(["control", "--machine", machine, "--duration", "0.04", "--out", str(out)]) == 0
    assert (tmp_path / "a" / "control.csv").read_bytes() == (tmp_path / "b" / "control.csv").read_bytes()
    assert json.loads((tmp_path / "b" / "summary.json").read_text())["machine"] == name


def test_one_set_of_verbs_serves_a_plant_beside_the_controllers_model():
    """The controller's model and a plant with other masses (a mismatch study) through one set
    of verbs, as the closed loop calls them: each model keeps its own warm start and compiled
    state, so interleaved calls answer as separate verbs would; a model of another mechanism
    is refused."""
    d = ex.builtin_dict("stewart")
    m = load_mechanism(d)
    for body in d["bodies"]:
        if "mass_kg" in body:
            body["mass_kg"] *= 1.3
    plant = load_mechanism(d)
    _, x, xd, xdd = _state(m, 8)
    shared = machine_verbs(m)
    alone_m, alone_p = machine_verbs(m), machine_verbs(plant)
    u = alone_m.inverse_dynamics(m, x, xd, xdd)
    for i in range(len(x)):
        a_m = shared.forward_dynamics_one(m, x[i], xd[i], u[i])
        a_p = shared.forward_dynamics_one(plant, x[i], xd[i], u[i])
        assert np.allclose(a_m, alone_m.forward_dynamics_one(m, x[i], xd[i], u[i]), rtol=1e-10, atol=1e-12)
        assert np.allclose(a_p, alone_p.forward_dynamics_one(plant, x[i], xd[i], u[i]), rtol=1e-10, atol=1e-12)
        assert np.allclose(a_m, xdd[i], rtol=1e-7, atol=1e-9 * np.abs(xdd).max())
        assert not np.allclose(a_p, a_m, rtol=1e-3)  # heavier bodies: another answer
    with pytest.raises(ParameterError, match="belong to mechanism"):
        shared.mass_matrix(load_mechanism(ex.builtin_dict("delta")), reference_task(m)[None])


def test_exact_encoders_read_the_plants_kinematics_and_the_pose_comes_from_the_direct_kinematics():
    """Exact encoders (the described default): each cycle's true actuator displacement is the
    plant's own inverse kinematics at its pose (against a batched solve of the recorded poses),
    and the controller's pose from the encoders (pose feedback off) is the direct kinematics of
    the quantised reading: within a few counts of the true pose. The first-order encoders of
    the hand-built machines differ from the exact ones by the second order of the tracking
    error, here made large by a heavier plant and a soft PD."""
    from dataclasses import replace

    from pkmdyn.jobs.control import described_control_settings
    from pkmdyn.control import gains, hermite_motion, loop_settings
    from pkmdyn.multibody import default_motion
    from pkmdyn.simulate import track

    d = ex.builtin_dict("stewart")
    m = load_mechanism(d)
    for body in d["bodies"]:
        body["mass_kg"] *= 3.0
    plant = load_mechanism(d)
    settings = described_control_settings(m)
    settings["sensors"]["pose_feedback_from_sensor"] = 0
    ls = loop_settings(settings)
    assert ls.exact_encoders
    mo = default_motion(m)
    fn = hermite_motion(mo.t, mo.x, mo.xd, mo.xdd, None)
    V = machine_verbs(m)
    g = gains(settings, "pd", m.nt)
    res = {}
    for exact in (True, False):
        res[exact] = track(V, m, plant, fn, 0.3, "pd", g, replace(ls, exact_encoders=exact), False).result
    r = res[True]
    kin = solve_kinematics(plant, r.q)
    a0 = solve_kinematics(plant, r.q[:1]).act_q[0]
    assert np.abs(r.s - m.drive_ratio * (kin.act_q - a0)).max() <= 1e-12
    count = float(np.max(ls.encoder_resolution))
    Jmax = np.abs(kin.J_ax).max()
    # the pose from the quantised reading: within a few counts of the truth (through dx/ds)
    lin = np.abs(r.q_s - r.q)[:, :3].max()
    assert lin <= 10 * count * max(1.0, 1.0 / Jmax)
    # first-order encoders: their reading is off the true displacement by the second order of the
    # tracking error (and the first-order pose inverts that same map, so it cannot see it)
    rl = res[False]
    a_true = solve_kinematics(plant, rl.q).act_q
    off = np.abs(rl.s - m.drive_ratio * (a_true - a0)).max()
    track_err = np.abs(rl.q - fn(rl.t)[0])[:, :3].max()
    assert track_err > 1e-3  # a soft PD on a heavier plant: millimetres
    assert 1e3 * 1e-12 < off <= 10.0 * track_err ** 2 / m.length_scale


def test_encoder_readings_follow_their_own_previous_reading():
    """The plant's encoder reading (exact encoders) starts from the reference assembly and then
    from its own previous reading, whatever the verbs solved in between (a batch far along the
    motion): it equals the inverse kinematics reached from the reference pose."""
    m = load_mechanism(ex.builtin_dict("stewart"))
    V = machine_verbs(m)
    x0 = reference_task(m)
    far = x0 + np.array([0.05, 0.0, 0.0, 0.6, 0.0, 0.0])
    zero = np.zeros(m.nt)
    first = V.actuator_coordinates_one(m, x0, zero, fresh=True)
    for k in range(5):
        V.mass_matrix(m, far[None])  # another verb solves far away
        x = x0 + 0.002 * k
        got = V.actuator_coordinates_one(m, x, zero)
        want = solve_kinematics(m, x[None]).act_q[0]
        assert np.abs(got - want).max() <= 1e-12
    assert np.abs(first - solve_kinematics(m, x0[None]).act_q[0]).max() <= 1e-12


@pytest.mark.parametrize("name", ["stewart", "delta", "bennett"])
def test_encoder_readings_one_at_a_time_are_the_inverse_kinematics(name):
    """The plant's encoders one reading at a time (``actuator_coordinates_one``: one compiled
    call from the previous reading's solution, the checked route where it cannot answer) read
    the batched inverse kinematics' actuated coordinates along a motion; the compiled call
    answered; a non-finite pose is refused by the checked route."""
    from pkmdyn.errors import MotionError
    from pkmdyn.multibody.dynamics import _sample_kernels as _one

    m = load_mechanism(ex.builtin_dict(name))
    t = np.linspace(0.0, 0.8, 200)
    amp = np.where(m.task_kind == 1, 0.04, 0.02 * m.length_scale)
    x, xd, xdd = ex.smooth_motion(reference_task(m), amp, t, 3)
    kin = solve_kinematics(m, x, xd, xdd, t)
    V = machine_verbs(m)
    got = np.array([V.actuator_coordinates_one(m, x[k], xd[k], fresh=k == 0) for k in range(len(t))])
    scale = np.where(m.coord_motion[m.act_coord] >= 3, 1.0 / m.length_scale, 1.0)
    assert np.abs((got - kin.act_q) * scale).max() <= 1e-12
    st = V._state(m)
    if _one.supported(m):
        # the compiled call answered: by the closed forms alone where every actuated coordinate
        # belongs to a leg placed from the task alone, else by the full solve
        alone = m.legs.count > 0 and np.all(m.legs.fixed_coord[m.act_coord] == 1)
        assert _one.state(st.encoder_pk)[0] == (_one.ALONE if alone else _one.FACTORED)
        assert alone == (name == "stewart")
    bad = x[5].copy()
    bad[0] = np.nan
    with pytest.raises(MotionError):
        V.actuator_coordinates_one(m, bad, xd[5])


def test_hip_encoder_readings_by_the_upper_legs_alone():
    """The hip's sliders are set by its upper legs, placed from the task alone: the readings
    one at a time come from those closed forms alone (no Newton on the lower platform) and are
    the batched inverse kinematics' sliders."""
    from pkmdyn.machines.hip_simulator import load_params
    from pkmdyn.machines.hip_simulator.description import hip_description
    from pkmdyn.multibody.dynamics import _sample_kernels as _one

    m = load_mechanism(hip_description(load_params()))
    t = np.linspace(0.0, 0.8, 200)
    x, xd, xdd = ex.smooth_motion(reference_task(m), np.full(m.nt, 0.1), t, 5)
    kin = solve_kinematics(m, x, xd, xdd, t)
    V = machine_verbs(m)
    got = np.array([V.actuator_coordinates_one(m, x[k], xd[k], fresh=k == 0) for k in range(len(t))])
    assert np.abs((got - kin.act_q) / m.length_scale).max() <= 1e-12
    assert _one.state(V._state(m).encoder_pk)[0] == _one.ALONE
