"""Dynamics of described mechanisms: actuator efforts against the energy balance, Lagrange's
equations by finite differences and the hip's closed form; every joint reaction against each
body's Newton-Euler balance; compliance-unique reactions of over-constrained mechanisms."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import multibody_examples as ex
from pkmdyn.errors import ParameterError, SingularityError
from pkmdyn.multibody import load_mechanism, reference_task, solve_kinematics
from pkmdyn.multibody.dynamics.newton_euler import energies, inverse_dynamics, joint_reactions

RIGID = {
    "delta": lambda: ex.builtin_dict("delta"),
    "stewart_sps": ex.stewart_sps,
    "stewart": lambda: ex.builtin_dict("stewart"),
    "stewart_flipped_spheres": ex.stewart_flipped_spheres,
    "stewart_with_tool": ex.stewart_with_tool,
    "rssr": ex.rssr,
    "serial_arm": ex.serial_arm,
}
ALL = {**RIGID, "bennett": lambda: ex.builtin_dict("bennett"),
       "rrr3": lambda: ex.builtin_dict("rrr3"), "four_bar_cut_b": ex.four_bar_cut_b, "sarrus": ex.sarrus,
       "slider_crank": ex.slider_crank}


def _amp(model):
    return np.where(model.task_kind == 1, 0.04, 0.02 * model.length_scale)


def _motion(model, n=60, T=1.0, seed=0):
    t = np.linspace(0.0, T, n)
    x, xd, xdd = ex.smooth_motion(reference_task(model), _amp(model), t, seed)
    return t, x, xd, xdd


def _kin(d, n=60, seed=0):
    m = load_mechanism(d)
    t, x, xd, xdd = _motion(m, n, seed=seed)
    return m, solve_kinematics(m, x, xd, xdd, t)


def _with_sections(d, E=2.1e11, diameters=None):
    """Every body a beam of circular section but those that are none (joints at one point, e.g.
    a slider pinned where it slides: a section there is refused)."""
    d = ex.deep(d)
    bodies = list(d.get("bodies", []))
    for leg in d.get("legs", []):
        bodies += leg.get("bodies", [])
    joints = list(d.get("joints", [])) + [j for leg in d.get("legs", []) for j in leg.get("joints", [])]
    for b in bodies:
        pts = [np.asarray(j["point_m"], float) for j in joints if b["name"] in (j["parent"], j["child"])]
        if not d.get("legs") and max((np.linalg.norm(p - q) for p in pts for q in pts), default=0.0) < 1e-9:
            continue
        od = (diameters or {}).get(b["name"], 0.02)
        b["section"] = {"outer_diameter_m": od, "inner_diameter_m": 0.0}
        b["material"] = {"youngs_modulus_Pa": E, "poisson_ratio": 0.3}
    return d


def _rel(a, b):
    return float(np.abs(a - b).max() / max(float(np.abs(b).max()), 1e-12))


@pytest.mark.parametrize("name", sorted(ALL))
def test_power_balance_exact_rates(name):
    """sum u qd_a = dT/dt + dV/dt with dT/dt = sum m v.a + w.(I wd) (body motions only)."""
    m, kin = _kin(ALL[name]())
    idyn = inverse_dynamics(m, kin)
    u, kin = idyn.u, idyn.kin
    Iw = np.einsum("nbij,bjk,nblk->nbil", kin.R, m.inertia, kin.R)
    dT = np.einsum("b,nbi,nbi->n", m.mass, kin.v, kin.a) + np.einsum("nbi,nbij,nbj->n", kin.w, Iw, kin.wd)
    dV = -np.einsum("b,i,nbi->n", m.mass, m.gravity, kin.v)
    P = np.einsum("na,na->n", u, kin.act_qd)
    assert np.abs(P - dT - dV).max() <= 1e-9 * max(np.abs(P).max(), np.abs(dT).max(), 1e-3)


@pytest.mark.parametrize("name", ["stewart", "four_bar_cut_b", "bennett", "stewart_flipped_spheres"])
def test_power_balance_finite_differences(name):
    """Actuator power = d(T + V)/dt, the derivative by fourth-order central differences of the
    energies computed from body poses and velocities alone."""
    m = load_mechanism(ALL[name]())
    h = 2e-4
    t = np.linspace(0.0, 0.4, 9)
    tt = (t[:, None] + h * np.array([-2, -1, 0, 1, 2])[None]).reshape(-1)
    x, xd, xdd = ex.smooth_motion(reference_task(m), _amp(m), tt, 3)
    kin = solve_kinematics(m, x, xd, xdd, tt)
    T, V = energies(m, kin)
    E = (T + V).reshape(-1, 5)
    dE = (E[:, 0] - 8 * E[:, 1] + 8 * E[:, 3] - E[:, 4]) / (12 * h)
    u = inverse_dynamics(m, kin).u
    P = np.einsum("na,na->n", u, kin.act_qd).reshape(-1, 5)[:, 2]
    assert np.abs(P - dE).max() <= 1e-7 * max(np.abs(P).max(), 1e-3)


def _task_energy(m, x, xd):
    """T (k,) and V (k,) at task poses x (k, nt) with task rates xd (k, nt), zero acceleration."""
    kin = solve_kinematics(m, x, xd, np.zeros_like(x))
    return energies(m, kin)


@pytest.mark.parametrize("name", ["stewart", "bennett", "four_bar_cut_b"])
def test_efforts_satisfy_lagrange_equations_by_finite_differences(name):
    """J_ax^T u = d/dt dL/dxd - dL/dx, with the mass matrix M(x) of T = 1/2 xd^T M xd and V(x)
    from body energies, their x-derivatives by central differences."""
    m = load_mechanism(ALL[name]())
    nt = m.nt
    rng = np.random.default_rng(5)
    x0 = reference_task(m) + 0.5 * _amp(m) * rng.uniform(-1, 1, nt)
    xd = _amp(m) * rng.uniform(-3, 3, nt)
    xdd = _amp(m) * rng.uniform(-10, 10, nt)
    kin = solve_kinematics(m, x0[None], xd[None], xdd[None])
    lhs = (kin.J_ax[0].T @ inverse_dynamics(m, kin).u[0])

    def mass_matrix(x):
        e = np.eye(nt)
        rates = [e[i] + e[j] for i in range(nt) for j in range(nt)] + [e[i] for i in range(nt)]
        T, _ = _task_energy(m, np.repeat(x[None], len(rates), 0), np.array(rates))
        Ti = T[nt * nt:]
        M = np.empty((nt, nt))
        for i in range(nt):
            for j in range(nt):
                M[i, j] = T[i * nt + j] - Ti[i] - Ti[j] if i != j else 2 * Ti[i]
        return M

    def potential(x):
        return _task_energy(m, x[None], np.zeros((1, nt)))[1][0]

    step = 1e-5 * np.where(m.task_kind == 1, 1.0, m.length_scale)
    M = mass_matrix(x0)
    dM = np.empty((nt, nt, nt))
    dV = np.empty(nt)
    for k in range(nt):
        e = np.zeros(nt)
        e[k] = step[k]
        dM[k] = (mass_matrix(x0 + e) - mass_matrix(x0 - e)) / (2 * step[k])
        dV[k] = (potential(x0 + e) - potential(x0 - e)) / (2 * step[k])
    Mdot = np.einsum("kij,k->ij", dM, xd)
    rhs = M @ xdd + Mdot @ xd - 0.5 * np.einsum("kij,i,j->k", dM, xd, xd) + dV
    assert np.abs(lhs - rhs).max() <= 1e-6 * np.abs(rhs).max()


@pytest.mark.parametrize("name", sorted(RIGID))
def test_reactions_balance_every_body(name):
    """Rigid mechanisms: the reactions solve every body's six equations and every joint's free
    directions carry only the actuator effort."""
    m, kin = _kin(RIGID[name]())
    r = joint_reactions(m, kin)
    kin = r.kin
    assert r.method == "rigid" and r.self_stress == 0
    scale = max(np.abs(r.joint_force).max(), 1.0)
    assert r.residual.max() <= 1e-10 * scale * max(m.length_scale, 1.0)
    _check_newton_euler(m.body_names, m.mass, m.inertia, m.gravity, kin, r.joint_force, r.joint_moment,
                        m.joint_parent, m.joint_child, _loads(m, kin))


def _loads(m, kin):
    out = []
    for b, F, M, pt in zip(m.load_body, m.load_force, m.load_moment, m.load_point):
        out.append((int(b), F, M, kin.origin[:, b] + np.einsum("nij,j->ni", kin.R[:, b], pt)))
    return out


def _check_newton_euler(names, mass, inertia, g, kin, F, Mj, parent, child, loads, tol=1e-9):
    """Every body: sum of joint forces + gravity + loads = m a; moments about the centre of mass
    = I wd + w x I w (base frame)."""
    n, nb = kin.p.shape[:2]
    fsum = np.zeros((n, nb, 3))
    msum = np.zeros((n, nb, 3))
    for j in range(F.shape[1]):
        for b, sg in ((child[j], 1.0), (parent[j], -1.0)):
            if b < 0:
                continue
            fsum[:, b] += sg * F[:, j]
            msum[:, b] += sg * (Mj[:, j] + np.cross(kin.joint_point[:, j] - kin.p[:, b], F[:, j]))
    for b, Fl, Ml, pt in loads:
        fsum[:, b] += Fl
        msum[:, b] += Ml + np.cross(pt - kin.p[:, b], np.broadcast_to(Fl, pt.shape))
    fsum += mass[None, :, None] * g
    Iw = np.einsum("nbij,bjk,nblk->nbil", kin.R, inertia, kin.R)
    need_f = mass[None, :, None] * kin.a
    need_m = np.einsum("nbij,nbj->nbi", Iw, kin.wd) + np.cross(kin.w, np.einsum("nbij,nbj->nbi", Iw, kin.w))
    fs = max(np.abs(F).max(), np.abs(need_f).max(), 1.0)
    assert np.abs(fsum - need_f).max() <= tol * fs, names[int(np.abs(fsum - need_f).max(axis=(0, 2)).argmax())]
    assert np.abs(msum - need_m).max() <= tol * fs * max(1.0, float(np.abs(kin.p).max()))


def test_hip_description_reproduces_the_closed_form_efforts():
    """The hip's description (sliders, levers, platforms) against Eq. 7-14 (the closed-form
    oracle, tests/oracles/hip.py) with its friction off: motor torque = (p / 2 pi) slider force +
    I_L Ldd (2 pi / p) (the screw's rotor inertia is no body of the description), on the ISO
    cycle and random variants."""
    from oracles import hip as hip_oracle
    from pkmdyn.machines.hip_simulator import model_from_dict
    from pkmdyn.machines.hip_simulator.description import hip_description
    from pkmdyn.machines.hip_simulator.params import default_params_dict
    from pkmdyn.profiles.iso14242 import iso14242_motion

    motion = iso14242_motion(cycles=1, samples_per_cycle=200)
    for seed in (None, 3, 4):
        d = default_params_dict()
        for k in d["friction"]:
            if "eps" not in k and "radius" not in k:
                d["friction"][k] = 0.0
        if seed is not None:
            rng = np.random.default_rng(seed)
            g = d["geometry"]
            g["platform_radius_m"] *= rng.uniform(0.9, 1.1)
            g["lever_length_m"] *= rng.uniform(0.98, 1.1)
            g["module_angles_deg"] = [a + rng.uniform(-5, 5) for a in g["module_angles_deg"]]
            for key, v in d["inertia"].items():
                if isinstance(v, (int, float)) and "gravity" not in key:
                    d["inertia"][key] = v * rng.uniform(0.8, 1.2)
        hip = model_from_dict(d, f"variant {seed}")
        ref = hip_oracle.inverse_dynamics(hip, hip_oracle.kinematics(hip, motion.angles, motion.rates, motion.accels),
                                          np.zeros(len(motion.t)))
        m = load_mechanism(hip_description(hip))
        kin = solve_kinematics(m, motion.angles, motion.rates, motion.accels, motion.t)
        r = joint_reactions(m, kin, split=True)
        gear = hip.geometry.p / (2 * np.pi)
        sl = [m.actuator_names.index(f"P_{i + 1}") for i in range(3)]
        tau = gear * r.u[:, sl] + hip.inertia.I_L * kin.act_qdd[:, sl] / gear
        assert _rel(tau, ref.tau) < 1e-9
        # the description's drives (screw lead, rotor I_L) and groups give the motor torques and
        # the parts of Eq. 14 themselves
        _check_hip_parts(m, kin, r, ref, sl)
        assert r.residual.max() < 1e-9 * np.abs(r.joint_force).max()


def _check_hip_parts(m, kin, r, ref, sl):
    """The generic motor torques and every part of the split against the hand-built Eq. 7-16
    torques ``ref`` (platform, lever, slider, screw = the rotor, friction = every joint's and
    the screws' friction; the oracle's), 1e-9 of each part's largest value."""
    from pkmdyn.multibody.dynamics.actuators import motor_efforts

    mot = motor_efforts(m, kin.act_q, kin.act_qd, kin.act_qdd, r.u)
    assert _rel(mot.effort[:, sl], ref.tau) < 1e-9
    k = m.drive_ratio[sl]
    for part in ("platform", "lever", "slider"):
        g = m.group_names.index(part)
        assert _rel(r.shares.groups[:, sl, g] / k, getattr(ref, part)) < 1e-9, part
    assert _rel(mot.rotor[:, sl], ref.screw) < 1e-9
    fr = r.shares.friction[:, sl].sum(axis=2) / k + mot.friction[:, sl]
    assert np.abs(fr - ref.friction).max() <= 1e-9 * max(np.abs(ref.friction).max(), 1e-12 * np.abs(ref.tau).max())


@pytest.mark.parametrize("name", ["bennett", "rrr3", "sarrus", "slider_crank", "four_bar_cut_b"])
def test_overconstrained_reactions_are_unique_by_compliance(name):
    d = _with_sections(ALL[name]())
    m, kin = _kin(d)
    r = joint_reactions(m, kin)
    kin = r.kin
    assert r.method == "compliance" and r.self_stress == m.topology.overconstraints
    assert r.residual.max() <= 1e-10 * max(np.abs(r.joint_force).max(), 1.0) * max(m.length_scale, 1.0)
    _check_newton_euler(m.body_names, m.mass, m.inertia, m.gravity, kin, r.joint_force, r.joint_moment,
                        m.joint_parent, m.joint_child, _loads(m, kin))
    # one Young's modulus for all: the reactions do not depend on it
    m2, kin2 = _kin(_with_sections(ALL[name](), E=7.0e10))
    r2 = joint_reactions(m2, kin2)
    assert _rel(r2.joint_force, r.joint_force) < 1e-9
    assert _rel(r2.joint_moment, r.joint_moment) < 1e-9
    # a thicker link carries more of the self-stress: the redundant reactions change
    rng = np.random.default_rng(2)
    thick = {b: float(rng.uniform(0.01, 0.06)) for b in m.body_names}
    m3, kin3 = _kin(_with_sections(ALL[name](), diameters=thick))
    r3 = joint_reactions(m3, kin3)
    assert _rel(r3.joint_force, r.joint_force) + _rel(r3.joint_moment, r.joint_moment) > 1e-4
    assert r3.residual.max() <= 1e-10 * max(np.abs(r3.joint_force).max(), 1.0) * max(m.length_scale, 1.0)
    # the actuator efforts do not depend on the self-stress
    assert _rel(r3.u, r.u) < 1e-9


def test_overconstrained_without_sections_is_refused_by_name():
    d = ex.builtin_dict("bennett")
    for b in d["bodies"]:
        b.pop("section", None)
        b.pop("material", None)
    m, kin = _kin(d)
    with pytest.raises(ParameterError, match="bennett.*over-constrained.*section"):
        joint_reactions(m, kin)


def test_singular_actuator_map_names_the_sample():
    m, kin = _kin(ex.builtin_dict("stewart"), n=5)
    J = kin.J_ax.copy()
    J[3] = 0.0
    bad = dataclasses.replace(kin, J_ax=J)
    with pytest.raises(SingularityError, match=r"sample 3 .*actuator map is singular"):
        inverse_dynamics(m, bad)


def test_loads_and_per_sample_loads_enter_the_balance():
    """A constant [[loads]] entry and the same load given per sample give the same efforts;
    the power balance holds with the load's power."""
    d = ex.builtin_dict("stewart")
    base = load_mechanism(d)
    t, x, xd, xdd = _motion(base, 20)
    F, Mo = np.array([30.0, -20.0, -400.0]), np.array([5.0, 1.0, -3.0])
    d2 = ex.deep(d)
    d2["loads"] = [{"body": "platform", "force_N": list(F), "moment_Nm": list(Mo)}]
    m2 = load_mechanism(d2)
    kin = solve_kinematics(base, x, xd, xdd, t)
    u1 = inverse_dynamics(m2, solve_kinematics(m2, x, xd, xdd, t)).u
    u2 = inverse_dynamics(base, kin, loads={"platform": (F, Mo)}).u
    assert _rel(u2, u1) < 1e-12
    u0 = inverse_dynamics(base, kin).u
    b = base.body_names.index("platform")
    P_load = kin.v[:, b] @ F + kin.w[:, b] @ Mo
    assert np.abs(np.einsum("na,na->n", u1 - u0, kin.act_qd) + P_load).max() < 1e-9 * np.abs(P_load).max()


def _balance_from_files(folder):
    """Every body's Newton-Euler balance recomputed from model.json and bodies.npz alone."""
    import json

    model = json.loads((folder / "model.json").read_text())
    z = np.load(folder / "bodies.npz")
    names = [b["name"] for b in model["bodies"]]
    assert list(z["body_names"]) == names
    idx = {n: i for i, n in enumerate(names)}
    mass = np.array([b["mass_kg"] for b in model["bodies"]])
    inertia = np.array([b["inertia_kgm2"] for b in model["bodies"]])
    g = np.array(model["gravity_m_s2"])
    parent = np.array([idx.get(j["parent"], -1) for j in model["joints"]])
    child = np.array([idx.get(j["child"], -1) for j in model["joints"]])

    class K:
        p, a, w, wd, R, joint_point = z["p"], z["a"], z["w"], z["wd"], z["R"], z["joint_point"]

    loads = []
    for ld in model["loads"]:
        b = idx[ld["body"]]
        pt = z["origin"][:, b] + np.einsum("nij,j->ni", z["R"][:, b], np.array(ld["point_m"]))
        loads.append((b, np.array(ld["force_N"]), np.array(ld["moment_Nm"]), pt))
    _check_newton_euler(names, mass, inertia, g, K, z["joint_force"], z["joint_moment"], parent, child, loads)
    return model, z


@pytest.mark.parametrize("name", ["stewart", "delta", "bennett"])
def test_run_files_let_an_independent_program_check_every_body(tmp_path, name):
    import csv

    import tomllib

    from pkmdyn.cli import main

    d = ex.builtin_dict(name)
    if name == "bennett":
        d = _with_sections(d)
    d.setdefault("loads", []).append({"body": d["bodies"][0]["name"], "force_N": [3.0, -2.0, -15.0],
                                      "moment_Nm": [0.5, 0.2, -0.1]})
    src = tmp_path / f"{name}.toml"
    src.write_text(_toml(d))
    assert tomllib.loads(src.read_text())["bodies"][0]["name"] == d["bodies"][0]["name"]
    out = tmp_path / "out"
    assert main(["run", "--machine", str(src), "--out", str(out)]) == 0
    model, z = _balance_from_files(out)
    with open(out / "results.csv") as fh:
        rows = list(csv.DictReader(fh))
    m = load_mechanism(d)
    for i, a in enumerate(m.actuator_names):
        unit = "N" if m.actuator_units[i] == "m" else "Nm"
        col = np.array([float(r[f"{a}_effort_{unit}"]) for r in rows])
        assert col.shape == (z["t"].shape[0],) and np.all(np.isfinite(col))
        # the effort is the actuated joint's free-direction component of its reaction
        j = m.joint_index(a)
        R_c = z["R"][:, m.joint_child[j]] if m.joint_child[j] >= 0 else None
        axis = np.einsum("nij,j->ni", R_c, m.joint_R_child[j][:, 2]) if R_c is not None else m.joint_R_child[j][:, 2]
        comp = np.einsum("ni,ni->n", z["joint_force"][:, j] if unit == "N" else z["joint_moment"][:, j], axis)
        assert np.abs(comp - col).max() <= 1e-9 * max(np.abs(col).max(), 1.0)


def _toml(d):
    """A minimal TOML writer for the description dicts of these tests."""
    def val(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return '"' + v + '"'
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{k} = {val(x)}" for k, x in v.items()) + " }"
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(val(x) for x in v) + "]"
        return repr(float(v)) if isinstance(v, float) else str(v)

    lines = []

    def table(name, t, array):
        lines.append(f"[[{name}]]" if array else f"[{name}]")
        subs = []
        for k, v in t.items():
            if isinstance(v, list) and v and isinstance(v[0], dict) and k in ("bodies", "joints"):
                subs.append((k, v))
            else:
                lines.append(f"{k} = {val(v)}")
        for k, v in subs:
            for item in v:
                table(f"{name}.{k}", item, True)

    for k, v in d.items():
        if isinstance(v, list):
            for item in v:
                table(k, item, True)
        else:
            table(k, v, False)
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("seed", [None, 21, 22])
def test_pdm_description_reproduces_the_hand_built_efforts_and_all_reactions(seed, tmp_path):
    """The PDM through its description (sections and material of its nine links): the four
    limb forces and all 19 joint wrenches, the nine redundant reactions included, against the
    hand-built Newton-Euler with compliance (Eq. 49-83); moments compared about the same point."""
    from test_pdm_description import _variant

    from pkmdyn.machines.pdm4 import inverse_kinematics
    from pkmdyn.machines.pdm4.description import pdm_description
    from oracles.pdm_newton_euler import JOINTS
    from oracles.pdm_newton_euler import inverse_dynamics as pdm_inverse_dynamics
    from pkmdyn.profiles.pdm_motion import cycloidal_motion

    pm = _variant(seed, tmp_path)
    tr = pm.trajectory
    strokes = tr.strokes if seed is None else tuple(np.array(tr.strokes) * np.random.default_rng(seed).uniform(-1, 1, 4))
    motion = cycloidal_motion(strokes, tr.period_s, 150)
    ref = pdm_inverse_dynamics(pm, inverse_kinematics(pm, motion))
    m = load_mechanism(pdm_description(pm))
    r = joint_reactions(m, solve_kinematics(m, motion.q, motion.qd, motion.qdd, motion.t))
    assert r.method == "compliance" and r.self_stress == 9
    limbs = [m.actuator_names.index(n) for n in ("P11", "P12", "P23", "P24")]
    assert _rel(r.u[:, limbs], ref.force) < 1e-9
    fs, ms = np.abs(ref.joint_force).max(), np.abs(ref.joint_moment).max()
    for j, (name, _, body_a, _) in enumerate(JOINTS):
        k = m.joint_index(name)
        parent = "ground" if m.joint_parent[k] < 0 else m.body_names[m.joint_parent[k]]
        sg = 1.0 if parent == body_a else -1.0
        M_ref = ref.joint_moment[:, j] + np.cross(ref.joint_point[:, j] - r.joint_point[:, k], ref.joint_force[:, j])
        assert np.abs(sg * r.joint_force[:, k] - ref.joint_force[:, j]).max() < 1e-9 * fs, name
        assert np.abs(sg * r.joint_moment[:, k] - M_ref).max() < 1e-9 * ms, name


def _stewart_with_friction(mu=0.1):
    d = ex.builtin_dict("stewart")
    for leg in d["legs"]:
        for j in leg["joints"]:
            if j["type"] == "spherical":
                j["friction"] = {"coefficient": mu, "ball_radius_m": 0.02, "coulomb_torque_Nm": 0.1,
                                 "viscous_Nm_s_rad": 0.05}
            if j["type"] == "universal":
                j["friction"] = {"coefficient": mu, "pin_radius_m": 0.01, "viscous_Nm_s_rad": 0.2,
                                 "coulomb_torque_Nm": 0.05}
            if j["type"] == "prismatic":
                j["friction"] = {"coefficient": mu, "coulomb_force_N": 5.0, "viscous_N_s_m": 20.0}
    if mu > 10.0:  # beyond the plausibility limit of a friction coefficient: raised, to make friction lock
        d["limits"] = {"max_friction_coefficient": 10.0 * mu}
    return d


def _power_error(m, r):
    k = r.kin
    Iw = np.einsum("nbij,bjk,nblk->nbil", k.R, m.inertia, k.R)
    dT = np.einsum("b,nbi,nbi->n", m.mass, k.v, k.a) + np.einsum("nbi,nbij,nbj->n", k.w, Iw, k.wd)
    dV = -np.einsum("b,i,nbi->n", m.mass, m.gravity, k.v)
    P = np.einsum("na,na->n", r.u, k.act_qd)
    return np.abs(P - dT - dV - r.dissipation).max() / np.abs(P).max()


def test_friction_power_balance_and_reactions():
    """Every friction family on (Coulomb, viscous, pin, ball, sliding guide; cut spherical
    joints included): actuator power = d(T + V)/dt + dissipation, dissipation >= 0, the fixed
    point converged, every body balances."""
    m, kin = _kin(_stewart_with_friction())
    r = joint_reactions(m, kin)
    assert 1 <= r.iterations < 50
    assert _power_error(m, r) < 1e-9
    assert r.dissipation.min() > 0.0
    r0 = joint_reactions(m, kin, friction=False)
    assert np.abs(r.u - r0.u).max() > 1.0  # friction changes the efforts
    _check_newton_euler(m.body_names, m.mass, m.inertia, m.gravity, r.kin, r.joint_force, r.joint_moment,
                        m.joint_parent, m.joint_child, _loads(m, r.kin))


def test_load_dependent_friction_uses_the_joints_own_reaction():
    """Recompute the pin and ball friction torques from the converged reactions (law F1)."""
    from pkmdyn.multibody.dynamics.friction import regularised_sign
    from pkmdyn.multibody.dynamics.newton_euler import coordinate_twists, free_twists
    from pkmdyn.multibody.dynamics.friction import EPS_ROTATION

    m, kin = _kin(_stewart_with_friction(0.3))
    r = joint_reactions(m, kin)
    S = coordinate_twists(m, r.kin.q)
    for name in ("U_1", "S_2"):
        j = m.joint_index(name)
        T, _ = free_twists(m, r.kin, S, j)
        f = r.joint_force[:, j]
        c, p = m.joint_child[j], m.joint_parent[j]
        w = (r.kin.w[:, c] if c >= 0 else 0.0) - (r.kin.w[:, p] if p >= 0 else 0.0)
        if name.startswith("U"):
            # the universal joint has two rotation axes: no single pin axis, so only Coulomb + viscous
            tau = 0.05 * regularised_sign(w, EPS_ROTATION, True) + 0.2 * w
        else:
            mag = 0.1 + 0.3 * 0.02 * np.linalg.norm(f, axis=1)
            tau = mag[:, None] * regularised_sign(w, EPS_ROTATION, True) + 0.05 * w
        expect = np.einsum("nfk,nk->nf", T[:, :, :3], tau)
        assert np.abs(r.friction[j] - expect).max() <= 1e-8 * max(np.abs(expect).max(), 1e-6), name


def test_friction_in_an_overconstrained_mechanism():
    d = _with_sections(ex.builtin_dict("bennett"))
    for j in d["joints"]:
        j["friction"] = {"coefficient": 0.2, "pin_radius_m": 0.01, "mean_radius_m": 0.015, "viscous_Nm_s_rad": 0.01}
    m, kin = _kin(d)
    r = joint_reactions(m, kin)
    assert r.method == "compliance" and r.iterations >= 1
    assert _power_error(m, r) < 1e-9


def test_locking_friction_is_refused_naming_the_joint():
    m, kin = _kin(_stewart_with_friction(200.0), n=5)
    with pytest.raises(ParameterError, match=r"joint P_\d: the load-dependent friction does not converge at sample"):
        joint_reactions(m, kin)


def test_cli_refuses_locking_friction_and_writes_nothing(tmp_path, capsys):
    from pkmdyn.cli import main

    src = tmp_path / "locked.toml"
    src.write_text(_toml(_stewart_with_friction(200.0)))
    out = tmp_path / "out"
    assert main(["run", "--machine", str(src), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "joint P_" in err[0] and "lock" in err[0]
    assert not out.exists()


@pytest.mark.parametrize("name", sorted(RIGID) + ["stewart_friction"])
def test_cut_route_equals_the_dense_equations(name):
    """The cut-wrench route and the dense equations of every joint wrench give the same
    reactions (friction included)."""
    d = _stewart_with_friction() if name == "stewart_friction" else RIGID[name]()
    m, kin = _kin(d, n=20)
    a = joint_reactions(m, kin)
    b = joint_reactions(m, kin, solver="dense")
    fs = max(np.abs(b.joint_force).max(), 1.0)
    assert np.abs(a.joint_force - b.joint_force).max() <= 1e-9 * fs
    assert np.abs(a.joint_moment - b.joint_moment).max() <= 1e-9 * fs * max(m.length_scale, 1.0)
    assert np.abs(a.u - b.u).max() <= 1e-9 * np.abs(b.u).max()
    assert a.residual.max() <= 1e-9 * fs * max(m.length_scale, 1.0)


@pytest.mark.parametrize("seed", [None, 7])
def test_hip_description_reproduces_the_closed_form_with_every_friction_family(seed):
    """Every friction family of the hip through its description, against Eq. 7-16 with the same
    coefficients on the ISO cycle with its load: Coulomb and viscous friction of the S, U joints
    and the sliders (Table 2), and the hip-joint and thrust-bearing law of Eq. 16 as the
    ``external`` friction of S0 driven by the named load ``hydraulic_N`` (a platform mass makes
    the thrust term's offset m_m g count). The lead screws' friction and rotor inertia are added
    to the slider forces as the motor sees them (no bodies of the description). Without the
    load the Eq. 16 torques are wrong, which the test also sees. The reference: the closed-form
    oracle (tests/oracles/hip.py)."""
    from oracles import hip as hip_oracle
    from pkmdyn.multibody.dynamics.friction import coulomb_viscous
    from pkmdyn.machines.hip_simulator import model_from_dict
    from pkmdyn.machines.hip_simulator.description import hip_description
    from pkmdyn.machines.hip_simulator.params import default_params_dict
    from pkmdyn.profiles.iso14242 import iso14242_motion

    rng = np.random.default_rng(seed)
    d = default_params_dict()
    fr = d["friction"]
    for key in ("slider_coulomb_N", "slider_viscous_Ns_m", "screw_coulomb_Nm", "screw_viscous_Nms_rad",
                "spherical_coulomb_Nm", "spherical_viscous_Nms_rad", "universal_coulomb_Nm",
                "universal_viscous_Nms_rad"):
        fr[key] = float(rng.uniform(0.05, 0.5)) * (20.0 if "slider" in key else 1.0)
    for key in ("hip_coefficient", "thrust_coefficient"):
        fr[key] *= float(rng.uniform(0.5, 2.0))
    d["inertia"]["platform_mass_kg"] = float(rng.uniform(1.0, 5.0))
    hip = model_from_dict(d, f"friction {seed}")
    motion = iso14242_motion(cycles=1, samples_per_cycle=200)
    ref = hip_oracle.inverse_dynamics(hip, hip_oracle.kinematics(hip, motion.angles, motion.rates, motion.accels),
                                      motion.load)
    m = load_mechanism(hip_description(hip))
    assert m.named_loads == ("hydraulic_N",)
    kin = solve_kinematics(m, motion.angles, motion.rates, motion.accels, motion.t)
    gear = hip.geometry.p / (2 * np.pi)
    f = hip.friction
    sl = [m.actuator_names.index(f"P_{i + 1}") for i in range(3)]
    theta_dot = kin.act_qd[:, sl] / gear

    def motor(r):
        return (gear * r.u[:, sl] + hip.inertia.I_L * kin.act_qdd[:, sl] / gear
                + coulomb_viscous(theta_dot, f.screw_coulomb, f.screw_viscous, f.eps_w, vector=False))

    r = joint_reactions(m, kin, named={"hydraulic_N": motion.load}, split=True)
    assert r.iterations >= 1
    assert _rel(motor(r), ref.tau) < 1e-9
    _check_hip_parts(m, kin, r, ref, sl)
    assert _power_error(m, r) < 1e-9
    # the Eq. 16 part is some 1e-3 of the torques here: the load must reach it
    assert _rel(motor(joint_reactions(m, kin)), ref.tau) > 1e-5


@pytest.mark.parametrize("name", ["bennett", "rrr3", "sarrus", "four_bar_cut_b"])
def test_compliance_in_cut_unknowns_equals_the_dense_equations(name):
    """Over-constrained: least complementary energy written in the cut joints' unknowns and in
    every joint wrench give the same reactions."""
    m, kin = _kin(_with_sections(ALL[name]()), n=20)
    a = joint_reactions(m, kin)
    b = joint_reactions(m, kin, solver="dense")
    assert a.method == b.method == "compliance" and a.self_stress == b.self_stress == m.topology.overconstraints
    fs = max(np.abs(b.joint_force).max(), 1.0)
    assert np.abs(a.joint_force - b.joint_force).max() <= 1e-9 * fs
    assert np.abs(a.joint_moment - b.joint_moment).max() <= 1e-9 * fs * max(m.length_scale, 1.0)


@pytest.mark.parametrize("name", sorted(ALL))
def test_twists_from_the_solved_poses_equal_those_from_q(name):
    from pkmdyn.multibody.dynamics.newton_euler import coordinate_twists

    m, kin = _kin(ALL[name](), n=10)
    assert np.abs(coordinate_twists(m, kin.q, kin) - coordinate_twists(m, kin.q)).max() < 1e-13


def test_run_without_sections_is_refused_or_writes_flagged_minimum_norm_reactions(tmp_path, capsys):
    """An over-constrained description without sections: the run is refused (one line naming
    the missing compliance data and the bodies, exit 2, nothing written); with
    --minimum-norm-reactions it writes its kinematics and efforts and reactions that balance
    every body (minimum norm), flagged as not unique in summary.json and on stderr."""
    import json

    from pkmdyn.cli import main

    d = ex.builtin_dict("bennett")
    for b in d["bodies"]:
        b.pop("section", None)
        b.pop("material", None)
    src = tmp_path / "bennett.toml"
    src.write_text(_toml(d))
    out = tmp_path / "out"
    capsys.readouterr()
    for extra in ([], ["--unique-reactions"]):
        assert main(["run", "--machine", str(src), *extra, "--out", str(out)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "over-constrained" in err[0] and "section" in err[0] and d["bodies"][0]["name"] in err[0]
        assert not out.exists() and sorted(p.name for p in tmp_path.iterdir()) == ["bennett.toml"]
    assert main(["run", "--machine", str(src), "--minimum-norm-reactions", "--out", str(out)]) == 0
    assert "not unique" in capsys.readouterr().err
    s = json.loads((out / "summary.json").read_text())
    assert s["reactions"]["method"] == "minimum-norm" and s["reactions"]["unique"] is False
    assert "section" in s["reactions"]["reason"]
    _balance_from_files(out)


def test_normal_equation_kernel_equals_least_squares_and_flags_dependent_columns():
    """The cut route's compiled least squares (normal equations, Cholesky) equals numpy's
    least squares on consistent and inconsistent systems, and flags a sample whose columns
    are dependent instead of returning a number for it."""
    from pkmdyn.multibody.dynamics._reaction_kernels import normal_solve

    rng = np.random.default_rng(3)
    n, m, k = 6, 21, 15
    A = rng.normal(size=(n, m, k))
    r = rng.normal(size=(n, m))
    r[:3] = np.einsum("nmk,nk->nm", A[:3], rng.normal(size=(3, k)))  # three consistent systems
    A[4, :, 7] = 2.0 * A[4, :, 2] - A[4, :, 5]  # sample 4: a dependent column
    lam = np.full((n, k), np.nan)
    ok = np.array([normal_solve(np.ascontiguousarray(A[s].T), r[s], np.empty((k, k)), lam[s]) for s in range(n)])
    assert ok.tolist() == [True, True, True, True, False, True]
    for s in np.flatnonzero(ok):
        ref = np.linalg.lstsq(A[s], r[s], rcond=None)[0]
        assert np.abs(lam[s] - ref).max() <= 1e-10 * np.abs(ref).max()


def test_cut_route_solves_a_sample_with_dependent_columns_by_least_squares():
    """Where the cut joints' columns become dependent at one sample, the cut route still returns
    wrenches that satisfy that sample's equations (least squares, not a failed factorisation),
    and the other samples are untouched."""
    from pkmdyn.multibody.dynamics.newton_euler import _cut_solve, _CutRoute, coordinate_twists, cut_table

    m, kin = _kin(ex.builtin_dict("stewart"), n=5)
    S = coordinate_twists(m, kin.q, kin)
    W = np.zeros((5, m.nb, 6))
    zero = np.zeros((5, m.nq))
    rng = np.random.default_rng(0)
    tab = cut_table(m)
    lam = rng.normal(size=(5, tab.K))
    before, _, _ = _cut_solve(m, tab, kin, S, W, np.einsum("nqk,nk->nq", _CutRoute(m, kin, S, 1e-10).A, lam), zero, None)
    # sample 2: the twists of the coordinates that move the first cut joint's child vanish, so
    # its columns do; the same multipliers make the right side
    S2 = S.copy()
    S2[2, np.flatnonzero(tab.cut_sign[0])] = 0.0
    cuts = _CutRoute(m, kin, S2, 1e-10)
    assert np.abs(cuts.A[2, :, :3]).max() == 0.0
    rhs = np.einsum("nqk,nk->nq", cuts.A, lam)
    z, _, res = _cut_solve(m, tab, kin, S2, W, rhs, zero, None)
    assert np.all(np.isfinite(z)) and np.all(np.isfinite(res))
    keep = [0, 1, 3, 4]
    assert np.abs(z[keep] - before[keep]).max() <= 1e-9 * np.abs(before).max()
    # sample 2: the least-squares multipliers of its (now rank-deficient) equations
    expect = lam.copy()
    expect[2] = np.linalg.lstsq(cuts.A[2], rhs[2], rcond=None)[0]
    assert np.abs(cuts.A[2] @ expect[2] - rhs[2]).max() <= 1e-9 * np.abs(rhs[2]).max()
    ref = cuts.assemble(m, W, expect, None)
    assert np.abs(z - ref).max() <= 1e-9 * np.abs(ref).max()
