"""Joint friction of described mechanisms: Coulomb, viscous and load-dependent (from the
joint's own reaction), in the free directions of every joint, tree or cut.

Relative motion of joint j (child relative to parent): the twist ``V_rel = V_c - V_p``
(Plücker at the base origin, :mod:`pkmdyn.multibody.dynamics.newton_euler`), with ``V_rel = T r`` in the joint's free
twists ``T (f, 6)`` (:func:`pkmdyn.multibody.dynamics.newton_euler.free_twists`), ``r = T^+ V_rel`` its free rates (for a
tree joint, its coordinate rates). The relative angular velocity is ``w = V_rel[:3]``, the
relative velocity of the child's point at the joint centre ``p`` is ``v = V_rel[3:] + w x p``.

Resisting torque and force (base frame), with ``f`` the reaction force the joint carries
(``joint_force``) and ``a`` its rotation axis (revolute, cylindrical: the joint frame's z):

    tau = (C_t + mu (r_pin |f - (f.a) a| + r_ball |f| + r_mean |f.a|)) u(w) + b_t w      (F1)
    phi = (C_f + mu_s |f - (f.e) e|) u(v) + b_f v                                         (F2)

A named external load adds to the Coulomb parts (``external``, the form of Eq. 16 of Chen, Cheng & Pang
2022: a prosthesis joint and a thrust bearing loaded by the test force): ``C_t += sum mu_k r_k |F_k + o_k|``
for a joint that rotates, ``C_f += sum mu_k |F_k + o_k|`` for one that only slides, with
``F_k`` [N] the named load's magnitude at the sample and ``o_k = offset_N``.

``C_t = coulomb_torque_Nm``, ``b_t = viscous_Nm_s_rad``, ``C_f = coulomb_force_N``,
``b_f = viscous_N_s_m``, ``mu = coefficient`` with ``r_pin = pin_radius_m`` (a journal: the
radial force on the pin), ``r_ball = ball_radius_m`` (a ball joint: the whole force),
``r_mean = mean_radius_m`` (a thrust face: the axial force); ``mu_s = coefficient`` for a
joint that slides and gives no radius (a prismatic guide: the force normal to its axis ``e``).
``u(x) = x / sqrt(|x|^2 + eps^2)`` is the regularised sign of :func:`pkmdyn.multibody.dynamics.friction.regularised_sign`
(``eps`` = :data:`EPS_ROTATION` rad/s, :data:`EPS_TRANSLATION` m/s), a vector law for a joint
with several rotations (the form of Chen, Cheng & Pang 2022, Eq. 16). The generalised resisting forces along
the free twists are ``F_i = T_i . [tau + p x phi; phi]`` (their power ``F . r`` is the
dissipation, >= 0), mapped to the tree coordinates by ``Q_f = B^T F`` with ``r = B qd``.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import NDArray

from ..description.joint_types import JOINT_TYPES
from ..model.compiler import MechanismModel
from ._dyn_kernels import friction_batch
from .loads import named_magnitudes

__all__ = ["JointFriction", "known_friction", "friction_diverges", "regularised_sign", "coulomb_viscous", "EPS_ROTATION",
           "EPS_TRANSLATION"]

Array = NDArray[np.float64]

#: regularisation of the sign at rest [rad/s] and [m/s]
EPS_ROTATION = 1e-3
EPS_TRANSLATION = 1e-4


def regularised_sign(w: Array, eps: float, vector: bool) -> Array:
    """``u(w) = w / sqrt(|w|^2 + eps^2)``: the sign (or unit direction) made smooth at rest.

    ``vector=True``: ``w (..., 3)`` is an angular velocity and the norm is taken over the last
    axis; otherwise ``w`` holds scalar velocities. ``|u| < 1`` always, and ``u(0) = 0``.
    """
    w = np.asarray(w, dtype=float)
    norm2 = np.sum(w * w, axis=-1, keepdims=True) if vector else w * w
    return w / np.sqrt(norm2 + eps * eps)


def coulomb_viscous(w: Array, coulomb: float, viscous: float, eps: float, vector: bool) -> Array:
    """Coulomb plus viscous friction ``coulomb * u(w) + viscous * w`` (spec, "Loads and friction").

    ``vector=True`` treats the last axis of ``w`` as a 3-vector (relative angular velocity of
    a joint); otherwise ``w`` holds scalar velocities.
    """
    w = np.asarray(w, dtype=float)
    return coulomb * regularised_sign(w, eps, vector) + viscous * w


def friction_diverges(history: list[float]) -> bool:
    """Whether the fixed point's relative changes grow: four successive increases, or a change
    above 1e6 (the friction feeds the reactions faster than it settles)."""
    if history and (history[-1] > 1e6 or not np.isfinite(history[-1])):
        return True
    return len(history) >= 5 and all(history[-k] > history[-k - 1] for k in range(1, 5))


class JointFriction:
    """The friction of every joint with friction data along one motion (module docstring)."""

    def __init__(self, model: MechanismModel, kin, S: Array, blocks: list,
                 named: Mapping[str, object] | None = None) -> None:
        self.model = model
        n = S.shape[0]
        mags = named_magnitudes(model, n, named) if model.named_loads else {}
        self.joints = []
        for j, T, coords in blocks:
            data = model.joint_friction[j]
            if data is None or not any(v for v in data.values()):
                continue
            if coords[0] >= 0:
                # a tree joint: its free twists are +-S_c, its free rates the coordinate rates
                r = kin.qd[:, coords]
                B = None
            else:
                c, p = model.joint_child[j], model.joint_parent[j]
                # V_rel = sum_c s_c S_c qd_c (s_c = +1 moves the child only, -1 the parent only)
                sgn = (model.ancestors[c].astype(float) if c >= 0 else 0.0) - \
                    (model.ancestors[p].astype(float) if p >= 0 else 0.0)
                idx = np.flatnonzero(sgn)
                TJ = np.einsum("nfk,nck->nfc", T, S[:, idx]) * sgn[idx]
                # V_rel = T^T r: r = (T T^T)^-1 T V_rel (the free twists are independent)
                gram = np.einsum("nfk,ngk->nfg", T, T)
                Bi = np.linalg.solve(gram, TJ)
                B = np.zeros((n, T.shape[1], model.nq))
                B[:, :, idx] = Bi
                r = np.einsum("nfc,nc->nf", Bi, kin.qd[:, idx])
            rot = np.abs(T[:, :, :3]).max(axis=(0, 2)) > 0.5
            axis = T[:, int(np.flatnonzero(rot)[0]), :3] if rot.sum() == 1 else None
            slide = np.flatnonzero(~rot)
            e = T[:, int(slide[0]), 3:] if len(slide) == 1 else None
            pt = kin.joint_point[:, j]
            w = np.einsum("nfk,nf->nk", T[:, :, :3], r)
            v = np.einsum("nfk,nf->nk", T[:, :, 3:], r) + np.cross(w, pt)
            ext = np.zeros(n)  # the named loads' Coulomb part [N m or N]
            for term in data.get("external", []):
                ext = ext + term["coefficient"] * (term["radius_m"] or 1.0) * np.abs(mags[term["load"]] + term["offset_N"])
            self.joints.append(dict(j=j, T=T, r=r, B=B, coords=coords, axis=axis, e=e, pt=pt, w=w, v=v, d=data,
                                    ext=ext, has_rot=bool(rot.any()), has_slide=bool((~rot).any())))

    def _forces_one(self, jd: dict, f: Array) -> Array:
        d = jd["d"]
        n = f.shape[0]
        mu = d.get("coefficient", 0.0)
        tau = np.zeros((n, 3))
        phi = np.zeros((n, 3))
        if jd["has_rot"]:
            mag = np.full(n, d.get("coulomb_torque_Nm", 0.0)) + jd["ext"]
            if mu:
                a = jd["axis"]
                if a is not None:
                    fa = np.einsum("ni,ni->n", f, a)
                    mag = mag + mu * d.get("pin_radius_m", 0.0) * np.linalg.norm(f - fa[:, None] * a, axis=1)
                    mag = mag + mu * d.get("mean_radius_m", 0.0) * np.abs(fa)
                mag = mag + mu * d.get("ball_radius_m", 0.0) * np.linalg.norm(f, axis=1)
            tau = mag[:, None] * regularised_sign(jd["w"], EPS_ROTATION, True) + d.get("viscous_Nm_s_rad", 0.0) * jd["w"]
        if jd["has_slide"]:
            mag = np.full(n, d.get("coulomb_force_N", 0.0)) + (0.0 if jd["has_rot"] else jd["ext"])
            radii = d.get("pin_radius_m", 0.0) or d.get("ball_radius_m", 0.0) or d.get("mean_radius_m", 0.0)
            if mu and not radii and jd["e"] is not None:
                e = jd["e"]
                fe = np.einsum("ni,ni->n", f, e)
                mag = mag + mu * np.linalg.norm(f - fe[:, None] * e, axis=1)
            phi = mag[:, None] * regularised_sign(jd["v"], EPS_TRANSLATION, True) + d.get("viscous_N_s_m", 0.0) * jd["v"]
        Wf = np.concatenate([tau + np.cross(jd["pt"], phi), phi], axis=1)
        return np.einsum("nfk,nk->nf", jd["T"], Wf)

    def initial(self) -> dict:
        """Friction with zero reactions (the load-independent part)."""
        n = self.joints[0]["r"].shape[0] if self.joints else 0
        return {jd["j"]: self._forces_one(jd, np.zeros((n, 3))) for jd in self.joints}

    def forces(self, Wj: Array) -> dict:
        """Generalised resisting forces ``{joint: (n, f)}`` from joint wrenches ``Wj (n, nj, 6)``."""
        return {jd["j"]: self._forces_one(jd, Wj[:, jd["j"], 3:]) for jd in self.joints}

    def generalised(self, F: dict) -> Array:
        """``Q_f (n, nq)`` = sum over joints of ``B^T F``."""
        n = next(iter(F.values())).shape[0] if F else 0
        Q = np.zeros((n, self.model.nq))
        for jd in self.joints:
            self.add_generalised(Q, jd, F[jd["j"]])
        return Q

    @staticmethod
    def add_generalised(Q: Array, jd: dict, F: Array) -> None:
        """``Q += B^T F`` for one joint's resisting forces ``F (n, f)``."""
        if jd["B"] is None:  # a tree joint: r = qd of its coordinates
            Q[:, jd["coords"]] += F
        else:
            Q += np.einsum("nfc,nf->nc", jd["B"], F)

    def dissipation(self, F: dict) -> Array:
        """Power dissipated by friction (n,) [W] = sum over joints of ``F . r``."""
        n = next(iter(F.values())).shape[0] if F else 0
        out = np.zeros(n)
        for jd in self.joints:
            out += np.einsum("nf,nf->n", F[jd["j"]], jd["r"])
        return out

    def change(self, old: dict, new: dict) -> tuple[float, int, int]:
        """Largest change between two friction sets, its joint and sample."""
        best, bj, bs = 0.0, -1, 0
        for j in new:
            d = np.abs(new[j] - old[j]).max(axis=1) if new[j].size else np.zeros(1)
            s = int(np.argmax(d))
            if d[s] >= best:
                best, bj, bs = float(d[s]), j, s
        return best, bj, bs

    def scale(self, F: dict) -> float:
        return max((float(np.abs(v).max()) for v in F.values() if v.size), default=0.0)


def friction_arrays(model: MechanismModel) -> dict[str, np.ndarray]:
    """The compiled friction's per-joint arrays (joints with Coulomb, viscous or named-load
    friction and no reaction-dependent part): ``fj`` joints, ``fch``/``fpa`` child and parent,
    ``frot``/``fslide`` whether the joint rotates / slides, ``coef (k, 4) = (C_t, b_t, C_f,
    b_f)``, ``fidx (k, nq)``/``fsc``/``fcnt`` the coordinates moving the child but not the parent
    (+1) or the reverse (-1), and per named-load term ``ecoef (k, E) = mu r``
    (``mu`` for a sliding joint), ``eoff`` the offset [N], ``eload`` the named load's index
    (-1 unused). A ``coefficient`` (reaction-dependent) is a ``ValueError``."""
    rows = []
    for j, d in enumerate(model.joint_friction):
        if not d or not any(v for v in d.values()):
            continue
        if d.get("coefficient", 0.0):
            raise ValueError(f"joint {model.joint_names[j]}: reaction-dependent friction")
        jt = JOINT_TYPES[model.joint_type[j]]
        if jt.freedoms:
            rows.append((j, jt, d))
    k, nq = len(rows), model.nq
    E = max([1] + [len(d.get("external", [])) for _, _, d in rows])
    out = {"fj": np.zeros(k, dtype=np.int64), "fch": np.zeros(k, dtype=np.int64), "fpa": np.zeros(k, dtype=np.int64),
           "frot": np.zeros(k, dtype=np.int64), "fslide": np.zeros(k, dtype=np.int64), "coef": np.zeros((k, 4)),
           "fidx": np.zeros((k, nq), dtype=np.int64), "fsc": np.zeros((k, nq)), "fcnt": np.zeros(k, dtype=np.int64),
           "ecoef": np.zeros((k, E)), "eoff": np.zeros((k, E)), "eload": np.full((k, E), -1, dtype=np.int64)}
    for i, (j, jt, d) in enumerate(rows):
        ch, pa = model.joint_child[j], model.joint_parent[j]
        out["fj"][i], out["fch"][i], out["fpa"][i] = j, ch, pa
        out["frot"][i] = any(mn[0] == "R" for mn in jt.motions)
        out["fslide"][i] = any(mn[0] == "T" for mn in jt.motions)
        out["coef"][i] = [d.get("coulomb_torque_Nm", 0.0), d.get("viscous_Nm_s_rad", 0.0),
                          d.get("coulomb_force_N", 0.0), d.get("viscous_N_s_m", 0.0)]
        sc = (model.ancestors[ch].astype(float) if ch >= 0 else np.zeros(nq)) - \
            (model.ancestors[pa].astype(float) if pa >= 0 else np.zeros(nq))
        idx = np.flatnonzero(sc)
        out["fcnt"][i] = idx.size
        out["fidx"][i, :idx.size] = idx
        out["fsc"][i, :idx.size] = sc[idx]
        for t, term in enumerate(d.get("external", [])):
            out["ecoef"][i, t] = term["coefficient"] * (term["radius_m"] or 1.0)
            out["eoff"][i, t] = term["offset_N"]
            out["eload"][i, t] = model.named_loads.index(term["load"])
    return out


def known_friction(model: MechanismModel, kin, S: Array, named: Mapping[str, object] | None = None) -> Array:
    """Generalised forces ``Q_f (n, nq)`` of the friction that does not depend on the joints'
    reactions (Coulomb, viscous and the named loads' part of laws F1-F2), compiled
    (:func:`pkmdyn.multibody.dynamics._dyn_kernels.friction_batch`, the virtual power of each joint's resisting wrench
    in its relative twist). Equal to ``JointFriction(...).generalised(initial())`` for tree
    joints; for cut joints up to constraint forces, so that the efforts (``G^T Q``) are the
    same. A ``coefficient`` (reaction-dependent) is a ``ValueError``."""
    n = S.shape[0]
    fa = friction_arrays(model)
    Q = np.zeros((n, model.nq))
    if not fa["fj"].size:
        return Q
    mags = named_magnitudes(model, n, named) if model.named_loads else {}
    F = np.stack([mags[nm] for nm in model.named_loads], axis=1) if model.named_loads else np.zeros((n, 0))
    ext = np.zeros((n, fa["fj"].size))
    for t in range(fa["eload"].shape[1]):
        use = fa["eload"][:, t] >= 0
        if use.any():
            ext[:, use] += fa["ecoef"][use, t] * np.abs(F[:, fa["eload"][use, t]] + fa["eoff"][use, t])
    friction_batch(np.ascontiguousarray(kin.w), np.ascontiguousarray(kin.origin_v), np.ascontiguousarray(kin.origin),
                   np.ascontiguousarray(kin.joint_point), np.ascontiguousarray(S), fa["fsc"], fa["fidx"], fa["fcnt"],
                   fa["fj"], fa["fch"], fa["fpa"], fa["frot"].astype(np.bool_), fa["fslide"].astype(np.bool_),
                   fa["coef"], ext, EPS_ROTATION, EPS_TRANSLATION, Q)
    return Q
