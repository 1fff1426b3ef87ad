"""Drives on actuated joints against independent closed-form oracles.

Two planar 2-DOF mechanisms in a vertical plane, described in the TOML format of
docs/mechanism_format.md and run through ``pkmdyn run``: a five-bar linkage whose base
revolutes are driven by geared motors, and a biglide whose sliders are driven by rotary
motors through ball screws. Each drive's motor torque column ``<name>_torque_Nm`` must equal
the oracle's (``tests/oracles/five_bar.py``, ``tests/oracles/biglide.py``: virtual work with
closed-form Jacobians, the motor's balance ``tau = u / k + I_r theta_dd + C sgn_eps(theta_d)
+ b theta_d``) to 1e-9 of the largest torque; so must the joint efforts ``<joint>_effort_*``
and the actuated joints' coordinates, rates and accelerations.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from oracles import biglide, five_bar

RTOL = 1e-9
Y0 = 0.05                     # the plane of the mechanism: y = Y0 [m]
N_SAMPLES = 201
DURATION = 2.0                # [s]


# ----------------------------------------------------------------------------------------
# description helpers
# ----------------------------------------------------------------------------------------

def _f(x) -> str:
    return repr(float(x))


def _vec(v) -> str:
    return "[" + ", ".join(_f(x) for x in v) + "]"


def _p3(p2, dy=0.0):
    """A planar point (x, z) in the plane y = Y0 (+ dy) of the base frame."""
    return np.array([p2[0], Y0 + dy, p2[1]])


def _inertia(rng, scale):
    """A centroidal inertia tensor (base frame at the reference configuration) with products
    of inertia: principal moments obeying the triangle inequality, turned at random."""
    p1, p2 = rng.uniform(0.6, 1.4, 2) * scale
    p3 = rng.uniform(abs(p1 - p2) + 0.1 * scale, p1 + p2 - 0.1 * scale)
    R = Rotation.random(random_state=rng).as_matrix()
    return R @ np.diag([p1, p2, p3]) @ R.T


def _inertia_entries(I):
    return [I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]]


def _body(name, mass, com3, I):
    return (f'[[bodies]]\nname = "{name}"\nmass_kg = {_f(mass)}\ncom_m = {_vec(com3)}\n'
            f"inertia_kgm2 = {_vec(_inertia_entries(I))}\n")


def _joint(name, kind, parent, child, point3, axis3, extra=""):
    return (f'[[joints]]\nname = "{name}"\ntype = "{kind}"\nparent = "{parent}"\n'
            f'child = "{child}"\npoint_m = {_vec(point3)}\naxis = {_vec(axis3)}\n{extra}')


def _actuator(joint, name, par, i, screw=False):
    s = f'[[actuators]]\njoint = "{joint}"\nname = "{name}"\n'
    s += f"gear_ratio = {_f(par.gear_ratio[i])}\n"
    if screw:
        s += f"screw_lead_m = {_f(par.screw_lead[i])}\n"
    s += (f"rotor_inertia_kgm2 = {_f(par.rotor_inertia[i])}\n"
          f"coulomb_torque_Nm = {_f(par.coulomb[i])}\nviscous_Nm_s_rad = {_f(par.viscous[i])}\n")
    return s


def _header(name, g2):
    return (f'[mechanism]\nname = "{name}"\nsource = "planar textbook mechanism with drives"\n'
            f"gravity_m_s2 = {_vec([g2[0], 0.0, g2[1]])}\n\n")


def _task(body, P):
    return f'[task]\nbody = "{body}"\npoint_m = {_vec(_p3(P))}\nposition = ["x", "z"]\n'


def _drives(rng, kind, friction):
    out = {"rotor_inertia": rng.uniform(2e-5, 9e-5, 2)}
    if kind == "five_bar":
        out["gear_ratio"] = rng.uniform(6.0, 40.0, 2)
    else:
        out["gear_ratio"] = rng.uniform(1.0, 3.0, 2)
        out["screw_lead"] = rng.uniform(0.004, 0.02, 2)
    if friction:
        out["coulomb"] = rng.uniform(0.01, 0.08, 2)
        out["viscous"] = rng.uniform(5e-5, 5e-4, 2)
    return out


def _in_plane_com(rng, n):
    """(along, across) offsets in the link frame and an out-of-plane offset for each link."""
    return rng.uniform(-0.02, 0.02, n)


# ----------------------------------------------------------------------------------------
# the two mechanisms
# ----------------------------------------------------------------------------------------

FIVE_BAR_CASES = {
    # seed: (friction on, joint signs, elbow branch)
    11: (False, (1.0, 1.0), (1.0, -1.0)),
    12: (True, (-1.0, 1.0), (1.0, -1.0)),
    13: (True, (1.0, -1.0), (1.0, 1.0)),
}

BIGLIDE_CASES = {
    # seed: (friction on, joint signs, rail angle [rad], rail origins, branch, pose)
    21: (False, (1.0, 1.0), np.pi / 2, [[-0.20, 0.0], [0.21, 0.0]], (1.0, 1.0), [0.01, -0.12]),
    22: (True, (-1.0, 1.0), np.pi / 2 + 0.3, [[-0.20, 0.0], [0.21, 0.03]], (1.0, 1.0),
         [0.0, -0.15]),
    23: (True, (1.0, -1.0), 0.15, [[0.0, 0.0], [0.02, 0.05]], (-1.0, 1.0), [0.03, -0.20]),
}


def five_bar_case(seed, tmp: Path):
    friction, signs, sigma = FIVE_BAR_CASES[seed]
    rng = np.random.default_rng(seed)
    I_prox = [_inertia(rng, 2.5e-3) for _ in range(2)]
    I_dist = [_inertia(rng, 3.0e-3) for _ in range(2)]
    base = np.array([[-0.12, 0.0], [0.13, 0.02]]) + rng.uniform(-0.01, 0.01, (2, 2))
    par = five_bar.FiveBar(
        base=base, l1=np.array([0.20, 0.22]) * rng.uniform(0.95, 1.05, 2),
        l2=np.array([0.28, 0.26]) * rng.uniform(0.95, 1.05, 2), sigma=sigma,
        mass_proximal=rng.uniform(0.4, 0.9, 2), mass_distal=rng.uniform(0.3, 0.7, 2),
        com_proximal=np.array([[0.10, 0.0], [0.11, 0.0]]) + _in_plane_com(rng, (2, 2)),
        com_distal=np.array([[0.13, 0.0], [0.12, 0.0]]) + _in_plane_com(rng, (2, 2)),
        inertia_proximal=[I[1, 1] for I in I_prox], inertia_distal=[I[1, 1] for I in I_dist],
        joint_sign=signs, **_drives(rng, "five_bar", friction),
    )
    P0 = five_bar.DEFAULT_POSE + rng.uniform(-0.01, 0.01, 2)
    t = np.linspace(0.0, DURATION, N_SAMPLES)
    motion = five_bar.sine_motion(t, P0, rng.uniform(0.02, 0.04, 2) * rng.choice([-1, 1], 2),
                                  rng.uniform(2.0, 5.0, 2), rng.uniform(-np.pi, np.pi, 2))
    # the description at the reference configuration P0
    ik = five_bar.inverse_kinematics(par, P0)
    bm = five_bar.body_motion(par, P0)
    dy = rng.uniform(-0.01, 0.01, 4)            # centres of mass off the plane
    names = ["proximal_1", "proximal_2", "distal_1", "distal_2"]
    tensors = I_prox + I_dist
    text = _header("five_bar_drives", par.gravity)
    for b in range(4):
        text += _body(names[b], bm["mass"][b], _p3(bm["c"][0, b], dy[b]), tensors[b]) + "\n"
    for i in range(2):
        axis = signs[i] * np.array([0.0, -1.0, 0.0])   # q = sign * phi, phi counter-clockwise
        text += _joint(f"A{i + 1}", "revolute", "ground", f"proximal_{i + 1}", _p3(par.base[i]),
                       axis, f"actuated = true\nangle_at_reference_rad = "
                       f"{_f(signs[i] * ik['phi'][0, i])}\n") + "\n"
        text += _joint(f"B{i + 1}", "revolute", f"proximal_{i + 1}", f"distal_{i + 1}",
                       _p3(ik["B"][0, i]), [0.0, 1.0, 0.0]) + "\n"
    text += _joint("P", "revolute", "distal_1", "distal_2", _p3(P0), [0.0, 1.0, 0.0]) + "\n"
    text += _task("distal_1", P0) + "\n"
    for i in range(2):
        text += _actuator(f"A{i + 1}", f"M{i + 1}", par, i) + "\n"
    return par, motion, text, ["A1", "A2"], "Nm", "distal_1"


def biglide_case(seed, tmp: Path):
    friction, signs, angle, origins, sigma, pose = BIGLIDE_CASES[seed]
    rng = np.random.default_rng(seed)
    I_slider = [_inertia(rng, 1e-3) for _ in range(2)]
    I_link = [_inertia(rng, 3.0e-3) for _ in range(2)]
    par = biglide.Biglide(
        rail_origin=np.array(origins), rail_angle=angle,
        length=np.array([0.30, 0.32]) * rng.uniform(0.97, 1.03, 2), sigma=sigma,
        mass_slider=rng.uniform(0.8, 1.5, 2), mass_link=rng.uniform(0.3, 0.6, 2),
        slider_com=rng.uniform(-0.03, 0.03, (2, 2)),
        com_link=np.array([[0.14, 0.0], [0.15, 0.0]]) + _in_plane_com(rng, (2, 2)),
        inertia_link=[I[1, 1] for I in I_link], joint_sign=signs,
        **_drives(rng, "biglide", friction),
    )
    P0 = np.array(pose) + rng.uniform(-0.01, 0.01, 2)
    t = np.linspace(0.0, DURATION, N_SAMPLES)
    motion = biglide.sine_motion(t, P0, rng.uniform(0.02, 0.035, 2) * rng.choice([-1, 1], 2),
                                 rng.uniform(2.0, 5.0, 2), rng.uniform(-np.pi, np.pi, 2))
    ik = biglide.inverse_kinematics(par, P0)
    bm = biglide.body_motion(par, P0)
    d3 = _p3(biglide._e(np.asarray(angle))) - np.array([0.0, Y0, 0.0])
    dy = rng.uniform(-0.01, 0.01, 4)
    names = ["slider_1", "slider_2", "link_1", "link_2"]
    tensors = I_slider + I_link
    text = _header("biglide_drives", par.gravity)
    for b in range(4):
        text += _body(names[b], bm["mass"][b], _p3(bm["c"][0, b], dy[b]), tensors[b]) + "\n"
    for i in range(2):
        text += _joint(f"S{i + 1}", "prismatic", "ground", f"slider_{i + 1}", _p3(ik["S"][0, i]),
                       signs[i] * d3, f"actuated = true\nposition_at_reference_m = "
                       f"{_f(signs[i] * ik['s'][0, i])}\n") + "\n"
        text += _joint(f"R{i + 1}", "revolute", f"slider_{i + 1}", f"link_{i + 1}",
                       _p3(ik["S"][0, i]), [0.0, 1.0, 0.0]) + "\n"
    text += _joint("P", "revolute", "link_1", "link_2", _p3(P0), [0.0, 1.0, 0.0]) + "\n"
    text += _task("link_1", P0) + "\n"
    for i in range(2):
        text += _actuator(f"S{i + 1}", f"M{i + 1}", par, i, screw=True) + "\n"
    return par, motion, text, ["S1", "S2"], "N", "link_1"


MECHANISMS = {"five_bar": (five_bar, five_bar_case), "biglide": (biglide, biglide_case)}
CASES = [("five_bar", s) for s in FIVE_BAR_CASES] + [("biglide", s) for s in BIGLIDE_CASES]


def _write_motion(path: Path, t, motion):
    P, Pd, Pdd = motion
    cols = {"t_s": t, "x_m": P[:, 0], "z_m": P[:, 1], "xd_m_s": Pd[:, 0], "zd_m_s": Pd[:, 1],
            "xdd_m_s2": Pdd[:, 0], "zdd_m_s2": Pdd[:, 1]}
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(list(cols))
        for k in range(len(t)):
            w.writerow([repr(float(c[k])) for c in cols.values()])


def _read_results(path: Path):
    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


_RUNS: dict = {}


def run_case(name, seed, tmp_path_factory):
    key = (name, seed)
    if key not in _RUNS:
        from pkmdyn.cli import main

        mod, build = MECHANISMS[name]
        tmp = tmp_path_factory.mktemp(f"{name}_{seed}")
        par, motion, text, joints, unit, task_body = build(seed, tmp)
        toml = tmp / f"{name}.toml"
        toml.write_text(text)
        t = np.linspace(0.0, DURATION, N_SAMPLES)
        csv_path = tmp / "motion.csv"
        _write_motion(csv_path, t, motion)
        out = tmp / "out"
        rc = main(["run", "--machine", str(toml), "--motion", str(csv_path),
                   "--minimum-norm-reactions", "--out", str(out)])
        assert rc == 0, f"pkmdyn run exited {rc}"
        _RUNS[key] = (mod, par, motion, joints, unit, _read_results(out / "results.csv"),
                      task_body)
    return _RUNS[key]


def _rel(actual, expected):
    return np.max(np.abs(actual - expected)) / np.max(np.abs(expected))


# ----------------------------------------------------------------------------------------
# the comparisons
# ----------------------------------------------------------------------------------------

@pytest.mark.parametrize("name,seed", CASES)
def test_motion_stays_regular(name, seed, tmp_path_factory):
    """Precondition: the motion keeps away from every singularity of the oracle."""
    mod, build = MECHANISMS[name]
    par, motion = build(seed, tmp_path_factory.mktemp("pre"))[:2]
    ik = mod.inverse_kinematics(par, *motion)
    if name == "five_bar":
        assert np.min(np.abs(ik["leg_sine"])) > 0.2 and np.min(np.abs(ik["distal_sine"])) > 0.2
    else:
        assert np.min(np.abs(ik["leg_cosine"])) > 0.2 and np.min(np.abs(ik["link_sine"])) > 0.2
    assert np.all(np.isfinite(ik["q"]))


@pytest.mark.parametrize("name,seed", CASES)
def test_motor_torques_match_the_oracle(name, seed, tmp_path_factory):
    mod, par, motion, joints, unit, res, _ = run_case(name, seed, tmp_path_factory)
    ref = mod.motor_torques(par, *motion)["torque"]
    got = np.stack([res[f"M{i + 1}_torque_Nm"] for i in range(2)], -1)
    err = np.max(np.abs(got - ref)) / np.max(np.abs(ref))
    assert err <= RTOL, (f"{name} seed {seed}: motor torques differ by {err:.3e} of the "
                         f"largest torque {np.max(np.abs(ref)):.4e} N m; per motor "
                         f"{np.max(np.abs(got - ref), axis=0)}")


@pytest.mark.parametrize("name,seed", CASES)
def test_joint_efforts_match_the_oracle(name, seed, tmp_path_factory):
    mod, par, motion, joints, unit, res, _ = run_case(name, seed, tmp_path_factory)
    ref = mod.motor_torques(par, *motion)["effort"]
    got = np.stack([res[f"{j}_effort_{unit}"] for j in joints], -1)
    err = np.max(np.abs(got - ref)) / np.max(np.abs(ref))
    assert err <= RTOL, f"{name} seed {seed}: joint efforts differ by {err:.3e}"


@pytest.mark.parametrize("name,seed", CASES)
def test_actuated_joint_motion_matches_the_oracle(name, seed, tmp_path_factory):
    mod, par, motion, joints, unit, res, _ = run_case(name, seed, tmp_path_factory)
    ik = mod.inverse_kinematics(par, *motion)
    u = "rad" if unit == "Nm" else "m"
    for key, col in (("q", f"_pos_{u}"), ("qd", f"_vel_{u}_s"), ("qdd", f"_acc_{u}_s2")):
        got = np.stack([res[j + col] for j in joints], -1)
        diff = got - ik[key]
        if key == "q" and u == "rad":
            diff = np.angle(np.exp(1j * diff))
        err = np.max(np.abs(diff)) / np.max(np.abs(ik[key]))
        assert err <= RTOL, f"{name} seed {seed}: {key} differs by {err:.3e}"
    # the task columns are the motion given
    assert np.max(np.abs(res["x_m"] - motion[0][:, 0])) < 1e-12
    assert np.max(np.abs(res["z_m"] - motion[0][:, 1])) < 1e-12


@pytest.mark.parametrize("name,seed", CASES)
def test_motor_motion_and_torque_split_match_the_oracle(name, seed, tmp_path_factory):
    """The motor's angle ``theta = k q`` (the joint's reference value included), its rate and
    acceleration; the rotor part ``I_r theta_dd``, the friction part and the bodies' shares
    ``u_b / k`` (default groups: the task body and ``other``)."""
    mod, par, motion, joints, unit, res, task_body = run_case(name, seed, tmp_path_factory)
    tq = mod.motor_torques(par, *motion)
    shares = mod.effort_shares(par, *motion)
    k = par.gear_ratio if name == "five_bar" else par.ratio
    scale = np.max(np.abs(tq["torque"]))
    for key, col in (("theta", "pos_rad"), ("theta_d", "vel_rad_s"), ("theta_dd", "acc_rad_s2")):
        got = np.stack([res[f"M{i + 1}_{col}"] for i in range(2)], -1)
        err = np.max(np.abs(got - tq[key])) / np.max(np.abs(tq[key]))
        assert err <= RTOL, f"{name} seed {seed}: motor {key} differs by {err:.3e}"
    parts = {"rotor": tq["rotor"], "friction": tq["friction"],
             task_body: shares[:, 2] / k[None],
             "other": (shares.sum(axis=1) - shares[:, 2]) / k[None]}
    for i in range(2):
        split = {c[len(f"M{i + 1}_torque_"):-len("_Nm")] for c in res
                 if c.startswith(f"M{i + 1}_torque_") and c.endswith("_Nm")
                 and c != f"M{i + 1}_torque_Nm"}
        assert split == set(parts), f"{name} seed {seed}: split columns {sorted(split)}"
        for part, ref in parts.items():
            err = np.max(np.abs(res[f"M{i + 1}_torque_{part}_Nm"] - ref[:, i])) / scale
            assert err <= RTOL, f"{name} seed {seed}: M{i + 1} {part} part differs by {err:.3e}"
