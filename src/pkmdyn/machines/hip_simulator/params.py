"""Parameters of the 2(3PUS+S) hip simulator: TOML description -> frozen :class:`HipModel`.

The file format is the one of the model specification (``docs/hip_simulator.md``); the
built-in default (``default.toml`` beside this module) holds the paper's Tables 1-2.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, field_validator, model_validator

from ...errors import LimitError, ParameterError
from ...io import DEFAULT_MAX_SAMPLES
from ...params_util import Section, check_limit, read_toml, validate
from ...spatial import check_sequence

__all__ = [
    "HipGeometry",
    "HipInertia",
    "HipFriction",
    "HipModel",
    "HipLimits",
    "LIMIT_KEYS",
    "load_params",
    "model_from_dict",
    "default_params_dict",
    "paper_params_path",
    "DEFAULT_PARAMS_TEXT",
]

Array = NDArray[np.float64]
Pos = Annotated[float, Field(gt=0.0)]
NonNeg = Annotated[float, Field(ge=0.0)]
# physically meaningful ranges: a value outside is a typing error, not a machine
Length = Annotated[float, Field(ge=1e-3, le=10.0)]  #: [m]
Angle = Annotated[float, Field(ge=-360.0, le=360.0)]  #: [deg]
Mass = Annotated[float, Field(gt=0.0, le=1e4)]  #: [kg]
Inertia = Annotated[float, Field(gt=0.0, le=1e4)]  #: [kg m^2]
Radius = Annotated[float, Field(ge=0.0, le=1.0)]  #: [m] friction radii
Coefficient = Annotated[float, Field(ge=0.0, le=5.0)]  #: friction coefficients
Force = Annotated[float, Field(ge=0.0, le=1e5)]  #: [N]
Torque = Annotated[float, Field(ge=0.0, le=1e4)]  #: [N m]
Damping = Annotated[float, Field(ge=0.0, le=1e6)]  #: [N s/m] or [N m s/rad]
Eps = Annotated[float, Field(ge=1e-9, le=1e3)]  #: friction regularisation velocities


def _vec(n: int, item: Any = float) -> Any:
    return Annotated[list[item], Field(min_length=n, max_length=n)]


class _Geometry(Section):
    base_radius_m: Length
    platform_radius_m: Length
    lever_length_m: Length
    platform_heights_m: _vec(2, Length)
    screw_lead_m: Annotated[float, Field(ge=1e-4, le=1.0)]
    module_angles_deg: _vec(3, Angle)
    platform_joint_angles_deg: _vec(3, Angle)
    euler_sequence: str = "XYZ"
    lever_spin: Literal["u_joint", "perpendicular"] = "u_joint"

    @field_validator("lever_spin")
    @classmethod
    def _spin(cls, v: str) -> str:
        if v != "u_joint":
            raise ValueError('"perpendicular" (the paper\'s Eq. 4 assumption: the levers without the spin their U '
                             "joints give them) is not a mechanism the engine computes; the levers turn as their U "
                             'joints let them (lever_spin = "u_joint", docs/hip_simulator.md)')
        return v

    @model_validator(mode="after")
    def _rules(self) -> "_Geometry":
        h1, h2 = self.platform_heights_m
        if not h1 > h2:
            raise ValueError("platform_heights_m: platform 1 is the upper one, so h1 must exceed h2")
        return self

    @field_validator("euler_sequence")
    @classmethod
    def _sequence(cls, v: str) -> str:
        try:
            return check_sequence(v)
        except ParameterError:
            shown = v if len(v) <= 20 else v[:20] + "..."
            raise ValueError(
                f"{shown!r} is not a valid Euler sequence (three axes from XYZ for intrinsic or xyz for "
                "extrinsic, no axis twice in a row)"
            ) from None


class _Inertia(Section):
    slider_mass_kg: Mass
    lever_mass_kg: Mass
    lever_inertia_kgm2: _vec(3, Inertia)
    screw_inertia_kgm2: Annotated[float, Field(gt=0.0, le=10.0)]
    platform_mass_kg: Annotated[float, Field(ge=0.0, le=1e4)]
    platform_inertia_kgm2: _vec(3, Inertia)
    gravity_m_s2: Annotated[float, Field(ge=0.0, le=100.0)]


class _Friction(Section):
    hip_radius_m: Radius
    hip_coefficient: Coefficient
    thrust_radius_m: Radius
    thrust_coefficient: Coefficient
    friction_velocity_eps_rad_s: Eps = 1e-3
    friction_velocity_eps_m_s: Eps = 1e-4
    slider_coulomb_N: Force = 0.0
    slider_viscous_Ns_m: Damping = 0.0
    screw_coulomb_Nm: Torque = 0.0
    screw_viscous_Nms_rad: Damping = 0.0
    spherical_coulomb_Nm: Torque = 0.0
    spherical_viscous_Nms_rad: Damping = 0.0
    universal_coulomb_Nm: Torque = 0.0
    universal_viscous_Nms_rad: Damping = 0.0


class _Limits(Section):
    """Plausibility limits: implausible but possible inputs are refused unless raised here."""

    max_samples: Annotated[int, Field(gt=0)] = DEFAULT_MAX_SAMPLES
    max_load_N: Pos = 20_000.0
    max_abs_angle_deg: Annotated[float, Field(gt=0.0, le=180.0)] = 45.0
    max_slider_speed_m_s: Pos = 2.0
    max_slider_acceleration_m_s2: Pos = 50.0
    max_duration_s: Pos = 1e7
    min_platform_gap_m: Pos = 0.05


#: the names of the ISO 14242-1 cycle presets (:func:`pkmdyn.machines.hip_simulator.paper.iso_cycle_preset`)
ISO_CYCLES = ("default", "paper-fit", "paper-fit-zxy")


class _Motion(Section):
    """The built-in motion a run takes when no motion file is given (``[motion]``, optional)."""

    iso_cycle: str = "default"

    @field_validator("iso_cycle")
    @classmethod
    def _preset(cls, v: str) -> str:
        if v not in ISO_CYCLES:
            raise ValueError(f"motion model {v!r}: expected one of {', '.join(ISO_CYCLES)}")
        return v


class _HipFile(Section):
    geometry: _Geometry
    inertia: _Inertia
    friction: _Friction
    limits: _Limits = _Limits()
    motion: _Motion = _Motion()


@dataclass(frozen=True)
class HipGeometry:
    """Geometry in SI units and radians (spec, "Frames and geometry")."""

    E: float  #: base radius [m]
    e: float  #: platform radius [m]
    l: float  #: lever length [m]
    h: Array  #: (2,) platform heights h1, h2 [m]
    p: float  #: screw lead [m]
    phi: Array  #: (3,) module angles [rad]
    psi: Array  #: (3,) platform joint angles [rad]
    euler_sequence: str
    lever_spin: str
    A: Array = field(repr=False)  #: (3, 3) module screw points A_i, base frame [m], [module, xyz]
    r_a: Array = field(repr=False)  #: (3, 3) S-joint centres o_j a_ji, platform frame [m], [module, xyz]
    t: Array = field(repr=False)  #: (3, 3) U-joint first axes t_i, base frame, [module, xyz]
    o: Array = field(repr=False)  #: (2, 3) platform centres o_j, base frame [m], [platform, xyz]


@dataclass(frozen=True)
class HipInertia:
    """Masses [kg], principal inertias [kg m^2] and gravity [m/s^2] (Table 2)."""

    m_L: float  #: slider mass
    m_l: float  #: lever mass
    I_l: Array  #: (3,) lever principal inertia (x = U second axis, z = b -> a)
    I_L: float  #: lead-screw rotor inertia
    m_m: float  #: platform mass
    I_m: Array  #: (3,) platform principal inertia, platform frame
    g: float  #: gravity, acting along -Z


@dataclass(frozen=True)
class HipFriction:
    """Friction parameters (Eq. 16 and the spec's further joint friction)."""

    r_h: float
    mu_h: float
    r_t: float
    mu_t: float
    eps_w: float  #: regularisation of angular velocities [rad/s]
    eps_v: float  #: regularisation of sliding velocities [m/s]
    slider_coulomb: float
    slider_viscous: float
    screw_coulomb: float
    screw_viscous: float
    spherical_coulomb: float
    spherical_viscous: float
    universal_coulomb: float
    universal_viscous: float


@dataclass(frozen=True)
class HipLimits:
    """Plausibility limits of a run (``[limits]``, all optional; ``docs/file_formats.md``).

    Inputs beyond them are refused with a message naming the limit; raise one in the parameter
    file or with ``--limit KEY=VALUE``.
    """

    max_samples: int = DEFAULT_MAX_SAMPLES  #: samples of one run, checked before allocating
    max_load_N: float = 20_000.0  #: hydraulic load on a platform [N]
    max_abs_angle_deg: float = 45.0  #: |Euler angle| of the platforms [deg]
    max_slider_speed_m_s: float = 2.0  #: |slider velocity| [m/s]
    max_slider_acceleration_m_s2: float = 50.0  #: |slider acceleration| [m/s^2]
    max_duration_s: float = 1e7  #: duration of a run's motion [s] (about 10 million ISO cycles)
    #: least distance h1 - h2 of the platforms [m]: the two sliders of a module ride on one screw
    #: ``L_1i - L_2i = h1 - h2`` apart, and a slider carriage is some centimetres long; checked
    #: when the parameter file is read, so it is raised (lowered) in the file only
    min_platform_gap_m: float = 0.05


#: the ``[limits]`` keys and their types (for ``--limit KEY=VALUE``; ``min_platform_gap_m`` is a
#: property of the parameter file and set there)
LIMIT_KEYS: dict[str, type] = {f: (int if f == "max_samples" else float) for f in HipLimits.__dataclass_fields__
                               if f != "min_platform_gap_m"}


@dataclass(frozen=True)
class HipModel:
    """The whole machine: immutable, plain numbers and arrays."""

    geometry: HipGeometry
    inertia: HipInertia
    friction: HipFriction
    limits: HipLimits = field(default_factory=HipLimits)
    #: the ISO 14242-1 cycle preset of the built-in motion (``[motion] iso_cycle``;
    #: :func:`pkmdyn.machines.hip_simulator.paper.iso_cycle_preset`)
    motion_model: str = "default"


def _build(d: _HipFile, source: str) -> HipModel:
    g = d.geometry
    phi = np.deg2rad(np.array(g.module_angles_deg))
    psi = np.deg2rad(np.array(g.platform_joint_angles_deg))
    A = g.base_radius_m * np.stack([np.cos(phi), np.sin(phi), np.zeros(3)], axis=-1)
    r_a = g.platform_radius_m * np.stack([np.cos(psi), np.sin(psi), np.zeros(3)], axis=-1)
    t = np.stack([-np.sin(phi), np.cos(phi), np.zeros(3)], axis=-1)
    h = np.array(g.platform_heights_m, dtype=float)
    gap = float(h[0] - h[1])
    if not gap >= d.limits.min_platform_gap_m:
        raise LimitError(
            f"{source}: [geometry] platform_heights_m: the platforms are {gap:.4g} m apart, closer than the limit "
            f"min_platform_gap_m = {d.limits.min_platform_gap_m:g} m (the two sliders of a module ride on one screw "
            "h1 - h2 apart; lower the limit with [limits] min_platform_gap_m in the parameter file)")
    o = np.stack([np.zeros(2), np.zeros(2), h], axis=-1)
    reach = np.linalg.norm((r_a - A)[:, :2], axis=-1)
    for i in range(3):
        if reach[i] >= g.lever_length_m:
            raise ParameterError(
                f"{source}: [geometry] lever_length_m: {g.lever_length_m} m is too short for leg {i + 1} "
                f"to reach its platform at the zero pose (horizontal distance {reach[i]:.4f} m)"
            )
    geom = HipGeometry(
        E=g.base_radius_m,
        e=g.platform_radius_m,
        l=g.lever_length_m,
        h=h,
        p=g.screw_lead_m,
        phi=phi,
        psi=psi,
        euler_sequence=g.euler_sequence,
        lever_spin=g.lever_spin,
        A=A,
        r_a=r_a,
        t=t,
        o=o,
    )
    i = d.inertia
    inertia = HipInertia(
        m_L=i.slider_mass_kg,
        m_l=i.lever_mass_kg,
        I_l=np.array(i.lever_inertia_kgm2, dtype=float),
        I_L=i.screw_inertia_kgm2,
        m_m=i.platform_mass_kg,
        I_m=np.array(i.platform_inertia_kgm2, dtype=float),
        g=i.gravity_m_s2,
    )
    f = d.friction
    friction = HipFriction(
        r_h=f.hip_radius_m,
        mu_h=f.hip_coefficient,
        r_t=f.thrust_radius_m,
        mu_t=f.thrust_coefficient,
        eps_w=f.friction_velocity_eps_rad_s,
        eps_v=f.friction_velocity_eps_m_s,
        slider_coulomb=f.slider_coulomb_N,
        slider_viscous=f.slider_viscous_Ns_m,
        screw_coulomb=f.screw_coulomb_Nm,
        screw_viscous=f.screw_viscous_Nms_rad,
        spherical_coulomb=f.spherical_coulomb_Nm,
        spherical_viscous=f.spherical_viscous_Nms_rad,
        universal_coulomb=f.universal_coulomb_Nm,
        universal_viscous=f.universal_viscous_Nms_rad,
    )
    return HipModel(geom, inertia, friction, HipLimits(**d.limits.model_dump()), d.motion.iso_cycle)


def model_from_dict(data: dict[str, Any], source: str = "parameters") -> HipModel:
    """Validate a description (the TOML structure as a dict) and build the model."""
    return _build(validate(_HipFile, data, source), source)


def load_params(path: str | Path | None = None) -> HipModel:
    """Load a parameter file; ``None`` gives the built-in paper parameters."""
    if path is None:
        return model_from_dict(default_params_dict(), "built-in parameters")
    return model_from_dict(read_toml(path), str(path))


def _default_resource() -> Any:
    return resources.files(__package__).joinpath("default.toml")


def paper_params_path() -> Path:
    """The built-in parameter file of the paper's own convention (``paper.toml``: the Euler
    sequence and ISO cycle under which the paper's §5 figures are reproduced best;
    ``docs/hip_simulator.md``, "The paper's own convention")."""
    return Path(str(resources.files(__package__).joinpath("paper.toml")))


DEFAULT_PARAMS_TEXT: str = _default_resource().read_text(encoding="utf-8")


def default_params_dict() -> dict[str, Any]:
    """A fresh copy of the built-in description, as a nested dict (safe to modify)."""
    return tomllib.loads(DEFAULT_PARAMS_TEXT)


def check_motion_limits(where: Any, motion: Any, limits: HipLimits) -> None:
    """The load and the angles of a motion (``load (n,)`` [N], ``angles (n, 3)`` [rad]) against the
    plausibility ``limits`` (before anything is computed); ``where(k)`` names row ``k``."""
    if motion.load.size:
        k = int(np.argmax(motion.load))
        check_limit(float(motion.load[k]), limits.max_load_N, f"{where(k)}: load", "max_load_N", "N")
        a = np.abs(np.rad2deg(motion.angles))
        r, c = np.unravel_index(int(np.argmax(a)), a.shape)
        name = ("alpha", "beta", "gamma")[c]
        check_limit(float(a[r, c]), limits.max_abs_angle_deg, f"{where(int(r))}: |{name}|", "max_abs_angle_deg", "deg")
