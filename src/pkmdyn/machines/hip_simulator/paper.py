"""The hip paper's view of the engine's results: its names, its quantities and its studies.

The engine (:mod:`pkmdyn.multibody`) solves the hip's mechanism description
(:func:`.description.hip_description`); this module says what the paper calls the results and
computes the few quantities the paper defines on top of them:

* :class:`PaperView`: the engine's model of a parameter file and one block of the paper's
  quantities (:class:`HipBlock`) from one engine solve: the slider positions, velocities and
  accelerations of both platforms ``L_ji`` (Eq. 2-5; the upper slider of screw i is the lower
  one, the platforms' height difference higher), the Jacobian measures of Eq. 3 (``J_a``
  diagonal ``e_i . e_z``, ``J_b`` rows ``r_i x e_i``, ``J = J_a^-1 J_b``: ``det(J_a)``,
  ``det(J_b)`` [m^3], ``cond(J)``), the motor torques and their parts of Eq. 14 (platform,
  lever, slider: the description's body groups; screw: the drives' rotors; friction: every
  joint's and the screws', of which ``hip_friction`` is Eq. 16's hip joints and thrust
  bearings) and the motor power;
* the results file's columns (:func:`block_columns`, ``docs/file_formats.md``) and the summary
  (:class:`SummaryAccumulator`);
* the ISO 14242-1 cycle presets (:func:`iso_cycle_preset`) and the paper's own study of its
  cycle: the cycle model fitted to the nine slider maxima it reports (§5.1):
  :func:`fit_iso_cycle` fits the six phases of :class:`IsoCycle` (maximum and minimum of FE,
  AA and IER; the ISO ranges and the load stay as they are) to :data:`PAPER_SLIDER_MAXIMA` by
  least squares on the relative differences (``scipy.optimize.least_squares`` from several
  starts), each rise and fall held between 30 % and 70 % of the cycle as the smooth model
  needs. Findings in ``docs/identification.md``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...errors import ParameterError
from ...multibody import load_mechanism
from ...multibody.dynamics.actuators import motor_efforts
from ...multibody.dynamics.friction import EPS_ROTATION, EPS_TRANSLATION
from ...multibody.dynamics.newton_euler import joint_reactions
from ...multibody.kinematics.inverse import solve_kinematics
from ...profiles.iso14242 import AxisWave, IsoCycle, iso14242_motion
from ...report import Extremes
from ...spatial import euler_kinematics
from .description import hip_description
from .params import DEFAULT_PARAMS_TEXT, ISO_CYCLES, HipModel

__all__ = ["PARTS", "PaperView", "HipBlock", "block_columns", "SummaryAccumulator", "parameters_text",
           "regularisation_note", "euler_rate_map",
           "PAPER_SLIDER_MAXIMA", "PAPER_FIT", "PAPER_FIT_ZXY", "iso_cycle_preset", "IsoFit", "slider_maxima",
           "fit_iso_cycle"]

Array = NDArray[np.float64]

#: the parts of Eq. (14) plus friction, in results-file order
PARTS = ("platform", "lever", "slider", "screw", "friction")


#: hip paper §5.1: max position of S11, S12, S13 [m]; max |Ld| [m/s] and max |Ldd| [m/s^2] per screw
PAPER_SLIDER_MAXIMA = np.array(
    [0.66558, 0.66047, 0.62442, 0.27515, 0.26780, 0.14397, 2.15240, 2.10080, 1.27090]
)

#: the phases fitted by :func:`fit_iso_cycle` to :data:`PAPER_SLIDER_MAXIMA` with the built-in
#: parameters (ranges and load as in the default :class:`IsoCycle`)
PAPER_FIT = IsoCycle(
    fe=AxisWave(25.0, 0.5773, -18.0, 0.0853),
    aa=AxisWave(7.0, 0.6432, -4.0, 0.0312),
    ier=AxisWave(2.0, 0.0636, -10.0, 0.4759),
)

#: the same fit with ``euler_sequence = "ZXY"`` in the parameter file (FE about the base Z axis
#: first, then AA, then IER): a motion for that parameter file only
PAPER_FIT_ZXY = IsoCycle(
    fe=AxisWave(25.0, 0.0397, -18.0, 0.5323),
    aa=AxisWave(7.0, 0.1731, -4.0, 0.6002),
    ier=AxisWave(2.0, 0.3350, -10.0, 0.9088),
)


def iso_cycle_preset(name: str) -> IsoCycle:
    """The cycle model by name: ``"default"`` (the documented choices), ``"paper-fit"`` (for the
    spec's ``XYZ`` sequence) or ``"paper-fit-zxy"`` (for a parameter file with ``euler_sequence =
    "ZXY"``; see ``docs/identification.md``)."""
    presets = dict(zip(ISO_CYCLES, (IsoCycle(), PAPER_FIT, PAPER_FIT_ZXY)))
    if name not in presets:
        raise ParameterError(f"motion model {name!r}: expected one of {', '.join(presets)}")
    return presets[name]


@dataclass(frozen=True)
class HipBlock:
    """The paper's quantities of one block of ``n`` samples (shapes below) and the engine's
    kinematics ``kin`` they come from.

    ``L, Ld, Ldd (n, 2, 3)`` [m, m/s, m/s^2]: slider ``i`` of platform ``j`` (upper, lower);
    ``det_Ja (n,)``, ``det_Jb (n,)`` [m^3], ``cond_J (n,)``; ``tau (n, 3)`` [N m] the motor
    torques; ``parts``: each of :data:`PARTS` ``(n, 3)`` [N m], summing to ``tau``;
    ``hip_friction (n, 3)`` [N m]; ``power (n,)`` [W] the motors' total power."""

    kin: Any
    L: Array
    Ld: Array
    Ldd: Array
    det_Ja: Array
    det_Jb: Array
    cond_J: Array
    tau: Array
    parts: dict[str, Array]
    hip_friction: Array
    power: Array

    def rows(self, start: int) -> "HipBlock":
        """Samples ``start ..`` of the block."""
        sl = slice(start, None)
        return HipBlock(self.kin.rows(start), self.L[sl], self.Ld[sl], self.Ldd[sl], self.det_Ja[sl],
                        self.det_Jb[sl], self.cond_J[sl], self.tau[sl], {k: v[sl] for k, v in self.parts.items()},
                        self.hip_friction[sl], self.power[sl])


class PaperView:
    """The engine's model of the hip ``model`` (its description compiled,
    :func:`pkmdyn.multibody.load_mechanism`) and the paper's names of its results."""

    def __init__(self, model: HipModel) -> None:

        self.model = model
        self.mech = mech = load_mechanism(hip_description(model))
        self.act = np.array([mech.actuator_names.index(f"P_{i + 1}") for i in range(3)])
        self.groups = [mech.group_names.index(g) for g in PARTS[:3]]
        self.bearings = [mech.joint_index(j) for j in ("S0_upper", "S0_lower")]
        self.centre = mech.joint_index("S0_upper")
        self.platform_joint = np.array([mech.joint_index(f"S_upper_{i + 1}") for i in range(3)])
        self.slider_joint = np.array([mech.joint_index(f"U_upper_{i + 1}") for i in range(3)])
        g = model.geometry
        self.dh = float(g.h[0] - g.h[1])
        self.lever = float(g.l)

    def solve(self, motion: Any, sample_offset: int = 1, q_start: Array | None = None) -> HipBlock:
        """One engine solve of ``motion`` (``t``, ``angles``, ``rates``, ``accels`` [rad, rad/s,
        rad/s^2] in the parameter file's Euler sequence, ``load`` [N] the hydraulic force) and
        the paper's quantities of it; ``sample_offset``: the number of the motion's first sample
        in messages (counted from 1, as a motion file's rows); ``q_start``: the tree coordinates
        to start from (the last sample of the block before)."""

        mech, a = self.mech, self.act
        kin = solve_kinematics(mech, motion.angles, motion.rates, motion.accels, motion.t, q_start=q_start,
                               sample_offset=sample_offset)
        reac = joint_reactions(mech, kin, named={"hydraulic_N": np.asarray(motion.load, dtype=float)}, split=True,
                               sample_offset=sample_offset)
        mot = motor_efforts(mech, kin.act_q, kin.act_qd, kin.act_qdd, reac.u)
        k = mech.drive_ratio[a]
        sh = reac.shares
        parts = {name: sh.groups[:, a, g] / k for name, g in zip(PARTS[:3], self.groups)}
        parts["screw"] = mot.rotor[:, a]
        parts["friction"] = sh.friction[:, a].sum(axis=2) / k + mot.friction[:, a]
        hip_friction = sh.friction[:, a][:, :, self.bearings].sum(axis=2) / k
        tau = mot.effort[:, a]
        lower = np.stack((kin.act_q[:, a], kin.act_qd[:, a], kin.act_qdd[:, a]))
        upper = lower.copy()
        upper[0] += self.dh  # the upper slider of a screw: the lower one, the platforms' height difference higher
        L, Ld, Ldd = np.stack((upper, lower), axis=2)
        # Eq. (3): rows of J_a (e_i . e_z) and J_b (r_i x e_i), from the joint centres of the engine's solution
        jp = kin.joint_point
        r = jp[:, self.platform_joint] - jp[:, self.centre, None]
        e = (jp[:, self.platform_joint] - jp[:, self.slider_joint]) / self.lever
        Ja = e[..., 2]
        Jb = np.cross(r, e)
        det_Jb = np.einsum("ni,ni->n", Jb[:, 0], np.cross(Jb[:, 1], Jb[:, 2]))
        cond_J = np.linalg.cond(Jb / Ja[..., None]) if len(kin) else np.zeros(0)
        return HipBlock(kin, L, Ld, Ldd, Ja.prod(axis=1), det_Jb, cond_J, tau, parts, hip_friction,
                        np.einsum("ni,ni->n", tau, mot.theta_dot[:, a]))


#: the results file's columns, in order (:func:`block_columns`)
RESULTS_COLUMNS = ("t_s", *(f"{q}{j}{i}_{u}" for j in (1, 2) for i in (1, 2, 3)
                             for q, u in (("L", "m"), ("Ld", "m_s"), ("Ldd", "m_s2"))),
                   "detJa", "detJb_m3", *(f"tau{i}{p}_Nm" for i in (1, 2, 3)
                                         for p in ("", *(f"_{part}" for part in PARTS))), "condJ")


def block_columns(t: Array, b: HipBlock) -> dict[str, Array]:
    """The results-file columns (``docs/file_formats.md``), in order, for one block of samples."""
    cols: dict[str, Array] = {"t_s": t}
    for j in range(2):
        for i in range(3):
            cols[f"L{j + 1}{i + 1}_m"] = b.L[:, j, i]
            cols[f"Ld{j + 1}{i + 1}_m_s"] = b.Ld[:, j, i]
            cols[f"Ldd{j + 1}{i + 1}_m_s2"] = b.Ldd[:, j, i]
    cols["detJa"] = b.det_Ja
    cols["detJb_m3"] = b.det_Jb
    for i in range(3):
        cols[f"tau{i + 1}_Nm"] = b.tau[:, i]
        for part in PARTS:
            cols[f"tau{i + 1}_{part}_Nm"] = b.parts[part][:, i]
    cols["condJ"] = b.cond_J
    return cols


class SummaryAccumulator:
    """Per-slider and per-motor extremes, updated block by block (the summary without the data;
    :class:`pkmdyn.report.Extremes`)."""

    def __init__(self) -> None:
        self.samples = 0
        self.t0 = math.nan
        self.t1 = math.nan
        self.ext = Extremes()

    def add(self, t: Array, b: HipBlock) -> None:
        if self.samples == 0:
            self.t0 = float(t[0])
        self.t1 = float(t[-1])
        self.samples += int(t.shape[0])
        e = self.ext
        e.max("L_max", b.L.max(axis=0))
        e.min("L_min", b.L.min(axis=0))
        e.max("Ld", np.abs(b.Ld).max(axis=0))
        e.max("Ldd", np.abs(b.Ldd).max(axis=0))
        e.max("tau", np.abs(b.tau).max(axis=0))
        for f in PARTS:
            e.max(f, np.abs(b.parts[f]).max(axis=0))
        e.max("hip_friction", np.abs(b.hip_friction).max(axis=0))
        e.min("detJa", np.abs(b.det_Ja).min())
        e.min("detJb", np.abs(b.det_Jb).min())
        e.max("condJ", b.cond_J.max())
        e.max("power", np.abs(b.power).max())

    def result(self) -> dict[str, Any]:
        """The summary document (JSON-ready, unit-suffixed keys)."""
        e = self.ext
        sliders = {}
        for j in range(e["L_max"].shape[0]):
            for i in range(3):
                sliders[f"S{j + 1}{i + 1}"] = {
                    "max_position_m": float(e["L_max"][j, i]),
                    "min_position_m": float(e["L_min"][j, i]),
                    "max_abs_velocity_m_s": float(e["Ld"][j, i]),
                    "max_abs_acceleration_m_s2": float(e["Ldd"][j, i]),
                }
        motors = {}
        for i in range(3):
            m = {"max_abs_tau_Nm": float(e["tau"][i])}
            for part in PARTS:
                m[f"max_abs_tau_{part}_Nm"] = float(e[part][i])
            m["max_abs_tau_hip_friction_Nm"] = float(e["hip_friction"][i])
            motors[f"motor{i + 1}"] = m
        return {
            "samples": self.samples,
            "duration_s": self.t1 - self.t0,
            "sliders": sliders,
            "motors": motors,
            "min_abs_detJa": float(e["detJa"]),
            "min_abs_detJb_m3": float(e["detJb"]),
            "max_condJ": float(e["condJ"]),
            "max_abs_power_W": float(e["power"]),
        }


def euler_rate_map(sequence: str, angles: Array) -> Array:
    """``E (n, 3, 3)``: the platform's angular velocity [rad/s] per unit rate of each Euler angle
    (column k for angle k) at ``angles (n, 3)`` [rad] in ``sequence``; the slider Jacobian of
    Eq. 3 in the angles' rates is then ``J E`` (the engine's ``J_ax``)."""
    zero = np.zeros_like(angles)
    return np.stack([euler_kinematics(sequence, angles, np.broadcast_to(np.eye(3)[k], angles.shape), zero)[1]
                     for k in range(3)], axis=-1)


def regularisation_note(model: HipModel) -> str | None:
    """What the run says of the parameter file's ``friction_velocity_eps_*`` when they are not the
    engine's (every friction is regularised at :data:`pkmdyn.multibody.dynamics.friction.EPS_ROTATION` and
    ``EPS_TRANSLATION``, the file's defaults), else None."""
    f = model.friction
    if (f.eps_w, f.eps_v) == (EPS_ROTATION, EPS_TRANSLATION):
        return None
    return (f"friction_velocity_eps_rad_s = {f.eps_w:g}, friction_velocity_eps_m_s = {f.eps_v:g} of the parameter "
            f"file are not used: the engine regularises friction at {EPS_ROTATION:g} rad/s and "
            f"{EPS_TRANSLATION:g} m/s")


def parameters_text(params_path: str | Path | None) -> str:
    """The parameter file's text (the built-in file when None), headed by where it came from."""
    if params_path is None:
        return "# built-in parameters (pkmdyn/machines/hip_simulator/default.toml)\n" + DEFAULT_PARAMS_TEXT
    try:
        return f"# {params_path}\n" + Path(params_path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return f"# {params_path}\n# (the file could not be read again for the report)"


def slider_maxima(model: HipModel | PaperView, cycle: IsoCycle, samples: int = 400) -> Array:
    """The nine §5.1 quantities of ``cycle`` on ``model`` (order of :data:`PAPER_SLIDER_MAXIMA`)."""
    view = model if isinstance(model, PaperView) else PaperView(model)
    m = iso14242_motion(1.0, samples, cycle)
    b = view.solve(m)
    return np.concatenate([b.L[:, 0].max(axis=0), np.abs(b.Ld[:, 0]).max(axis=0), np.abs(b.Ldd[:, 0]).max(axis=0)])


def _cycle(base: IsoCycle, x: Array) -> IsoCycle:
    waves = []
    for k, w in enumerate((base.fe, base.aa, base.ier)):
        p_max, d = float(x[2 * k]) % 1.0, float(x[2 * k + 1])
        waves.append(replace(w, max_phase=p_max, min_phase=(p_max + d) % 1.0))
    return replace(base, fe=waves[0], aa=waves[1], ier=waves[2])


@dataclass(frozen=True)
class IsoFit:
    """A fitted cycle, its nine maxima and their relative differences from the targets."""

    cycle: IsoCycle
    maxima: Array
    relative_difference: Array


def fit_iso_cycle(model, targets: Array = PAPER_SLIDER_MAXIMA, base: IsoCycle = IsoCycle(), starts: int = 6,
                  seed: int = 0, samples: int = 300) -> IsoFit:
    """Fit the six phases of ``base`` to the nine ``targets`` (module docstring)."""
    from scipy.optimize import least_squares

    targets = np.asarray(targets, dtype=float)
    if targets.shape != (9,) or not np.all(targets > 0):
        raise ParameterError("targets: expected nine positive maxima")

    view = PaperView(model)

    def res(x: Array) -> Array:
        return slider_maxima(view, _cycle(base, x), samples) / targets - 1.0

    rng = np.random.default_rng(seed)
    x0 = []
    for w in (base.fe, base.aa, base.ier):
        x0 += [w.max_phase, (w.min_phase - w.max_phase) % 1.0]
    lo = np.tile([-1.0, 0.3], 3)
    hi = np.tile([2.0, 0.7], 3)
    best = None
    for k in range(starts):
        x = np.array(x0) if k == 0 else np.tile([0.0, 0.3], 3) + rng.uniform(0, 1, 6) * np.tile([1.0, 0.4], 3)
        sol = least_squares(res, x, bounds=(lo, hi), diff_step=1e-3, max_nfev=200)
        if best is None or sol.cost < best.cost:
            best = sol
    cycle = _cycle(base, best.x)
    maxima = slider_maxima(view, cycle, samples)
    return IsoFit(cycle, maxima, maxima / targets - 1.0)
