"""Named external loads of a description (a magnitude per sample) and the friction they drive
(``friction.external``, the hip paper's Eq. 16 form), through the API, the machine verbs and
``pkmdyn run``."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

import multibody_examples as ex
from pkmdyn.cli import main
from pkmdyn.errors import ParameterError
from pkmdyn.multibody import load_mechanism, reference_task, solve_kinematics
from pkmdyn.multibody.dynamics.newton_euler import joint_reactions, load_forces
from pkmdyn.multibody.dynamics.friction import EPS_ROTATION, EPS_TRANSLATION
from pkmdyn.multibody.description.joint_types import type_code
from pkmdyn.multibody.dynamics.verbs import machine_verbs

PUSH_DIR = np.array([0.3, -0.2, -1.0])
PUSH_POINT = [0.05, 0.02, 0.0]  # off the platform's centre: the load has a moment


def _stewart(mu_s=0.0, mu_p=0.0, offset=0.0, magnitude=None):
    """The built-in Stewart platform with a named load ``push_N`` on the platform and, on
    request, friction of the platform's spherical joints and the legs' guides driven by it."""
    d = ex.builtin_dict("stewart")
    plat = next(b for b in d["bodies"] if b["name"] == "platform")
    point = (np.array(plat["com_m"]) + PUSH_POINT).tolist()
    load = {"name": "push_N", "body": "platform", "direction": PUSH_DIR.tolist(), "point_m": point}
    if magnitude is not None:
        load["magnitude_N"] = magnitude
    d["loads"] = [load]
    for leg in d["legs"]:
        for j in leg["joints"]:
            if j["type"] == "spherical" and mu_s:
                j["friction"] = {"external": [{"load": "push_N", "coefficient": mu_s, "radius_m": 0.02,
                                               "offset_N": offset}]}
            if j["type"] == "prismatic" and mu_p:
                j["friction"] = {"external": [{"load": "push_N", "coefficient": mu_p}]}
    return d


def _motion(m, n=80, seed=3):
    t = np.linspace(0.0, 1.0, n)
    amp = np.array([0.03, 0.03, 0.03, 0.08, 0.08, 0.08])
    x, xd, xdd = ex.smooth_motion(reference_task(m), amp, t, seed)
    return t, x, xd, xdd


def _push(t):
    return 400.0 + 300.0 * np.sin(2 * np.pi * 1.3 * t)


def _balance_error(m, kin, r, LF, LM, LP):
    """Largest force and moment imbalance of any body, relative, recomputed from the joint
    wrenches, gravity and the per-sample loads (centre-of-mass form)."""
    n, nb = kin.p.shape[:2]
    fsum = np.zeros((n, nb, 3))
    msum = np.zeros((n, nb, 3))
    for j in range(len(m.joint_names)):
        for b, sg in ((m.joint_child[j], 1.0), (m.joint_parent[j], -1.0)):
            if b >= 0:
                fsum[:, b] += sg * r.joint_force[:, j]
                msum[:, b] += sg * (r.joint_moment[:, j] + np.cross(kin.joint_point[:, j] - kin.p[:, b],
                                                                    r.joint_force[:, j]))
    for k, b in enumerate(m.load_body):
        fsum[:, b] += LF[:, k]
        msum[:, b] += LM[:, k] + np.cross(LP[:, k] - kin.p[:, b], LF[:, k])
    fsum += m.mass[None, :, None] * m.gravity
    Iw = np.einsum("nbij,bjk,nblk->nbil", kin.R, m.inertia, kin.R)
    need_m = np.einsum("nbij,nbj->nbi", Iw, kin.wd) + np.cross(kin.w, np.einsum("nbij,nbj->nbi", Iw, kin.w))
    scale = max(np.abs(r.joint_force).max(), 1.0)
    return max(np.abs(fsum - m.mass[None, :, None] * kin.a).max(), np.abs(msum - need_m).max()) / scale


def test_a_named_load_is_its_direction_times_the_magnitude_of_each_sample():
    """Every body balances with the per-sample load; a constant magnitude gives the reactions
    of the same load written as a constant force; the efforts follow the magnitude."""
    m = load_mechanism(_stewart())
    t, x, xd, xdd = _motion(m)
    kin = solve_kinematics(m, x, xd, xdd, t)
    F = _push(t)
    r = joint_reactions(m, kin, named={"push_N": F})
    LF, LM = load_forces(m, len(t), {"push_N": F})
    assert np.allclose(LF[:, 0], F[:, None] * PUSH_DIR / np.linalg.norm(PUSH_DIR), rtol=1e-15, atol=0)
    LP = r.kin.origin[:, m.load_body] + np.einsum("nlij,lj->nli", r.kin.R[:, m.load_body], m.load_point)
    assert _balance_error(m, r.kin, r, LF, LM, LP) < 1e-9
    # a constant magnitude: the same as the constant load of the description format
    d = ex.builtin_dict("stewart")
    plat = next(b for b in d["bodies"] if b["name"] == "platform")
    d["loads"] = [{"body": "platform", "force_N": (500.0 * PUSH_DIR / np.linalg.norm(PUSH_DIR)).tolist(),
                   "point_m": (np.array(plat["com_m"]) + PUSH_POINT).tolist()}]
    mc = load_mechanism(d)
    rc = joint_reactions(mc, solve_kinematics(mc, x, xd, xdd, t))
    r5 = joint_reactions(m, kin, named={"push_N": 500.0})
    assert np.abs(r5.joint_force - rc.joint_force).max() <= 1e-12 * np.abs(rc.joint_force).max()
    assert np.abs(r5.u - rc.u).max() <= 1e-12 * np.abs(rc.u).max()
    # without a magnitude the description's magnitude_N (default 0): no load at all
    r0 = joint_reactions(m, kin)
    assert np.abs(r.u - r0.u).max() > 10.0


def test_friction_driven_by_a_named_load_follows_its_law():
    """``external`` friction: torque mu r |F + offset| u(w) at the spherical joints, force
    mu |F| u(v) in the guides; the dissipation is recomputed from the joints' relative rates, and
    actuator power + load power = d(T + V)/dt + dissipation."""
    mu_s, mu_p, off = 0.08, 0.05, -150.0
    m = load_mechanism(_stewart(mu_s, mu_p, off))
    t, x, xd, xdd = _motion(m)
    kin = solve_kinematics(m, x, xd, xdd, t)
    F = _push(t)
    r = joint_reactions(m, kin, named={"push_N": F})
    k = r.kin
    # dissipation from the law, joint by joint
    V = np.zeros(k.p.shape[:2] + (6,))
    V[..., :3] = k.w
    V[..., 3:] = k.v - np.cross(k.w, k.p)  # velocity of the body point at the origin
    expect = np.zeros(len(t))
    for j, name in enumerate(m.joint_names):
        fr = m.joint_friction[j]
        if not fr:
            continue
        c, p = m.joint_child[j], m.joint_parent[j]
        Vr = (V[:, c] if c >= 0 else 0.0) - (V[:, p] if p >= 0 else 0.0)
        w = Vr[:, :3]
        v = Vr[:, 3:] + np.cross(w, k.joint_point[:, j])
        if m.joint_type[j] == type_code("spherical"):
            mag = mu_s * 0.02 * np.abs(F + off)
            s = np.einsum("ni,ni->n", w, w)
            expect += mag * s / np.sqrt(s + EPS_ROTATION**2)
        else:
            mag = mu_p * np.abs(F)
            s = np.einsum("ni,ni->n", v, v)
            expect += mag * s / np.sqrt(s + EPS_TRANSLATION**2)
    assert np.abs(r.dissipation - expect).max() <= 1e-9 * np.abs(expect).max()
    assert expect.min() > 0.0
    # power balance with the load's power
    LF, _ = load_forces(m, len(t), {"push_N": F})
    pt = k.origin[:, m.load_body[0]] + np.einsum("nij,j->ni", k.R[:, m.load_body[0]], m.load_point[0])
    b = m.load_body[0]
    v_pt = k.v[:, b] + np.cross(k.w[:, b], pt - k.p[:, b])
    P_load = np.einsum("ni,ni->n", LF[:, 0], v_pt)
    Iw = np.einsum("nbij,bjk,nblk->nbil", k.R, m.inertia, k.R)
    dT = np.einsum("b,nbi,nbi->n", m.mass, k.v, k.a) + np.einsum("nbi,nbij,nbj->n", k.w, Iw, k.wd)
    dV = -np.einsum("b,i,nbi->n", m.mass, m.gravity, k.v)
    P = np.einsum("na,na->n", r.u, k.act_qd)
    assert np.abs(P + P_load - dT - dV - r.dissipation).max() <= 1e-9 * np.abs(P).max()


def test_machine_verbs_take_the_named_loads_magnitudes():
    m = load_mechanism(_stewart(0.08, 0.05))
    t, x, xd, xdd = _motion(m, n=20)
    F = _push(t)
    V = machine_verbs(m)
    u = V.inverse_dynamics(m, x, xd, xdd, F)
    u0 = V.inverse_dynamics(m, x, xd, xdd)
    assert np.abs(u - u0).max() > 1.0
    a = V.forward_dynamics(m, x, xd, u, F)
    assert np.abs(a - xdd).max() <= 1e-8 * np.abs(xdd).max()
    one = V.forward_dynamics_one(m, x[3], xd[3], u[3], float(F[3]))
    assert np.abs(one - xdd[3]).max() <= 1e-8 * np.abs(xdd).max()
    with pytest.raises(ParameterError, match="push_N"):
        V.inverse_dynamics(m, x, xd, xdd, np.ones(3))


@pytest.mark.parametrize("edit, match", [
    (lambda d: d["loads"][0].pop("direction"), "direction"),
    (lambda d: d["loads"][0].update(force_N=[0.0, 0.0, 1.0]), "force_N"),
    (lambda d: d["loads"][0].update(name="push"), "name"),
    (lambda d: d["loads"].append({"body": "platform", "direction": [1, 0, 0]}), "direction"),
    (lambda d: d["legs"][0]["joints"][-1].update(friction={"external": [{"load": "pull_N", "coefficient": 0.1,
                                                                        "radius_m": 0.01}]}), "pull_N"),
    (lambda d: d["legs"][0]["joints"][-1].update(friction={"external": [{"load": "push_N", "coefficient": 0.1}]}),
     "radius_m"),
])
def test_bad_named_loads_are_refused_by_name(edit, match):
    d = _stewart()
    assert d["legs"][0]["joints"][-1]["type"] == "spherical"
    edit(d)
    with pytest.raises(ParameterError, match=match):
        load_mechanism(d)


def test_a_sliding_joint_takes_no_radius():
    d = _stewart()
    guide = next(j for j in d["legs"][0]["joints"] if j["type"] == "prismatic")
    guide["friction"] = {"external": [{"load": "push_N", "coefficient": 0.1, "radius_m": 0.01}]}
    with pytest.raises(ParameterError, match="only slides"):
        load_mechanism(d)


def test_run_reads_the_load_column_and_writes_the_loads(tmp_path):
    """``pkmdyn run --machine FILE --motion M.csv`` with a ``push_N`` column: the column in
    results.csv, the per-sample load forces in bodies.npz, and every body's balance from the
    files alone; without the column the description's magnitude_N."""
    import tomlkit

    d = _stewart(0.08, 0.05, magnitude=250.0)
    src = tmp_path / "stewart_push.toml"
    src.write_text(tomlkit.dumps(d))
    m = load_mechanism(src)
    t, x, xd, xdd = _motion(m, n=40)
    F = _push(t)
    mot = tmp_path / "motion.csv"
    cols = ["t_s"] + [f"{n}_{u}" for n, u in zip(m.task_names, m.task_units)] + ["push_N"]
    with mot.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(cols)
        for i in range(len(t)):
            w.writerow([repr(float(v)) for v in (t[i], *x[i], F[i])])
    out = tmp_path / "run"
    assert main(["run", "--machine", str(src), "--motion", str(mot), "--out", str(out)]) == 0
    with (out / "results.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert np.allclose([float(r["push_N"]) for r in rows], F, rtol=1e-12)
    z = np.load(out / "bodies.npz")
    u = PUSH_DIR / np.linalg.norm(PUSH_DIR)
    assert np.allclose(z["load_force"][:, 0], F[:, None] * u, rtol=1e-12, atol=1e-9)
    model = json.loads((out / "model.json").read_text())
    assert model["loads"][0]["name"] == "push_N"
    # the balance from the files
    mm = load_mechanism(src)

    class R:
        joint_force, joint_moment = z["joint_force"], z["joint_moment"]

    class K:
        p, a, w, wd, R, joint_point = z["p"], z["a"], z["w"], z["wd"], z["R"], z["joint_point"]

    assert _balance_error(mm, K, R, z["load_force"], z["load_moment"], z["load_point"]) < 1e-8
    # no column: the description's magnitude
    mot2 = tmp_path / "motion2.csv"
    mot2.write_text("\n".join(",".join(r.split(",")[:-1]) for r in mot.read_text().splitlines()) + "\n")
    out2 = tmp_path / "run2"
    assert main(["run", "--machine", str(src), "--motion", str(mot2), "--out", str(out2)]) == 0
    z2 = np.load(out2 / "bodies.npz")
    assert np.allclose(z2["load_force"][:, 0], 250.0 * u, rtol=1e-12)


def test_inverse_dynamics_includes_the_friction():
    """Efforts from inverse_dynamics (friction of known magnitude added to the tree forces)
    equal those of the reaction solver, which balances every joint with its friction; without
    friction they differ."""
    from pkmdyn.multibody.dynamics.newton_euler import inverse_dynamics

    d = _stewart(0.08, 0.05, 20.0)
    for leg in d["legs"]:
        for j in leg["joints"]:
            if j["type"] == "universal":
                j["friction"] = {"coulomb_torque_Nm": 0.3, "viscous_Nm_s_rad": 0.1}
    m = load_mechanism(d)
    t, x, xd, xdd = _motion(m, n=40)
    kin = solve_kinematics(m, x, xd, xdd, t)
    F = {"push_N": _push(t)}
    a = inverse_dynamics(m, kin, named=F).u
    b = joint_reactions(m, kin, named=F).u
    assert np.abs(a - b).max() <= 1e-10 * np.abs(b).max()
    c = inverse_dynamics(m, kin, named=F, friction=False).u
    assert np.abs(c - b).max() > 1e-3 * np.abs(b).max()


def test_a_negative_default_magnitude_keeps_its_sign():
    """``magnitude_N`` below zero is a force against ``direction``, the same with or without a
    per-sample value."""
    m = load_mechanism(_stewart(magnitude=-120.0))
    F, _ = load_forces(m, 3)
    u = PUSH_DIR / np.linalg.norm(PUSH_DIR)
    assert np.allclose(F[:, 0], -120.0 * u, rtol=1e-15)
    F2, _ = load_forces(m, 3, {"push_N": -120.0})
    assert np.array_equal(F, F2)


@pytest.mark.parametrize("edit, match", [
    (lambda d: d["loads"].append(dict(d["loads"][0], magnitude_N=3.0)), "share one magnitude"),
    (lambda d: d["loads"][0].update(name="P_1_effort_N"), "column"),
    (lambda d: d["loads"][0].update(direction=[1e308, 1e308, 0.0]), None),
])
def test_named_loads_shared_colliding_or_huge(edit, match):
    d = _stewart(magnitude=0.0)
    edit(d)
    if match is None:  # a huge direction is only a direction
        m = load_mechanism(d)
        assert np.allclose(m.load_direction[0], [2 ** -0.5, 2 ** -0.5, 0.0], rtol=1e-15)
        return
    with pytest.raises(ParameterError, match=match):
        load_mechanism(d)


def test_friction_of_a_joint_that_turns_and_slides():
    """A cylindrical joint's Coulomb torque and force (laws F1 and F2 together): its dissipation
    is 0.3 |w|^2 / sqrt(|w|^2 + eps^2) + 2 |v|^2 / sqrt(|v|^2 + eps_t^2) from its relative
    rates, and the efforts of inverse_dynamics carry it (power balance)."""
    from pkmdyn.multibody.dynamics.newton_euler import coordinate_twists, free_blocks, inverse_dynamics
    from pkmdyn.multibody.dynamics.friction import JointFriction

    d = ex.slider_crank("cylindrical")
    for j in d["joints"]:
        if j["type"] == "cylindrical":
            j["friction"] = {"coulomb_force_N": 2.0, "coulomb_torque_Nm": 0.3}
            name = j["name"]
    m = load_mechanism(d)
    t = np.linspace(0.0, 1.0, 30)
    x, xd, xdd = ex.smooth_motion(reference_task(m), np.full(m.nt, 0.3), t, 1)
    kin = solve_kinematics(m, x, xd, xdd, t)
    S = coordinate_twists(m, kin.q, kin)
    fr = JointFriction(m, kin, S, free_blocks(m, kin, S))
    F = fr.initial()
    jd = next(jd for jd in fr.joints if m.joint_names[jd["j"]] == name)
    w2 = np.einsum("ni,ni->n", jd["w"], jd["w"])
    v2 = np.einsum("ni,ni->n", jd["v"], jd["v"])
    expect = 0.3 * w2 / np.sqrt(w2 + EPS_ROTATION**2) + 2.0 * v2 / np.sqrt(v2 + EPS_TRANSLATION**2)
    got = fr.dissipation(F)
    assert expect.max() > 0.1 and np.abs(got - expect).max() <= 1e-12 * expect.max()
    idyn = inverse_dynamics(m, kin)
    k = idyn.kin
    Iw = np.einsum("nbij,bjk,nblk->nbil", k.R, m.inertia, k.R)
    dT = np.einsum("b,nbi,nbi->n", m.mass, k.v, k.a) + np.einsum("nbi,nbij,nbj->n", k.w, Iw, k.wd)
    dV = -np.einsum("b,i,nbi->n", m.mass, m.gravity, k.v)
    P = np.einsum("na,na->n", idyn.u, k.act_qd)
    assert np.abs(P - dT - dV - got).max() <= 1e-9 * np.abs(P).max()


def _write_motion(path, m, t, x, columns=None):
    """A task motion CSV (positions only) with extra named-load ``columns {name: (n,)}``."""
    columns = columns or {}
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["t_s"] + [f"{n}_{u}" for n, u in zip(m.task_names, m.task_units)] + list(columns))
        for i in range(len(t)):
            w.writerow([repr(float(v)) for v in (t[i], *x[i], *(c[i] for c in columns.values()))])


def test_control_drives_the_named_load_of_the_motion(tmp_path):
    """``pkmdyn control --machine FILE --motion M.csv`` with a ``push_N`` column: the plant and
    the controller feel the column's load (written beside the efforts); a column equal to the
    description's magnitude_N runs as the file without the column; another load moves the
    efforts."""
    import tomlkit

    d = _stewart(0.08, 0.05, magnitude=250.0)
    src = tmp_path / "stewart_push.toml"
    src.write_text(tomlkit.dumps(d))
    m = load_mechanism(src)
    t, x, _, _ = _motion(m, n=200)
    runs = {}
    for name, cols in (("none", {}), ("same", {"push_N": np.full(len(t), 250.0)}), ("push", {"push_N": _push(t)})):
        mot = tmp_path / f"{name}.csv"
        _write_motion(mot, m, t, x, cols)
        out = tmp_path / name
        assert main(["control", "--machine", str(src), "--motion", str(mot), "--duration", "0.1", "--out",
                     str(out)]) == 0
        with (out / "control.csv").open() as fh:
            runs[name] = list(csv.DictReader(fh))
    eff = [f"{a}_N" for a in m.actuator_names]
    assert "push_N" not in runs["none"][0] and "push_N" in runs["push"][0]
    tk = np.array([float(r["t_s"]) for r in runs["push"]])
    assert np.allclose([float(r["push_N"]) for r in runs["push"]], np.interp(tk, t, _push(t)), rtol=1e-12)
    u = {k: np.array([[float(r[c]) for c in eff] for r in v]) for k, v in runs.items()}
    scale = np.abs(u["none"]).max()
    assert np.abs(u["same"] - u["none"]).max() <= 1e-9 * scale
    assert np.abs(u["push"] - u["none"]).max() >= 1e-2 * scale  # 150 to 700 N against 250 N on the platform


def _second_load(d):
    d["loads"].append({**d["loads"][0], "name": "pull_N"})
    return "push_N"


def _effort_name(d):
    d["loads"][0]["name"] = "P_1_N"  # actuator P_1's effort column in control.csv
    return "P_1_N"


@pytest.mark.parametrize("edit, words", [(_second_load, "2 (push_N, pull_N)"), (_effort_name, "effort column")],
                         ids=["two-named-loads", "named-like-an-effort"])
def test_control_refuses_named_load_columns_it_cannot_drive(tmp_path, capsys, edit, words):
    """A load column the loop cannot drive as it stands (the mechanism has two named loads; the
    load has the name of an actuator's effort column, which it would replace in control.csv):
    exit 2 naming the column, nothing written."""
    import tomlkit

    d = _stewart()
    column = edit(d)
    src = tmp_path / "m.toml"
    src.write_text(tomlkit.dumps(d))
    m = load_mechanism(src)
    t, x, _, _ = _motion(m, n=50)
    mot = tmp_path / "m.csv"
    _write_motion(mot, m, t, x, {column: _push(t)})
    out = tmp_path / "out"
    assert main(["control", "--machine", str(src), "--motion", str(mot), "--duration", "0.05", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"'{column}'" in err and words in err and len(err.strip().splitlines()) == 1
    assert not out.exists()
