"""The plant integrator (pkmdyn.simulate): accuracy against a tight stiff reference through
velocity reversals (the default explicit/ROS2 step, its RK4 variant and ROS2 alone), its
order where friction is smooth, stability while sticking, the fast path against the batched verbs, timing
checks. Runs on the small two-link machine of ``toy_machine`` (friction as stiff as the hip's)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import toy_machine as toy
from pkmdyn.errors import ParameterError
from pkmdyn.simulate import check_timing, hold_interval, make_plant, make_work

T = 1e-3  # control cycle [s]
MODEL = replace(toy.ToyModel(), g=0.0)


def _u(k: int) -> np.ndarray:
    t = k * T
    return np.array([2.2 * np.sin(2 * np.pi * 2 * t) + 0.3, 1.6 * np.cos(2 * np.pi * 3 * t)])


def _load(t):
    return 1000 + 800 * np.sin(2 * np.pi * t) ** 2


def _reference(K: int, model=MODEL) -> np.ndarray:
    """States at the cycle ends by Radau at rtol = atol = 1e-10 (efforts held per cycle)."""
    y = np.array([0.1, 0.5, 0.0, 0.0])
    out = []
    for k in range(K):
        u = _u(k)[None]

        def rhs(t, y, u=u):
            qdd = toy.forward_dynamics(model, y[None, :2], y[None, 2:], u, np.array([_load(t)]))[0]
            return np.r_[y[2:], qdd]

        y = solve_ivp(rhs, (k * T, (k + 1) * T), y, method="Radau", rtol=1e-10, atol=1e-10).y[:, -1]
        out.append(y)
    return np.array(out)


def _simulate(K: int, sub: int, fast: bool = True, model=MODEL, method: str = "rk3-ros2") -> np.ndarray:
    plant = make_plant(toy.verbs(fast), model, has_load=True)
    work = make_work(plant, method)
    q, qd = np.array([0.1, 0.5]), np.zeros(2)
    dt = T / sub
    out = []
    for k in range(K):
        hold_interval(plant, q, qd, _u(k), _load(k * T + 0.5 * dt * np.arange(2 * sub + 1)), dt, work)
        out.append(np.r_[q, qd])
    return np.array(out)


@pytest.fixture(scope="module")
def reference() -> np.ndarray:
    return _reference(150)


def test_reference_has_velocity_reversals(reference):
    """The comparison below is only meaningful if both velocities reverse in the window."""
    for c in (2, 3):
        assert np.count_nonzero(np.diff(np.sign(reference[:, c]))) >= 1


def test_error_against_radau_through_reversals(reference):
    """ROS2 alone (``method="ros2"``) against Radau (1e-10): small at one step per 1 ms cycle
    and converging as the step shrinks, through the velocity reversals of a friction-dominated
    machine."""
    errs = []
    for sub in (1, 2, 4):
        x = _simulate(reference.shape[0], sub, method="ros2")
        errs.append(np.max(np.abs(x[:, :2] - reference[:, :2])))
    assert errs[0] < 1e-4  # rad, dt = 1 ms, |qd| up to several rad/s
    assert errs[2] < 2e-5
    assert errs[0] > 2 * errs[1] > 4 * errs[2]


@pytest.mark.parametrize("method", ["ros2", "rk3-ros2"])
@pytest.mark.parametrize("effort", [(2.5, 1.6), (-2.5, -1.6)])
def test_a_start_from_rest_is_refined_whichever_way_it_goes(method, effort):
    """The machine at rest, its friction turning on in the first step: that step is refined as
    a reversal is, whether the velocities leave zero upwards or downwards."""
    plant = make_plant(toy.verbs(True), MODEL, has_load=True)
    work = make_work(plant, method)
    q, qd = np.array([0.1, 0.5]), np.zeros(2)
    hold_interval(plant, q, qd, np.array(effort), np.full(3, 1000.0), T, work)
    assert np.all(np.sign(qd) == np.sign(effort))  # both velocities left zero the effort's way
    assert work.refined_steps == 1


def test_a_start_from_rest_stays_close(reference):
    """ROS2 alone from rest against Radau over the first 10 cycles. Unrefined, its first step
    made a velocity error that the position then carried, growing by about 3e-5 rad a cycle."""
    x = _simulate(10, 1, method="ros2")
    assert np.max(np.abs(x[:, :2] - reference[:10, :2])) < 3e-5  # rad


@pytest.mark.parametrize("method", ["rk3-ros2", "rk4-ros2"])
def test_explicit_ros2_against_radau_through_reversals(reference, method):
    """The default step (Nystroem's third order away from the friction band, ROS2 in it) and
    its RK4 variant against Radau: close at one step per 1 ms cycle and converging with the
    step. (Their third order over ROS2's second, where the motion is smooth:
    :func:`test_higher_order_where_friction_is_smooth`.)"""
    K = reference.shape[0]
    errs = [np.max(np.abs(_simulate(K, sub, method=method)[:, :2] - reference[:, :2])) for sub in (1, 2, 4, 8)]
    assert errs[0] < 1e-4  # rad, dt = 1 ms
    assert errs[3] < 3e-6
    assert errs[0] > 2 * errs[1] > 4 * errs[2]


def test_higher_order_where_friction_is_smooth():
    """With a wide friction regularisation (eps = 0.1 rad/s, nowhere stiff at these steps) the
    explicit steps converge faster than second order: two halvings of the step cut the error by
    more than the 16 a second-order method gives (ROS2 alone: less than 16), and at one step
    per cycle they are fifty times closer than ROS2."""
    model = replace(MODEL, eps=0.1)
    ref = _reference(150, model)
    errs = {m: [np.max(np.abs(_simulate(150, sub, model=model, method=m)[:, :2] - ref[:, :2])) for sub in (1, 2, 4)]
            for m in ("rk3-ros2", "rk4-ros2", "ros2")}
    assert errs["ros2"][0] < 16 * errs["ros2"][2]
    for m in ("rk3-ros2", "rk4-ros2"):
        assert errs[m][0] > 20 * errs[m][2]
        assert errs[m][0] < errs["ros2"][0] / 50
        assert errs[m][0] < 2e-6  # rad, one 1 ms step per cycle


STICK = replace(MODEL, mu0=3.0, mu_load=0.0, viscous=0.0)
STICK_EFFORT = np.array([0.6, 0.4])  # generalised force B u well inside the friction cone (|B u| < 3 N m)


def _stick(method: str = "rk3-ros2"):
    """200 cycles of 1 ms on ``STICK`` at rest under efforts inside the friction cone: the
    plant, its work buffers, the final ``q, qd`` and the largest ``|qd|`` on the way."""
    plant = make_plant(toy.verbs(True), STICK, has_load=True)
    work = make_work(plant, method)
    q, qd = np.array([0.1, 0.5]), np.zeros(2)
    assert np.linalg.norm(np.asarray(STICK.B) @ STICK_EFFORT) < STICK.mu0
    peak = 0.0
    with np.errstate(all="ignore"):
        for _ in range(200):
            hold_interval(plant, q, qd, STICK_EFFORT, np.zeros(3), T, work)
            peak = max(peak, float(np.max(np.abs(qd)))) if np.all(np.isfinite(qd)) else np.inf
    return plant, work, q, qd, peak


@pytest.mark.parametrize("method", ["rk3-ros2", "rk4-ros2", "ros2"])
def test_sticking_is_stable_with_large_steps(method):
    """Efforts below the breakaway friction on a machine at rest: the exact solution stays
    (almost) at rest. An explicit step of 1 ms with a friction slope of ~2000 N m s/rad against
    ~0.1 kg m^2 cannot hold it; the linearly implicit step must (the default step detects the
    friction band and takes ROS2 there)."""
    _, _, q, qd, peak = _stick(method)
    assert peak < 10 * STICK.eps
    assert np.all(np.abs(q - [0.1, 0.5]) < 1e-3)


@pytest.mark.parametrize("method", ["rk3-ros2", "rk4-ros2"])
def test_band_detection_takes_every_sticking_step_linearly_implicit(method):
    """At rest below the breakaway friction the friction's slope makes ``dt |d f / d qd|``
    two orders above ``EXPLICIT_LIMIT`` (about 130 against 0.5): the step's own stiffness
    estimate must send every step to ROS2 - no explicit step is accepted in 200 cycles - and
    the Jacobian kept at the end confirms the band."""
    from pkmdyn.simulate._plant import EXPLICIT_LIMIT, _stiffness

    _, work, q, qd, _ = _stick(method)
    assert work.stiff
    assert work.explicit_steps == 0
    assert T * _stiffness(work.A) > 20 * EXPLICIT_LIMIT
    assert np.all(np.abs(qd) < STICK.eps) and np.all(np.abs(q - [0.1, 0.5]) < 1e-3)


@pytest.mark.parametrize("method", ["rk3-ros2", "rk4-ros2"])
def test_explicit_step_is_unstable_where_the_band_detection_switches(method):
    """Why the switch matters, as a property of one step rather than of a long run: about the
    held state a velocity perturbation of 1e-9 rad/s grows by orders of magnitude in one
    explicit step (its stability polynomial at ``dt lambda`` of about -100; measured 6e4 for
    Nystroem, 1e6 for RK4) and is damped by one ROS2 step (L-stable; measured 0.2).

    A run of explicit steps there is an unstable iteration about the creep equilibrium, so
    where it ends is decided by rounding (it differs between BLAS kernels); the amplification
    of one step is not."""
    from pkmdyn.simulate._plant import _ros2_step

    plant, _, q, qd, _ = _stick(method)
    u = STICK_EFFORT
    delta = 1e-9  # rad/s, far inside the regularisation band (eps = 1e-3 rad/s)

    def one_step(explicit: bool, dv: float) -> np.ndarray:
        qq, vv = q.copy(), qd.copy()
        vv[0] += dv
        w = make_work(plant, method)
        f0 = plant.f(qq, vv, u, 0.0)
        if explicit:
            w.step(plant, qq, vv, u, 0.0, 0.0, 0.0, T, w, f0)
        else:
            _ros2_step(plant, qq, vv, u, 0.0, 0.0, T, w, force_jacobian=True, f0=f0)
        return vv

    growth = {e: np.max(np.abs(one_step(e, delta) - one_step(e, 0.0))) / delta for e in (True, False)}
    assert growth[True] > 100.0
    assert growth[False] < 1.0


def test_unknown_method_rejected():
    with pytest.raises(ValueError, match="unknown"):
        make_work(make_plant(toy.verbs(True), MODEL, has_load=True), "euler")


@pytest.mark.parametrize("cycle, step", [(1e-3, 3e-4), (1e-3, 2e-3), (1e-3, 0.0), (-1e-3, 1e-3), (np.nan, 1e-3)])
def test_timing_must_divide(cycle, step):
    with pytest.raises(ParameterError, match="control_cycle_s|integration_step_s"):
        check_timing(cycle, step)


def test_timing_whole_multiple():
    assert check_timing(2e-3, 5e-4) == 4
    assert check_timing(1e-3, 1e-3) == 1


def test_a_velocity_of_rounding_size_does_not_reverse():
    """A step is refined where a velocity component crosses zero, leaves it or comes to it; a
    component held at rest by symmetry, whose velocity is rounding about zero, must not decide
    it by the rounding's sign."""
    from pkmdyn.simulate._plant import _reversed

    moving = 1e-2
    for noise in (-8.8e-18, 4.0e-19, 0.0):
        # rounding at both ends: at rest, whatever its signs
        assert not _reversed(np.array([noise, moving]), np.array([-noise * 3 + 1e-19, moving]))
        # rounding at the start, a real motion at the end: a start from rest, either way
        assert _reversed(np.array([noise, moving]), np.array([2e-8, moving]))
        assert _reversed(np.array([noise, moving]), np.array([-2e-8, moving]))
        # a real motion that comes to rest
        assert _reversed(np.array([-2e-8, moving]), np.array([noise, moving]))
    assert _reversed(np.array([-1e-6, moving]), np.array([2e-8, moving]))  # a real crossing, however slow
    assert _reversed(np.array([0.3, moving]), np.array([-0.1, moving]))
    assert not _reversed(np.array([0.3, moving]), np.array([0.1, moving]))
    assert not _reversed(np.zeros(2), np.zeros(2))
    assert not _reversed(np.array([1e-18, -1e-18]), np.array([-1e-18, 1e-18]))  # a machine held still
