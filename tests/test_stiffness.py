"""Stiffness, deflection and natural frequencies with the actuators locked
(pkmdyn.multibody.analyses.stiffness), against closed forms (Gosselin's J^T diag(k) J with the Stewart
oracle's Jacobian, cantilever and bar formulas), an independent frame finite-element model
(tests/oracles/frame_fe.py) and the eigenvalues of M^-1 K; and the command."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys

import numpy as np
import pytest

import multibody_examples as ex
from oracles import stewart
from oracles.frame_fe import Frame
from pkmdyn.multibody import load_mechanism, solve_kinematics
from pkmdyn.multibody.dynamics.verbs import machine_verbs
from pkmdyn.multibody.dynamics.newton_euler import joint_reactions
from pkmdyn.multibody.description.schema import load_description
from pkmdyn.multibody.kinematics.inverse import reference_task
from pkmdyn.multibody.model.compiler import compile_model
from pkmdyn.multibody.analyses.stiffness import StiffnessDataMissing, deflection, stiffness

E_STEEL, NU = 2.1e11, 0.3
G_STEEL = E_STEEL / (2 * (1 + NU))


def _rel(a, b):
    return float(np.abs(np.asarray(a) - np.asarray(b)).max() / max(np.abs(np.asarray(b)).max(), 1e-300))


def _with_drives(d, k):
    """The description's model with leg P_i's drive stiffness ``k[i]`` [N/m] (the legs come from
    two templates, so the values are set on the expanded joints)."""
    desc = load_description(d)
    joints = [dataclasses.replace(js, stiffness={"drive": float(k[int(js.name.split("_")[1]) - 1])})
              if js.actuated else js for js in desc.joints]
    return compile_model(dataclasses.replace(desc, joints=type(desc.joints)(joints)))


def _poses(m, n, seed):
    rng = np.random.default_rng(seed)
    amp = np.array([0.08, 0.08, 0.08, 0.1, 0.1, 0.15])
    return reference_task(m) + rng.uniform(-1, 1, (n, 6)) * amp


def _oracle_J(x):
    """dL/dx of the six legs (oracle order) at task poses x (n, 6), Euler XYZ."""
    a, b, _ = stewart.default_geometry()
    ref = stewart.inverse_kinematics(a, b, x[:, :3], x[:, 3:], "XYZ")
    E = np.stack([stewart.euler_kinematics(x[:, 3:], "XYZ", np.eye(3)[k][None].repeat(len(x), 0))["omega"]
                  for k in range(3)], axis=-1)
    return np.concatenate([ref["J"][:, :, :3], np.einsum("nij,njk->nik", ref["J"][:, :, 3:], E)], axis=-1), ref["L"]


def test_stewart_with_drive_springs_is_gosselin():
    k = np.array([1.0e7, 2.0e7, 3.5e7, 1.5e7, 2.5e7, 0.8e7])
    m = _with_drives(ex.builtin_dict("stewart"), k)
    x = _poses(m, 12, seed=5)
    st = stiffness(m, solve_kinematics(m, x))
    J, _ = _oracle_J(x)
    K_ref = np.einsum("nat,a,nas->nts", J, k, J)
    assert _rel(st.K_task, K_ref) < 1e-10
    # the inverse is the compliance, and the eigen-stiffnesses are K's
    assert _rel(np.einsum("nij,njk->nik", st.K_task, st.C_task), np.broadcast_to(np.eye(6), (12, 6, 6))) < 1e-10
    assert _rel(st.eigenvalues, np.linalg.eigvalsh(K_ref)) < 1e-10


def test_stewart_beam_pistons_add_EA_over_L_in_series():
    k = np.full(6, 2.0e7)
    outer, inner = 0.03, 0.02
    d = ex.builtin_dict("stewart")
    for leg in d["legs"]:
        for b in leg["bodies"]:
            if b["name"] == "piston":
                b["section"] = {"outer_diameter_m": outer, "inner_diameter_m": inner}
                b["material"] = {"youngs_modulus_Pa": E_STEEL, "poisson_ratio": NU}
        for j in leg["joints"]:
            if j["name"] == "P":  # its node on both bodies the cylinder's point, at the U centre
                j["bearing"] = "cylinder"
    m = _with_drives(d, k)
    x = _poses(m, 6, seed=8)
    st = stiffness(m, solve_kinematics(m, x))
    J, L = _oracle_J(x)
    EA = E_STEEL * np.pi * (outer**2 - inner**2) / 4
    k_leg = 1.0 / (1.0 / k + L / EA)  # the piston's beam spans the leg, U centre to S centre
    K_ref = np.einsum("nat,na,nas->nts", J, k_leg, J)
    assert _rel(st.K_task, K_ref) < 1e-10
    # and it is softer than the drives alone by a visible amount
    assert _rel(st.K_task, np.einsum("nat,a,nas->nts", J, k, J)) > 1e-3


def _tube_stewart(piston_parent=False, bearing=None, k=2.0e7):
    """The Stewart platform with cylinders and pistons both tubes (different sections) and each
    prismatic joint at the cylinder's mouth, half-way along the leg at the reference pose; with
    ``piston_parent`` the joint names the piston as its parent (its axis reversed, so the
    coordinate is still the leg length); ``bearing``: "cylinder" or "piston" (the joint's key)."""
    d = ex.builtin_dict("stewart")
    mat = {"youngs_modulus_Pa": E_STEEL, "poisson_ratio": NU}
    for leg in d["legs"]:
        for b in leg["bodies"]:
            outer = 0.05 if b["name"] == "cylinder" else 0.03
            b.update(section={"outer_diameter_m": outer, "inner_diameter_m": outer - 0.01}, material=mat)
        joints = {j["name"]: j for j in leg["joints"]}
        P, S = joints["P"], joints["S"]
        base, top = np.array(P["point_m"], float), np.array(S["point_m"], float)
        P["point_m"] = (base + 0.5 * (top - base)).tolist()
        P["stiffness"] = {"drive_N_m": k}
        if piston_parent:
            P["parent"], P["child"] = P["child"], P["parent"]
            P["axis"] = (-np.array(P["axis"], float)).tolist()
        if bearing is not None:
            P["bearing"] = bearing
    return d


def _tube_EA(outer):
    return E_STEEL * np.pi * (outer**2 - (outer - 0.01) ** 2) / 4


@pytest.mark.parametrize("bearing", [None, "cylinder", "piston"])
def test_tube_legs_do_not_depend_on_which_body_is_the_parent(bearing):
    """Cylinder and piston both tubes: the Cartesian stiffness and the frequencies are the same
    whichever body the prismatic joint names its parent (1e-12), and the legs' axial stiffness is
    the closed form of three springs in series, each tube of the length the bearing decides:
    without one each tube keeps its own length (half the reference leg each); with the cylinder
    (or piston) as the bearing the other tube's free length takes the stroke."""
    m1 = load_mechanism(_tube_stewart(False, bearing))
    m2 = load_mechanism(_tube_stewart(True, bearing))
    x = _poses(m1, 6, seed=11)
    s1, s2 = stiffness(m1, solve_kinematics(m1, x)), stiffness(m2, solve_kinematics(m2, x))
    assert _rel(s2.K_task, s1.K_task) < 1e-12
    assert _rel(s2.frequencies, s1.frequencies) < 1e-12
    J, L = _oracle_J(x)
    L0 = stewart.inverse_kinematics(*stewart.default_geometry()[:2], reference_task(m1)[None, :3],
                                    reference_task(m1)[None, 3:], "XYZ")["L"]
    half = 0.5 * L0
    cyl = {None: half, "cylinder": half, "piston": L - half}[bearing]
    pis = {None: half, "cylinder": L - half, "piston": half}[bearing]
    k_leg = 1.0 / (1.0 / 2.0e7 + cyl / _tube_EA(0.05) + pis / _tube_EA(0.03))
    assert _rel(s1.K_task, np.einsum("nat,na,nas->nts", J, k_leg, J)) < 1e-10
    # the three models differ visibly at these poses, so the check can tell them apart
    other = 1.0 / (1.0 / 2.0e7 + (L - half) / _tube_EA(0.05) + half / _tube_EA(0.03))
    if bearing != "piston":
        assert _rel(s1.K_task, np.einsum("nat,na,nas->nts", J, other, J)) > 1e-5


def test_a_bearing_must_be_a_body_of_a_sliding_joint(tmp_path, capsys):
    from pkmdyn.errors import ParameterError

    d = _tube_stewart(False, "platform")
    with pytest.raises(ParameterError, match=r"bearing: 'platform_?\w*' is neither the joint's parent"):
        load_mechanism(d)
    d = _tube_stewart(False)
    d["legs"][0]["joints"][0]["bearing"] = "cylinder"  # the universal joint: it does not slide
    with pytest.raises(ParameterError, match="bearing: only for a joint that slides, not a universal joint"):
        load_mechanism(d)


def _four_bar(a=0.5, b=0.8, c=0.6, D=0.02, kd=2.0e4, elastic=("crank", "rocker"), crank_x=0.0):
    """A planar four-bar in z = 0: crank A(0,0)-B(crank_x, a), coupler B-C(b, ...), rocker C-D;
    the crank's drive a torsional spring; the listed links beams of diameter D."""
    A, B = (0.0, 0.0, 0.0), (crank_x, a, 0.0)
    C, Dp = (crank_x + b, a + 0.1, 0.0), (b + 0.2, a + 0.1 - c, 0.0)
    sec = {"outer_diameter_m": D}
    mat = {"youngs_modulus_Pa": E_STEEL, "poisson_ratio": NU}
    bodies = []
    for name, p, q in (("crank", A, B), ("coupler", B, C), ("rocker", C, Dp)):
        bd = ex.body(name, tuple((np.add(p, q) / 2).tolist()), mass=2.0)
        if name in elastic:
            bd.update(section=sec, material=mat)
        bodies.append(bd)
    Z = [0.0, 0.0, 1.0]
    joints = [ex.joint("A", "revolute", "ground", "crank", A, axis=Z, actuated=True, stiffness={"drive_Nm_rad": kd}),
              ex.joint("B", "revolute", "crank", "coupler", B, axis=Z),
              ex.joint("C", "revolute", "coupler", "rocker", C, axis=Z),
              ex.joint("D", "revolute", "rocker", "ground", Dp, axis=Z)]
    return {"mechanism": {"name": "beam_four_bar", "gravity_m_s2": [0.0, -9.81, 0.0]}, "bodies": bodies,
            "joints": joints, "task": {"body": "coupler", "position": ["x"]}}, (A, B, C, Dp)


def test_square_four_bar_against_textbook_beams():
    """Crank A(0,0)-B(0,a) and rocker C(b,a)-D(b,0) of one section, a rigid coupler B-C: a
    horizontal force at the coupler bends the crank as a cantilever on its drive spring
    (the rocker, pinned at both ends, carries nothing); a vertical force at the coupler's middle
    is shared by the two links in tension; a moment turns the coupler by their opposite
    stretches."""
    a, b, D, kd = 0.5, 0.8, 0.02, 2.0e4
    d = {"mechanism": {"name": "square"},
         "bodies": [dict(ex.body("crank", (0, a / 2, 0)), section={"outer_diameter_m": D},
                         material={"youngs_modulus_Pa": E_STEEL, "poisson_ratio": NU}),
                    ex.body("coupler", (b / 2, a, 0)),
                    dict(ex.body("rocker", (b, a / 2, 0)), section={"outer_diameter_m": D},
                         material={"youngs_modulus_Pa": E_STEEL, "poisson_ratio": NU})],
         "joints": [ex.joint("A", "revolute", "ground", "crank", (0, 0, 0), axis=ex.Z, actuated=True,
                             stiffness={"drive_Nm_rad": kd}),
                    ex.joint("B", "revolute", "crank", "coupler", (0, a, 0), axis=ex.Z),
                    ex.joint("C", "revolute", "coupler", "rocker", (b, a, 0), axis=ex.Z),
                    ex.joint("D", "revolute", "rocker", "ground", (b, 0, 0), axis=ex.Z)],
         "task": {"body": "coupler", "position": ["x"]}}
    m = load_mechanism(d)
    st = stiffness(m, solve_kinematics(m, reference_task(m)[None]))
    I, A = np.pi * D**4 / 64, np.pi * D**2 / 4
    C = st.C_point[0]
    assert C[3, 3] == pytest.approx(a**3 / (3 * E_STEEL * I) + a**2 / kd, rel=1e-10)
    assert C[4, 4] == pytest.approx(a / (2 * E_STEEL * A), rel=1e-10)
    assert C[2, 2] == pytest.approx(2 * a / (E_STEEL * A * b**2), rel=1e-10)
    assert st.K_task[0, 0, 0] == pytest.approx(1.0 / (a**3 / (3 * E_STEEL * I) + a**2 / kd), rel=1e-10)


def _fe_four_bar(pts, D, kd, elastic, loads=None):
    """The same four-bar as a frame: beams for the elastic links, rigid links otherwise, revolute
    hinges about z (translations and the two other rotations coupled), the drive a spring."""
    A, B, C, Dp = (np.array(p) for p in pts)
    f = Frame()
    I, Ar = np.pi * D**4 / 64, np.pi * D**2 / 4
    ends = {}
    for name, p, q in (("crank", A, B), ("coupler", B, C), ("rocker", C, Dp)):
        n1, n2 = f.add_node(p), f.add_node(q)
        mid = f.add_node((p + q) / 2)
        if name in elastic:
            nodes = f.add_beam(n1, n2, E_STEEL, G_STEEL, Ar, I, I, 2 * I, segments=2)
            assert len(nodes) == 3
            f.couple(nodes[1], mid, (0, 1, 2, 3, 4, 5))
        else:
            f.add_rigid(mid, n1)
            f.add_rigid(mid, n2)
        ends[name] = (n1, n2, mid)
    hinge = (0, 1, 2, 3, 4)
    f.support(ends["crank"][0], hinge)
    f.spring(ends["crank"][0], 5, kd)
    f.couple(ends["crank"][1], ends["coupler"][0], hinge)
    f.couple(ends["coupler"][1], ends["rocker"][0], hinge)
    f.support(ends["rocker"][1], hinge)
    return f, ends


@pytest.mark.parametrize("elastic", [("crank", "coupler", "rocker"), ("crank", "rocker"), ("coupler",)])
def test_over_constrained_four_bar_of_beams_against_frame_elements(elastic):
    """A spatially over-constrained four-bar (three parallel-axis hinges too many): the 6 x 6
    compliance of the coupler's middle, every direction including the out-of-plane ones that
    the self-stress decides, against the independent frame model."""
    kd, D = 3.0e4, 0.02
    d, pts = _four_bar(elastic=elastic, crank_x=0.15, kd=kd, D=D)
    m = load_mechanism(d)
    assert m.topology.overconstraints == 3
    st = stiffness(m, solve_kinematics(m, reference_task(m)[None]))
    f, ends = _fe_four_bar(pts, D, kd, elastic)
    C_fe = f.compliance(ends["coupler"][2])
    perm = [3, 4, 5, 0, 1, 2]  # [rotations; translations] -> the frame's [translations; rotations]
    C = st.C_point[0][np.ix_(perm, perm)]
    assert _rel(C, C_fe) < 1e-9


def test_deflection_under_gravity_against_frame_elements():
    """The four-bar under its own weight (static): the coupler's deflection along the task
    coordinate from the motion's reactions (unit-load method) against the frame model loaded
    by the same weights at the links' middles."""
    kd, D = 3.0e4, 0.02
    elastic = ("crank", "coupler", "rocker")
    d, pts = _four_bar(elastic=elastic, crank_x=0.15, kd=kd, D=D)
    m = load_mechanism(d)
    x = reference_task(m)[None]
    kin = solve_kinematics(m, x)
    reac = joint_reactions(m, kin)
    dx = deflection(m, kin, reac)
    f, ends = _fe_four_bar(pts, D, kd, elastic)
    g = np.array([0.0, -9.81, 0.0])
    loads = {ends[name][2]: np.concatenate([2.0 * g, np.zeros(3)]) for name in ("crank", "coupler", "rocker")}
    u = f.solve(loads)
    # the task point is the coupler's centre of mass, its x the task coordinate
    assert dx[0, 0] == pytest.approx(u[ends["coupler"][2]][0], rel=1e-9)
    assert abs(dx[0, 0]) > 1e-7  # a real deflection, not zero against zero


def test_deflection_is_compliance_times_load():
    """A constant wrench on the Stewart platform, no gravity, at rest: the deflection from the
    reactions equals the task compliance times the generalised force (two routes)."""
    k = np.array([1.0e7, 2.0e7, 3.5e7, 1.5e7, 2.5e7, 0.8e7])
    d = ex.builtin_dict("stewart")
    d["mechanism"]["gravity_m_s2"] = [0.0, 0.0, 0.0]
    F, M = np.array([120.0, -80.0, 300.0]), np.array([15.0, -25.0, 40.0])
    d["loads"] = [{"body": "platform", "force_N": F.tolist(), "moment_Nm": M.tolist(), "point_m": [0.1, 0.05, 1.0]}]
    m = _with_drives(d, k)
    x = _poses(m, 4, seed=3)
    kin = solve_kinematics(m, x)
    dx = deflection(m, kin, joint_reactions(m, kin))
    st = stiffness(m, kin)
    # the load as a wrench at the task point [moment; force], then the task body's displacement
    pl = m.task_body
    p_task = kin.origin[:, pl] + np.einsum("nij,j->ni", kin.R[:, pl], m.task_point)
    p_load = kin.origin[:, pl] + np.einsum("nij,j->ni", kin.R[:, pl], m.load_point[0])
    w = np.concatenate([M + np.cross(p_load - p_task, F), np.broadcast_to(F, (4, 3))], axis=1)
    t = np.einsum("nij,nj->ni", st.C_point, w)  # [dtheta; dp_task]
    J, _ = _oracle_J(x)
    # the same displacement in task coordinates: dp directly, the angles through omega = E phi_dot
    E = np.stack([stewart.euler_kinematics(x[:, 3:], "XYZ", np.eye(3)[k_][None].repeat(4, 0))["omega"]
                  for k_ in range(3)], axis=-1)
    dphi = np.linalg.solve(E, t[:, :3, None])[..., 0]
    assert _rel(dx[:, :3], t[:, 3:]) < 1e-9
    assert _rel(dx[:, 3:], dphi) < 1e-9
    # and from the drives' efforts: a drive pushing with u is compressed by u / k, dx = J^-1 (-u / k)
    u = joint_reactions(m, kin).u
    legs = [m.actuator_names.index(f"P_{i + 1}") for i in range(6)]
    assert _rel(np.linalg.solve(J, (-u[:, legs] / k)[..., None])[..., 0], dx) < 1e-9


def test_stewart_frequencies_are_the_eigenvalues_of_M_inv_K():
    m = load_mechanism(ex.MACHINES / "stewart" / "stewart.toml")
    x = _poses(m, 5, seed=11)
    st = stiffness(m, solve_kinematics(m, x))
    M = machine_verbs(m).mass_matrix(m, x)  # the dynamics' own mass matrix (no drives here)
    lam = np.sort(np.linalg.eigvals(np.linalg.solve(M, st.K_task)).real, axis=1)
    assert _rel((2 * np.pi * st.frequencies) ** 2, lam) < 1e-8
    # energy of a mode: phi^T K phi = omega^2 phi^T M phi, the modes M-orthogonal
    w2 = (2 * np.pi * st.frequencies) ** 2
    for s in range(5):
        phi = st.modes[s]
        Km, Mm = phi.T @ st.K_task[s] @ phi, phi.T @ M[s] @ phi
        assert _rel(np.diag(Km), w2[s] * np.diag(Mm)) < 1e-8
        assert _rel(np.diag(Mm), st.modal_mass[s]) < 1e-10
        off = Mm - np.diag(np.diag(Mm))
        assert np.abs(off).max() < 1e-8 * np.abs(Mm).max()
        assert np.abs(phi).max(axis=0) == pytest.approx(np.ones(6), rel=1e-12)


def _stewart_with_rotors(lead=0.005, gear=2.0, rotor=3e-5):
    d = ex.builtin_dict("stewart")
    for leg in d["legs"]:
        leg["actuators"] = [{"joint": "P", "name": "M", "screw_lead_m": lead, "gear_ratio": gear,
                             "rotor_inertia_kgm2": rotor}]
    return d, gear * 2 * np.pi / lead


def test_the_rotors_held_or_moving():
    """Screw drives of large reflected inertia: the same stiffness either way; with the rotors
    moving the frequencies are those of the dynamics' own mass matrix (which carries the rotors),
    held those of that matrix less J^T diag(k^2 I_r) J, J from the closed-form oracle."""
    d, k = _stewart_with_rotors()
    m = load_mechanism(d)
    x = _poses(m, 4, seed=21)
    kin = solve_kinematics(m, x)
    held, moving = stiffness(m, kin), stiffness(m, kin, rotors="moving")
    assert held.rotors == "held" and moving.rotors == "moving"
    assert _rel(moving.K_task, held.K_task) < 1e-14
    M = machine_verbs(m).mass_matrix(m, x)
    J, _ = _oracle_J(x)
    M_held = M - np.einsum("nat,nas->nts", J, J) * (k * k * 3e-5)
    for st, MM in ((moving, M), (held, M_held)):
        lam = np.sort(np.linalg.eigvals(np.linalg.solve(MM, st.K_task)).real, axis=1)
        assert _rel((2 * np.pi * st.frequencies) ** 2, lam) < 1e-8
    for st in (held, moving):
        assert _rel(st.frequencies_rotors_held, held.frequencies) < 1e-14
        assert _rel(st.frequencies_rotors_moving, moving.frequencies) < 1e-14
    assert np.all(moving.frequencies[:, 0] < 0.8 * held.frequencies[:, 0])  # 190 kg reflected per leg
    # without rotors the two conventions are one
    plain = load_mechanism(ex.MACHINES / "stewart" / "stewart.toml")
    st = stiffness(plain, solve_kinematics(plain, x), rotors="moving")
    assert np.array_equal(st.frequencies_rotors_held, st.frequencies_rotors_moving)
    from pkmdyn.errors import ParameterError

    with pytest.raises(ParameterError, match="rotors: 'free' is not one of held, moving"):
        stiffness(m, kin, rotors="free")


def test_the_command_writes_both_rotor_conventions(tmp_path, capsys):
    import tomlkit

    d, _ = _stewart_with_rotors()
    path = tmp_path / "stewart_screws.toml"
    path.write_text(tomlkit.dumps(d))
    from pkmdyn.cli import main

    out = {}
    for rotors in ("held", "moving"):
        out[rotors] = tmp_path / rotors
        assert main(["stiffness", "--machine", str(path), "--rotors", rotors, "--out", str(out[rotors])]) == 0
        assert f"natural frequencies (rotors {rotors})" in capsys.readouterr().out
    docs = {r: json.loads((out[r] / "stiffness.json").read_text()) for r in out}
    for r, doc in docs.items():
        pose = doc["poses"][0]
        assert doc["rotors"] == pose["rotors"] == r
        assert pose["frequencies_Hz"] == pose[f"frequencies_rotors_{r}_Hz"]
        assert pose["modes"][0]["frequency_Hz"] == pose["frequencies_Hz"][0]
    a, b = docs["held"]["poses"][0], docs["moving"]["poses"][0]
    assert a["frequencies_rotors_moving_Hz"] == b["frequencies_rotors_moving_Hz"]
    assert b["frequencies_Hz"][0] < 0.8 * a["frequencies_Hz"][0]
    bad = tmp_path / "bad"
    assert main(["stiffness", "--machine", str(path), "--rotors", "free", "--out", str(bad)]) == 2
    assert not bad.exists()


def test_worst_directions_of_a_stewart():
    m = load_mechanism(ex.MACHINES / "stewart" / "stewart.toml")
    x = _poses(m, 3, seed=2)
    st = stiffness(m, solve_kinematics(m, x))
    for s in range(3):
        Cf = st.C_point[s, 3:, 3:]
        d = st.min_stiffness_direction[s]
        # the worst direction's compliance is the largest over random directions
        rng = np.random.default_rng(s)
        v = rng.normal(size=(500, 3))
        v /= np.linalg.norm(v, axis=1, keepdims=True)
        assert np.einsum("ki,ij,kj->k", v, Cf, v).max() <= d @ Cf @ d * (1 + 1e-12)
        assert st.min_stiffness[s] == pytest.approx(1.0 / (d @ Cf @ d), rel=1e-10)


def test_delta_with_drive_springs_against_the_closed_form_jacobian():
    """The Delta robot (rigid arms and rods, torsional drives of stiffness k): K = J^T k J with
    J = d theta/d p = B^-1 A of the independent closed form (tests/oracles/delta.py); its platform
    cannot turn."""
    from oracles import delta

    m = load_mechanism(ex.MACHINES / "delta" / "delta.toml")
    rng = np.random.default_rng(4)
    x = reference_task(m) + rng.uniform(-1, 1, (8, 3)) * np.array([0.15, 0.15, 0.1])
    kin = solve_kinematics(m, x)
    st = stiffness(m, kin)
    g = delta.williams_irb360_geometry()
    theta = delta.inverse_kinematics(x, g["R_b"], g["R_p"], g["L_A"], g["L_B"])
    A, B, _ = delta.jacobian(x, theta, g["R_b"], g["R_p"], g["L_A"])
    J = np.linalg.solve(B, A)
    k = m.joint_stiffness[m.act_joint[0]]["drive"]
    assert _rel(st.K_task, k * np.einsum("nat,nas->nts", J, J)) < 1e-9
    assert np.all(np.isinf(st.min_rot_stiffness))
    assert np.all(np.isfinite(st.min_stiffness)) and np.all(st.min_stiffness > 0)


def test_no_compliance_source_is_refused():
    d = ex.builtin_dict("stewart")
    for leg in d["legs"]:
        for j in leg["joints"]:
            j.pop("stiffness", None)
    m = load_mechanism(d)
    with pytest.raises(StiffnessDataMissing, match="no compliance source"):
        stiffness(m, solve_kinematics(m, reference_task(m)[None]))


def test_section_without_material_is_named():
    d, _ = _four_bar()
    d["bodies"][0].pop("material")
    m = load_mechanism(d)
    with pytest.raises(StiffnessDataMissing, match="'crank'.*no material"):
        stiffness(m, solve_kinematics(m, reference_task(m)[None]))


def _cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "pkmdyn.cli", *args], capture_output=True, text=True, cwd=cwd)


def _write(tmp_path, d, name="m.toml"):
    import tomlkit

    p = tmp_path / name
    p.write_text(tomlkit.dumps(d))
    return p


@pytest.mark.parametrize("change, words", [
    (lambda d: d["joints"][0].update(stiffness={"drive_Nm_rad": -5.0}), "drive_Nm_rad"),
    (lambda d: d["joints"][1].update(stiffness={"drive_Nm_rad": 5.0}), "only an actuated joint"),
    (lambda d: d["joints"][0].update(stiffness={"drive_N_m": 5.0}), "drive_Nm_rad"),
    (lambda d: d["joints"][1].update(stiffness={"force_N_m": [1e8, 0.0, 1e8]}), "force_N_m"),
    (lambda d: d["bodies"][0]["material"].update(youngs_modulus_Pa=0.0), "youngs_modulus_Pa"),
    (lambda d: d["bodies"][2].pop("material"), "no material"),
    (lambda d: [j.pop("stiffness", None) for j in d["joints"]] and [b.pop(k, None) for b in d["bodies"]
                                                                     for k in ("section", "material")],
     "no compliance source"),
])
def test_bad_compliance_data_exit_2_nothing_written(tmp_path, change, words):
    d, _ = _four_bar()
    change(d)
    path = _write(tmp_path, d)
    out = tmp_path / "out"
    r = _cli("stiffness", "--machine", str(path), "--out", str(out))
    assert r.returncode == 2, r.stderr
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and words in lines[0], r.stderr
    assert not out.exists()


def test_singular_pose_is_refused(tmp_path):
    """Coupler and rocker in line: with the crank locked, the coupler's far end moves across the
    line freely (infinite compliance)."""
    d, _ = _four_bar()
    B = (0.0, 0.5, 0.0)
    d["joints"][1]["point_m"] = list(B)
    d["joints"][2]["point_m"] = [0.8, 0.5, 0.0]
    d["joints"][3]["point_m"] = [1.4, 0.5, 0.0]
    d["bodies"][1]["com_m"] = [0.4, 0.5, 0.0]
    d["bodies"][2]["com_m"] = [1.1, 0.5, 0.0]
    path = _write(tmp_path, d)
    out = tmp_path / "out"
    r = _cli("stiffness", "--machine", str(path), "--out", str(out))
    assert r.returncode == 2, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and "singular" in r.stderr, r.stderr
    assert not out.exists()


def test_command_pose_motion_and_grid(tmp_path):
    out = tmp_path / "pose"
    r = _cli("stiffness", "--machine", "stewart", "--pose", "x=0.02,euler3_rad=0.05", "--out", str(out))
    assert r.returncode == 0, r.stderr
    doc = json.loads((out / "stiffness.json").read_text())
    p = doc["poses"][0]
    assert p["task"]["x_m"] == 0.02 and p["task"]["euler3_rad"] == 0.05
    K = np.array(p["K_task"])
    assert K.shape == (6, 6) and np.allclose(K, K.T, rtol=1e-12, atol=0)
    assert p["K_task_units"][0][3] == "N/rad" and p["K_task_units"][3][0] == "N m/m"
    assert len(p["frequencies_Hz"]) == 6 and p["frequencies_Hz"] == sorted(p["frequencies_Hz"])
    assert doc["sources"]["drives"] and (out / "report.html").exists()

    # a motion: the deflection columns, the same stiffness at its samples as the API's
    from pkmdyn.multibody import default_motion

    m = load_mechanism(ex.MACHINES / "stewart" / "stewart.toml")
    mo = default_motion(m)
    cols = {"t_s": mo.t}
    for i, (n, u) in enumerate(zip(m.task_names, m.task_units)):
        cols[f"{n}_{u}"] = mo.x[:, i]
    mfile = tmp_path / "motion.csv"
    names = list(cols)
    mfile.write_text(",".join(names) + "\n" + "\n".join(",".join(repr(float(cols[k][s])) for k in names)
                                                        for s in range(len(mo.t))) + "\n")
    out = tmp_path / "motion"
    r = _cli("stiffness", "--machine", "stewart", "--motion", str(mfile), "--out", str(out))
    assert r.returncode == 0, r.stderr
    head = (out / "results.csv").read_text().splitlines()[0].split(",")
    for n, u in zip(m.task_names, m.task_units):
        assert f"{n}_deflection_{u}" in head
    assert "lowest_frequency_Hz" in head and "min_stiffness_N_m" in head
    # the library's result turns into the same columns (pkmdyn.stiffness(...).columns)
    import pkmdyn

    rows = [line.split(",") for line in (out / "results.csv").read_text().splitlines()]
    table = {name: np.array([float(r[k]) for r in rows[1:]]) for k, name in enumerate(rows[0])}
    kin = pkmdyn.kinematics(m, mo)
    got = pkmdyn.stiffness(m, kin).columns(m)
    assert set(got) == {f"{n}_{u}" for n, u in zip(m.task_names, m.task_units)} | {
        "min_stiffness_N_m", "min_rot_stiffness_Nm_rad", "lowest_frequency_Hz"}
    for name, v in got.items():
        np.testing.assert_allclose(v, table[name], rtol=1e-9, atol=1e-12, err_msg=name)

    out = tmp_path / "grid"
    r = _cli("stiffness", "--machine", "stewart", "--grid", "x=-0.1:0.1:3,z=0.95:1.05:3", "--out", str(out))
    assert r.returncode == 0, r.stderr
    assert (out / "stiffness_map.png").stat().st_size > 0
    rows = (out / "grid.csv").read_text().splitlines()
    assert len(rows) == 1 + 9
    doc = json.loads((out / "stiffness.json").read_text())
    worst = doc["worst"]
    assert worst["min_stiffness_N_m"] == min(p["min_stiffness_N_m"] for p in doc["poses"])


def test_sweep_reports_stiffness_metrics_that_scale_with_the_drives(tmp_path):
    """Doubling every drive's stiffness (the only source) doubles the stiffness and multiplies
    the frequencies by sqrt(2), design by design."""
    pq = pytest.importorskip("pyarrow.parquet")
    from pkmdyn.cli import main

    space = tmp_path / "space.toml"
    space.write_text('[sampling]\nmethod = "grid"\n[motion]\nreactions = false\n[parameters]\n'
                     '"parameters.drive_stiffness_N_m" = { values = [1.0e7, 2.0e7] }\n'
                     '[objectives]\nmin_stiffness_N_m = "max"\n')
    out = tmp_path / "out"
    assert main(["sweep", "--machine", "stewart", "--space", str(space), "--workers", "0", "--no-plots",
                 "--out", str(out)]) == 0
    rows = sorted(pq.read_table(out / "designs.parquet").to_pylist(), key=lambda r: r["design_id"])
    assert [r["status"] for r in rows] == ["ok", "ok"]
    assert rows[1]["min_stiffness_N_m"] == pytest.approx(2 * rows[0]["min_stiffness_N_m"], rel=1e-9)
    assert rows[1]["min_rot_stiffness_Nm_rad"] == pytest.approx(2 * rows[0]["min_rot_stiffness_Nm_rad"], rel=1e-9)
    assert rows[1]["lowest_frequency_Hz"] == pytest.approx(np.sqrt(2) * rows[0]["lowest_frequency_Hz"], rel=1e-9)


def test_sweep_without_stiffness_has_no_stiffness_columns(tmp_path, capsys):
    """[motion] stiffness = false: the same rows without the stiffness metrics, and an objective
    naming one is refused before any work, naming it."""
    pq = pytest.importorskip("pyarrow.parquet")
    from pkmdyn.cli import main

    text = ('[sampling]\nmethod = "grid"\n[motion]\nreactions = false\nstiffness = {flag}\n[parameters]\n'
            '"parameters.height_m" = {{ values = [0.95, 1.05] }}\n[objectives]\n{objective} = "max"\n')
    tables = {}
    for flag in ("true", "false"):
        space = tmp_path / f"space_{flag}.toml"
        space.write_text(text.format(flag=flag, objective="gci"))
        out = tmp_path / flag
        assert main(["sweep", "--machine", "stewart", "--space", str(space), "--workers", "0", "--no-plots",
                     "--out", str(out)]) == 0
        tables[flag] = pq.read_table(out / "designs.parquet")
    names = {"min_stiffness_N_m", "min_rot_stiffness_Nm_rad", "lowest_frequency_Hz"}
    assert names <= set(tables["true"].column_names)
    assert not names & set(tables["false"].column_names)
    assert tables["false"].column_names == [c for c in tables["true"].column_names if c not in names]
    assert tables["false"].column("gci").to_pylist() == tables["true"].column("gci").to_pylist()
    space = tmp_path / "space_bad.toml"
    space.write_text(text.format(flag="false", objective="min_stiffness_N_m"))
    capsys.readouterr()
    assert main(["sweep", "--machine", "stewart", "--space", str(space), "--workers", "0", "--no-plots",
                 "--out", str(tmp_path / "bad")]) == 2
    assert "min_stiffness_N_m" in capsys.readouterr().err
    assert not (tmp_path / "bad").exists()


def test_a_long_motion_in_chunks_equals_one_chunk(tmp_path, monkeypatch):
    """pkmdyn stiffness --motion computes the structure chunk by chunk: the same rows and the
    same worst sample with a chunk of 37 samples as with one chunk."""
    import csv

    import pkmdyn.jobs.stiffness as job
    from pkmdyn.multibody import default_motion

    m = load_mechanism(ex.MACHINES / "stewart" / "stewart.toml")
    mo = default_motion(m)
    out = []
    for size in (10_000, 37):
        monkeypatch.setattr(job, "MOTION_CHUNK", size)
        folder = tmp_path / f"c{size}"
        folder.mkdir()
        doc, _ = job.run_stiffness(m, folder, motion=mo)
        rows = list(csv.DictReader((folder / "results.csv").open()))
        out.append((doc["worst"]["index"], np.array([[float(v) for v in r.values()] for r in rows])))
    assert out[0][0] == out[1][0]
    # per sample the same computation; only the batched linear algebra's rounding may differ
    scale = np.abs(out[0][1]).max(axis=0)
    assert np.all(np.abs(out[0][1] - out[1][1]) <= 1e-10 * scale + 1e-300)


def test_run_writes_the_deflection_columns(tmp_path):
    """pkmdyn run --deflection: the Stewart platform's deflection under gravity and inertia is,
    at every sample, the legs' change of length mapped to the task: a drive that pushes with the
    effort u is compressed by u/k, so dx = J^-1 (-u / k) (the platform sinks under its weight)."""
    import csv

    from pkmdyn.cli import main

    out = tmp_path / "run"
    assert main(["run", "--machine", "stewart", "--deflection", "--out", str(out)]) == 0
    rows = list(csv.DictReader((out / "results.csv").open()))
    m = load_mechanism(ex.MACHINES / "stewart" / "stewart.toml")
    names = [f"{n}_{u}" for n, u in zip(m.task_names, m.task_units)]
    x = np.array([[float(r[c]) for c in names] for r in rows])
    dx = np.array([[float(r[f"{n}_deflection_{u}"]) for n, u in zip(m.task_names, m.task_units)] for r in rows])
    u = np.array([[float(r[f"P_{i + 1}_effort_N"]) for i in range(6)] for r in rows])
    k = m.joint_stiffness[m.act_joint[0]]["drive"]
    J, _ = _oracle_J(x)
    ref = np.linalg.solve(J, (-u / k)[..., None])[..., 0]
    assert _rel(dx, ref) < 1e-8
    assert np.all(dx[:, 2] < -1e-7)


def test_a_joint_spring_on_a_driven_joint_leaves_the_drive_alone():
    """A bearing's tilt stiffness given as one number on the crank's driven revolute joint: along
    the driven axis the drive carries the load, so the task stiffness in the plane is the same as
    without the joint's spring, while the joint's spring softens the out-of-plane tilt."""
    d, _ = _four_bar(kd=2.0e4)
    m0 = load_mechanism(d)
    d["joints"][0]["stiffness"] = {"drive_Nm_rad": 2.0e4, "moment_Nm_rad": 2.0e4}
    m1 = load_mechanism(d)
    a, b = (stiffness(m, solve_kinematics(m, reference_task(m)[None])) for m in (m0, m1))
    assert _rel(b.K_task, a.K_task) < 1e-10
    assert b.C_point[0, 0, 0] > a.C_point[0, 0, 0] * (1 + 1e-6)


def test_a_fixed_joint_with_a_spring_runs(tmp_path):
    """A tool bolted to the coupler through a compliant interface (a fixed joint with springs):
    the run writes its model.json with the spring listed."""
    from pkmdyn.cli import main

    d, _ = _four_bar()
    d["bodies"].append(ex.body("tool", (0.6, 0.6, 0.0), mass=0.5))
    d["joints"].append(ex.joint("bolt", "fixed", "coupler", "tool", (0.6, 0.6, 0.0),
                                stiffness={"force_N_m": 1.0e6, "moment_Nm_rad": 1.0e4}))
    d["task"] = {"body": "tool", "position": ["x"]}
    path = _write(tmp_path, d)
    out = tmp_path / "run"
    assert main(["run", "--machine", str(path), "--deflection", "--out", str(out)]) == 0
    doc = json.loads((out / "model.json").read_text())
    bolt = next(j for j in doc["joints"] if j["name"] == "bolt")
    assert bolt["stiffness"] == {"force_N_m": [1.0e6] * 3, "moment_Nm_rad": [1.0e4] * 3}


@pytest.mark.parametrize("case, words", [
    ("coincident", "[bodies] cylinder_1 section: its joints meet at one point"),
    ("one_joint", "[bodies] lump section: the body has 1 joint, and a beam needs two"),
])
def test_a_section_with_no_beam_is_refused(tmp_path, capsys, case, words):
    """A section on a body whose joints meet at one point (the built-in Stewart's cylinders: U and
    P both at the base joint), or on a body with one joint, would stay rigid without a word."""
    import tomlkit

    from pkmdyn.cli import main

    d = ex.builtin_dict("stewart")
    mat = {"youngs_modulus_Pa": E_STEEL, "poisson_ratio": NU}
    if case == "coincident":
        for leg in d["legs"]:
            for b in leg["bodies"]:
                if b["name"] == "cylinder":
                    b.update(section={"outer_diameter_m": 0.05}, material=mat)
    else:
        d["bodies"].append(dict(ex.body("lump", (0.0, 0.0, 1.2)), section={"outer_diameter_m": 0.05}, material=mat))
        d["joints"] = [ex.joint("lump_weld", "fixed", "platform", "lump", (0.0, 0.0, 1.1))]
    path = tmp_path / "stewart.toml"
    path.write_text(tomlkit.dumps(d))
    out = tmp_path / "out"
    assert main(["stiffness", "--machine", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0], err
    assert not out.exists()


def test_the_job_result_carries_the_reports_scene_and_what_the_folder_holds(tmp_path):
    """pkmdyn.jobs.stiffness.job: the result's scene is the report's modes animation (16 frames
    a mode, the joints of the machine), and summary.json lists every file of the folder."""
    import pkmdyn.jobs.stiffness as job

    res = job.job(str(ex.MACHINES / "stewart" / "stewart.toml"), tmp_path / "o")
    assert res.scene is not None and res.scene.t.shape[0] % 16 == 0 and res.scene.t.shape[0] >= 16
    m = load_mechanism(ex.MACHINES / "stewart" / "stewart.toml")
    assert res.scene.points.shape[1:] == (len(m.joint_names), 3)
    assert set(res.files) >= {"stiffness", "report"} and all(p.exists() for p in res.files.values())
    assert res.report.title.startswith(m.name)
