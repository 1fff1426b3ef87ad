"""Mobility and over-constraints (Eq. 1 and the screw analysis of section 5.2) on mechanisms
whose answers are known, and on the PDM itself."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pkmdyn.analysis.mobility import (
    Joint,
    analyse,
    cycle_basis,
    joint_twists,
    kutzbach_mobility,
    overconstraint_count,
    reciprocal_wrenches,
)
from pkmdyn.errors import ParameterError
from pkmdyn.machines.pdm4 import load_params
from pkmdyn.machines.pdm4.kinematics import mechanism_joints

Z = (0.0, 0.0, 1.0)
PLANAR = {"force_z", "couple_x", "couple_y"}


def _unit(v):
    v = np.asarray(v, dtype=float)
    return tuple(v / np.linalg.norm(v))


def _check_consistent(rep):
    # Eq. 1 with A = the screw mobility gives the screw over-constraint count
    assert rep.eq1_overconstraints == rep.overconstraints
    assert rep.kutzbach == rep.mobility - rep.overconstraints


def test_planar_four_bar():
    pts = [(0, 0, 0.3), (0.2, 0.9, 0.3), (1.7, 1.4, 0.3), (2.0, 0.0, 0.3)]
    bodies = ["ground", "crank", "coupler", "rocker", "ground"]
    joints = [Joint(f"R{k}", "R", bodies[k], bodies[k + 1], pts[k], (Z,)) for k in range(4)]
    rep = analyse(joints, "ground", "coupler")
    _check_consistent(rep)
    assert (rep.mobility, rep.overconstraints, rep.output_dof) == (1, 3, 1)
    assert rep.kutzbach == -2
    (loop,) = rep.loops
    assert set(loop.directions) == PLANAR
    assert np.allclose(loop.wrenches, [[0, 0, 1, 0, 0, 0], [0, 0, 0, 1, 0, 0], [0, 0, 0, 0, 1, 0]])


def test_spatial_rssr_four_bar_has_one_idle_freedom_and_no_overconstraint():
    a, b, c, d = (0, 0, 0), (0.3, 0.1, 0.2), (1.1, 0.7, 0.5), (1.4, 0.2, -0.1)
    joints = [
        Joint("R1", "R", "ground", "crank", a, (_unit((0.2, 0.1, 1.0)),)),
        Joint("S1", "S", "crank", "coupler", b),
        Joint("S2", "S", "coupler", "rocker", c),
        Joint("R2", "R", "rocker", "ground", d, (_unit((1.0, 0.3, 0.2)),)),
    ]
    rep = analyse(joints, "ground", "rocker")
    _check_consistent(rep)
    assert (rep.mobility, rep.overconstraints, rep.output_dof) == (2, 0, 1)
    assert rep.loops[0].directions == ()


def test_spherical_four_bar_is_constrained_by_three_forces_through_its_centre():
    axes = [_unit(v) for v in ((0.1, 0.2, 1.0), (1.0, 0.1, 0.3), (0.2, 1.0, 0.4), (-0.7, 0.6, 0.2))]
    bodies = ["ground", "a", "b", "c", "ground"]
    joints = [Joint(f"R{k}", "R", bodies[k], bodies[k + 1], (0, 0, 0), (axes[k],)) for k in range(4)]
    rep = analyse(joints, "ground")
    _check_consistent(rep)
    assert (rep.mobility, rep.overconstraints) == (1, 3)
    assert set(rep.loops[0].directions) == {"force_x", "force_y", "force_z"}


def test_general_spatial_4r_loop_is_rigid_and_twice_overconstrained():
    rng = np.random.default_rng(1)
    bodies = ["ground", "a", "b", "c", "ground"]
    joints = [Joint(f"R{k}", "R", bodies[k], bodies[k + 1], tuple(rng.normal(size=3)), (_unit(rng.normal(size=3)),))
              for k in range(4)]
    rep = analyse(joints, "ground")
    _check_consistent(rep)
    assert (rep.mobility, rep.overconstraints) == (0, 2)


def test_6ups_stewart_platform():
    joints = []
    for k in range(6):
        phi = math.radians(120 * (k // 2) + (-12 if k % 2 == 0 else 12))
        psi = math.radians(120 * (k // 2) + 60 * (1 if k % 2 else -1) + (8 if k % 2 == 0 else -8))
        base = np.array([math.cos(phi), math.sin(phi), 0.0])
        top = np.array([0.5 * math.cos(psi), 0.5 * math.sin(psi), 1.0])
        leg = top - base
        t1 = np.array([-math.sin(phi), math.cos(phi), 0.0])
        joints += [
            Joint(f"U{k}", "U", "ground", f"cyl{k}", tuple(base), (tuple(t1), _unit(np.cross(leg, t1)))),
            Joint(f"P{k}", "P", f"cyl{k}", f"rod{k}", tuple(top), (_unit(leg),)),
            Joint(f"S{k}", "S", f"rod{k}", "platform", tuple(top)),
        ]
    rep = analyse(joints, "ground", "platform")
    _check_consistent(rep)
    assert rep.moving_links == 13
    assert (rep.mobility, rep.overconstraints, rep.output_dof) == (6, 0, 6)
    assert rep.kutzbach == 6
    assert all(loop.overconstraints == 0 for loop in rep.loops)


def test_hip_simulator_3pus_plus_s():
    """One platform of the hip simulator (specs/hip_simulator.md): three vertical P joints,
    U joints (first axis tangential, second perpendicular to it and to the lever), S joints on
    the platform and the central S joint at the hip centre; 3 rotational freedoms."""
    E, e, lever, h = 0.265, 0.144, 0.328, 0.899
    o = np.array([0.0, 0.0, h])
    c, s = math.cos(0.2), math.sin(0.2)
    R = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    joints = [Joint("S0", "S", "ground", "platform", tuple(o))]
    for i, (phi, psi) in enumerate(zip((-60.0, 60.0, 180.0), (-30.0, 90.0, 210.0))):
        phi, psi = math.radians(phi), math.radians(psi)
        A = E * np.array([math.cos(phi), math.sin(phi), 0.0])
        a = o + R @ (e * np.array([math.cos(psi), math.sin(psi), 0.0]))
        b = np.array([A[0], A[1], a[2] - math.sqrt(lever**2 - np.sum((a[:2] - A[:2]) ** 2))])
        t = np.array([-math.sin(phi), math.cos(phi), 0.0])
        joints += [
            Joint(f"P{i}", "P", "ground", f"slider{i}", tuple(b), (Z,)),
            Joint(f"U{i}", "U", f"slider{i}", f"lever{i}", tuple(b), (tuple(t), _unit(np.cross(t, a - b)))),
            Joint(f"S{i}", "S", f"lever{i}", "platform", tuple(a)),
        ]
    rep = analyse(joints, "ground", "platform")
    _check_consistent(rep)
    assert rep.joint_counts == {"S": 4, "P": 3, "U": 3}
    assert (rep.moving_links, rep.mobility, rep.overconstraints, rep.output_dof) == (7, 3, 0, 3)
    assert overconstraint_count(rep.joint_counts, 7, 3) == 0


def test_eq1_for_the_joint_table_of_the_pdm():
    counts = {"S": 2, "U": 2, "R": 11, "P": 4}
    assert overconstraint_count(counts, moving_links=14, dof=4) == 3 * 2 + 4 * 2 + 5 * 11 + 5 * 4 + 4 - 6 * 14
    assert overconstraint_count(counts, 14, 4) == 9
    assert kutzbach_mobility(counts, 14) == -5


@pytest.mark.parametrize("q", [None, (0.01, -0.008, 0.05, 0.2)])
def test_pdm_screw_analysis(q):
    rep = analyse(mechanism_joints(load_params(), q), "ground", "platform")
    _check_consistent(rep)
    assert rep.joint_counts == {"R": 11, "P": 4, "S": 2, "U": 2}
    assert (rep.moving_links, rep.mobility, rep.output_dof, rep.overconstraints) == (14, 4, 4, 9)
    planar = [loop for loop in rep.loops if loop.overconstraints]
    assert len(planar) == 3 and sum(loop.overconstraints for loop in rep.loops) == 9
    for loop in planar:
        assert set(loop.directions) == PLANAR
        assert not any(name.startswith(("S", "U")) for name in loop.joints)


def test_reciprocal_wrenches_do_no_work_on_the_twists():
    rng = np.random.default_rng(5)
    for k in range(1, 6):
        tw = rng.normal(size=(k, 6))
        w = reciprocal_wrenches(tw)
        assert w.shape == (6 - k, 6)
        power = w[:, :3] @ tw[:, 3:].T + w[:, 3:] @ tw[:, :3].T
        assert np.abs(power).max() < 1e-10
    assert joint_twists(Joint("s", "S", "a", "b", (1, 2, 3))).shape == (3, 6)


def test_cycle_basis_size_and_bad_joints():
    joints = [Joint("a", "R", "g", "x", axes=(Z,)), Joint("b", "R", "x", "g", axes=(Z,)), Joint("c", "P", "x", "y", axes=(Z,))]
    assert len(cycle_basis(joints)) == 1
    with pytest.raises(ParameterError, match="joint q: a U joint needs 2 axes"):
        Joint("q", "U", "a", "b", axes=(Z,))
    with pytest.raises(ParameterError, match="unknown kind"):
        Joint("q", "X", "a", "b")
