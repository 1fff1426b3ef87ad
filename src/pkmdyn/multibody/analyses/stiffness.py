"""Stiffness and vibration of any described mechanism with its actuators locked.

**Compliance sources** (``docs/stiffness.md``, "Compliance sources"): the elastic bodies'
beam segments (a body's ``section`` and ``material``, the beam model of :mod:`pkmdyn.multibody.dynamics.compliance.reactions`:
tension, torsion and bending, Eq. 63-64 of the PDM paper), the drives
(``[joints.stiffness] drive_N_m`` or ``drive_Nm_rad`` of an actuated joint, joint side) and the
joints' own springs (``force_N_m``, ``moment_Nm_rad`` against the joint's reaction, along the
axes of its frame on the parent). Everything else is rigid.

**Method: the force method (matrix structural analysis in forces).** With the actuators
locked, the mechanism is a structure. A wrench ``w`` applied to the task body is carried by
joint wrenches ``z`` in equilibrium with it (the equations of :mod:`pkmdyn.multibody.dynamics.newton_euler` without the
actuated coordinates' rows, which leave each drive's effort free); each compliant member's
internal force is linear in ``z``: ``e = E z + e_w`` (a beam segment's wrench, a drive's
effort ``u_a = T_a . W_j``, a joint spring's reaction), and the complementary energy is
``U* = 1/2 e^T F e`` with ``F`` the members' flexibilities (``L/EA`` ..., ``1/k``). Of all the
admissible ``z`` (the cut joints' constraint wrenches ``lambda`` parameterise them,
``z = z_w + Z lambda``, :class:`pkmdyn.multibody.dynamics.newton_euler._CutRoute`), the real one minimises ``U*``
(Menabrea); the displacement conjugate to ``w`` is ``dU*/dw`` (Castigliano), so the task
body's small twist ``[dtheta; dp_O]`` (Plücker at the base origin) under ``w = [n_O; f]`` is
``C_O w`` with the compliance matrix ``C_O = E_w^T F E_w`` (``E_w`` the members' forces per unit
wrench at the minimum). This holds for statically indeterminate (over-constrained)
mechanisms, whose redundant reactions the minimum decides.

**Task stiffness.** ``dx = D t`` maps the task body's small twist to the task coordinates
(a position row ``e_i . (dp_O + dtheta x p)``, an Euler angle's row from the inverse of the
rate map ``omega = Omega(phi) phi_dot``), and a generalised force ``f`` along the task
coordinates is the wrench ``D^T f`` (same power), so ``C_task = D C_O D^T`` and ``K_task =
C_task^-1`` (n_t x n_t, the task coordinates' order and units: N/m, N/rad, N m/m, N m/rad).
For the Gough-Stewart platform with rigid links and drives of stiffness ``k`` this is
``J^T diag(k) J`` with ``J = dl/dx`` (Gosselin 1990). No preload term: the stiffness about
the unloaded structure (the geometric stiffness of a loaded pose, ``dJ^T/dx u``, is left out).

**Worst directions** at the task point: ``C_P = X C_O X^T`` (``X`` moves the twist's reference
to the task point ``p``). The translational compliance ``C_ff`` (the point's displacement per
force, moments zero, the body free to turn) gives the translational stiffness in the worst
direction ``1 / lambda_max(C_ff)`` [N/m] and its direction; ``C_mm`` the rotational one [N m/rad].

**Natural frequencies** with the actuators locked: ``K_task phi = omega^2 M_task phi`` with
``M_task = G^T M G`` the rigid mechanism's mass matrix in task coordinates (every body's
rigid-body inertia; the elastic members massless), in one of two conventions for the drives'
rotors (``rotors``): **held** (default), the rotor does not move, so its inertia is left out:
the compliance lies between a locked rotor and the joint (a brake, or a position loop much
stiffer than the screw, belt or gearbox that the drive stiffness describes); **moving**, the
rotor moves with its joint through a rigid transmission and the compliance is at the motor (the
servo's holding stiffness), so its reflected inertia ``k^2 I_r`` joins the actuator's row:
``M_task + J_ax^T diag(k^2 I_r) J_ax``. The stiffness ``K_task`` is the same in both; both
frequency sets are kept (``frequencies_rotors_held``, ``frequencies_rotors_moving``). A drive
whose transmission and servo compliances are comparable has a two-mass mode that neither
convention holds.
This is the task coordinates' modes: a compliance that moves the task body outside its task
coordinates (a Delta's platform tilting on elastic rods) adds modes this model leaves out.
A mode ``phi`` (largest component 1) has modal mass ``phi^T M phi`` and modal stiffness
``phi^T K phi = omega^2 phi^T M phi``.

**Deflection under loads** (unit-load method): with the real joint wrenches ``z`` of a motion
(its gravity, inertia, external loads and friction; compatible, so unique by the same energy
where over-constrained), the task body's twist is ``t_i = e_i^T F e_real`` per unit wrench ``i``
and the task coordinates' deflection ``dx = D t``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ...errors import ParameterError, SingularityError
from ...spatial import skew
from ..dynamics.newton_euler import (
    _CutRoute,
    body_wrenches,
    coordinate_twists,
    generalised_forces,
    task_mass_matrix,
)
from ..dynamics.compliance.reactions import compliance_terms
from ..kinematics.inverse import MechanismKinematics, solve_kinematics
from ..model._tree_kernels import euler_angles, euler_rate_map
from ..model.compiler import MechanismModel

__all__ = ["Stiffness", "stiffness", "metric_columns", "deflection", "compliance_sources", "reaction_route", "StiffnessDataMissing",
           "internal_force_stiffness"]

Array = NDArray[np.float64]

#: a task direction whose compliance is below this fraction of the largest is rigid (no source
#: strains it): the task stiffness is then infinite and refused
RIGID = 1e-12
#: the locked structure cannot carry a unit wrench on the task body where the equilibrium
#: residual of the least-squares solve exceeds this (a singularity of the actuated mechanism)
UNBALANCED = 1e-7


class StiffnessDataMissing(ParameterError):
    """A stiffness asked of a mechanism whose compliance data are missing or incomplete."""


@dataclass(frozen=True)
class Stiffness:
    """Stiffness of a mechanism at n poses (module docstring), SI.

    ``x`` (n, nt) the poses; ``K_task`` (n, nt, nt) and ``C_task`` its inverse; ``C_point``
    (n, 6, 6) the task body's compliance at the task point, rows ``[dtheta; dp]`` [rad, m] per
    ``[moment; force]`` [N m, N] (base frame); ``eigenvalues`` (n, nt), ``eigenvectors``
    (n, nt, nt) of ``K_task`` (columns); ``min_stiffness`` (n,) [N/m] and
    ``min_stiffness_direction`` (n, 3); ``min_rot_stiffness`` (n,) [N m/rad] and its
    direction; ``inf`` where the task point cannot translate (turn) at all;
    ``M_task`` (n, nt, nt); ``frequencies`` (n, nt) [Hz] ascending; ``modes`` (n, nt, nt)
    (columns, largest component 1); ``modal_mass``, ``modal_stiffness`` (n, nt), all in the
    rotor convention ``rotors`` (``"held"`` or ``"moving"``); ``frequencies_rotors_held`` and
    ``frequencies_rotors_moving`` (n, nt) [Hz] both conventions' frequencies."""

    x: Array
    K_task: Array
    C_task: Array
    C_point: Array
    eigenvalues: Array
    eigenvectors: Array
    min_stiffness: Array
    min_stiffness_direction: Array
    min_rot_stiffness: Array
    min_rot_stiffness_direction: Array
    M_task: Array
    frequencies: Array
    modes: Array
    modal_mass: Array
    modal_stiffness: Array
    rotors: str
    frequencies_rotors_held: Array
    frequencies_rotors_moving: Array

    def columns(self, model: MechanismModel) -> dict[str, Array]:
        """The columns ``pkmdyn stiffness`` writes for these poses (``grid.csv``; ``results.csv``
        along a motion less its time and deflections), by name: the task coordinates
        ``<name>_<unit>`` and :func:`metric_columns`."""
        cols = {f"{n}_{u}": self.x[:, i] for i, (n, u) in enumerate(zip(model.task_names, model.task_units))}
        cols.update(metric_columns(self.min_stiffness, self.min_rot_stiffness, self.frequencies[:, 0]))
        return cols


def metric_columns(k_trans: Array, k_rot: Array, f_lowest: Array) -> dict[str, Array]:
    """The stiffness metrics' columns of ``pkmdyn stiffness``'s tables, one value per pose:
    ``min_stiffness_N_m`` (``k_trans``) and ``min_rot_stiffness_Nm_rad`` (``k_rot``) where every
    pose has a finite one (infinite where the task point cannot translate, or turn, at all),
    ``lowest_frequency_Hz`` (``f_lowest``)."""
    cols: dict[str, Array] = {}
    if np.all(np.isfinite(k_trans)):
        cols["min_stiffness_N_m"] = np.asarray(k_trans)
    if np.all(np.isfinite(k_rot)):
        cols["min_rot_stiffness_Nm_rad"] = np.asarray(k_rot)
    cols["lowest_frequency_Hz"] = np.asarray(f_lowest)
    return cols


#: the rotor conventions of the natural frequencies (module docstring)
ROTORS = ("held", "moving")


def compliance_sources(model: MechanismModel) -> dict[str, list[str]]:
    """The compliant members by kind: ``bodies`` (section and material), ``drives`` (actuated
    joints with a drive stiffness), ``joints`` (joints with their own springs). Raises
    :class:`StiffnessDataMissing` naming a body with a section and no material or the reverse."""
    bodies = []
    for name, ex in zip(model.body_names, model.body_extra):
        if bool(ex.get("section")) != bool(ex.get("material")):
            have, lack = ("section", "material") if ex.get("section") else ("material", "section")
            raise StiffnessDataMissing(f"body {name!r}: has a {have} but no {lack} (a beam needs both)")
        if ex.get("section"):
            bodies.append(name)
    drives = [model.joint_names[j] for j in model.act_joint
              if model.joint_stiffness[j] and "drive" in model.joint_stiffness[j]]
    joints = [n for n, st in zip(model.joint_names, model.joint_stiffness)
              if st and ("force_N_m" in st or "moment_Nm_rad" in st)]
    return {"bodies": bodies, "drives": drives, "joints": joints}


def reaction_route(model: MechanismModel) -> str:
    """``joint_reactions``' ``overconstrained`` choice for the deflection and the wear of a
    motion: ``"compliance"`` where links or joints are compliant or the mechanism is not
    over-constrained; else ``"minimum-norm"``: with rigid links and joints a self-stress strains
    no compliant member (the drives' efforts are fixed), so those reactions give the same
    deflection (and are what ``pkmdyn run`` writes for such a mechanism)."""
    src = compliance_sources(model)
    return "compliance" if src["bodies"] or src["joints"] or not model.topology.overconstraints else "minimum-norm"


class _Members:
    """The compliant members' forces ``e = E z + e_w`` and flexibility ``F`` (module docstring)
    at n poses: ``E (n, m, 6 nj)``, ``F (n, m, m)`` (block diagonal)."""

    def __init__(self, model: MechanismModel, kin: MechanismKinematics, S: Array) -> None:
        n, nj = len(kin), len(model.joint_names)
        zeroW = np.zeros((n, model.nb, 6))
        G, _, C = compliance_terms(model, kin, zeroW)
        ns = G.shape[1]
        drives = [(a, j, float(model.joint_stiffness[j]["drive"])) for a, j in enumerate(model.act_joint)
                  if model.joint_stiffness[j] and "drive" in model.joint_stiffness[j]]
        m = 6 * ns + len(drives)
        self.E = np.zeros((n, m, 6 * nj))
        self.E[:, :6 * ns] = G.reshape(n, 6 * ns, 6 * nj)
        self.F = np.zeros((n, m, m))
        for s in range(ns):
            self.F[:, 6 * s:6 * s + 6, 6 * s:6 * s + 6] = C[:, s]
        for i, (a, j, k) in enumerate(drives):
            c = int(model.act_coord[a])
            sign = -1.0 if model.joint_flipped[j] else 1.0
            self.E[:, 6 * ns + i, 6 * j:6 * j + 6] = sign * S[:, c]
            self.F[:, 6 * ns + i, 6 * ns + i] = 1.0 / k
        self.ns = ns
        self._model, self._kin = model, kin

    def offset(self, W: Array) -> Array:
        """``e_w (n, m)``: the members' forces from the loads ``W (n, nb, 6)`` on elastic bodies
        (the beam segments' ``w0``; zero for drives and joint springs)."""
        n, m = W.shape[0], self.E.shape[1]
        out = np.zeros((n, m))
        if self.ns and np.any(W):
            _, w0, _ = compliance_terms(self._model, self._kin, W)
            out[:, :6 * self.ns] = w0.reshape(n, -1)
        return out


def _task_map(model: MechanismModel, kin: MechanismKinematics) -> Array:
    """``D (n, nt, 6)``: the task coordinates' small change per small twist ``[dtheta; dp_O]``
    of the task body (module docstring)."""
    n, nt, tb = len(kin), model.nt, model.task_body
    R = kin.R[:, tb]
    p = kin.origin[:, tb] + np.einsum("nij,j->ni", R, model.task_point)
    D = np.zeros((n, nt, 6))
    eye = np.eye(3)
    angles = np.empty(3)
    Om = np.empty((3, 3))
    inv = None
    for r in range(nt):
        i = int(model.task_index[r])
        if model.task_kind[r] == 0:
            D[:, r, :3] = np.cross(p, eye[i])
            D[:, r, 3 + i] = 1.0
            continue
        if inv is None:
            inv = np.empty((n, 3, 3))
            for s in range(n):
                euler_angles(np.ascontiguousarray(R[s]), model.euler_axes, angles)
                euler_rate_map(angles, model.euler_axes, Om)
                inv[s] = np.linalg.inv(Om)
        D[:, r, :3] = inv[:, i]
    return D


def _point_transfer(p: Array) -> Array:
    """``X (n, 6, 6)``: ``[dtheta; dp_P] = X [dtheta; dp_O]`` for the point ``p (n, 3)``."""
    X = np.tile(np.eye(6), (p.shape[0], 1, 1))
    X[:, 3:, :3] = -skew(p)  # dp_P = dp_O + dtheta x p
    return X


def _check_task(model: MechanismModel) -> None:
    """Refuse a task with joint coordinates: the stiffness is the task body's (a wrench on it
    against its small twist), which a joint's coordinate is not a function of."""
    if np.any(model.task_kind == 2):
        names = [n for n, k in zip(model.task_names, model.task_kind) if k == 2]
        raise ParameterError(f"[task] joints: the stiffness is the task body's, and task coordinate {names[0]!r} is a "
                             "joint's; describe the task by a body's position and orientation for the stiffness")


def _check_sources(model: MechanismModel) -> dict[str, list[str]]:
    src = compliance_sources(model)
    if not any(src.values()):
        raise StiffnessDataMissing(
            f"mechanism {model.name!r} has no compliance source: give its drives a stiffness ([[joints]] "
            "stiffness.drive_N_m or drive_Nm_rad), its links a section and a material, or its joints springs "
            "(docs/stiffness.md, \"Compliance sources\")")
    return src


class _Structure:
    """The locked structure at n poses: the unit-wrench solutions ``e_i`` of the members'
    forces (module docstring) and the maps of the task body's twist."""

    def __init__(self, model: MechanismModel, kin: MechanismKinematics, sample_offset: int = 0) -> None:
        n = len(kin)
        S = coordinate_twists(model, kin.q, kin)
        cuts = _CutRoute(model, kin, S, 1e-10)
        K = cuts.A.shape[2]
        members = _Members(model, kin, S)
        self.members = members
        tb = model.task_body
        passive = np.setdiff1d(np.arange(model.nq), model.act_coord)
        Ap = cuts.A[:, passive]  # (n, np, K): the passive coordinates' balance in lambda
        _, Z = cuts.affine(model, np.zeros((n, model.nb, 6)), None)
        B = members.E @ Z  # (n, m, K)
        # the flexibilities scaled to O(1) (the minimiser does not change)
        fscale = max(float(np.abs(members.F).max()), 1e-300)
        Fs = members.F / fscale
        e0 = np.zeros((n, members.E.shape[1], 6))
        rhs = np.zeros((n, passive.size, 6))
        for i in range(6):
            W = np.zeros((n, model.nb, 6))
            W[:, tb, i] = -1.0  # a unit external wrench: the joints must supply its opposite
            z0 = cuts.assemble(model, W, np.zeros((n, K)), None)
            e0[:, :, i] = np.einsum("nmk,nk->nm", members.E, z0) + members.offset(W)
            rhs[:, :, i] = generalised_forces(model, S, W)[:, passive]
        npas = passive.size
        H = np.swapaxes(B, 1, 2) @ Fs @ B
        g = np.swapaxes(B, 1, 2) @ Fs @ e0
        # symmetric equilibration: lambda = Dc mu (each unknown scaled by the larger of its energy's
        # and its equations' size), each equation row by its size, so that members of very
        # different stiffness and wrenches of N and N m meet at O(1) before the least squares
        tiny = 1e-300
        dc = 1.0 / np.maximum(np.maximum(np.sqrt(np.abs(np.einsum("nkk->nk", H))),
                                         np.linalg.norm(Ap, axis=1) if npas else 0.0), tiny)
        Aps = Ap * dc[:, None, :]
        dr = 1.0 / np.maximum(np.linalg.norm(Aps, axis=2), tiny) if npas else np.ones((n, 0))
        Aps = Aps * dr[:, :, None]
        kkt = np.zeros((n, K + npas, K + npas))
        kkt[:, :K, :K] = H * dc[:, :, None] * dc[:, None, :]
        kkt[:, :K, K:] = np.swapaxes(Aps, 1, 2)
        kkt[:, K:, :K] = Aps
        r = np.concatenate([-g * dc[:, :, None], rhs * dr[:, :, None]], axis=1)
        sol = np.linalg.pinv(kkt, rcond=1e-12, hermitian=True) @ r if K + npas else np.zeros((n, 0, 6))
        lam = sol[:, :K] * dc[:, :, None]
        res = np.abs(Ap @ lam - rhs).max(axis=(1, 2)) if npas else np.zeros(n)
        size = np.maximum(np.abs(rhs).max(axis=(1, 2)) if npas else 0.0, 1.0)
        bad = np.flatnonzero(res > UNBALANCED * size * max(1.0, model.length_scale))
        if bad.size:
            s = int(bad[0])
            pose = ", ".join(f"{nm} = {v + 0.0:.6g} {u}" for nm, u, v in zip(model.task_names, model.task_units, kin.x[s]))
            raise SingularityError(f"sample {s + sample_offset}: with its actuators locked the mechanism cannot carry "
                                   f"a load on task body {model.body_names[tb]!r} (a singularity of the actuated "
                                   f"mechanism, infinite compliance; task pose {pose})")
        self.e = e0 + B @ lam  # (n, m, 6): members' forces per unit wrench [n_O; f]
        self.C_O = np.swapaxes(self.e, 1, 2) @ members.F @ self.e
        self.C_O = 0.5 * (self.C_O + np.swapaxes(self.C_O, 1, 2))
        self.D = _task_map(model, kin)
        R = kin.R[:, tb]
        self.point = kin.origin[:, tb] + np.einsum("nij,j->ni", R, model.task_point)


def _worst(C: Array, scale: Array) -> tuple[Array, Array]:
    """Stiffness in the worst direction ``1 / lambda_max(C)`` and that direction, for compliance
    blocks ``C (n, 3, 3)``; inf where ``lambda_max`` is below :data:`RIGID` times ``scale (n,)``
    (rounding: nothing strains these directions)."""
    lam, vec = np.linalg.eigh(C)
    top = lam[:, -1]
    k = np.full(top.shape, np.inf)
    ok = top > RIGID * scale
    k[ok] = 1.0 / top[ok]
    d = vec[:, :, -1]
    d = d * np.where(d[np.arange(len(d)), np.abs(d).argmax(axis=1)] < 0, -1.0, 1.0)[:, None]
    return k, d


def stiffness(model: MechanismModel, kin: MechanismKinematics, sample_offset: int = 0,
              rotors: str = "held") -> Stiffness:
    """The stiffness, worst directions and natural frequencies of the mechanism with its
    actuators locked at the poses of ``kin`` (module docstring), the modes with the drives'
    rotors ``"held"`` or ``"moving"``.

    Raises :class:`StiffnessDataMissing` when no compliance source exists or one task
    coordinate is strained by none (its stiffness would be infinite), and
    :class:`~pkmdyn.errors.SingularityError` naming the sample where the locked mechanism
    cannot carry a load on the task body or its mass matrix is singular."""
    if rotors not in ROTORS:
        raise ParameterError(f"rotors: {rotors!r} is not one of {', '.join(ROTORS)}")
    _check_task(model)
    _check_sources(model)
    st = _Structure(model, kin, sample_offset)
    nt = model.nt
    C_task = st.D @ st.C_O @ np.swapaxes(st.D, 1, 2)
    C_task = 0.5 * (C_task + np.swapaxes(C_task, 1, 2))
    # a task direction no member strains: its stiffness is infinite (the diagonal compared per
    # sample in one unit, an angle's compliance times the length scale squared; then the
    # correlation matrix's smallest singular value, whose vector names the coordinate)
    unit = np.array([1.0 if u == "m" else model.length_scale for u in model.task_units])
    cs = np.sqrt(np.maximum(np.einsum("nii->ni", C_task), 0.0)) * unit
    _, sv, vt = np.linalg.svd(C_task / np.maximum(cs[:, :, None] * cs[:, None, :], 1e-300) * unit[:, None] * unit
                              if nt else C_task)
    zero = cs.min(axis=1) <= RIGID * np.maximum(cs.max(axis=1), 1e-300)
    lo = zero | (sv[:, -1] <= RIGID)
    if np.any(lo):
        s = int(np.flatnonzero(lo)[0])
        r = int(np.argmin(cs[s])) if zero[s] else int(np.argmax(np.abs(vt[s, -1])))
        raise StiffnessDataMissing(f"sample {s + sample_offset}: no compliance source strains task coordinate "
                                   f"{model.task_names[r]!r} (its stiffness would be infinite): give the drives a "
                                   "stiffness, the links a section and a material, or the joints springs")
    K_task = np.linalg.inv(C_task)
    K_task = 0.5 * (K_task + np.swapaxes(K_task, 1, 2))
    ev, evec = np.linalg.eigh(K_task)
    X = _point_transfer(st.point)
    C_point = X @ st.C_O @ np.swapaxes(X, 1, 2)
    # the blocks compared in one unit (rotational compliance times the length scale squared)
    L2 = model.length_scale ** 2
    scale = np.maximum(np.linalg.eigvalsh(C_point[:, 3:, 3:])[:, -1], np.linalg.eigvalsh(C_point[:, :3, :3])[:, -1] * L2)
    k_t, d_t = _worst(C_point[:, 3:, 3:], scale)
    k_r, d_r = _worst(C_point[:, :3, :3], scale / L2)
    S = coordinate_twists(model, kin.q, kin)
    M_held = task_mass_matrix(model, kin, S, rotors=False)
    M_moving = task_mass_matrix(model, kin, S, rotors=True) if np.any(model.drive_rotor) else M_held
    both = {"held": _modes(model, M_held, K_task, sample_offset)}
    both["moving"] = _modes(model, M_moving, K_task, sample_offset) if M_moving is not M_held else both["held"]
    freq, modes, mm, mk = both[rotors]
    return Stiffness(x=kin.x.copy(), K_task=K_task, C_task=C_task, C_point=C_point, eigenvalues=ev,
                     eigenvectors=evec, min_stiffness=k_t, min_stiffness_direction=d_t, min_rot_stiffness=k_r,
                     min_rot_stiffness_direction=d_r, M_task=M_held if rotors == "held" else M_moving,
                     frequencies=freq, modes=modes, modal_mass=mm, modal_stiffness=mk, rotors=rotors,
                     frequencies_rotors_held=both["held"][0], frequencies_rotors_moving=both["moving"][0])


def _modes(model: MechanismModel, M: Array, K: Array, sample_offset: int) -> tuple[Array, Array, Array, Array]:
    """``K phi = omega^2 M phi`` by Cholesky of ``M``: frequencies [Hz] ascending, modes
    (largest component 1), modal masses and stiffnesses."""
    try:
        L = np.linalg.cholesky(M)
    except np.linalg.LinAlgError:
        bad = [s for s in range(M.shape[0]) if np.linalg.eigvalsh(M[s])[0] <= 0]
        raise SingularityError(f"sample {(bad[0] if bad else 0) + sample_offset}: the mass matrix in task coordinates "
                               "is singular (a task coordinate moves no mass): no natural frequencies") from None
    Li = np.linalg.inv(L)
    A = Li @ K @ np.swapaxes(Li, 1, 2)
    w2, y = np.linalg.eigh(0.5 * (A + np.swapaxes(A, 1, 2)))
    phi = np.swapaxes(Li, 1, 2) @ y
    big = np.take_along_axis(phi, np.abs(phi).argmax(axis=1)[:, None, :], axis=1)
    phi = phi / big
    mm = np.einsum("nim,nij,njm->nm", phi, M, phi)
    mk = np.einsum("nim,nij,njm->nm", phi, K, phi)
    freq = np.sqrt(np.maximum(w2, 0.0)) / (2.0 * np.pi)
    return freq, phi, mm, mk


def deflection(model: MechanismModel, kin: MechanismKinematics, reactions: object, loads: dict | None = None,
               named: dict | None = None, sample_offset: int = 0) -> Array:
    """The task coordinates' elastic deflection ``dx (n, nt)`` [m, rad] under the motion's own
    loads (unit-load method, module docstring): ``reactions`` the motion's
    :class:`~pkmdyn.multibody.dynamics.newton_euler.JointReactions` (every joint's wrench), ``loads``/``named`` as for
    :func:`pkmdyn.multibody.dynamics.newton_euler.body_wrenches` (the same as the reactions were computed with)."""
    _check_task(model)
    _check_sources(model)
    st = _Structure(model, kin, sample_offset)
    n = len(kin)
    f = np.asarray(reactions.joint_force)
    m = np.asarray(reactions.joint_moment)
    nO = m + np.cross(np.asarray(reactions.joint_point), f)
    z = np.concatenate([nO, f], axis=2).reshape(n, -1)
    W = body_wrenches(model, kin, loads, named)
    e_real = np.einsum("nmk,nk->nm", st.members.E, z) + st.members.offset(W)
    t = np.einsum("nmi,nmp,np->ni", st.e, st.members.F, e_real)  # the task body's twist [dtheta; dp_O]
    return np.einsum("nti,ni->nt", st.D, t)


def internal_force_stiffness(model: MechanismModel, x: Array, u: Array, step: float = 1e-5) -> Array:
    """The task stiffness ``K_u (n, nt, nt)`` that actuator efforts ``u (n, na)`` held fixed add
    at task poses ``x (n, nt)``: ``K_u = -d(J_ax^T u)/dx``, Eq. (S-U) of ``docs/stiffness.md``
    (symmetric: ``-sum_a u_a d^2 q_a / dx^2``, the Hessians of the actuated coordinates), by
    central differences of the actuator map over the inverse kinematics (step ``step`` rad, or
    times the length scale in m). For a redundantly actuated mechanism's internal force (a
    preload) it is the antagonistic stiffness the preload adds with the drives holding their
    efforts; the actuators locked, as :func:`stiffness` takes them, it adds nothing.
    Units: N/m, N/rad, N m/m, N m/rad as ``K_task``."""
    x = np.atleast_2d(np.asarray(x, dtype=float))
    u = np.atleast_2d(np.asarray(u, dtype=float))
    n, nt = x.shape
    h = step * np.where(model.task_length, model.length_scale, 1.0)
    K = np.empty((n, nt, nt))
    z = np.zeros_like(x)
    for j in range(nt):
        e = np.zeros(nt)
        e[j] = h[j]
        plus = solve_kinematics(model, x + e, z, z).J_ax  # (n, na, nt)
        minus = solve_kinematics(model, x - e, z, z).J_ax
        K[:, :, j] = -np.einsum("nat,na->nt", plus - minus, u) / (2 * h[j])
    return K
