"""The closed loop's cycles in one compiled call (pkmdyn.simulate._cycles) against the same
cycles in Python (``compiled_cycles = False``): the same records, step counts and end state for
every law, with exact and first-order encoders, a plant other than the controller's model, joint
friction that takes the integrator into its ROS2 and refined steps; the same message where a run
diverges; and a run compiles nothing but the signature the install compiles."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import multibody_examples as ex
from pkmdyn.jobs.control import described_control_settings
from pkmdyn.control import gains, hermite_motion, loop_settings
from pkmdyn.multibody import default_motion, load_mechanism
from pkmdyn.multibody.dynamics.verbs import machine_verbs
from pkmdyn.simulate import DivergenceError, track
from pkmdyn.simulate import _cycles

FIELDS = ("q", "qd", "u", "q_s", "qd_s", "q_att", "s", "s_enc", "sd_enc", "sdd_enc", "q_end", "qd_end")


@pytest.fixture(scope="module", autouse=True)
def _compiled():
    _cycles.compile_for_runs()  # once per cache (some 30 s cold)


def _stewart(mass=1.0, friction=None):
    d = ex.builtin_dict("stewart")
    for body in d["bodies"]:
        if "mass_kg" in body:
            body["mass_kg"] *= mass
    for leg in d["legs"]:
        for body in leg["bodies"]:
            if "mass_kg" in body:
                body["mass_kg"] *= mass
        for j in leg["joints"]:
            if friction is not None and j["name"] == "P":
                j["friction"] = dict(friction)
    return load_mechanism(d)


def _counted(monkeypatch):
    """A list that receives the cycles each compiled call takes."""
    taken = []
    run = _cycles.CompiledCycles.run

    def counted(self, i0, i1, *rest):
        j = run(self, i0, i1, *rest)
        taken.append(j - i0)
        return j

    monkeypatch.setattr(_cycles.CompiledCycles, "run", counted)
    return taken


def _motion(m, load=None):
    mo = default_motion(m)
    return hermite_motion(mo.t, mo.x, mo.xd, mo.xdd, None if load is None else load(mo.t))


def _both(m, plant, law, seconds, ls, monkeypatch, load=None):
    """The run through the compiled cycles and through Python, and the cycles the compiled
    calls took."""
    settings = described_control_settings(m)
    g = gains(settings, law, m.nt)
    fn = _motion(m, load)
    taken = _counted(monkeypatch)
    out = {}
    for flag in (True, False):
        tr = track(machine_verbs(m), m, plant, fn, seconds, law, g, replace(ls, compiled_cycles=flag),
                   load is not None)
        out[flag] = tr
    return out[True], out[False], sum(taken)


def _settings(m, exact=True):
    settings = described_control_settings(m)
    settings["sensors"]["pose_feedback_from_sensor"] = 0
    return replace(loop_settings(settings), exact_encoders=exact)


def _same(a, b, what):
    for f in FIELDS:
        x, y = np.asarray(getattr(a, f), dtype=float), np.asarray(getattr(b, f), dtype=float)
        scale = max(1.0, float(np.abs(y).max()))
        assert np.abs(x - y).max() <= 1e-12 * scale, f"{what}: {f}"
    assert np.array_equal(a.saturated, b.saturated), what


@pytest.mark.parametrize("law", ["computed-torque", "pd", "augmented-pd", "feedforward", "pid"])
def test_compiled_cycles_keep_the_python_cycles_records(law, monkeypatch):
    """Exact encoders (the pose by the direct kinematics of the reading) on a plant 1.3 times as
    heavy as the controller's model (the open loop on the model itself): every record equal to
    rounding, and every cycle taken by the compiled calls (the encoders and the direct
    kinematics primed at the run's first pose)."""
    m, plant = _stewart(), _stewart(mass=1.0 if law == "feedforward" else 1.3)
    fast, slow, taken = _both(m, plant, law, 0.4, _settings(m), monkeypatch)
    _same(fast.result, slow.result, law)
    K = slow.result.q.shape[0]
    assert taken == K
    assert np.abs(fast.result.q - slow.reference.q[:K]).max() < 0.05  # a tracking run, not a stopped one


@pytest.mark.parametrize("friction", [{"coulomb_force_N": 40.0, "viscous_N_s_m": 20.0}, {"coulomb_force_N": 10.0}])
@pytest.mark.parametrize("method", ["rk3-ros2", "rk4-ros2", "ros2"])
def test_first_order_encoders_and_friction_through_the_stiff_and_refined_steps(method, friction, monkeypatch):
    """First-order encoders, and friction in the six slides sharp enough that the plant's steps
    at the legs' reversals are refined and some are ROS2 (the softer one: a step whose
    stiffness estimate lands just past the explicit step's limit), by each step method: the
    same records and the same counts of explicit and refined steps by both routes."""
    m = _stewart(friction=friction)
    ls = replace(_settings(m, exact=False), method=method)
    counts = {}
    from pkmdyn.simulate import _loop

    made = _loop.make_work

    def kept(plant, method="rk3-ros2"):
        w = made(plant, method)
        counts.setdefault(len(counts), w)
        return w

    monkeypatch.setattr(_loop, "make_work", kept)
    fast, slow, taken = _both(m, m, "computed-torque", 1.0, ls, monkeypatch)
    _same(fast.result, slow.result, "friction")
    wf, ws = counts[0], counts[1]
    assert wf.refined_steps == ws.refined_steps > 0
    assert wf.explicit_steps == ws.explicit_steps
    K = slow.result.q.shape[0]
    steps = int(round(ls.cycle_s / ls.step_s))
    if method == "ros2":
        assert wf.explicit_steps == 0
    else:  # some steps of the band taken by ROS2, the rest explicit
        assert 0 < wf.explicit_steps < K * steps - wf.refined_steps
    assert taken == K


def test_a_diverging_run_stops_with_the_python_cycles_message(monkeypatch):
    """A divergence limit the run crosses: the compiled call hands the cycle back and the same
    error, at the same time and coordinate, is raised."""
    m = _stewart()
    ls = _settings(m)
    ls = replace(ls, divergence_limit=np.full(m.nt, 1e-3))  # a heavier plant sags past 1 mm
    settings = described_control_settings(m)
    g = gains(settings, "pd", m.nt)
    mo = default_motion(m)
    fn = hermite_motion(mo.t, mo.x, mo.xd, mo.xdd, None)
    errors = []
    taken = _counted(monkeypatch)
    for flag in (True, False):
        with pytest.raises(DivergenceError) as info:
            track(machine_verbs(m), m, _stewart(mass=2.0), fn, 0.4, "pd", replace(g, kp=g.kp * 0.1),
                  replace(ls, compiled_cycles=flag), False)
        errors.append((str(info.value), info.value.coordinate, info.value.t))
    assert errors[0] == errors[1]
    assert errors[0][2] > 0.01 and sum(taken) > 0  # the compiled cycles ran before it


def test_a_run_compiles_only_the_signature_compiled_at_install(monkeypatch):
    """The loop's arguments have the types of ``example_signature`` (which the install compiles,
    ``pkmdyn compile``): a run adds no signature, and the kernel is reported available."""
    m = _stewart()
    _, _, taken = _both(m, m, "computed-torque", 0.1, _settings(m), monkeypatch)
    assert taken > 0
    assert set(_cycles.run_cycles.signatures) == {_cycles.example_signature()}
    assert _cycles.available()


@pytest.mark.parametrize("law", ["pd", "computed-torque"])
def test_spans_and_a_delayed_noisy_pose_sensor(law, monkeypatch):
    """The pose fed back from a pose sensor two cycles late with noise (the rate from the
    direct kinematics of the encoders), run whole and in spans of 37 cycles: the compiled
    cycles' spans join to the Python cycles' whole run, the spans' joint references to the
    whole run's (computed when read where the loop does not read it: computed torque)."""
    from pkmdyn.simulate import track_spans

    m = _stewart()
    ls = replace(_settings(m), pose_from_sensor=True, pose_delay_cycles=2, pose_noise=np.full(m.nt, 1e-6))
    fast, slow, taken = _both(m, m, law, 0.3, ls, monkeypatch)
    _same(fast.result, slow.result, "pose sensor")
    assert taken == slow.result.q.shape[0]
    settings = described_control_settings(m)
    mo = default_motion(m)
    fn = hermite_motion(mo.t, mo.x, mo.xd, mo.xdd, None)
    taken = _counted(monkeypatch)
    parts = list(track_spans(machine_verbs(m), m, m, fn, 0.3, law, gains(settings, law, m.nt), ls, False,
                             span_cycles=37))
    assert len(parts) > 3
    assert sum(taken) == slow.result.q.shape[0]
    for f in ("q", "qd", "u", "q_s", "qd_s", "q_att", "s_enc", "sd_enc"):
        joined = np.concatenate([getattr(p.result, f) for p in parts])
        ref = getattr(slow.result, f)
        assert np.abs(joined - ref).max() <= 1e-9 * max(1.0, float(np.abs(ref).max())), f
    for f in ("s", "sd", "Bt"):
        joined = np.concatenate([getattr(p.joint, f)[:-1] for p in parts])
        ref = getattr(slow.joint, f)[:-1]
        assert np.abs(joined - ref).max() <= 1e-12 * max(1.0, float(np.abs(ref).max())), f


@pytest.mark.parametrize("where", ["direct kinematics", "law"])
def test_a_cycle_handed_back_runs_in_python_from_the_state_it_started_from(where, monkeypatch):
    """Every compiled cycle made to fail after its encoders, sensors and filters have run (the
    direct kinematics' answer refused; the law's inverse dynamics on a buffer that has no
    solution to start from): each cycle is handed back and taken in Python from the restored
    state, and the run is the Python cycles' run (the kernels' warm starts, which are not
    restored, move the Newton solves' answers within their tolerances only)."""
    m, plant = _stewart(), _stewart(mass=1.3)
    made = _cycles.compiled_cycles

    def failing(*args, **kwargs):
        cc = made(*args, **kwargs)
        if cc is None:
            return None
        tail = list(cc.tail)
        if where == "direct kinematics":
            d = list(tail[3])
            d[3] = -99  # no status the kernel returns
            tail[3] = tuple(d)
        else:
            from pkmdyn.multibody.dynamics import _sample_kernels as _one

            c = list(tail[4])
            c[0] = c[0].copy()
            _one.state(c[0])[0] = _one.COLD_STATE
            tail[4] = tuple(c)
        cc.tail = tuple(tail)
        return cc

    monkeypatch.setattr(_cycles, "compiled_cycles", failing)
    fast, slow, taken = _both(m, plant, "computed-torque", 0.3, _settings(m), monkeypatch)
    assert taken == 0
    for f in FIELDS:
        x, y = np.asarray(getattr(fast.result, f), dtype=float), np.asarray(getattr(slow.result, f), dtype=float)
        assert np.abs(x - y).max() <= 1e-9 * max(1.0, float(np.abs(y).max())), f


def test_a_named_load_reaches_the_compiled_plant_and_law(monkeypatch):
    """A named load on the platform, its magnitude from the motion: the compiled cycles feed it
    to the plant at every step and to the computed torque's model as the Python cycles do, and
    it matters (the run without it differs)."""
    d = ex.builtin_dict("stewart")
    d["loads"] = [{"name": "push_N", "body": "platform", "direction": [0.3, 0.0, 1.0]}]
    m = load_mechanism(d)

    def load(t):
        return 400.0 * np.sin(2.0 * np.pi * t / t[-1])

    fast, slow, taken = _both(m, m, "computed-torque", 0.3, _settings(m), monkeypatch, load=load)
    _same(fast.result, slow.result, "named load")
    assert taken == slow.result.q.shape[0]
    none, _, _ = _both(m, m, "computed-torque", 0.3, _settings(m), monkeypatch)
    assert np.abs(none.result.u - fast.result.u).max() > 1.0


@pytest.mark.parametrize("law", ["computed-torque", "feedforward"])
@pytest.mark.parametrize("flag", [True, False])
def test_exact_encoders_read_the_joint_references_at_the_first_instant_alone(law, flag):
    """With exact encoders, computed torque and feedforward read the controller's joint
    reference at the run's first instant alone (the filters' start) and neither the plant's nor
    the rate map: a loop given those with every other entry NaN keeps the records of one given
    the real ones (compiled and Python cycles); :func:`track`'s result computes the joint
    reference when read, with the numbers of the direct call."""
    from pkmdyn.control import joint_reference, make_controller, sample_reference
    from pkmdyn.simulate import closed_loop
    from pkmdyn.simulate import make_plant
    from pkmdyn.simulate._run import loop_reads_joint

    m = _stewart()
    ls = replace(_settings(m), compiled_cycles=flag)
    assert not loop_reads_joint(law, ls) and loop_reads_joint(law, replace(ls, exact_encoders=False))
    assert loop_reads_joint("pid", ls) and loop_reads_joint("pd", ls)
    V = machine_verbs(m)
    fn = _motion(m)
    ref = sample_reference(fn, 0.2, ls.cycle_s)
    joint = joint_reference(V, m, ref, fn, False)  # as track computes it by default
    g = gains(described_control_settings(m), law, m.nt)
    runs = []
    for blind in (False, True):
        cj, pj, rm = joint, joint, np.linalg.inv(joint.Bt)
        if blind:
            nan = np.full_like(joint.s, np.nan)
            cj = type(joint)(joint.Bt * np.nan, np.vstack([joint.s[:1], nan[1:]]),
                             np.vstack([joint.sd[:1], nan[1:]]), np.vstack([joint.sdd[:1], nan[1:]]))
            pj = type(joint)(joint.Bt * np.nan, nan, nan, nan)
            rm = rm * np.nan
        ctrl = make_controller(law, g, V, m, ref, cj)
        runs.append(closed_loop(make_plant(V, m, False), ctrl, ref, pj, cj, rm, ls, ctrl_model=m))
    for f in FIELDS:
        x, y = np.asarray(getattr(runs[1], f), dtype=float), np.asarray(getattr(runs[0], f), dtype=float)
        assert np.all(np.isfinite(x)), f
        assert np.abs(x - y).max() <= 1e-12 * max(1.0, float(np.abs(y).max())), f
    tr = track(V, m, m, fn, 0.2, law, g, ls, False)
    assert callable(tr.joint_source)
    for f in ("Bt", "s", "sd", "sdd"):
        a, b = getattr(tr.joint, f), getattr(joint, f)
        assert a.shape == b.shape and np.abs(a - b).max() <= 1e-12 * max(1.0, float(np.abs(b).max())), f
