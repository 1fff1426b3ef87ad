"""PDM dynamics: Newton-Euler of every body from the public outputs of ``pdm run``, the
hand-derived oracles (Newton-Euler, Eq. 49-83, and the virtual-power route in minimal
coordinates) against each other, the compliance solution (Eq. 63-83) and its invariances, the
U-joint study, bad inputs."""

from __future__ import annotations

import json
import math
import tomllib

import numpy as np
import pytest

from pkmdyn.analysis.compliance import compatibility_rows, unique_reactions
from pkmdyn.cli import main
from pkmdyn.errors import ParameterError
from pkmdyn.machines.pdm4 import BODY_NAMES, default_params_path, inverse_kinematics, load_params
from pkmdyn.machines.pdm4.params import params_from_dict
from pkmdyn.profiles.pdm_motion import PdmMotion

from oracles import pdm_minimal as minimal
from oracles import pdm_newton_euler as dyn

MODEL = load_params()
H = 1e-5


def _raw():
    return tomllib.loads(default_params_path().read_text(encoding="utf-8"))


def _motion(seed: int, n: int = 6, t0: float = 0.1) -> PdmMotion:
    """Smooth random motion q = offset + amp sin(freq t + phase) with exact derivatives."""
    rng = np.random.default_rng(seed)
    amp = rng.uniform(0.2, 1.0, 4) * np.array([0.012, 0.012, math.radians(4), math.radians(10)])
    freq = rng.uniform(1.0, 8.0, 4)
    phase = rng.uniform(0, 2 * np.pi, 4)
    off = rng.uniform(-1, 1, 4) * np.array([0.01, 0.01, math.radians(3), math.radians(8)])
    t = np.linspace(t0, t0 + 1.2, n)
    arg = freq * t[:, None] + phase
    return PdmMotion(t, off + amp * np.sin(arg), amp * freq * np.cos(arg), -amp * freq**2 * np.sin(arg))


def _random_model(seed: int):
    """Default layout with random inertia, gravity, layers, sections and material."""
    rng = np.random.default_rng(100 + seed)
    raw = _raw()
    raw["inertia"]["gravity_m_s2"] = list(rng.normal(size=3) * 5.0)
    raw["inertia"]["density_kg_m3"] = float(rng.uniform(1500, 8000))
    bodies = {}
    for name in rng.choice(BODY_NAMES, 5, replace=False):
        a, b, c = rng.uniform(0.1, 1.0, 3)  # second moments of a mass distribution: physical tensor
        Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        J = Q @ np.diag([b + c, a + c, a + b]) @ Q.T
        bodies[str(name)] = {"mass_kg": float(rng.uniform(0.2, 3.0)), "inertia_kgm2": (J * 1e-3).tolist()}
    raw["inertia"]["bodies"] = bodies
    for key in ("coupler_layer_z_m", "crank_layer_z_m", "rpr_limb_layer_z_m"):
        raw["geometry"][key] = float(rng.uniform(-0.1, 0.1))
    raw["material"]["section_diameters_m"] = list(rng.uniform(0.02, 0.07, 3))
    raw["material"]["youngs_modulus_Pa"] = float(rng.uniform(5e10, 2.1e11))
    raw["material"]["poisson_ratio"] = float(rng.uniform(0.2, 0.45))
    raw["limbs"]["rpr_cylinder_com_m"] = float(rng.uniform(0.08, 0.15))
    raw["limbs"]["spu_piston_com_m"] = float(rng.uniform(0.05, 0.12))
    return params_from_dict(raw, f"random{seed}.toml")


# ----------------------------------------------------------------------------- body frames
@pytest.mark.parametrize("seed", [0, 1])
def test_body_rotations_are_proper_and_their_rate_is_the_angular_velocity(seed):
    m = _random_model(seed)
    ks = [inverse_kinematics(m, _motion(seed, t0=0.1 + s)) for s in (-H, 0.0, H)]
    for name in BODY_NAMES:
        R = ks[1].body(name).R
        assert np.abs(R @ np.swapaxes(R, 1, 2) - np.eye(3)).max() < 1e-12, name
        assert np.allclose(np.linalg.det(R), 1.0), name
        Rd = (ks[2].body(name).R - ks[0].body(name).R) / (2 * H)
        W = Rd @ np.swapaxes(R, 1, 2)
        w = np.stack([W[:, 2, 1], W[:, 0, 2], W[:, 1, 0]], axis=-1)
        assert np.abs(w - ks[1].body(name).w).max() < 1e-7 * max(1.0, np.abs(w).max()), name


def test_body_x_axes_follow_the_links():
    k = inverse_kinematics(MODEL, _motion(3))
    pos = k.pos
    for i in range(2):
        e = pos.R2[:, i] - MODEL.R1[i]
        assert np.allclose(k.body(f"crank{i + 1}").R[:, :, 0], e / np.linalg.norm(e, axis=1)[:, None])
        e = pos.R3[:, i] - pos.R2[:, i]
        assert np.allclose(k.body(f"coupler{i + 1}").R[:, :, 0], e / np.linalg.norm(e, axis=1)[:, None])
    for j in range(4):
        assert np.allclose(k.body(f"piston{j + 1}").R[:, :, 0], k.u[:, j])
    assert np.allclose(k.body("link4").R[:, :, 0], (pos.R3[:, 1] - pos.R3[:, 0]) / MODEL.r4)


# ----------------------------------------------------------------------------- public outputs
def _toml_text(raw) -> str:
    def val(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(val(x) for x in v) + "]"
        if isinstance(v, str):
            return json.dumps(v)
        return repr(v)

    lines = []
    nested = []
    for sec, table in raw.items():
        lines.append(f"[{sec}]")
        for k, v in table.items():
            if isinstance(v, dict):
                nested.append((f"{sec}.{k}", v))
            else:
                lines.append(f"{k} = {val(v)}")
    for name, table in nested:
        for sub, entries in table.items():
            if isinstance(entries, dict):
                lines.append(f"[{name}.{sub}]")
                lines += [f"{k} = {val(v)}" for k, v in entries.items()]
            else:
                lines.append(f"[{name}]")
                lines.append(f"{sub} = {val(entries)}")
    return "\n".join(lines) + "\n"


def _small(raw):
    raw["trajectory"]["samples"] = 25
    raw["workspace"].update(gamma_layers=1, directions=8, radial_step_m=0.02)
    return raw


def _run(tmp_path, raw, name="o", extra=()):
    p = tmp_path / f"{name}.toml"
    p.write_text(_toml_text(raw), encoding="utf-8")
    out = tmp_path / name
    assert main(["pdm", "run", "--params", str(p), "--no-plots", *extra, "--out", str(out)]) == 0
    return out


def _check_newton_euler(out, rng):
    """Every body: sum of joint wrenches + gravity = rate of momentum, about random points."""
    model = json.loads((out / "model.json").read_text())
    z = np.load(out / "bodies.npz")
    g = np.array(model["gravity_m_s2"])
    names = [b["name"] for b in model["bodies"]]
    assert names == list(z["body_names"])
    R, p, a, w, wd = z["R"], z["p"], z["a"], z["w"], z["wd"]
    jp, jf, jm = z["joint_point"], z["joint_force"], z["joint_moment"]
    n = R.shape[0]
    assert jp.shape == (n, len(model["joints"]), 3) and z["t"].shape == (n,)
    worst = 0.0
    for b, body in enumerate(model["bodies"]):
        m, I0 = body["mass_kg"], np.array(body["inertia_kgm2"])
        I = R[:, b] @ I0 @ np.swapaxes(R[:, b], 1, 2)
        Q = p[:, b] + rng.normal(size=(n, 3)) * 0.5  # an arbitrary (fixed) point per sample
        F = np.broadcast_to(m * g, (n, 3))
        M = np.cross(p[:, b] - Q, m * g)
        for j, joint in enumerate(model["joints"]):
            s = 1.0 if joint["body_b"] == body["name"] else -1.0 if joint["body_a"] == body["name"] else 0.0
            if s:
                F = F + s * jf[:, j]
                M = M + s * (jm[:, j] + np.cross(jp[:, j] - Q, jf[:, j]))
        dP = m * a[:, b]
        dH = np.cross(p[:, b] - Q, m * a[:, b]) + np.einsum("nab,nb->na", I, wd[:, b]) + np.cross(
            w[:, b], np.einsum("nab,nb->na", I, w[:, b]))
        scale = max(np.abs(jf).max(), m * np.linalg.norm(g), 1e-30)
        worst = max(worst, np.abs(F - dP).max() / scale,
                    np.abs(M - dH).max() / (scale * (1.0 + np.abs(Q - p[:, b]).max())))
    assert worst < 1e-9, worst


def test_newton_euler_of_every_body_from_the_files_default(tmp_path):
    out = _run(tmp_path, _small(_raw()))
    _check_newton_euler(out, np.random.default_rng(0))
    model = json.loads((out / "model.json").read_text())
    assert len(model["bodies"]) == 14 and len(model["joints"]) == 19
    counts = {t: sum(j["type"] == t for j in model["joints"]) for t in "RPUS"}
    assert counts == {"R": 11, "P": 4, "U": 2, "S": 2}  # the paper's R = 11, n = 14 (84 eq., 93 unknowns)


def test_newton_euler_of_every_body_from_the_files_modified(tmp_path):
    raw = _small(_raw())
    raw["inertia"]["gravity_m_s2"] = [1.5, -3.0, -9.0]
    raw["inertia"]["bodies"] = {"platform": {"mass_kg": 6.0, "inertia_kgm2": [[0.03, 0.002, 0.0], [0.002, 0.05, 0.001], [0.0, 0.001, 0.06]]},
                                "piston3": {"mass_kg": 0.9}}
    raw["geometry"]["coupler_layer_z_m"] = 0.03
    raw["trajectory"]["period_s"] = 0.6
    out = _run(tmp_path, raw)
    _check_newton_euler(out, np.random.default_rng(1))
    z = np.load(out / "bodies.npz")
    # the kinematic fields of the file against finite differences of its own poses
    t, p, R = z["t"], z["p"], z["R"]
    dt = t[1] - t[0]
    v_fd = (p[2:] - p[:-2]) / (2 * dt)
    assert np.abs(v_fd - z["v"][1:-1]).max() < 2e-2 * np.abs(z["v"]).max()  # 25 samples: O(dt^2) error


def test_results_columns_and_summary(tmp_path):
    out = _run(tmp_path, _small(_raw()), extra=("--peak-y-accel", "1.0"))
    text = (out / "results.csv").read_text().splitlines()
    head = text[0].split(",")
    for name in ("f1_N", "f2_N", "f3_N", "f4_N", *dyn.REDUNDANT_LABELS, "U23_torque_Nm"):
        assert name in head
    cols = np.array([[float(x) for x in r.split(",")] for r in text[1:]])
    ydd = cols[:, head.index("ydd_m_s2")]
    assert abs(np.abs(ydd).max() - 1.0) < 2e-2  # 25 samples: the peak at T/4 is sampled to within 2 %
    summ = json.loads((out / "summary.json").read_text())
    assert summ["samples"] == 24 + 1
    f1 = cols[:, head.index("f1_N")]
    assert math.isclose(summ["max_abs_actuator_force_N"]["f1_N"], np.abs(f1).max())
    assert "bodies.npz" in summ["files"] and "model.json" in summ["files"]


# ----------------------------------------------------------------------------- independent route
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_actuator_forces_agree_with_the_independent_route(seed):
    m = _random_model(seed)
    mot = _motion(seed, n=8)
    f_ne = dyn.inverse_dynamics(m, inverse_kinematics(m, mot)).force
    f_vp = minimal.inverse_dynamics(m, mot.q, mot.qd, mot.qdd, None)
    assert np.abs(f_ne - f_vp).max() <= 1e-8 * np.abs(f_vp).max()
    assert np.allclose(dyn.actuator_forces(m, inverse_kinematics(m, mot)), f_ne, rtol=0, atol=1e-12 * np.abs(f_ne).max())


# ----------------------------------------------------------------------------- compliance
@pytest.mark.parametrize("seed", [0, 1])
def test_fast_route_equals_the_general_solver_and_eq83_holds(seed):
    m = _random_model(seed)
    kin = inverse_kinematics(m, _motion(seed, n=4))
    reac = dyn.inverse_dynamics(m, kin)
    A, b, _ = dyn.equilibrium_system(m, kin)
    assert A.shape[1:] == (84, 93)
    G, w0, C = dyn.compliance_system(m, kin)
    gen = unique_reactions(A, b, G, w0, C)
    lam = dyn.wrench_to_components(reac, kin)
    assert np.abs(gen.lam - lam).max() <= 1e-9 * np.abs(lam).max()
    assert np.all(gen.rank == 84)
    # Eq. 83: the deflection of R32, R21', R22' is the same from both sides (module by module)
    d = dyn.compatibility_deflections(m, kin, reac)
    scale = np.abs(d).max(axis=(0, 2), keepdims=True)
    assert np.all(scale > 0)
    assert np.abs(d[:, :, 0] - d[:, :, 1]).max(axis=0).max() <= 1e-9 * scale.max()
    for comp in range(3):
        assert np.abs(d[:, :, 0, comp] - d[:, :, 1, comp]).max() <= 1e-9 * scale[0, 0, 0, comp]


def test_compiled_kernel_equals_the_batched_array_route_and_single_rows_equal_batch_rows():
    from pkmdyn.analysis.compliance import solve_redundants

    m = _random_model(3)
    mot = _motion(3, n=6)
    kin = inverse_kinematics(m, mot)
    reac = dyn.inverse_dynamics(m, kin)
    # the array route: tree + cut equations (redundant columns kept), segments, redundants
    D, pts, W0, Wx, _ = dyn._solve_cuts(m, kin, with_redundants=True)
    F0, C = dyn._segments(m, kin, pts, W0, D)
    Fx, _ = dyn._segments(m, kin, pts, Wx, None)
    W = W0 + np.einsum("njkr,nr->njk", Wx, solve_redundants(Fx, C, F0))
    assert np.abs(W[..., :3] - reac.joint_force).max() <= 1e-10 * np.abs(reac.joint_force).max()
    for s in (0, 4):
        one = dyn.inverse_dynamics(m, inverse_kinematics(m, mot.slice(s, s + 1)))
        assert np.allclose(one.joint_force[0], reac.joint_force[s], rtol=0, atol=1e-12 * np.abs(reac.joint_force).max())
        assert np.allclose(one.redundant[0], reac.redundant[s], rtol=0, atol=1e-12 * np.abs(reac.redundant).max())


def test_without_the_compatibility_rows_the_system_lacks_exactly_nine_ranks():
    kin = inverse_kinematics(MODEL, _motion(5, n=3))
    A, b, _ = dyn.equilibrium_system(MODEL, kin)
    G, w0, C = dyn.compliance_system(MODEL, kin)
    gen = unique_reactions(A, b, G, w0, C)
    rows, rhs = compatibility_rows(G, C, w0, gen.null)
    for s in range(A.shape[0]):
        full = np.vstack([A[s], rows[s]])
        assert full.shape == (93, 93)
        assert np.linalg.matrix_rank(full) == 93
        assert 93 - np.linalg.matrix_rank(A[s]) == 9
        lam = np.linalg.solve(full, np.concatenate([b[s], rhs[s]]))
        assert np.allclose(lam, gen.lam[s], rtol=0, atol=1e-9 * np.abs(lam).max())


def test_reactions_do_not_depend_on_youngs_modulus():
    raw = _raw()
    kin = inverse_kinematics(MODEL, _motion(7))
    r0 = dyn.inverse_dynamics(MODEL, kin)
    raw["material"]["youngs_modulus_Pa"] *= 13.7
    m2 = params_from_dict(raw, "stiff.toml")
    r1 = dyn.inverse_dynamics(m2, inverse_kinematics(m2, _motion(7)))
    for f in ("joint_force", "joint_moment"):
        a, b = getattr(r0, f), getattr(r1, f)
        assert np.abs(a - b).max() <= 1e-9 * np.abs(a).max()
    # the general solver, which uses E as given, too
    lam = []
    for m in (MODEL, m2):
        k = inverse_kinematics(m, _motion(7, n=3))
        lam.append(unique_reactions(*dyn.equilibrium_system(m, k)[:2], *dyn.compliance_system(m, k)).lam)
    assert np.abs(lam[0] - lam[1]).max() <= 1e-9 * np.abs(lam[0]).max()


def test_one_link_section_changes_redundant_reactions_but_not_actuator_forces():
    kin = inverse_kinematics(MODEL, _motion(8))
    r0 = dyn.inverse_dynamics(MODEL, kin)
    raw = _raw()
    raw["material"]["stiffness_diameters_m"] = {"coupler2": 0.05}
    m2 = params_from_dict(raw, "section.toml")
    assert np.array_equal(m2.mass, MODEL.mass) and np.array_equal(m2.inertia, MODEL.inertia)
    r1 = dyn.inverse_dynamics(m2, inverse_kinematics(m2, _motion(8)))
    assert np.abs(r1.force - r0.force).max() <= 1e-10 * np.abs(r0.force).max()
    diff = np.abs(r1.redundant - r0.redundant).max(axis=0) / np.abs(r0.redundant).max(axis=0)
    assert diff.max() > 1e-2  # the stiffer coupler draws load: the split of the redundants moves


def test_u_joint_torque_and_the_error_of_neglecting_it_grow_with_acceleration():
    from pkmdyn.machines.pdm4.ujoint import u_joint_study

    rows = u_joint_study(MODEL, (0.05, 1.0), samples=41)
    torque = [max(r["max_abs_u_joint_torque_Nm"]) for r in rows]
    err = [max(r["max_force_error_percent"]) for r in rows]
    assert 0 < torque[0] < torque[1] and 0 < err[0] < err[1]
    # neglecting the torque leaves the RPR limbs (not attached to a U joint's limb) almost as they are
    assert max(rows[1]["max_force_error_percent"][:2]) < max(rows[1]["max_force_error_percent"][2:])


# ----------------------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    "edit, key",
    [
        (lambda r: r["inertia"].update(bodies={"crank1": {"mass_kg": -1.0}}), "mass_kg"),
        (lambda r: r["inertia"].update(bodies={"crank1": {"mass_kg": 0.0}}), "mass_kg"),
        (lambda r: r["inertia"].update(bodies={"link4": {"inertia_kgm2": [[0.0, 0, 0], [0, 0, 0], [0, 0, 0]]}}), "inertia_kgm2"),
        (lambda r: r["inertia"].update(bodies={"link4": {"inertia_kgm2": [[1.0, 0.2, 0], [0, 1, 0], [0, 0, 1]]}}), "symmetric"),
        (lambda r: r["inertia"].update(bodies={"link4": {"inertia_kgm2": [[1.0, 0, 0], [0, -1, 0], [0, 0, 1]]}}), "positive definite"),
        (lambda r: r["inertia"].update(bodies={"link4": {"inertia_kgm2": [[0.1, 0, 0], [0, 0.1, 0], [0, 0, 1.0]]}}), "triangle"),
        (lambda r: r["inertia"].update(bodies={"link5": {"mass_kg": 1.0}}), "link5"),
        (lambda r: r["material"].update(stiffness_diameters_m={"crank9": 0.03}), "crank9"),
        (lambda r: r["material"].update(youngs_modulus_Pa=0.0), "youngs_modulus_Pa"),
        (lambda r: r["material"].update(youngs_modulus_Pa=-7e10), "youngs_modulus_Pa"),
        (lambda r: r["material"].update(poisson_ratio=0.5), "poisson_ratio"),
        (lambda r: r["material"].update(poisson_ratio=-1.0), "poisson_ratio"),
        (lambda r: r["inertia"].update(density_kg_m3=0.0), "density_kg_m3"),
    ],
)
def test_bad_inertia_or_material_is_one_line_status_2_nothing_written(tmp_path, capsys, edit, key):
    raw = _small(_raw())
    edit(raw)
    p = tmp_path / "bad.toml"
    p.write_text(_toml_text(raw), encoding="utf-8")
    out = tmp_path / "o"
    assert main(["pdm", "run", "--params", str(p), "--no-plots", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and key in err and str(p) in err, err
    assert not out.exists()
    with pytest.raises(ParameterError):
        params_from_dict(raw, "bad.toml")


@pytest.mark.parametrize(
    "args, key",
    [
        (["--period-s", "nan"], "--period-s"),
        (["--period-s", "0"], "--period-s"),
        (["--peak-y-accel", "-1"], "--peak-y-accel"),
        (["--peak-y-accel", "1", "--period-s", "2"], "--peak-y-accel"),
        (["--stroke-y-m", "inf"], "--stroke-y-m"),
        (["--stroke-y-m", "0.2"], "limb"),
    ],
)
def test_bad_trajectory_options_are_one_line_status_2(tmp_path, capsys, args, key):
    out = tmp_path / "o"
    assert main(["pdm", "run", "--no-plots", *args, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and key in err, err
    assert not out.exists()


def test_a_rerun_replaces_the_earlier_run_whole(tmp_path):
    raw = _small(_raw())
    p = tmp_path / "p.toml"
    p.write_text(_toml_text(raw), encoding="utf-8")
    out = tmp_path / "o"
    assert main(["pdm", "run", "--params", str(p), "--out", str(out)]) == 0
    assert (out / "forces.png").exists() and (out / "overconstraints.png").exists()
    assert main(["pdm", "run", "--params", str(p), "--no-plots", "--out", str(out)]) == 0
    assert not (out / "forces.png").exists()
    summ = json.loads((out / "summary.json").read_text())
    assert sorted(f.name for f in out.iterdir() if not f.name.startswith(".")) == summ["files"]
