"""The hip simulator's identification: the engine's identification of its description, named
and written in the hip's parameters.

The fit is the engine's (:func:`pkmdyn.multibody.analyses.regressor.regressor` of the description of
:func:`.description.hip_description`, through :func:`pkmdyn.identify._identify.fit_regressor`);
this module names its result in the parameters of the hip's parameter file and writes it
back there.

Parameters (name with unit, what it is)
  friction: ``bearing_load_coeff_m`` and ``bearing_weight_friction_Nm`` (Eq. 16, see below),
  and the Coulomb/viscous coefficients of the sliders, screws, S joints and U joints.
  inertia: ``slider_mass_kg`` (m_L), ``screw_inertia_kgm2`` (I_L), ``lever_mass_kg`` (m_l), the
  lever's and the platform's principal inertias ``..._I{x,y,z}_kgm2``.

Each is a linear map of the engine's parameters (:func:`engine_values`): the engine's body
parameters (mass, first moments, inertia about the body frame's origin) are linear in the
hip's masses and principal inertias at the file's geometry (the centres of mass and principal
axes fixed); a slider is one body of twice the carriage's mass and friction; the screws'
friction and rotor inertia are the drives' motor parameters; every S and U joint has the
family's coefficient. What the hip does not identify (the platform mass, the geometry, the
sliders' rotational inertia, which a slider that never turns does not show) is held at the
file's value and goes into the regressor's offset, ``u = (Y_e A) theta + (Y_e b + u_0)`` with
``theta_e = A theta + b``.

Linearisation of the products. Eq. (16) gives each platform the friction torque magnitude
``r_h mu_h F + r_t mu_t |F + m_m g|``. Since ``F >= 0`` and ``m_m >= 0`` this is exactly

    S F + C,   S = r_h mu_h + r_t mu_t  (bearing_load_coeff_m),   C = r_t mu_t m_m g  (bearing_weight_friction_Nm),

linear in ``S`` and ``C``. In the engine these are the load-driven friction terms
(``friction.external``) of the platforms' centre joints ``S0_upper`` and ``S0_lower``; the
regressor's description gives each two terms of unit radius driven by the hydraulic load,
offsets 0 and :data:`F_REF`, whose columns are ``F u(w)`` and ``(F + F_REF) u(w)``: ``S`` is
the first coefficient plus the second, ``C`` is ``F_REF`` times the second. Radii and
coefficients enter only through these products, and the platform mass enters the torques
nowhere else (its centre of mass is the fixed hip centre), so ``S`` and ``C`` are all that
torques can tell: the hip-joint and thrust-bearing coefficients are separable only given the
platform mass (``r_t mu_t = C / (m_m g)``). Writing the file, ``S`` and ``C`` are split back
by :func:`bearing_split`.

Physical consistency. Friction coefficients ``>= 0``; masses and the screw inertia ``> 0``
(lower bound 1e-9 of the unit); principal inertias satisfy the triangle inequality
``I_x + I_y >= I_z`` (and cyclic), imposed exactly by solving for the second moments of mass
``(s_x, s_y, s_z) >= 0`` with ``I_x = s_y + s_z, I_y = s_x + s_z, I_z = s_x + s_y``.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, replace
from pathlib import Path
from types import SimpleNamespace
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from ...errors import MotionError, ParameterError
from ...identify._base import DEFAULT_RANK_TOL, BaseParameters
from ...identify._identify import check_efforts, fit_regressor
from ...identify._regressor import Regressor
from ...identify._solve import Estimate
from ...io import read_csv_columns
from ...multibody import load_mechanism, solve_kinematics
from ...multibody.analyses.regressor import BODY_PARAMETERS, inertial_parameters, regressor
from ...profiles._columns import savgol_derivatives
from ...profiles.orientation import MOTION_COLUMNS, OrientationMotion, make_motion
from .description import hip_description
from .paper import PaperView
from .params import HipModel, model_from_dict

__all__ = [
    "FRICTION_NAMES",
    "INERTIA_NAMES",
    "TORQUE_COLUMNS",
    "FRICTION_ATTR",
    "F_REF",
    "Which",
    "parameter_names",
    "parameter_vector",
    "with_parameters",
    "bearing_split",
    "regressor_mechanism",
    "engine_values",
    "engine_kinematics",
    "hip_regressor",
    "consistency_transform",
    "HipIdentification",
    "identify_hip",
    "identified_description",
    "read_measured_csv",
    "savgol_derivatives",
    "engine_torques",
]

Array = NDArray[np.float64]
Which = Literal["friction", "inertia", "all"]

TORQUE_COLUMNS = ("tau1_Nm", "tau2_Nm", "tau3_Nm")

#: (parameter name, [friction] key it writes)
_FRICTION = (
    ("bearing_load_coeff_m", "hip_coefficient"),
    ("bearing_weight_friction_Nm", "thrust_coefficient"),
    ("slider_coulomb_N", "slider_coulomb_N"),
    ("slider_viscous_Ns_m", "slider_viscous_Ns_m"),
    ("screw_coulomb_Nm", "screw_coulomb_Nm"),
    ("screw_viscous_Nms_rad", "screw_viscous_Nms_rad"),
    ("spherical_coulomb_Nm", "spherical_coulomb_Nm"),
    ("spherical_viscous_Nms_rad", "spherical_viscous_Nms_rad"),
    ("universal_coulomb_Nm", "universal_coulomb_Nm"),
    ("universal_viscous_Nms_rad", "universal_viscous_Nms_rad"),
)
FRICTION_NAMES = tuple(n for n, _ in _FRICTION)
INERTIA_NAMES = (
    "slider_mass_kg",
    "screw_inertia_kgm2",
    "lever_mass_kg",
    "lever_Ix_kgm2",
    "lever_Iy_kgm2",
    "lever_Iz_kgm2",
    "platform_Ix_kgm2",
    "platform_Iy_kgm2",
    "platform_Iz_kgm2",
)
ALL_NAMES = INERTIA_NAMES + FRICTION_NAMES
_FIELD = {n: k for n, k in _FRICTION[2:]}
#: friction keys of the parameter file -> fields of :class:`HipFriction` (the optional families)
FRICTION_ATTR = {
    "slider_coulomb_N": "slider_coulomb",
    "slider_viscous_Ns_m": "slider_viscous",
    "screw_coulomb_Nm": "screw_coulomb",
    "screw_viscous_Nms_rad": "screw_viscous",
    "spherical_coulomb_Nm": "spherical_coulomb",
    "spherical_viscous_Nms_rad": "spherical_viscous",
    "universal_coulomb_Nm": "universal_coulomb",
    "universal_viscous_Nms_rad": "universal_viscous",
}
_POSITIVE_FLOOR = 1e-9
#: offset [N] of the second load-driven friction term of the regressor's description (module docstring)
F_REF = 1000.0
_LOAD = "hydraulic_N"
_CENTRES = ("S0_upper", "S0_lower")


def parameter_names(which: Which) -> tuple[str, ...]:
    """The parameters identified for ``which`` = ``friction``, ``inertia`` or ``all``."""
    if which == "friction":
        return FRICTION_NAMES
    if which == "inertia":
        return INERTIA_NAMES
    if which == "all":
        return INERTIA_NAMES + FRICTION_NAMES
    raise ParameterError(f"identify: expected friction, inertia or all, got {which!r}")


def parameter_vector(model: HipModel, names: tuple[str, ...]) -> Array:
    """The model's values of ``names`` (units as in the names)."""
    f, m = model.friction, model.inertia
    value = {
        "bearing_load_coeff_m": f.r_h * f.mu_h + f.r_t * f.mu_t,
        "bearing_weight_friction_Nm": f.r_t * f.mu_t * m.m_m * m.g,
        "slider_mass_kg": m.m_L,
        "screw_inertia_kgm2": m.I_L,
        "lever_mass_kg": m.m_l,
    }
    value.update({n: getattr(f, a) for n, a in FRICTION_ATTR.items()})
    value.update({f"lever_I{x}_kgm2": m.I_l[k] for k, x in enumerate("xyz")})
    value.update({f"platform_I{x}_kgm2": m.I_m[k] for k, x in enumerate("xyz")})
    return np.array([value[n] for n in names], dtype=float)


def bearing_split(model: HipModel, S: float, C: float) -> tuple[float, float, float]:
    """Hip-joint and thrust-bearing coefficients and platform mass ``(mu_h, mu_t, m_m)`` with
    ``r_h mu_h + r_t mu_t = S`` and ``r_t mu_t m_m g = C`` (radii and gravity from ``model``).

    With ``C = 0`` the file's platform mass is kept, and with it zero the file's hip/thrust
    share of ``S``. The file's platform mass is kept when it can be (``m_m > 0`` and ``C / (m_m g) <= S``);
    otherwise the model's share of the thrust bearing in ``S`` is kept (all of ``S`` when that
    share is zero) and the platform mass follows. Raises :class:`ParameterError` where no
    admissible split exists (a radius or gravity of zero that the values need).
    """
    f, m = model.friction, model.inertia
    a0, b0 = f.r_h * f.mu_h, f.r_t * f.mu_t
    if C > 0 and not (m.g > 0 and S > 0):
        raise ParameterError(
            f"bearing_weight_friction_Nm = {C:.6g} N m needs gravity > 0 and bearing_load_coeff_m > 0 to be "
            "written as thrust-bearing friction of the platform weight"
        )
    share = b0 / (a0 + b0) if a0 + b0 > 0 else 0.0
    if C <= 0:
        b = 0.0 if m.m_m > 0 else S * share  # with m_m = 0 any split fits: keep the file's
        a, m_m = S - b, m.m_m
    elif m.m_m > 0 and C / (m.m_m * m.g) <= S:
        b = C / (m.m_m * m.g)
        a, m_m = S - b, m.m_m
    else:
        b = S * (share if share > 0 else 1.0)
        a, m_m = S - b, C / (b * m.g)
    for value, radius, key in ((a, f.r_h, "hip_radius_m"), (b, f.r_t, "thrust_radius_m")):
        if value > 0 and not radius > 0:
            raise ParameterError(f"[friction] {key} is 0 in the parameter file; the identified friction needs it > 0")
    return (a / f.r_h if a > 0 else 0.0), (b / f.r_t if b > 0 else 0.0), m_m


def _set_values(model: HipModel, values: dict[str, float]) -> HipModel:
    """``model`` with the inertia and joint-friction families of ``values`` (no bearing friction,
    no validation: zeros are allowed)."""
    f, m = model.friction, model.inertia
    fr: dict[str, Any] = {a: values[n] for n, a in FRICTION_ATTR.items() if n in values}
    inr: dict[str, Any] = {}
    for name, attr in (("slider_mass_kg", "m_L"), ("screw_inertia_kgm2", "I_L"), ("lever_mass_kg", "m_l")):
        if name in values:
            inr[attr] = values[name]
    for body, attr in (("lever", "I_l"), ("platform", "I_m")):
        keys = [f"{body}_I{x}_kgm2" for x in "xyz"]
        if any(k in values for k in keys):
            current = getattr(m, attr)
            inr[attr] = np.array([values.get(k, current[i]) for i, k in enumerate(keys)])
    return replace(model, friction=replace(f, **fr), inertia=replace(m, **inr))


def with_parameters(model: HipModel, names: tuple[str, ...], theta: Array) -> HipModel:
    """A copy of ``model`` with ``names`` set to ``theta`` (no validation: zeros are allowed).
    The bearing products are split by :func:`bearing_split` and need both to be given."""
    values = dict(zip(names, np.asarray(theta, dtype=float).tolist()))
    out = _set_values(model, values)
    if "bearing_load_coeff_m" in values:
        mu_h, mu_t, m_m = bearing_split(model, values["bearing_load_coeff_m"], values["bearing_weight_friction_Nm"])
        out = replace(out, friction=replace(out.friction, mu_h=mu_h, mu_t=mu_t),
                      inertia=replace(out.inertia, m_m=m_m))
    return out


def _regressor_description(model: HipModel) -> dict[str, Any]:
    """The hip's description with every friction family present (unit coefficients) and the
    centre joints' load-driven friction as the two unit-radius terms of the module docstring:
    the regressor's columns do not depend on the values, only on which terms exist."""
    ones = {a: 1.0 for a in FRICTION_ATTR.values()}
    probe = replace(model, friction=replace(model.friction, **ones, r_h=1.0, mu_h=1.0, r_t=1.0, mu_t=1.0))
    desc = hip_description(probe)
    for j in desc["joints"]:
        if j["name"] in _CENTRES:
            j["friction"] = {"external": [
                {"load": _LOAD, "coefficient": 1.0, "radius_m": 1.0, "offset_N": 0.0},
                {"load": _LOAD, "coefficient": 1.0, "radius_m": 1.0, "offset_N": F_REF},
            ]}
    return desc


def regressor_mechanism(model: HipModel) -> Any:
    """The compiled description whose regressor the identification uses (:func:`_regressor_description`)."""
    return load_mechanism(_regressor_description(model))


def _inertia(v: list[float]) -> Array:
    """``[Ixx, Iyy, Izz, Ixy, Ixz, Iyz]`` -> (3, 3), unchecked (a probe may be zero)."""
    xx, yy, zz, xy, xz, yz = (float(x) for x in v)
    return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


def engine_values(model: HipModel, mech: Any, names_e: tuple[str, ...], values: dict[str, float]) -> Array:
    """The engine's parameters ``names_e`` (the regressor's) of the hip with the parameters
    ``values`` (every name of :data:`ALL_NAMES`; the rest of ``model`` as it is), linear in
    ``values``; ``mech`` the compiled :func:`regressor_mechanism`."""

    desc = hip_description(_set_values(replace(model, friction=replace(model.friction, mu_h=0.0, mu_t=0.0)), values))
    bodies = {b["name"]: b for b in desc["bodies"]}
    mass = np.array([float(bodies[n]["mass_kg"]) for n in mech.body_names])
    R0, p0 = mech.R0, mech.p0
    com = np.stack([R0[k].T @ (np.asarray(bodies[n]["com_m"], float) - p0[k]) for k, n in enumerate(mech.body_names)])
    inertia = np.stack([R0[k].T @ _inertia(bodies[n]["inertia_kgm2"]) @ R0[k] for k, n in enumerate(mech.body_names)])
    bary = inertial_parameters(replace(mech, mass=mass, com=com, inertia=inertia))
    out: dict[str, float] = {}
    for k, b in enumerate(mech.body_names):
        out.update({f"{b}_{p}": float(bary[k, i]) for i, p in enumerate(BODY_PARAMETERS)})
    for j in desc["joints"]:
        fr = j.get("friction", {})
        out[f"{j['name']}_coulomb"] = float(fr.get("coulomb_torque_Nm", fr.get("coulomb_force_N", 0.0)))
        out[f"{j['name']}_viscous"] = float(fr.get("viscous_Nm_s_rad", fr.get("viscous_N_s_m", 0.0)))
    S, C = values["bearing_load_coeff_m"], values["bearing_weight_friction_Nm"]
    for centre in _CENTRES:
        out[f"{centre}_external1_{_LOAD}_coefficient"] = S - C / F_REF
        out[f"{centre}_external2_{_LOAD}_coefficient"] = C / F_REF
    for a in desc["actuators"]:
        out[f"{a['name']}_rotor_inertia_kgm2"] = float(a["rotor_inertia_kgm2"])
        out[f"{a['name']}_motor_coulomb"] = float(a.get("coulomb_torque_Nm", 0.0))
        out[f"{a['name']}_motor_viscous"] = float(a.get("viscous_Nm_s_rad", 0.0))
    missing = [n for n in names_e if n not in out]
    if missing:
        raise ParameterError(f"hip identification: no hip parameter gives the engine's {', '.join(missing)}")
    return np.array([out[n] for n in names_e])


def _parameter_map(model: HipModel, mech: Any, names_e: tuple[str, ...], names: tuple[str, ...]) -> tuple[Array, Array]:
    """``A (p_e, p)`` and ``b (p_e,)`` with ``theta_e = A theta + b`` (exact: every entry is linear)."""
    held = dict(zip(ALL_NAMES, parameter_vector(model, ALL_NAMES).tolist()))
    base = {**held, **{n: 0.0 for n in names}}
    b = engine_values(model, mech, names_e, base)
    A = np.column_stack([engine_values(model, mech, names_e, {**base, n: 1.0}) - b for n in names]) \
        if names else np.zeros((len(names_e), 0))
    return A, b


def engine_kinematics(mech: Any, motion: OrientationMotion) -> Any:
    """The engine's kinematics of ``mech`` along the motion (task: the Euler angles)."""
    return solve_kinematics(mech, motion.angles, motion.rates, motion.accels, motion.t)


def hip_regressor(model: HipModel, motion: OrientationMotion, names: tuple[str, ...], mech: Any = None,
                  kin: Any = None, memo: list[Any] | None = None) -> Regressor:
    """``tau = Y theta + offset`` along ``motion``, ``Y (n, 3, p)`` [N m per unit]: the engine's
    regressor of the hip's description mapped into ``names`` (module docstring). ``mech`` (the
    :func:`regressor_mechanism` of ``model``) and ``kin`` (its kinematics along ``motion``), when
    given, are used as they are; ``memo``, a list, keeps the parameter map (the same for every
    motion of one model and ``names``) for the next call."""
    mech = regressor_mechanism(model) if mech is None else mech
    kin = engine_kinematics(mech, motion) if kin is None else kin
    load = np.zeros(len(motion)) if motion.load is None else np.asarray(motion.load, dtype=float)
    reg = regressor(mech, kin, {_LOAD: load})
    if memo:
        A, b = memo[0]
    else:
        A, b = _parameter_map(model, mech, reg.names, names)
        if memo is not None:
            memo.append((A, b))
    Y = np.einsum("nue,ep->nup", reg.Y, A)
    offset = reg.u0 + np.einsum("nue,e->nu", reg.Y, b)
    return Regressor(Y, offset, tuple(names))


def consistency_transform(names: tuple[str, ...]) -> tuple[Array, Array, Array]:
    """``theta = T s`` and bounds ``lower <= s <= upper`` that express physical consistency.

    Principal-inertia triplets map to second moments of mass (module docstring); everything
    else maps to itself. Friction ``>= 0``; masses and inertias ``>= 1e-9`` of their unit.
    """
    p = len(names)
    T = np.eye(p)
    lower = np.zeros(p)
    for k, n in enumerate(names):
        if n in INERTIA_NAMES:
            lower[k] = _POSITIVE_FLOOR
    for body in ("lever", "platform"):
        keys = [f"{body}_I{x}_kgm2" for x in "xyz"]
        idx = [names.index(k) for k in keys if k in names]
        if len(idx) == 3:
            T[np.ix_(idx, idx)] = np.array([[0.0, 1.0, 1.0], [1.0, 0.0, 1.0], [1.0, 1.0, 0.0]])
            lower[idx] = 0.5 * _POSITIVE_FLOOR
    return T, lower, np.full(p, np.inf)


@dataclass(frozen=True)
class HipIdentification:
    """Everything one identification found.

    ``names (p,)`` the parameters asked for; ``prior (p,)`` their values in the parameter file;
    ``regressor``, ``base``, ``estimate`` (see those classes); ``tau_measured, tau_identified
    (n, 3)`` [N m]; ``residual_rms (3,)`` [N m] per motor; ``model`` the identified machine.
    """

    names: tuple[str, ...]
    prior: Array
    regressor: Regressor
    base: BaseParameters
    estimate: Estimate
    tau_measured: Array
    tau_identified: Array
    residual_rms: Array
    model: HipModel


def identify_hip(
    model: HipModel,
    motion: OrientationMotion,
    tau_measured: Array,
    which: Which = "friction",
    rank_tol: float = DEFAULT_RANK_TOL,
    source: str = "measured",
) -> HipIdentification:
    """Identify the parameters of ``which`` from measured motor torques ``(n, 3)`` [N m].

    Raises :class:`MotionError` (naming ``source``) for non-finite torques, too few samples
    for the parameters asked for, or a motion that excites none of them.
    """
    names = parameter_names(which)
    what = f"{which} parameters"
    tau = check_efforts(tau_measured, len(motion), TORQUE_COLUMNS, len(names), source, what)
    reg = hip_regressor(model, motion, names)
    res = fit_regressor(reg, tau, parameter_vector(model, names), consistency_transform(names), rank_tol, source,
                        what)
    identified = with_parameters(model, names, res.estimate.theta)
    return HipIdentification(
        names, res.prior, res.regressor, res.base, res.estimate, res.u_measured, res.u_identified, res.residual_rms,
        identified,
    )


def identified_description(description: dict[str, Any], result: HipIdentification) -> dict[str, Any]:
    """The parameter-file structure of ``description`` with the identified values written in.

    The bearing friction is written as split by :func:`bearing_split` (which may change
    ``platform_mass_kg`` when the file's value cannot carry the identified weight friction).
    """
    d = copy.deepcopy(description)
    fr, inr = d["friction"], d["inertia"]
    values = dict(zip(result.names, result.estimate.theta.tolist()))
    if "bearing_load_coeff_m" in values:
        m = result.model
        fr["hip_coefficient"], fr["thrust_coefficient"] = float(m.friction.mu_h), float(m.friction.mu_t)
        inr["platform_mass_kg"] = float(m.inertia.m_m)
    for name, key in _FIELD.items():
        if name in values:
            fr[key] = values[name]
    for name in ("slider_mass_kg", "screw_inertia_kgm2", "lever_mass_kg"):
        if name in values:
            inr[name] = values[name]
    for body in ("lever", "platform"):
        keys = [f"{body}_I{x}_kgm2" for x in "xyz"]
        if keys[0] in values:
            inr[f"{body}_inertia_kgm2"] = [values[k] for k in keys]
    model_from_dict(d, "identified parameters")  # validates: every value is admissible
    return d


#: plausibility limits of a measured run's columns (``read_measured_csv``)
MAX_ANGLE_DEG = 360.0
MAX_TORQUE_NM = 1e4
MAX_LOAD_N = 1e5


def read_measured_csv(path: str | Path, sg_window: int = 15, sg_order: int = 5) -> tuple[OrientationMotion, Array, dict[str, Any]]:
    """Read a measurement file: the motion columns plus ``tau1_Nm, tau2_Nm, tau3_Nm``.

    Derivative columns that are given are used as they are; missing rates and accelerations
    come from :func:`savgol_derivatives` of the angles (or the accelerations from the given
    rates). Returns the motion, the torques ``(n, 3)`` [N m] and how the derivatives were had.
    """
    ang, rate, acc = MOTION_COLUMNS[1:4], MOTION_COLUMNS[4:7], MOTION_COLUMNS[7:10]
    cols = read_csv_columns(path, ("t_s", *ang, *TORQUE_COLUMNS), (*rate, *acc, "load_N"))
    for names, limit, unit in ((ang, MAX_ANGLE_DEG, "deg"), (TORQUE_COLUMNS, MAX_TORQUE_NM, "N m"),
                               (("load_N",), MAX_LOAD_N, "N")):
        for name in names:
            if name in cols:
                big = np.flatnonzero(np.abs(cols[name]) > limit)
                if big.size:
                    raise MotionError(f"{path}: row {big[0] + 1}, column {name!r}: |{cols[name][big[0]]:g}| {unit} is "
                                      f"above the plausibility limit {limit:g} {unit}")
    t = cols["t_s"]
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        raise MotionError(f"{path}: row {bad[0] + 2}, column 't_s': time must increase strictly")

    def group(names: tuple[str, ...]) -> Array | None:
        present = [c for c in names if c in cols]
        if not present:
            return None
        if len(present) != 3:
            missing = next(c for c in names if c not in cols)
            raise MotionError(f"{path}: missing column {missing!r} (give all of {', '.join(names)} or none)")
        return np.deg2rad(np.stack([cols[c] for c in names], axis=-1))

    q, qd, qdd = group(ang), group(rate), group(acc)
    if qd is None and qdd is not None:
        raise MotionError(f"{path}: acceleration columns need the rate columns ({', '.join(rate)})")
    info: dict[str, Any] = {"rates": "given", "accelerations": "given"}
    if qd is None:
        qd, qdd = savgol_derivatives(t, q, sg_window, sg_order, str(path))
        info = {"rates": "savitzky_golay", "accelerations": "savitzky_golay"}
    elif qdd is None:
        qdd = savgol_derivatives(t, qd, sg_window, sg_order, str(path))[0]
        info["accelerations"] = "savitzky_golay"
    if "savitzky_golay" in info.values():
        info.update(sg_window_samples=sg_window, sg_order=sg_order)
    load = cols.get("load_N")
    if load is not None:
        neg = np.flatnonzero(load < 0)
        if neg.size:
            raise MotionError(f"{path}: row {neg[0] + 1}, column 'load_N': {load[neg[0]]:g} N is negative")
    motion = make_motion(t, q, qd, qdd, load)
    tau = np.stack([cols[c] for c in TORQUE_COLUMNS], axis=-1)
    return motion, tau, info


def engine_torques(model: HipModel, motion: OrientationMotion) -> Array:
    """The motor torques ``(n, 3)`` [N m] of ``model`` along ``motion`` by the engine's inverse
    dynamics of its description (:class:`.paper.PaperView`: joint reactions with friction, then
    the drives, Eq. A1): independent of the regressor, for synthetic measurements."""
    load = np.zeros(len(motion)) if motion.load is None else np.asarray(motion.load, dtype=float)
    m = SimpleNamespace(t=motion.t, angles=motion.angles, rates=motion.rates, accels=motion.accels, load=load)
    return PaperView(model).solve(m).tau
