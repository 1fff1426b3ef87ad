"""Explicit leg closure (multibody/model/legs.py): recognition from the description, and the
explicit and the Newton routes giving the same kinematics, branches included.

The mechanisms beside the built-ins are made here: six-legged platforms whose legs are
U-P-S, R-U-S or P-U-S, or R-S-S and P-S-S rods, turned as a whole by an arbitrary rotation
(legs in unusual orientations), and a planar 3-RPR; each is solved by both routes on random smooth motions.
"""

from __future__ import annotations

import numpy as np
import pytest

from pkmdyn.multibody import load_mechanism, reference_task, solve_kinematics
from pkmdyn.multibody.kinematics.inverse import TOLERANCE, loop_residuals
from pkmdyn.multibody.model.legs import newton_only, place
from pkmdyn.multibody.model.topology import constraint_jacobian

from multibody_examples import MACHINES


def _rot(axis, ang):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(ang) * k + (1 - np.cos(ang)) * k @ k


def _unit(v):
    return v / np.linalg.norm(v)


def _hexagon(Q: np.ndarray):
    """The six-legged platforms' common parts: the turn ``T`` of a point or axis by ``Q``, the
    platform body, and per leg its base joint ``b`` (pairs on a 1 m circle), platform joint
    ``s`` (on a 0.5 m circle 1 m above) and the base circle's tangent there."""
    T = lambda v: [float(x) for x in Q @ np.asarray(v, float)]  # noqa: E731
    bodies = [{"name": "platform", "mass_kg": 10.0, "com_m": T([0, 0, 1.0]),
               "inertia_kgm2": [0.6, 0.6, 1.2, 0, 0, 0]}]
    legs = []
    for i in range(6):
        pair, side = divmod(i, 2)
        sg = -1.0 if side == 0 else 1.0
        ab = np.radians(120 * pair + 10 * sg)
        ap = np.radians(120 * pair + 50 * sg)
        legs.append((np.array([np.cos(ab), np.sin(ab), 0.0]), np.array([0.5 * np.cos(ap), 0.5 * np.sin(ap), 1.0]),
                     np.array([-np.sin(ab), np.cos(ab), 0.0])))
    return T, bodies, legs


def platform(leg: str, Q: np.ndarray = np.eye(3)) -> dict:
    """A six-legged platform with legs of type ``leg`` (``UPS``, ``RUS``, ``PUS``), base joints
    in pairs on a 1 m circle, platform joints on a 0.5 m circle 1 m above, every point and
    axis turned by ``Q``."""
    T, bodies, layout = _hexagon(Q)
    joints = []
    for i, (b, s, tangent) in enumerate(layout):
        radial = b.copy()
        n1, n2 = f"first_{i + 1}", f"second_{i + 1}"
        if leg == "UPS":
            u = b
            d = _unit(s - u)
            a1 = _unit(np.cross(d, [0, 0, 1.0]))
            joints += [{"name": f"U_{i + 1}", "type": "universal", "parent": "ground", "child": n1, "point_m": T(u),
                        "axes": [T(a1), T(np.cross(d, a1))]},
                       {"name": f"P_{i + 1}", "type": "prismatic", "parent": n1, "child": n2, "point_m": T(u),
                        "axis": T(d), "actuated": True,
                        "position_at_reference_m": float(np.linalg.norm(s - u))}]
        elif leg == "RUS":
            u = b + 0.3 * radial + np.array([0, 0, 0.1])
            d = _unit(s - u)
            a2 = _unit(np.cross(d, tangent))
            joints += [{"name": f"R_{i + 1}", "type": "revolute", "parent": "ground", "child": n1, "point_m": T(b),
                        "axis": T(tangent), "actuated": True, "angle_at_reference_rad": 0.0},
                       {"name": f"U_{i + 1}", "type": "universal", "parent": n1, "child": n2, "point_m": T(u),
                        "axes": [T(tangent), T(a2)]}]
        else:  # PUS: a vertical slider, a universal joint on it
            u = b + np.array([0, 0, 0.2])
            d = _unit(s - u)
            a2 = _unit(np.cross(d, tangent))
            joints += [{"name": f"P_{i + 1}", "type": "prismatic", "parent": "ground", "child": n1, "point_m": T(b),
                        "axis": T([0, 0, 1.0]), "actuated": True, "position_at_reference_m": 0.2},
                       {"name": f"U_{i + 1}", "type": "universal", "parent": n1, "child": n2, "point_m": T(u),
                        "axes": [T(tangent), T(a2)]}]
        joints.append({"name": f"S_{i + 1}", "type": "spherical", "parent": n2, "child": "platform",
                       "point_m": T(s), "axis": T(d)})
        bodies += [{"name": n1, "mass_kg": 1.0, "com_m": T(u), "inertia_kgm2": [0.01, 0.01, 0.01, 0, 0, 0]},
                   {"name": n2, "mass_kg": 1.0, "com_m": T(0.5 * (u + s)), "inertia_kgm2": [0.02, 0.02, 0.02, 0, 0, 0]}]
    return {"mechanism": {"name": f"hexa_{leg.lower()}", "gravity_m_s2": T([0, 0, -9.80665])},
            "bodies": bodies, "joints": joints,
            "task": {"body": "platform", "point_m": T([0, 0, 1.0]), "position": ["x", "y", "z"],
                     "euler_sequence": "XYZ", "orientation": [1, 2, 3]}}


def rod_platform(first: str, Q: np.ndarray = np.eye(3), along: bool = True) -> dict:
    """A six-legged platform on S-S rods: per leg a first joint (``R``: a revolute on the
    ground, tangential; ``P``: a vertical slider), a ball at the rod's lower end and a ball
    (the cut) on the platform; with ``along``, the lower ball's frame z lies along the rod (its
    spin about the rod one of its coordinates), else the description's default frame. Turned
    as a whole by ``Q``."""
    T, bodies, layout = _hexagon(Q)
    joints = []
    for i, (b, s, tangent) in enumerate(layout):
        u = 1.3 * b + np.array([0, 0, 0.1])
        d = _unit(s - u)
        n1, n2 = f"first_{i + 1}", f"rod_{i + 1}"
        if first == "R":
            joints.append({"name": f"R_{i + 1}", "type": "revolute", "parent": "ground", "child": n1, "point_m": T(b),
                           "axis": T(tangent), "actuated": True, "angle_at_reference_rad": 0.0})
        else:
            joints.append({"name": f"P_{i + 1}", "type": "prismatic", "parent": "ground", "child": n1,
                           "point_m": T(b), "axis": T([0, 0, 1.0]), "actuated": True,
                           "position_at_reference_m": 0.1})
        lower = {"name": f"SA_{i + 1}", "type": "spherical", "parent": n1, "child": n2, "point_m": T(u)}
        if along:
            lower["axis"] = T(d)
        joints += [lower, {"name": f"SB_{i + 1}", "type": "spherical", "parent": n2, "child": "platform",
                           "point_m": T(s), "axis": T(d)}]
        bodies += [{"name": n1, "mass_kg": 1.0, "com_m": T(0.5 * (b + u)), "inertia_kgm2": [0.01, 0.01, 0.01, 0, 0, 0]},
                   {"name": n2, "mass_kg": 1.0, "com_m": T(0.5 * (u + s)),
                    "inertia_kgm2": [0.02, 0.02, 0.001, 0, 0, 0]}]
    return {"mechanism": {"name": f"hexa_{first.lower()}ss", "gravity_m_s2": T([0, 0, -9.80665])},
            "bodies": bodies, "joints": joints,
            "task": {"body": "platform", "point_m": T([0, 0, 1.0]), "position": ["x", "y", "z"],
                     "euler_sequence": "XYZ", "orientation": [1, 2, 3]}}


def rpr3() -> dict:
    """A planar 3-RPR: base revolutes at 120 deg on a 1 m circle, sliding legs, platform
    revolutes on a 0.3 m circle."""
    bodies = [{"name": "platform", "mass_kg": 2.0, "com_m": [0, 0, 0], "inertia_kgm2": [0.1, 0.1, 0.1, 0, 0, 0]}]
    joints = []
    for i in range(3):
        a = np.radians(120 * i + 90)
        b = np.array([np.cos(a), np.sin(a), 0.0])
        s = 0.3 * np.array([np.cos(a + 0.5), np.sin(a + 0.5), 0.0])
        d = _unit(s - b)
        joints += [{"name": f"RA_{i + 1}", "type": "revolute", "parent": "ground", "child": f"cyl_{i + 1}",
                    "point_m": b.tolist(), "axis": [0, 0, 1.0], "angle_at_reference_rad": 0.0},
                   {"name": f"P_{i + 1}", "type": "prismatic", "parent": f"cyl_{i + 1}", "child": f"rod_{i + 1}",
                    "point_m": b.tolist(), "axis": d.tolist(), "actuated": True,
                    "position_at_reference_m": float(np.linalg.norm(s - b))},
                   {"name": f"RC_{i + 1}", "type": "revolute", "parent": f"rod_{i + 1}", "child": "platform",
                    "point_m": s.tolist(), "axis": [0, 0, 1.0], "angle_at_reference_rad": 0.0}]
        bodies += [{"name": f"cyl_{i + 1}", "mass_kg": 1.0, "com_m": b.tolist(), "inertia_kgm2": [0.01] * 3 + [0] * 3},
                   {"name": f"rod_{i + 1}", "mass_kg": 1.0, "com_m": s.tolist(), "inertia_kgm2": [0.01] * 3 + [0] * 3}]
    return {"mechanism": {"name": "rpr3", "gravity_m_s2": [0, 0, -9.80665]}, "bodies": bodies, "joints": joints,
            "task": {"body": "platform", "point_m": [0, 0, 0], "position": ["x", "y"], "euler_sequence": "ZYX",
                     "orientation": [1]}}


def _motion(model, amp, n=120, seed=0):
    rng = np.random.default_rng(seed)
    x0 = reference_task(model)
    t = np.linspace(0.0, 2.0, n)
    w = rng.uniform(1.0, 3.0, x0.size)
    ph = rng.uniform(0, 2 * np.pi, x0.size)
    a = np.broadcast_to(amp, x0.shape)
    s, c = np.sin(w * t[:, None] + ph), np.cos(w * t[:, None] + ph)
    return t, x0 + a * (s - np.sin(ph)), a * w * c, -a * w**2 * s


#: the two routes agree to what Newton leaves: both solve the blocks that are not explicit
#: legs (the leg carrying the platform, coupled sub-chains) by Newton to a dimensionless
#: residual of TOLERANCE = 1e-13, which moves the coordinates by up to the condition number
#: of the scaled Newton matrix times that (taken as at most 100 here); the explicit legs
#: themselves close to rounding (test_closed_form_closes_each_leg_alone)
AGREE = 100 * TOLERANCE


def _compare(model, amp, seeds=(0, 1)):
    """Largest difference of q, qd, qdd and G between the two routes, each relative to the
    largest entry (at least 1)."""
    worst = 0.0
    for seed in seeds:
        t, x, xd, xdd = _motion(model, amp, seed=seed)
        a = solve_kinematics(model, x, xd, xdd, t)
        b = solve_kinematics(newton_only(model), x, xd, xdd, t)
        for k in ("q", "qd", "qdd", "G"):
            va, vb = getattr(a, k), getattr(b, k)
            worst = max(worst, float(np.abs(va - vb).max() / max(np.abs(vb).max(), 1.0)))
    return worst


#: explicit legs of each built-in (the Stewart platform: every block, the leg carrying the platform
#: from the task; the 3-RRR: the two legs off the spanning tree; the Delta's parallelograms and the
#: Bennett linkage: none)
BUILT_IN = {"stewart": (6, 0.04), "rrr3": (2, 0.03), "delta": (0, 0.05), "bennett": (0, 0.3)}


@pytest.mark.parametrize("name", sorted(BUILT_IN))
def test_built_in_routes_agree(name):
    model = load_mechanism(MACHINES / name / f"{name}.toml")
    count, amp = BUILT_IN[name]
    assert model.legs.count == count
    assert _compare(model, amp) <= AGREE


def test_hip_and_pdm_descriptions_routes_agree():
    from pkmdyn.machines.hip_simulator.description import hip_description
    from pkmdyn.machines.hip_simulator.params import load_params
    from pkmdyn.machines.pdm4.description import pdm_description
    from pkmdyn.machines.pdm4.params import load_params as pdm_params

    hip = load_mechanism(hip_description(load_params()))
    # the upper platform on its ball from the task, the three upper P-U-S legs (slide, then a
    # universal joint); the lower platform's legs are coupled through it and stay with Newton
    assert [nm[2] for nm in hip.legs.names] == [10, 2, 2, 2]
    assert _compare(hip, 0.1) <= AGREE
    pdm = load_mechanism(pdm_description(pdm_params()))
    assert _compare(pdm, np.array([0.01, 0.01, 0.02, 0.02])) <= AGREE


def test_legs_placed_from_the_task_alone():
    """The legs whose closed form depends on the task alone (from and to the ground or bodies
    only such legs move) are solved once per sample; Newton leaves their coordinates."""
    from pkmdyn.machines.hip_simulator.description import hip_description
    from pkmdyn.machines.hip_simulator.params import load_params
    from pkmdyn.machines.pdm4.description import pdm_description
    from pkmdyn.machines.pdm4.params import load_params as pdm_params

    stewart = load_mechanism(MACHINES / "stewart" / "stewart.toml")
    assert stewart.legs.fixed.tolist() == [1] * 6 and stewart.legs.fixed_coord.tolist() == [1] * stewart.nq
    hip = load_mechanism(hip_description(load_params()))
    assert hip.legs.fixed.tolist() == [1, 1, 1, 1]
    joint_of = {}
    for b in range(hip.nb):
        k = int(hip.body_joint[b])
        for c in range(hip.joint_q0[k], hip.joint_q0[k] + hip.joint_nq[k]):
            joint_of[c] = hip.joint_names[k]
    names = [joint_of[int(c)] for c in np.flatnonzero(hip.legs.fixed_coord)]
    # the upper ball's three angles, each upper leg's slide and universal joint; nothing of the
    # lower platform, which hangs on the slides but is closed by Newton
    assert len(names) == 12 and not any("lower" in nm for nm in names)
    # the 3-RRR's and the PDM's legs meet a platform that Newton places
    assert load_mechanism(MACHINES / "rrr3" / "rrr3.toml").legs.fixed.tolist() == [0, 0]
    pdm = load_mechanism(pdm_description(pdm_params()))
    assert pdm.legs.count > 0 and not pdm.legs.fixed.any() and not pdm.legs.fixed_coord.any()
    # along a timed motion the upper legs keep their closed form: the solution's coordinates
    # are the closed form's at the solution to rounding
    t, x, xd, xdd = _motion(hip, 0.1)
    kin = solve_kinematics(hip, x, xd, xdd, t)
    fx = hip.legs.fixed_coord.astype(bool)
    for k in (0, 37, len(t) - 1):
        again = place(hip, kin.q[k], x[k])
        assert np.abs(again[fx] - kin.q[k][fx]).max() <= 1e-14 * max(1.0, np.abs(kin.q[k]).max())


@pytest.mark.parametrize("leg,pattern", [("UPS", 4), ("RUS", 2), ("PUS", 2)])
@pytest.mark.parametrize("turned", [False, True])
def test_leg_types_in_any_orientation(leg, pattern, turned):
    Q = _rot([0.3, -0.8, 0.5], 2.1) if turned else np.eye(3)
    model = load_mechanism(platform(leg, Q))
    # the leg that carries the platform from the task (its ball placed by the same pattern), the
    # other five from the platform: every block explicit
    assert model.legs.count == 6 == model.solver_blocks.shape[0] - 1
    assert [nm[2] for nm in model.legs.names] == [10 + pattern] + [pattern] * 5
    assert _compare(model, np.array([0.03, 0.03, 0.03, 0.05, 0.05, 0.05])) <= AGREE


@pytest.mark.parametrize("first", ["R", "P"])
@pytest.mark.parametrize("turned", [False, True])
def test_rods_between_two_balls_are_explicit_with_their_spin_held(first, turned):
    """R-S-S and P-S-S legs: each rod's spin about its axis is an idle freedom, held by an
    idle row of its own (the lower ball's coordinate about the rod); the five legs off the
    spanning tree are then A2 legs (first joint, two turns of the ball) and agree with Newton.
    The leg that carries the platform keeps its spin in the task block (the difference of its
    two balls' spins), which Newton solves: a mechanism where only some legs are explicit."""
    Q = _rot([0.3, -0.8, 0.5], 2.1) if turned else np.eye(3)
    model = load_mechanism(rod_platform(first, Q))
    idle = model.solver_idle
    assert idle.shape[0] == 6
    units = [int(np.flatnonzero(r)[0]) for r in idle if np.count_nonzero(r) == 1]
    spins = {model.joint_q0[model.joint_index(f"SA_{i}")] + 2 for i in range(2, 7)}
    assert set(units) == spins
    assert model.legs.count == 5 and [nm[2] for nm in model.legs.names] == [2] * 5
    assert sorted(nm[0] for nm in model.legs.names) == [f"SB_{i}" for i in range(2, 7)]
    amp = np.array([0.03, 0.03, 0.03, 0.05, 0.05, 0.05])
    assert _compare(model, amp) <= AGREE
    # the single-sample dynamics through the held spins: the efforts of the Newton route's
    # inverse dynamics give its accelerations back
    from pkmdyn.multibody.dynamics.verbs import machine_verbs

    t, x, xd, xdd = _motion(model, amp, n=20)
    u = machine_verbs(newton_only(model)).inverse_dynamics(newton_only(model), x, xd, xdd)
    V = machine_verbs(model)
    back = np.array([V.forward_dynamics_one(model, x[i], xd[i], u[i]) for i in range(len(t))])
    assert np.abs(back - xdd).max() <= 1e-9 * max(1.0, np.abs(xdd).max())


def test_a_ball_frame_off_the_rod_leaves_the_leg_to_newton():
    """Where the lower ball's frame has no axis along the rod, the spin is a mix of the ball's
    coordinates: no coordinate is held alone, no leg is explicit, and Newton solves (the same
    kinematics as with the frame along the rod: the frame changes the coordinates, not the
    motion of the bodies)."""
    model = load_mechanism(rod_platform("R", along=False))
    assert model.legs.count == 0
    along = load_mechanism(rod_platform("R"))
    t, x, xd, xdd = _motion(model, np.array([0.03, 0.03, 0.03, 0.05, 0.05, 0.05]))
    a = solve_kinematics(model, x, xd, xdd, t)
    b = solve_kinematics(along, x, xd, xdd, t)
    acts = [model.joint_q0[model.joint_index(f"R_{i}")] for i in range(1, 7)]
    assert np.abs(a.q[:, acts] - b.q[:, acts]).max() <= AGREE
    assert np.abs(a.qd[:, acts] - b.qd[:, acts]).max() <= AGREE * max(1.0, np.abs(b.qd[:, acts]).max())


def test_planar_rpr():
    model = load_mechanism(rpr3())
    assert [nm[2] for nm in model.legs.names] == [3, 3]
    assert _compare(model, np.array([0.05, 0.05, 0.1])) <= AGREE


def _place(model, q, x=None):
    """``q`` with the explicit legs set in closed form (one pass of the positions) for the task
    ``x`` (default: the reference task), and the loop residuals there."""
    q = place(model, q, reference_task(model) if x is None else x)
    return q, loop_residuals(model, q[None])[0]


def _leg_rows(model):
    cuts = [model.joint_index(nm[0]) for nm in model.legs.names]
    return np.isin(model.loop_joint[model.row_loop], cuts) & (model.row_kind == 0)


@pytest.mark.parametrize("leg", ["UPS", "RUS", "PUS"])
def test_closed_form_closes_each_leg_alone(leg):
    """From coordinates far from the solution, one pass of the positions closes every loop and
    reaches the task pose to rounding (no Newton step: every block is an explicit leg)."""
    model = load_mechanism(platform(leg, _rot([1.0, 2.0, -0.5], 0.7)))
    rng = np.random.default_rng(3)
    x = reference_task(model) + np.array([0.02, -0.03, 0.01, 0.04, -0.02, 0.05])
    q0 = model.coord_offset + rng.uniform(-0.1, 0.1, model.nq)
    nr = model.row_loop.shape[0]
    before = np.abs(loop_residuals(model, q0[None])[0]).max()
    q = place(model, q0, x)
    val, _ = constraint_jacobian(model, q)
    assert before > 1e-3
    assert np.abs(val[0, :nr]).max() <= 1e-13 * model.length_scale
    assert np.abs(val[0, nr:] - x).max() <= 1e-13
    # the same coordinates as the Newton route's at that pose
    kin = solve_kinematics(newton_only(model), x[None], np.zeros((1, 6)), np.zeros((1, 6)))
    assert np.abs(q - kin.q[0]).max() <= AGREE


def test_branch_is_kept():
    """Each explicit 3-RRR leg has two closed solutions (its elbow on either side); the closed
    form takes the one nearest the coordinates it starts from, so a leg placed again stays
    where it is, on either branch."""
    model = load_mechanism(MACHINES / "rrr3" / "rrr3.toml")
    q_ref, _ = _place(model, model.coord_offset)
    assert np.abs(q_ref - model.coord_offset).max() <= 1e-9
    for L in range(model.legs.count):
        c0, c1 = model.legs.coord[L, :2]
        found = []
        for d in np.linspace(-3.0, 3.0, 13):
            start = q_ref.copy()
            start[c0] += d
            q, res = _place(model, start)
            assert np.abs(res[_leg_rows(model)]).max() <= 1e-12
            key = (round(float(np.sin(q[c1])), 6), round(float(np.cos(q[c1])), 6))
            if key not in [k for k, _ in found]:
                found.append((key, q))
        assert len(found) == 2
        for _, q in found:
            q_again, _ = _place(model, q)
            assert np.abs(q_again - q).max() <= 1e-12


def _elbow_sign(kin, model, L):
    """Sign of the turn from a 3-RRR leg's first link to its second (about z)."""
    cut = model.joint_index(model.legs.names[L][0])
    ja, jb = (model.joint_index(nm) for nm in model.legs.names[L][1])
    a, b, c = kin.joint_point[:, ja], kin.joint_point[:, jb], kin.joint_point[:, cut]
    return np.sign(np.cross(b - a, c - b)[:, 2])


def test_elbow_kept_along_a_motion():
    """Along a motion, each explicit 3-RRR elbow keeps the side it has at the reference."""
    model = load_mechanism(MACHINES / "rrr3" / "rrr3.toml")
    t, x, xd, xdd = _motion(model, np.array([0.03, 0.03, 0.1]), n=200, seed=5)
    kin = solve_kinematics(model, x, xd, xdd, t)
    ref = solve_kinematics(model, reference_task(model)[None], np.zeros((1, 3)), np.zeros((1, 3)))
    for L in range(model.legs.count):
        s = _elbow_sign(kin, model, L)
        assert np.all(s == _elbow_sign(ref, model, L)[0]) and s[0] != 0


def test_describe_lists_the_explicit_legs(capsys):
    from pkmdyn.cli import main

    assert main(["describe", "--machine", "stewart"]) == 0
    line = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("explicit legs")][0]
    assert "(closed form, 6)" in line and "U_1-P_1-S_1 to the task body (T+B2)" in line and "S_6 (B2)" in line
    assert main(["describe", "--machine", "delta"]) == 0
    assert "explicit legs (closed form, 0): none" in capsys.readouterr().out


def test_describe_names_a_held_spin(capsys, tmp_path):
    import tomlkit

    from pkmdyn.cli import main

    f = tmp_path / "rss.toml"
    f.write_text(tomlkit.dumps(rod_platform("R")))
    assert main(["describe", "--machine", str(f)]) == 0
    line = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("explicit legs")][0]
    assert "(closed form, 5)" in line and "R_2-SA_2 to SB_2 (A2, SA_2 spin held)" in line
