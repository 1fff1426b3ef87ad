"""Mobility, over-constraint and idle-freedom counts of known mechanisms, the spanning tree
and cut joints, against the textbook answers and the independent count of tests/oracles."""

from __future__ import annotations

import multibody_examples as ex
import numpy as np
import pytest
from oracles import mobility as oracle_mobility

from pkmdyn.errors import ParameterError
from pkmdyn.multibody import (
    analyse_topology,
    load_mechanism,
    reference_task,
    solve_kinematics,
)
from pkmdyn.multibody.dynamics.newton_euler import inverse_dynamics

# name: (kutzbach, mobility, overconstraints, idle, dof, loops)
KNOWN = {
    "four_bar": (ex.four_bar, (-2, 1, 3, 0, 1, 1)),
    "slider_crank": (ex.slider_crank, (-2, 1, 3, 0, 1, 1)),
    "slider_crank_c": (lambda: ex.slider_crank("cylindrical"), (-1, 1, 2, 0, 1, 1)),
    "rssr": (ex.rssr, (2, 2, 0, 1, 1, 1)),
    "stewart": (lambda: ex.MACHINES / "stewart" / "stewart.toml", (6, 6, 0, 0, 6, 5)),
    "stewart_sps": (ex.stewart_sps, (12, 12, 0, 6, 6, 5)),
    "delta": (lambda: ex.MACHINES / "delta" / "delta.toml", (9, 9, 0, 6, 3, 5)),
    "rrr3": (lambda: ex.MACHINES / "rrr3" / "rrr3.toml", (-3, 3, 6, 0, 3, 2)),
    "bennett": (lambda: ex.MACHINES / "bennett" / "bennett.toml", (-2, 1, 3, 0, 1, 1)),
    "rrr3_planar": (ex.rrr3_planar_platform, (-6, 3, 9, 0, 3, 3)),
    "sarrus": (ex.sarrus, (0, 1, 1, 0, 1, 1)),
    "serial_arm": (ex.serial_arm, (2, 2, 0, 0, 2, 0)),
}


@pytest.mark.parametrize("name", sorted(KNOWN))
def test_counts(name):
    make, (gk, mob, t, idle, dof, loops) = KNOWN[name]
    rep = analyse_topology(load_mechanism(make()))
    assert (rep.kutzbach, rep.mobility, rep.overconstraints, rep.idle, rep.dof, rep.loops) == (gk, mob, t, idle, dof, loops)
    assert rep.mobility == rep.kutzbach + rep.overconstraints
    assert len(rep.overconstrained) == rep.overconstraints
    assert len(rep.tree_joints) == rep.bodies and len(rep.cut_joints) == rep.loops


@pytest.mark.parametrize("name", ["stewart", "delta", "rrr3", "bennett"])
def test_kutzbach_against_the_oracle_count(name):
    m = load_mechanism(ex.MACHINES / name / f"{name}.toml")
    joints = [k for k, c in m.topology.joint_counts.items() for _ in range(c)]
    assert m.topology.kutzbach == oracle_mobility.kutzbach(m.nb + 1, joints)


def test_planar_loops_are_overconstrained_in_the_plane_normal_directions():
    rep = analyse_topology(load_mechanism(ex.MACHINES / "rrr3" / "rrr3.toml"))
    # each planar loop: a force normal to the plane and the two couples in it (joint frame z = plane normal)
    assert sorted(d for _, d in rep.overconstrained) == sorted(["force_z", "couple_x", "couple_y"] * 2)


def test_stewart_cuts_the_spherical_joints_and_keeps_the_actuators_in_the_tree():
    m = load_mechanism(ex.MACHINES / "stewart" / "stewart.toml")
    assert all(c.startswith("S_") for c in m.topology.cut_joints)
    assert not any(m.joint_cut[m.act_joint])
    loop = m.loops[0]
    assert loop.type == "spherical" and loop.directions == ("force_x", "force_y", "force_z")
    assert loop.joint == "S_3" and loop.path == ("P_3", "U_3", "U_1", "P_1", "S_1")


def test_cut_joints_can_be_chosen_by_name():
    m = load_mechanism(ex.rrr3_planar_platform(cut_legs=True))
    assert m.topology.cut_joints == ("RC_1", "RC_2", "RC_3")
    assert "plane" in m.topology.tree_joints
    d = ex.four_bar()
    d["mechanism"]["cut_joints"] = ["B"]
    assert load_mechanism(d).topology.cut_joints == ("B",)


def test_cutting_an_actuated_joint_is_refused():
    d = ex.four_bar()
    d["mechanism"]["cut_joints"] = ["A"]
    with pytest.raises(ParameterError, match="cut_joints: 'A' is actuated"):
        load_mechanism(d)


def test_task_must_match_the_degrees_of_freedom():
    d = ex.four_bar()
    d["task"] = {"body": "coupler", "position": ["x", "y"]}
    with pytest.raises(ParameterError, match=r"\[task\] gives 2 coordinate\(s\) but the mechanism has 1 degree"):
        load_mechanism(d)


def test_more_actuators_than_freedoms_is_redundant_actuation():
    """A four-bar with two actuated joints: its least-norm efforts lie along J_ax (one freedom,
    u = A^+ w with A = J_ax^T a row), and the internal force along the other direction."""
    d = ex.four_bar()
    d["joints"][1]["actuated"] = True
    m = load_mechanism(d)
    assert (m.na, m.nt) == (2, 1)
    kin = solve_kinematics(m, *[np.atleast_2d(v) for v in (reference_task(m), [0.3], [1.0])])
    u = inverse_dynamics(m, kin).u[0]
    J = kin.J_ax[0, :, 0]
    assert abs(u[0] * J[1] - u[1] * J[0]) <= 1e-12 * np.abs(u).max() * np.abs(J).max()
    assert np.abs(u).max() > 0


def test_a_rigid_loop_is_refused():
    """A general spatial 4R loop (not Bennett) is rigid: mobility 0, nothing can move."""
    d = ex.four_bar()
    d["joints"][2]["axis"] = [0.3, 0.0, 1.0]
    with pytest.raises(ParameterError, match="mechanism has 0 degree"):
        load_mechanism(d)


def test_sparse_basis_spans_the_same_space_with_fewest_entries():
    """The idle rows' basis: the same row space as the given basis, unit rows, and a
    coordinate direction that the space holds comes out as a unit vector on it."""
    from pkmdyn.multibody.model.topology import sparse_basis

    rng = np.random.default_rng(7)
    # a space holding e_2 and e_5 and one mixed direction over coordinates 0, 1, 3
    mixed = np.zeros(7)
    mixed[[0, 1, 3]] = [0.3, -1.2, 0.8]
    E = np.zeros((3, 7))
    E[0, 2] = E[1, 5] = 1.0
    E[2] = mixed
    B = rng.normal(size=(3, 3)) @ E  # an arbitrary basis of that space
    S = sparse_basis(B)
    assert S.shape == (3, 7)
    assert np.allclose(np.linalg.norm(S, axis=1), 1.0, atol=1e-14)
    assert np.linalg.matrix_rank(np.vstack([S, E]), tol=1e-10) == 3  # the same space
    supports = sorted(tuple(np.flatnonzero(r)) for r in S)
    assert supports == [(0, 1, 3), (2,), (5,)]
    assert np.allclose(abs(S[[tuple(np.flatnonzero(r)) for r in S].index((0, 1, 3))]), abs(mixed) / np.linalg.norm(mixed),
                       atol=1e-12)
