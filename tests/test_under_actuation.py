"""An under-actuated mechanism (fewer actuated joints than freedoms) run from an actuator motion:
its passive freedoms simulated (:mod:`pkmdyn.simulate.passive`).

Oracle written apart from the engine: the cart-pole (``tests/data/cart_pole.toml``), a cart on
a rail following ``x_c(t)`` and a pendulum hinged on it about +y, its centre of mass ``l`` below
the hinge, turned by ``th`` (the task's ``euler1``). Its equation of motion from its Lagrangian
(the centre of mass at ``x_c - l sin th``, height ``-l cos th``):

    (I + m l^2) th'' = -m g l sin th + m l x_c'' cos th - k (th - th_s) - c th'

(``k`` a spring, ``c`` viscous damping in the hinge), integrated by scipy's DOP853 to 1e-12."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import pkmdyn
from pkmdyn.cli import main
from pkmdyn.simulate.passive import passive_motion

DATA = Path(__file__).parent / "data"
M_POLE, L_COM, I_COM, G = 0.4, 0.3, 0.004, 9.80665
A, W = 0.1, 4.0  # the cart's motion x_c = A sin(W t) [m, rad/s]


def _cart_pole(tmp_path: Path, spring: float = 0.0, damping: float = 0.0) -> Path:
    text = (DATA / "cart_pole.toml").read_text()
    extra = []
    if spring:
        extra.append(f"spring = {{ stiffness_Nm_rad = {spring} }}")
    if damping:
        extra.append(f"friction = {{ viscous_Nm_s_rad = {damping} }}")
    text = text.replace('axis = [0.0, 1.0, 0.0]\n', 'axis = [0.0, 1.0, 0.0]\n' + "\n".join(extra) + "\n")
    f = tmp_path / "cart_pole.toml"
    f.write_text(text)
    return f


def _f(tt, y, spring=0.0, damping=0.0):
    th, thd = y
    xcdd = -A * W * W * np.sin(W * tt)
    torque = -M_POLE * G * L_COM * np.sin(th) + M_POLE * L_COM * xcdd * np.cos(th) - spring * th - damping * thd
    return [thd, torque / (I_COM + M_POLE * L_COM ** 2)]


def _oracle(t: np.ndarray, spring: float, damping: float, rates: bool = False) -> np.ndarray:
    y = solve_ivp(_f, (t[0], t[-1]), [0.0, 0.0], t_eval=t, rtol=1e-12, atol=1e-14, method="DOP853",
                  args=(spring, damping)).y
    return y if rates else y[0]


def _cart(t):
    return (A * np.sin(W * t))[:, None], (A * W * np.cos(W * t))[:, None], (-A * W * W * np.sin(W * t))[:, None]


@pytest.mark.parametrize("spring, damping", [(0.0, 0.0), (0.8, 0.05)])
def test_the_passive_pendulum_follows_its_equation_of_motion(tmp_path, spring, damping):
    m = pkmdyn.load(_cart_pole(tmp_path, spring, damping))
    assert (m.na, m.nt) == (1, 2)
    t = np.linspace(0.0, 1.5, 151)
    mo = passive_motion(m, t, *_cart(t))
    th = _oracle(t, spring, damping)
    assert np.abs(th).max() > 0.1  # the pendulum swings
    assert np.abs(mo.x[:, 1] - th).max() <= 1e-8 * np.abs(th).max()
    assert np.abs(mo.x[:, 0] - _cart(t)[0][:, 0]).max() <= 1e-10  # the cart follows its motion


def test_run_takes_an_under_actuated_mechanisms_actuator_motion(tmp_path):
    t = np.linspace(0.0, 1.0, 101)
    s, sd, sdd = _cart(t)
    path = tmp_path / "cart.csv"
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["t_s", "P_pos_m", "P_vel_m_s", "P_acc_m_s2"])
        for row in zip(t, s[:, 0], sd[:, 0], sdd[:, 0]):
            w.writerow([repr(float(v)) for v in row])
    out = tmp_path / "run"
    assert main(["run", "--machine", str(_cart_pole(tmp_path)), "--actuator-motion", str(path), "--out", str(out)]) == 0
    with open(out / "results.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    th = np.array([float(r["euler1_rad"]) for r in rows])
    th_o, thd_o = _oracle(t, 0.0, 0.0, rates=True)
    assert np.abs(th - th_o).max() <= 1e-7
    # the cart's force moves the cart and swings the pendulum (its centre of mass at x_c - l sin th):
    # F = m_c x_c'' + m_p (x_c'' - l (th'' cos th - th'^2 sin th))
    thdd_o = np.array([_f(tt, (a, b))[1] for tt, a, b in zip(t, th_o, thd_o)])
    force = 1.5 * sdd[:, 0] + M_POLE * (sdd[:, 0] - L_COM * (thdd_o * np.cos(th_o) - thd_o ** 2 * np.sin(th_o)))
    got = np.array([float(r["P_effort_N"]) for r in rows])
    assert np.abs(got - force).max() <= 1e-6 * np.abs(force).max()
    # the simulated motion is dynamically consistent: the cart alone makes it, to rounding (its
    # accelerations are the equations' at each state; the run refuses a ratio above 1e-8)
    ratio = np.array([float(r["unactuated_force_ratio"]) for r in rows])
    assert np.all(ratio <= 1e-11)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["max_unactuated_force_ratio"] == ratio.max()


def test_control_refuses_an_under_actuated_mechanism_in_one_line(tmp_path, capsys):
    """The sensors' pose and rates come through the actuated joints and the laws map a task
    effort: ``control`` of the cart-pole is refused in one line, with its default motion and
    with a consistent motion (the run's own simulated one), and writes nothing."""
    import csv

    run = tmp_path / "run"
    assert main(["run", "--machine", str(_cart_pole(tmp_path)), "--out", str(run)]) == 0
    capsys.readouterr()
    motion = tmp_path / "motion.csv"
    with open(run / "results.csv", newline="") as fh, open(motion, "w", newline="") as out:
        w = csv.writer(out)
        w.writerow(["t_s", "x_m", "euler1_rad"])
        w.writerows([r["t_s"], r["x_m"], r["euler1_rad"]] for r in csv.DictReader(fh))
    for extra in ([], ["--motion", str(motion)]):
        out = tmp_path / "c"
        assert main(["control", "--machine", str(_cart_pole(tmp_path)), *extra, "--out", str(out)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "under-actuated (1 actuator(s) for 2 degrees of freedom)" in err[0]
        assert not out.exists()


def test_the_unactuated_force_ratio_is_the_hinge_torque_no_actuator_gives(tmp_path):
    """A motion off the pendulum's equation by a hinge torque ``tau = eps F`` (``F`` the cart
    force it needs): the reactions give, per sample, ``|tau| / max(|(F, tau)|, 1e-6 max |(F, tau)|)``
    (the cart's actuator gives ``F``, nothing gives ``tau``), computed here from the cart-pole's
    own equations; ``eps`` a thousand times the tolerance is refused, naming the sample."""
    from pkmdyn.errors import MotionError
    from pkmdyn.multibody import solve_kinematics
    from pkmdyn.multibody.dynamics.newton_euler import UNDERACTUATED_TOLERANCE, joint_reactions

    m = pkmdyn.load(_cart_pole(tmp_path))
    t = np.linspace(0.0, 1.5, 301)
    th, thd = _oracle(t, 0.0, 0.0, rates=True)
    xc, xcd, xcdd = (v[:, 0] for v in _cart(t))
    thdd0 = np.array([_f(tt, (a, b))[1] for tt, a, b in zip(t, th, thd)])
    inertia = I_COM + M_POLE * L_COM ** 2

    def cart_force(thdd):
        return 1.5 * xcdd + M_POLE * (xcdd - L_COM * (thdd * np.cos(th) - thd ** 2 * np.sin(th)))

    for eps, refused in ((3.0 * UNDERACTUATED_TOLERANCE / 10.0, False), (1e3 * UNDERACTUATED_TOLERANCE, True)):
        thdd = thdd0 + eps * cart_force(thdd0) / inertia
        # the hinge torque the motion needs: zero on the equation of motion
        tau = inertia * thdd + M_POLE * G * L_COM * np.sin(th) - M_POLE * L_COM * xcdd * np.cos(th)
        force = cart_force(thdd)
        size = np.hypot(force, tau)
        want = np.abs(tau) / np.maximum(size, 1e-6 * size.max())
        kin = solve_kinematics(m, np.c_[xc, th], np.c_[xcd, thd], np.c_[xcdd, thdd], t)
        if refused:
            with pytest.raises(MotionError, match=r"sample \d+.*under-actuated"):
                joint_reactions(m, kin)
            continue
        r = joint_reactions(m, kin)
        assert r.unactuated is not None and r.unactuated.shape == t.shape
        assert want.max() > 0.5 * eps  # the motion is off its equation at most samples
        assert np.abs(r.unactuated - want).max() <= 1e-3 * eps
        assert np.abs(r.u[:, 0] - force).max() <= 1e-9 * np.abs(force).max()


def test_a_simulation_that_stops_advancing_is_stopped_naming_the_time(tmp_path, monkeypatch):
    """The passive simulation checks its progress every STALL_WINDOW evaluations: with a window
    of 200 evaluations that must cover 90 % of the motion (or 1 s), the cart-pole's simulation
    (some 6,000 evaluations for 1.5 s) is stopped and named, with the measure there; with the
    defaults it is not."""
    import pkmdyn.simulate.passive as passive
    from pkmdyn.errors import MotionError

    monkeypatch.setattr(passive, "STALL_WINDOW", 200)
    monkeypatch.setattr(passive, "STALL_PROGRESS", 0.9)
    monkeypatch.setattr(passive, "STALL_SECONDS", 1.0)
    m = pkmdyn.load(_cart_pole(tmp_path))
    t = np.linspace(0.0, 1.5, 151)
    with pytest.raises(MotionError, match=r"t = [0-9.e-]+ s: .*stopped.*inverse singularity measure is [0-9.e-]+ there"):
        passive_motion(m, t, *_cart(t))
