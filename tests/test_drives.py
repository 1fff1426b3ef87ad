"""Drives, the effort split, held idle freedoms, plausibility limits and streamed runs of any
described mechanism: motor efforts against the power balance with rotors and motor friction,
the split's parts against their total, every exported motion against finite differences, a
chunked run against one solved whole, and bad input refused by name."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

import multibody_examples as ex
from pkmdyn.cli import main
from pkmdyn.errors import LimitError, ParameterError
from pkmdyn.multibody import load_mechanism, reference_task, solve_kinematics
from pkmdyn.multibody.kinematics.inverse import TOLERANCE
from pkmdyn.multibody.dynamics.actuators import motor_efforts, rotor_energy
from pkmdyn.multibody.dynamics.newton_euler import joint_reactions

DRIVE = {"joint": "P", "name": "M", "screw_lead_m": 0.005, "gear_ratio": 2.0, "rotor_inertia_kgm2": 3e-5,
         "coulomb_torque_Nm": 0.04, "viscous_Nm_s_rad": 2e-4}


def _stewart_with_drives(drive=DRIVE):
    d = ex.builtin_dict("stewart")
    for leg in d["legs"]:
        leg["actuators"] = [dict(drive)]
    return d


def _geared_rrr3():
    """The planar 3-RRR with a gearbox on every base motor (ratio 50) and friction in its joints."""
    d = ex.builtin_dict("rrr3")
    for leg in d["legs"]:
        act = next(j["name"] for j in leg["joints"] if j.get("actuated"))
        leg["actuators"] = [{"joint": act, "name": "gm", "gear_ratio": 50.0, "rotor_inertia_kgm2": 2e-5,
                             "coulomb_torque_Nm": 0.01, "viscous_Nm_s_rad": 1e-5}]
        for j in leg["joints"]:
            if not j.get("actuated"):
                j["friction"] = {"coulomb_torque_Nm": 0.05, "viscous_Nm_s_rad": 0.01}
    return d


def _motion(model, n=80, T=1.0, seed=0, scale=1.0):
    t = np.linspace(0.0, T, n)
    amp = np.where(model.task_kind == 1, 0.04, 0.02 * model.length_scale) * scale
    x, xd, xdd = ex.smooth_motion(reference_task(model), amp, t, seed)
    return t, x, xd, xdd


def _rel(a, b):
    return float(np.abs(a - b).max() / max(float(np.abs(b).max()), 1e-12))


# --------------------------------------------------------------------------- drives
def test_motor_efforts_follow_the_transmission():
    """Eq. A1 term by term: tau = u / k + I_r k qdd + C u(k qd) + b k qd, k = gear 2 pi / lead."""
    from pkmdyn.multibody.dynamics.friction import regularised_sign

    m = load_mechanism(_stewart_with_drives())
    k = DRIVE["gear_ratio"] * 2 * np.pi / DRIVE["screw_lead_m"]
    assert np.allclose(m.drive_ratio, k) and m.drive_name == tuple(f"M_{i}" for i in (1, 3, 5, 2, 4, 6))
    t, x, xd, xdd = _motion(m)
    kin = solve_kinematics(m, x, xd, xdd, t)
    r = joint_reactions(m, kin)
    mot = motor_efforts(m, kin.act_q, kin.act_qd, kin.act_qdd, r.u)
    thd = k * kin.act_qd
    expect = (r.u / k + DRIVE["rotor_inertia_kgm2"] * k * kin.act_qdd
              + DRIVE["coulomb_torque_Nm"] * regularised_sign(thd, 1e-3, False) + DRIVE["viscous_Nm_s_rad"] * thd)
    assert _rel(mot.effort, expect) < 1e-13
    assert np.allclose(mot.theta, k * kin.act_q) and np.allclose(mot.theta_ddot, k * kin.act_qdd)


@pytest.mark.parametrize("build", [_stewart_with_drives, _geared_rrr3])
def test_power_balance_with_rotors_and_motor_friction(build):
    """sum tau theta_dot = d/dt (T + V + rotor energy) + joint friction + motor friction losses,
    the time derivative of the rotors' energy by central differences of the solved motion."""
    d = build()
    m = load_mechanism(d if build is _stewart_with_drives else _with_sections(d))
    t, x, xd, xdd = _motion(m, n=401, T=1.0, seed=2)
    kin = solve_kinematics(m, x, xd, xdd, t)
    r = joint_reactions(m, kin)
    mot = motor_efforts(m, kin.act_q, kin.act_qd, kin.act_qdd, r.u)
    Iw = np.einsum("nbij,bjk,nblk->nbil", kin.R, m.inertia, kin.R)
    dT = np.einsum("b,nbi,nbi->n", m.mass, kin.v, kin.a) + np.einsum("nbi,nbij,nbj->n", kin.w, Iw, kin.wd)
    dV = -np.einsum("b,i,nbi->n", m.mass, m.gravity, kin.v)
    Er = rotor_energy(m, kin.act_qd)
    h = t[1] - t[0]
    dEr = (Er[:-4] - 8 * Er[1:-3] + 8 * Er[3:-1] - Er[4:]) / (12 * h)  # fourth-order central differences
    P = np.einsum("na,na->n", mot.effort, mot.theta_dot)
    loss = r.dissipation + np.einsum("na,na->n", mot.friction, mot.theta_dot)
    inner = slice(2, -2)
    err = np.abs((P - dT - dV - loss)[inner] - dEr).max() / np.abs(P).max()
    assert err < 1e-6  # the differences' own error at 400 steps: some 1e-8
    # the same with the rotors' power exact: sum I_r theta_dot theta_ddot
    dEr_exact = np.einsum("a,na,na->n", m.drive_rotor, mot.theta_dot, mot.theta_ddot)
    assert np.abs(P - dT - dV - dEr_exact - loss).max() / np.abs(P).max() < 1e-9
    assert np.abs(dEr_exact).max() > 1e-3 * np.abs(P).max()  # the rotors matter in this test
    # leaving the rotors out breaks it
    assert np.abs(P - dT - dV - loss).max() / np.abs(P).max() > 1e-4


def _with_sections(d):
    d = ex.deep(d)
    for leg in d.get("legs", []):
        for b in leg.get("bodies", []):
            b["section"] = {"outer_diameter_m": 0.02}
            b["material"] = {"youngs_modulus_Pa": 2.1e11}
    for b in d.get("bodies", []):
        b["section"] = {"outer_diameter_m": 0.02}
        b["material"] = {"youngs_modulus_Pa": 2.1e11}
    return d


def test_verbs_with_drives_are_the_motor_side_equations():
    """The machine verbs take motor efforts: forward(inverse) = identity; x_dot^T M x_dot / 2 is
    the bodies' and the rotors' kinetic energy; B = J_ax^T k; the single-sample path agrees
    with the batched verbs; the inverse verb equals the motor efforts of joint_reactions."""
    from pkmdyn.multibody.dynamics.newton_euler import energies
    from pkmdyn.multibody.dynamics.verbs import machine_verbs

    m = load_mechanism(_stewart_with_drives())
    v = machine_verbs(m)
    assert v.ACTUATORS[0] == "M_1_Nm"
    t, x, xd, xdd = _motion(m, n=20)
    tau = v.inverse_dynamics(m, x, xd, xdd)
    assert _rel(v.forward_dynamics(m, x, xd, tau), xdd) < 1e-9
    kin = solve_kinematics(m, x, xd, xdd, t)
    ref = motor_efforts(m, kin.act_q, kin.act_qd, kin.act_qdd, joint_reactions(m, kin).u).effort
    assert _rel(tau, ref) < 1e-9
    M = v.mass_matrix(m, x)
    T, _ = energies(m, kin)
    assert _rel(0.5 * np.einsum("ni,nij,nj->n", xd, M, xd), T + rotor_energy(m, kin.act_qd)) < 1e-12
    B = v.actuator_map(m, x)
    # the verbs solve each pose from their own start, the run along the motion: both close the loops
    # to the solver's TOLERANCE (1e-13, dimensionless), which moves J_ax by up to the condition
    # number of the Newton matrix times that
    assert _rel(B, np.swapaxes(kin.J_ax, 1, 2) * m.drive_ratio) < 100 * TOLERANCE
    for i in range(len(t)):
        one = v.inverse_dynamics_one(m, x[i], xd[i], xdd[i])
        assert _rel(one, tau[i]) < 1e-9
        assert _rel(v.forward_dynamics_one(m, x[i], xd[i], tau[i]), xdd[i]) < 1e-8


def test_control_with_drives_reads_motor_encoders_and_clips_rated_torque(tmp_path):
    """pkmdyn control on a mechanism with drives: the efforts are the motor torques (columns
    named after the drives), each encoder reads its motor's angle in whole counts of
    2 pi / 1000 rad (within one count of the true angle), and the rated torque clips the command."""
    drive = {**DRIVE, "encoder_counts_per_turn": 1000, "max_torque_Nm": 0.15}
    path = tmp_path / "stewart_drives.toml"
    _write_toml(path, _stewart_with_drives(drive))
    out = tmp_path / "ctl"
    assert main(["control", "--machine", str(path), "--duration", "0.2", "--out", str(out)]) == 0
    c = _read_csv(out / "control.csv")
    res = 2 * np.pi / 1000
    for i in (1, 2, 3, 4, 5, 6):
        enc, true = c[f"M_{i}_enc_rad"], c[f"M_{i}_rad"]
        assert np.abs(enc / res - np.round(enc / res)).max() < 1e-6
        assert np.all((true - enc >= -1e-9) & (true - enc < res + 1e-9))
        assert np.abs(c[f"M_{i}_Nm"]).max() <= 0.15 + 1e-12
    assert max(np.abs(c[f"M_{i}_Nm"]).max() for i in range(1, 7)) == pytest.approx(0.15)  # it saturates


def _write_toml(path, d):
    import tomlkit

    path.write_text(tomlkit.dumps(d), encoding="utf-8")


# --------------------------------------------------------------------------- effort split
@pytest.mark.parametrize("name", ["stewart", "delta", "rrr3", "bennett", "hip", "pdm"])
def test_split_parts_add_up_to_the_total_in_the_run_files(tmp_path, name):
    """Every built-in machine's results.csv: per actuator the parts (each group, the rotor,
    friction) add up to its effort, 1e-12 of the largest effort; the groups cover every body."""
    out = tmp_path / name
    assert main(["run", "--machine", name, "--out", str(out)]) == 0
    with open(out / "results.csv") as fh:
        reader = csv.reader(fh)
        head = next(reader)
        data = np.array([[float(v) for v in row] for row in reader])
    col = {c: data[:, k] for k, c in enumerate(head)}
    summary = json.loads((out / "summary.json").read_text())
    parts = summary["effort_split"]["parts"]
    bodies = json.loads((out / "model.json").read_text())["bodies"]
    grouped = [b for g in summary["effort_split"]["groups"].values() for b in g]
    assert sorted(grouped) == sorted(b["name"] for b in bodies)
    checked = 0
    for c in head:
        for word in ("_torque_", "_effort_"):
            if word not in c or c.count("_") == 0:
                continue
            base, unit = c.split(word)[0], c.rsplit("_", 1)[1]
            if c != f"{base}{word}{unit}":
                continue
            total = col[c]
            got = [col[f"{base}{word}{p}_{unit}"] for p in parts if f"{base}{word}{p}_{unit}" in col]
            if not got:
                continue
            assert len(got) >= len(parts) - 1
            assert np.abs(sum(got) - total).max() <= 1e-12 * np.abs(total).max(), c
            checked += 1
    assert checked == len(summary["actuators"])  # every actuator's split: its motor's for a drive, else the joint's
    # the columns identify --machine accepts from a run are the ones a run writes
    from pkmdyn.jobs import load_machine
    from pkmdyn.multibody.columns import results_column_names

    assert head == results_column_names(load_machine(name)[0])


# --------------------------------------------------------------------------- idle freedoms
def _fd_check(z, t):
    """Central differences of p, v, R, w, origin against v, a, w, wd, origin_v (interior samples);
    returns the largest relative error of each."""
    h = np.diff(t)
    assert np.allclose(h, h[0])
    h = h[0]
    out = {}

    def d(a):
        return (a[2:] - a[:-2]) / (2 * h)

    for pos, vel in (("p", "v"), ("v", "a"), ("w", "wd"), ("origin", "origin_v"), ("origin_v", "origin_a"),
                     ("joint_point", "joint_point_v"), ("joint_point_v", "joint_point_a"), ("q", "qd"),
                     ("qd", "qdd")):
        ref = z[vel][1:-1]
        out[vel] = np.abs(d(z[pos]) - ref).max() / max(np.abs(ref).max(), 1e-9)
    R = z["R"]
    Rd = d(R)
    W = np.einsum("nbij,nbkj->nbik", Rd, R[1:-1])  # dR/dt R^T = [w]x
    w = np.stack([W[..., 2, 1], W[..., 0, 2], W[..., 1, 0]], axis=-1)
    out["w"] = np.abs(w - z["w"][1:-1]).max() / max(np.abs(z["w"]).max(), 1e-9)
    return out


@pytest.mark.parametrize("name", ["stewart", "delta", "rrr3", "bennett", "hip", "pdm"])
def test_every_exported_motion_is_the_derivative_of_the_one_before(tmp_path, name):
    """bodies.npz of every built-in machine's default run (2,001 samples a cycle; the hip's and
    the PDM's own motions): v, a, w, wd, the origins' and joint points' motion, qd and qdd each
    the time derivative of the one before (central differences, error O(h^2)); idle freedoms
    (the Delta's rod spins) included: they are held by their rule, whose exact derivatives the
    files carry."""
    out = tmp_path / name
    args = ["run", "--machine", name, "--out", str(out)]
    if name not in ("hip", "pdm"):
        args[3:3] = ["--samples-per-cycle", "2000"]
    assert main(args) == 0
    z = np.load(out / "bodies.npz")
    errs = _fd_check(z, z["t"])
    worst = max(errs, key=errs.get)
    # measured 2e-6 to 5e-5 (the PDM's 401 samples); a rule-and-dynamics mix of an idle
    # freedom's rate and acceleration was 4e-2 on the Delta
    assert errs[worst] < 3e-4, (worst, errs)


def test_idle_freedoms_are_held_and_their_holding_force_balances_the_rods():
    """The Delta's rods spin idly between two spherical joints: the kinematics hold the spin by
    its rule, its acceleration the exact derivative of its rate (the same as solving the held
    motion), the reactions balance every body with the holding force in the rods' own joints,
    which is small (the rods' spin inertia) and reported."""
    from pkmdyn.multibody.dynamics.newton_euler import idle_holding

    m = load_mechanism(ex.builtin_dict("delta"))
    assert m.topology.idle == 6
    t, x, xd, xdd = _motion(m, n=60)
    kin = solve_kinematics(m, x, xd, xdd, t)
    r = joint_reactions(m, kin)
    assert r.kin is kin
    assert r.residual.max() <= 1e-9 * np.abs(r.joint_force).max()
    H = idle_holding(m)
    assert r.holding.shape == (len(t), m.nq) and np.abs(r.holding).max() > 0
    # the holding force lies in the span of the rules' directions, on the rods' coordinates only
    mu, *_ = np.linalg.lstsq(H, r.holding.T, rcond=None)
    assert np.abs(H @ mu - r.holding.T).max() <= 1e-12 * np.abs(r.holding).max()
    # ... on the coordinates of the joints at the rods' ends only (a rod's spin turns its own
    # joint and, where the tree goes on through the rod, the next body's joint back)
    rod = {b for b, nm in enumerate(m.body_names) if nm.startswith("rod")}
    rod_coords = [c for c in range(m.nq)
                  if {int(m.joint_parent[m.coord_joint[c]]), int(m.joint_child[m.coord_joint[c]])} & rod]
    assert len(rod_coords) < m.nq
    assert np.abs(np.delete(r.holding, rod_coords, axis=1)).max() <= 1e-12 * np.abs(r.holding).max()
    assert np.abs(r.holding).max() < 1e-2 * np.abs(r.u).max()
    # the dense route gives the same reactions and holding force
    rd = joint_reactions(m, kin, solver="dense")
    fs = np.abs(r.joint_force).max()
    assert np.abs(rd.joint_force - r.joint_force).max() <= 1e-9 * fs
    assert np.abs(rd.holding - r.holding).max() <= 1e-9 * fs


# --------------------------------------------------------------------------- streaming
def test_a_chunked_run_equals_one_solved_whole(tmp_path):
    """The same motion through run_mechanism in chunks of 7 and of 10,000 samples: the same
    results to 1e-12 of each column's size, every bodies.npz array alike, the summary's
    extremes equal."""
    from pkmdyn.multibody.kinematics.motion import periodic_motion
    from pkmdyn.jobs.run import run_mechanism

    m = load_mechanism(_stewart_with_drives())
    mo = periodic_motion(m, 1.0, 120)
    a = run_mechanism(m, mo, tmp_path / "a", chunk=7)
    b = run_mechanism(m, mo, tmp_path / "b", chunk=10_000)
    ca, cb = _read_csv(tmp_path / "a" / "results.csv"), _read_csv(tmp_path / "b" / "results.csv")
    assert ca.keys() == cb.keys()
    for k in ca:
        assert np.abs(ca[k] - cb[k]).max() <= 1e-12 * max(np.abs(cb[k]).max(), 1.0), k
    za, zb = np.load(tmp_path / "a" / "bodies.npz"), np.load(tmp_path / "b" / "bodies.npz")
    assert sorted(za.files) == sorted(zb.files)
    for k in za.files:
        if za[k].dtype.kind == "f":
            assert np.abs(za[k] - zb[k]).max() <= 1e-9 * max(np.abs(zb[k]).max(), 1.0), k
    assert a.summary["max_residual"] <= 1e-9
    assert abs(a.summary["min_inverse_singularity_measure"] - b.summary["min_inverse_singularity_measure"]) < 1e-12


def _read_csv(path):
    with open(path) as fh:
        reader = csv.reader(fh)
        head = next(reader)
        data = np.array([[float(v) for v in row] for row in reader])
    return {c: data[:, k] for k, c in enumerate(head)}


def test_long_run_keeps_the_first_body_samples_and_every_result_row(tmp_path):
    """--cycles with max_body_samples lowered: results.csv has every sample, bodies.npz the
    first max_body_samples, the summary says both; --format parquet gives the same table."""
    out = tmp_path / "long"
    assert main(["run", "--machine", "rrr3", "--cycles", "3", "--samples-per-cycle", "100",
                 "--limit", "max_body_samples=150", "--out", str(out)]) == 0
    res = _read_csv(out / "results.csv")
    assert res["t_s"].shape == (301,)
    z = np.load(out / "bodies.npz")
    assert z["t"].shape == (150,) and np.array_equal(z["t"], res["t_s"][:150])
    s = json.loads((out / "summary.json").read_text())
    assert s["samples"] == 301 and s["bodies_samples"] == 150
    # periodic: the third cycle repeats the first
    assert np.abs(res["x_m"][200:] - res["x_m"][:101]).max() < 1e-12
    pq = tmp_path / "pq"
    assert main(["run", "--machine", "rrr3", "--cycles", "3", "--samples-per-cycle", "100", "--format", "parquet",
                 "--out", str(pq)]) == 0
    import pyarrow.parquet as papq

    table = papq.read_table(pq / "results.parquet")
    assert table.column_names == list(res)
    for k in res:
        assert np.abs(table.column(k).to_numpy() - res[k]).max() <= 1e-12 * max(np.abs(res[k]).max(), 1.0)


def test_hip_description_repeats_its_iso_cycle(tmp_path):
    """run --machine hip --cycles 2 repeats the ISO cycle (with its load) and its motor torques
    repeat too."""
    out = tmp_path / "hip2"
    assert main(["run", "--machine", "hip", "--cycles", "2", "--out", str(out)]) == 0
    res = _read_csv(out / "results.csv")
    n = res["t_s"].shape[0]
    assert n == 2001
    for c in ("motor_1_torque_Nm", "hydraulic_N", "motor_3_torque_friction_Nm"):
        assert np.abs(res[c][1000:] - res[c][:1001]).max() <= 1e-9 * np.abs(res[c]).max(), c


# --------------------------------------------------------------------------- limits and bad input
def test_a_motion_beyond_a_rate_limit_is_refused_naming_joint_sample_and_value(tmp_path, capsys):
    """A motor speed limit and the joints' default speed limit: one line naming the actuator
    or joint, the sample (of the whole run, beyond the first chunk) and the value; nothing
    written; --limit raises a default."""
    m = load_mechanism(_stewart_with_drives())
    # a motion whose speed grows: z = z_ref + a (t / T) sin(w t)
    t = np.linspace(0.0, 2.0, 3000)
    a, w = 0.03, 2 * np.pi
    x = np.tile(reference_task(m), (t.size, 1))
    xd, xdd = np.zeros_like(x), np.zeros_like(x)
    x[:, 2] += a * t / 2 * np.sin(w * t)
    xd[:, 2] = a / 2 * (np.sin(w * t) + w * t * np.cos(w * t))
    xdd[:, 2] = a / 2 * (2 * w * np.cos(w * t) - w * w * t * np.sin(w * t))
    kin = solve_kinematics(m, x, xd, xdd, t)
    speed = np.abs(kin.act_qd * m.drive_ratio).max(axis=1)
    limit = 1.001 * speed[:1500].max()  # reached first after the first chunk (1024 samples)
    expect = int(np.flatnonzero(speed > limit)[0])
    assert expect >= 1500
    motion = tmp_path / "m.csv"
    names = ["x_m", "y_m", "z_m", "euler1_rad", "euler2_rad", "euler3_rad"]
    head = ["t_s", *names, *(n.replace("_", "d_", 1) + "_s" for n in names),
            *(n.replace("_", "dd_", 1) + "_s2" for n in names)]
    np.savetxt(motion, np.column_stack([t, x, xd, xdd]), delimiter=",", header=",".join(head), comments="",
               fmt="%.17g")
    path = tmp_path / "s.toml"
    _write_toml(path, _stewart_with_drives({**DRIVE, "max_speed_rad_s": float(limit)}))
    out = tmp_path / "out"
    assert main(["run", "--machine", str(path), "--motion", str(motion), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "actuator 'M_" in err[0] and "motor speed" in err[0] and "max_speed_rad_s" in err[0]
    assert int(err[0].split("sample ")[1].split()[0]) == expect  # the sample's number in the whole run
    assert not out.exists()
    # the default joint-speed limit, raised on the command line
    assert main(["run", "--machine", "stewart", "--limit", "max_joint_speed_m_s=0.001", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "actuated joint 'P_" in err and "max_joint_speed_m_s" in err and not out.exists()
    assert main(["run", "--machine", "stewart", "--limit", "max_task_speed_rad_s=1e-4", "--out", str(out)]) == 2
    assert "task coordinate euler" in capsys.readouterr().err


def test_limits_guard_the_task_motion_before_kinematics():
    from pkmdyn.multibody.dynamics.actuators import check_task_rates, effective_limits

    m = load_mechanism(ex.builtin_dict("rrr3"))
    t = np.linspace(0, 1, 5)
    xd = np.zeros((5, m.nt))
    xd[3, 0] = 20.0
    with pytest.raises(LimitError, match=r"sample 13 .*x_m rate 20 m/s exceeds the limit max_task_speed_m_s = 10"):
        check_task_rates(m, t, xd, np.zeros_like(xd), effective_limits(m), 10)
    check_task_rates(m, t, xd, np.zeros_like(xd), effective_limits(m, {"max_task_speed_m_s": 30.0}), 10)


BAD = [
    ({"joint": "nope"}, "joint 'nope' is not a joint of the leg template"),
    ({"joint": "U"}, "is not actuated"),
    ({"joint": "P", "screw_lead_m": 0.0}, "screw_lead_m: must be a finite number > 0"),
    ({"joint": "P", "screw_lead_m": -0.01}, "screw_lead_m: must be a finite number > 0"),
    ({"joint": "P", "screw_lead_m": 0.01, "gear_ratio": 0.0}, "gear_ratio: must be a finite number > 0"),
    ({"joint": "P", "screw_lead_m": 0.01, "rotor_inertia_kgm2": -1e-5}, "rotor_inertia_kgm2: must be >= 0"),
    ({"joint": "P", "screw_lead_m": 0.01, "coulomb_torque_Nm": -0.1}, "coulomb_torque_Nm: must be >= 0"),
    ({"joint": "P", "screw_lead_m": 0.01, "viscous_Nm_s_rad": -0.1}, "viscous_Nm_s_rad: must be >= 0"),
    ({"joint": "P", "screw_lead_m": 0.01, "moving_mass_kg": 1.0}, "moving_mass_kg: the motor of joint"),
    ({"joint": "P", "coulomb_torque_Nm": 0.1}, "coulomb_torque_Nm: the motor of joint"),
    ({"joint": "P", "gear_ratio": 3.0}, "gear_ratio: joint 'P_1' is prismatic"),
    ({"joint": "P", "name": "U", "screw_lead_m": 0.01}, "is the name of a joint or body"),
    ({"joint": "P", "screw_lead_m": 0.01, "max_speed_rad_s": 0.0}, "max_speed_rad_s: must be > 0"),
    ({"joint": "P", "screw_lead_m": 0.01, "gear_ratio": 1e-9}, "gear_ratio: 1e-09 is outside the plausible range"),
    ({"joint": "P", "screw_lead_m": 100.0}, "screw_lead_m: 100 is outside the plausible range"),
    ({"joint": "P", "screw_lead_m": 0.01, "coulomb_torque_Nm": 1e300}, "coulomb_torque_Nm: 1e+300 exceeds"),
]


@pytest.mark.parametrize("entry, message", BAD)
def test_bad_actuator_entries_are_refused_by_name(tmp_path, capsys, entry, message):
    d = ex.builtin_dict("stewart")
    d["legs"][0]["actuators"] = [entry]
    with pytest.raises(ParameterError) as exc:
        load_mechanism(d)
    text = str(exc.value)
    assert "\n" not in text and "[legs][0]" in text and message in text, text
    path = tmp_path / "bad.toml"
    _write_toml(path, d)
    out = tmp_path / "out"
    assert main(["run", "--machine", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and not out.exists()


def test_an_actuator_named_after_a_joint_or_twice_on_one_joint_is_refused():
    d = ex.builtin_dict("stewart")
    d["actuators"] = [{"joint": "P_1", "name": "U_1", "screw_lead_m": 0.01}]
    with pytest.raises(ParameterError, match=r"\[actuators\] U_1: name: 'U_1' is the name of a joint or body"):
        load_mechanism(d)
    d["actuators"] = [{"joint": "P_1", "screw_lead_m": 0.01}, {"joint": "P_1", "name": "x", "screw_lead_m": 0.01}]
    with pytest.raises(ParameterError, match="driven by 'P_1_motor' already"):
        load_mechanism(d)


@pytest.mark.parametrize("groups, message", [
    ([{"name": "a", "bodies": ["platform", "nobody"]}], "'nobody' is not a body"),
    ([{"name": "a", "bodies": ["platform"]}, {"name": "b", "bodies": ["platform"]}], "is in group 'a' already"),
    ([{"name": "a", "bodies": ["cylinder"]}, {"name": "b", "bodies": ["cylinder_1"]}], "is in group 'a' already"),
    ([{"name": "friction", "bodies": ["platform"]}], "is a part of the split of its own"),
    ([{"name": "a", "bodies": ["platform"]}, {"name": "a", "bodies": ["piston"]}], "group 'a' is defined twice"),
])
def test_bad_groups_are_refused_by_name(groups, message):
    d = ex.builtin_dict("stewart")
    d["groups"] = groups
    with pytest.raises(ParameterError, match=message):
        load_mechanism(d)


def test_groups_name_template_bodies_and_leave_the_rest_in_other():
    d = ex.builtin_dict("stewart")
    d["groups"] = [{"name": "cylinders", "bodies": ["cylinder"]}]
    m = load_mechanism(d)
    assert m.group_names == ("cylinders", "other")
    cyl = [m.body_names[b] for b in np.flatnonzero(m.body_group == 0)]
    assert sorted(cyl) == [f"cylinder_{i}" for i in range(1, 7)]
    default = load_mechanism(ex.builtin_dict("stewart"))
    assert default.group_names == ("leg_1", "leg_3", "leg_5", "leg_2", "leg_4", "leg_6", "platform")


def test_friction_that_locks_is_named_at_its_sample_of_the_whole_run():
    """A chunk's friction iteration names the sample by its number in the whole run."""
    import test_multibody_dynamics as tmd

    m = load_mechanism(tmd._stewart_with_friction(200.0))
    t, x, xd, xdd = _motion(m, n=5)
    kin = solve_kinematics(m, x, xd, xdd, t)
    with pytest.raises(ParameterError) as a:
        joint_reactions(m, kin)
    with pytest.raises(ParameterError) as b:
        joint_reactions(m, kin, sample_offset=5000)
    sa = int(str(a.value).split("sample ")[1].split()[0])
    sb = int(str(b.value).split("sample ")[1].split()[0])
    assert sb == sa + 5000


def test_run_machine_hip_writes_the_hip_runs_motor_torques_and_parts(tmp_path):
    """The two commands on the built-in ISO cycle: pkmdyn run --machine hip (the generic engine
    through the hip's description) writes the motor torques of pkmdyn hip run (Eq. 7-16, its
    own closed form) and every part of their split (platform, lever, slider, screw = rotor,
    friction), each to 1e-9 of that part's largest value."""
    assert main(["hip", "run", "--no-plots", "--out", str(tmp_path / "own")]) == 0
    assert main(["run", "--machine", "hip", "--out", str(tmp_path / "gen")]) == 0
    own, gen = _read_csv(tmp_path / "own" / "results.csv"), _read_csv(tmp_path / "gen" / "results.csv")
    assert np.array_equal(own["t_s"], gen["t_s"])
    for i in (1, 2, 3):
        for part, word in (("", ""), ("_platform", "_platform"), ("_lever", "_lever"), ("_slider", "_slider"),
                           ("_screw", "_rotor"), ("_friction", "_friction")):
            ref, got = own[f"tau{i}{part}_Nm"], gen[f"motor_{i}_torque{word}_Nm"]
            assert np.abs(got - ref).max() <= 1e-9 * np.abs(ref).max(), (i, part)


def test_a_short_last_chunk_beyond_the_bodies_window_and_an_odd_body_limit(tmp_path, capsys):
    """A run whose last chunk lies beyond the bodies' window and holds no sample of the
    singularity stride completes; max_body_samples takes whole numbers only (one line)."""
    out = tmp_path / "a"
    assert main(["run", "--machine", "rrr3", "--samples-per-cycle", "1026", "--limit", "max_body_samples=10",
                 "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["samples"] == 1027 and s["bodies_samples"] == 10 and s["min_inverse_singularity_measure"] > 0
    assert np.load(out / "bodies.npz")["t"].shape == (10,)
    capsys.readouterr()
    assert main(["run", "--machine", "rrr3", "--limit", "max_body_samples=0.5", "--out", str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "max_body_samples" in err[0] and not (tmp_path / "b").exists()


def test_a_chunked_run_beyond_the_bodies_window_keeps_its_extremes(tmp_path):
    """Chunks of 50 against one chunk, the bodies' window 130 of 301 samples: the same results,
    the same bodies.npz, and the smallest singularity measures of the stride within those of
    every sample."""
    from pkmdyn.multibody.kinematics.motion import periodic_motion
    from pkmdyn.jobs.run import run_mechanism

    m = load_mechanism(ex.builtin_dict("delta"))
    mo = periodic_motion(m, 1.0, 300)
    a = run_mechanism(m, mo, tmp_path / "a", chunk=50, limits={"max_body_samples": 130})
    b = run_mechanism(m, mo, tmp_path / "b", chunk=1000, limits={"max_body_samples": 130})
    ca, cb = _read_csv(tmp_path / "a" / "results.csv"), _read_csv(tmp_path / "b" / "results.csv")
    for k in ca:
        assert np.abs(ca[k] - cb[k]).max() <= 1e-12 * max(np.abs(cb[k]).max(), 1.0), k
    za, zb = np.load(tmp_path / "a" / "bodies.npz"), np.load(tmp_path / "b" / "bodies.npz")
    assert za["t"].shape == (130,)
    for k in ("q", "wd", "joint_force"):
        assert np.abs(za[k] - zb[k]).max() <= 1e-9 * max(np.abs(zb[k]).max(), 1.0), k
    from pkmdyn.multibody import singularity_measures

    kin = solve_kinematics(m, mo.chunk(0, 301).x, mo.chunk(0, 301).xd, mo.chunk(0, 301).xdd)
    every = singularity_measures(m, kin.q).inverse.min()
    assert a.summary["min_inverse_singularity_measure"] >= every - 1e-12
    assert a.summary["min_inverse_singularity_measure"] == pytest.approx(b.summary["min_inverse_singularity_measure"], abs=1e-12)


def test_an_actuator_singularity_names_its_sample_of_the_whole_run(monkeypatch):
    """The actuator map's singularity message gives the sample's number in the whole run (here
    every sample made singular by raising the threshold)."""
    from pkmdyn.errors import SingularityError
    from pkmdyn.multibody.dynamics import newton_euler as dynamics

    m = load_mechanism(ex.builtin_dict("rrr3"))
    t, x, xd, xdd = _motion(m, n=5)
    kin = solve_kinematics(m, x, xd, xdd, t)
    monkeypatch.setattr(dynamics, "SINGULAR_ACTUATION", 2.0)
    with pytest.raises(SingularityError, match=r"^sample 5000 \(t = 0 s\): the actuator map is singular"):
        joint_reactions(m, kin, sample_offset=5000)


def test_the_split_adds_up_under_friction_that_depends_on_the_reactions():
    """Load-dependent friction (iterated): the split's parts add up to the efforts to rounding,
    and the dissipation is that of the friction the efforts hold with."""
    import test_multibody_dynamics as tmd

    m = load_mechanism(tmd._stewart_with_friction(1.0))
    t, x, xd, xdd = _motion(m, n=20)
    kin = solve_kinematics(m, x, xd, xdd, t)
    r = joint_reactions(m, kin, split=True)
    assert r.iterations > 2
    total = r.shares.groups.sum(axis=2) + r.shares.friction.sum(axis=2)
    assert np.abs(total - r.u).max() <= 1e-12 * np.abs(r.u).max()
    assert tmd._power_error(m, r) < 1e-12


def test_a_drives_encoder_too_coarse_for_the_motion_is_refused(tmp_path, capsys):
    """pkmdyn control checks a drive's own encoder: fewer than 10 counts over the motor's travel
    is refused naming the drive and its key (a linear motor: encoder_counts_per_m)."""
    d = ex.builtin_dict("stewart")
    for leg in d["legs"]:
        leg["actuators"] = [{"joint": "P", "name": "L", "moving_mass_kg": 0.5, "encoder_counts_per_m": 0.5}]
    path = tmp_path / "lin.toml"
    _write_toml(path, d)
    out = tmp_path / "out"
    assert main(["control", "--machine", str(path), "--duration", "0.2", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "[[actuators]] L_" in err[0] and "encoder_counts_per_m" in err[0] and not out.exists()


def test_control_summary_names_every_actuator_whole(tmp_path):
    """summary.json of a described mechanism's control run: one entry per actuator, under its
    whole name (names hold underscores)."""
    out = tmp_path / "ctl"
    assert main(["control", "--machine", "stewart", "--duration", "0.1", "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    efforts = next(v for k, v in s.items() if isinstance(v, dict) and "P_1" in v)
    assert sorted(efforts) == [f"P_{i}" for i in range(1, 7)]


def test_a_part_of_a_cycle_needs_no_periodic_motion(tmp_path):
    """--cycles 0.5 of the PDM's default motion (not periodic) takes its first half."""
    out = tmp_path / "pdm"
    assert main(["run", "--machine", "pdm", "--cycles", "0.5", "--out", str(out)]) == 0
    assert json.loads((out / "summary.json").read_text())["samples"] == 201
