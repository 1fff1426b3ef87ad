"""PDM parameters: TOML description -> validated, immutable model.

The description (``default.toml`` or a user file) is checked by pydantic (strict types, no
unknown keys, ranges) and turned into :class:`PdmModel`, a frozen dataclass of plain numbers
and arrays in SI units, including the joint positions that the layout derives from them
(docs/pdm4.md, "Reconstructed layout").

Frames: base frame A-xyz with its origin at the home position of the output-link midpoint C,
x from R11 towards R12, y from the crank pivots towards the output link, z normal to the
plane of the six-bar (right-handed).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Annotated, Any

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, field_validator

from ...errors import ParameterError
from ...params_util import Section as _Section
from ...params_util import check_limit, read_toml, validate
from .inertia import body_inertia  # the inertia and material model, docs/pdm4.md section 10

__all__ = ["PdmModel", "TrajectorySettings", "WorkspaceSettings", "load_params", "default_params_path", "LIMIT_KEYS",
           "crank_angle"]

#: the run limits ``--limit KEY=VALUE`` may override (``[limits]`` of the parameter file)
LIMIT_KEYS: dict[str, type] = {"max_samples": int, "max_limb_speed_m_s": float, "max_limb_acceleration_m_s2": float,
                               "max_actuator_force_N": float, "max_duration_s": float}

Array = NDArray[np.float64]
_Pos = Annotated[float, Field(gt=0, le=10)]  # a length [m]: > 0 and, for plausibility, at most 10 m


class _Geometry(_Section):
    platform_offset_m: float = Field(ge=0, le=10)
    crank_pivot_spacing_m: _Pos
    crank_length_m: _Pos
    coupler_length_m: _Pos
    output_link_length_m: _Pos
    crank_pivot_y_m: float = Field(ge=-10, le=10)
    assembly_branch: list[int] = Field(min_length=2, max_length=2)
    u_joint_half_spacing_m: _Pos
    u_joint_height_m: float = Field(ge=-10, le=10)
    rpr_home_length_m: _Pos
    rpr_home_direction_deg: list[float] = Field(min_length=2, max_length=2)
    spu_home_length_m: _Pos
    spu_home_azimuth_deg: list[float] = Field(min_length=2, max_length=2)
    spu_home_elevation_deg: float = Field(gt=-90, lt=90)
    # z of each planar link layer above the output link's plane (CHOSEN; docs/pdm4.md)
    coupler_layer_z_m: float = Field(default=-0.025, ge=-1, le=1)
    crank_layer_z_m: float = Field(default=-0.050, ge=-1, le=1)
    rpr_limb_layer_z_m: float = Field(default=-0.075, ge=-1, le=1)

    @field_validator("assembly_branch")
    @classmethod
    def _signs(cls, v: list[int]) -> list[int]:
        if any(b not in (-1, 1) for b in v):
            raise ValueError("each entry must be 1 or -1")
        return v


class _Limbs(_Section):
    stroke_limit_m: _Pos
    rpr_cylinder_com_m: float = Field(ge=0)
    rpr_piston_com_m: float = Field(ge=0)
    spu_cylinder_com_m: float = Field(ge=0)
    spu_piston_com_m: float = Field(ge=0)
    min_transmission_angle_deg: float = Field(ge=0, lt=90)


class _Material(_Section):
    youngs_modulus_Pa: float = Field(gt=0, le=1e13)
    poisson_ratio: float = Field(gt=-1, lt=0.5)
    section_diameters_m: list[Annotated[float, Field(gt=0, le=10)]] = Field(min_length=3, max_length=3)
    cylinder_wall_m: float = Field(default=0.005, gt=0, le=1)
    stiffness_diameters_m: dict[str, Annotated[float, Field(gt=0, le=10)]] = Field(default_factory=dict)


class _BodyInertia(_Section):
    mass_kg: float | None = Field(default=None, gt=0, le=1e6)
    inertia_kgm2: list[Annotated[list[Annotated[float, Field(ge=-1e6, le=1e6)]], Field(min_length=3, max_length=3)]] | None = Field(
        default=None, min_length=3, max_length=3)


class _Inertia(_Section):
    gravity_m_s2: list[Annotated[float, Field(ge=-1000, le=1000)]] = Field(
        default_factory=lambda: [0.0, 0.0, -9.80665], min_length=3, max_length=3)
    density_kg_m3: float = Field(default=2700.0, gt=0, le=1e5)
    bodies: dict[str, _BodyInertia] = Field(default_factory=dict)


class _Trajectory(_Section):
    stroke_x_m: float = Field(ge=-10, le=10)
    stroke_y_m: float = Field(ge=-10, le=10)
    stroke_alpha_deg: float = Field(ge=-360, le=360)
    stroke_gamma_deg: float = Field(ge=-360, le=360)
    period_s: float = Field(ge=1e-3, le=1e6)
    samples: int = Field(ge=6)


class _Workspace(_Section):
    alpha_deg: float = Field(ge=-360, le=360)
    gamma_min_deg: float = Field(ge=-360, le=360)
    gamma_max_deg: float = Field(ge=-360, le=360)
    gamma_layers: int = Field(ge=1, le=361)
    directions: int = Field(ge=8, le=3600)
    radial_step_m: float = Field(ge=1e-6, le=10)
    max_radius_m: float = Field(gt=0, le=10)


class _Limits(_Section):
    """Plausibility limits on the run's size (docs/file_formats.md, "Limits"); raise them here."""

    max_samples: int = Field(default=200_000, gt=0)  # trajectory samples or motion-file rows
    max_workspace_points: int = Field(default=5_000_000, gt=0)  # layers x directions x ray samples
    max_limb_speed_m_s: float = Field(default=1.0, gt=0)  # |limb extension rate| of every sample
    max_limb_acceleration_m_s2: float = Field(default=20.0, gt=0)
    max_actuator_force_N: float = Field(default=5000.0, gt=0)  # |limb force| of every sample
    max_duration_s: float = Field(default=1e6, gt=0)  # duration of the motion


class _Description(_Section):
    geometry: _Geometry
    limbs: _Limbs
    material: _Material
    trajectory: _Trajectory
    workspace: _Workspace
    limits: _Limits = Field(default_factory=_Limits)
    inertia: _Inertia = Field(default_factory=_Inertia)


@dataclass(frozen=True)
class TrajectorySettings:
    """Eq. 84 amplitudes ``S = (S_x [m], S_y [m], S_alpha [rad], S_gamma [rad])``, period ``T`` [s]."""

    strokes: tuple[float, float, float, float]
    period_s: float
    samples: int


@dataclass(frozen=True)
class WorkspaceSettings:
    """Boundary-search settings (section 2.2): angles [rad], lengths [m]."""

    alpha_rad: float
    gamma_rad: tuple[float, ...]
    directions: int
    radial_step_m: float
    max_radius_m: float


@dataclass(frozen=True)
class PdmModel:
    """The PDM as plain numbers; every length in metres, every angle in radians, base frame A.

    Symbols follow the paper: ``r0 .. r4`` (App. A), ``n1`` (App. B). Index ``i = 0, 1`` is the
    paper's i = 1, 2 (cranks, couplers, RPR limbs); ``j = 0, 1`` is the paper's j = 3, 4 (SPU).

    ``R1`` (2, 3): crank pivots R11, R12. ``R4`` (2, 3): RPR ground pivots R41, R42.
    ``S`` (2, 3): SPU ground spherical joints S23, S24. ``U_local`` (2, 3): U23, U24 centres
    in the platform frame, relative to the output-link midpoint C (on the R4 axis).
    ``R3_local`` (2, 3): R31, R32 in the output-link frame relative to C.
    ``U1_local`` (3,): first U-joint axis, fixed in the platform (its x axis, parallel to R4).
    ``P_local`` (3,): platform point P in the platform frame relative to C, ``(0, 0, r0)``.
    ``home_lengths`` (4,): limb lengths l11, l12, l23, l24 at the home pose.

    Inertia and material (``pdm4.inertia``, docs/pdm4.md section 10), every body array in
    ``BODY_NAMES`` order: ``gravity`` (3,) [m/s^2], base frame; ``mass`` (14,) [kg];
    ``inertia`` (14, 3, 3) [kg m^2] about the centre of mass in the body's own frame (the frame
    of ``BodyState.R``); ``layer_z`` (14,) [m] z of each planar body's plane (0 for the platform
    and the SPU limbs, which are spatial); ``section_outer``, ``section_inner`` (14,) [m] outer
    and inner diameter of each body's section for its stiffness (Eq. 64; inner 0: solid rod);
    ``body_length`` (14,) [m] the rod or tube length used for its mass and inertia.
    """

    r0: float
    r1: float
    r2: float
    r3: float
    r4: float
    n1: float
    branch: tuple[int, int]
    R1: Array
    R4: Array
    S: Array
    U_local: Array
    R3_local: Array
    U1_local: Array
    P_local: Array
    home_lengths: Array
    stroke_limit: float
    cylinder_com: Array
    piston_com: Array
    min_transmission: float
    youngs_modulus_Pa: float
    poisson_ratio: float
    section_diameters: tuple[float, float, float]
    trajectory: TrajectorySettings
    workspace: WorkspaceSettings
    source: str
    gravity: Array
    mass: Array
    inertia: Array
    layer_z: Array
    section_outer: Array
    section_inner: Array
    body_length: Array
    #: ``[limits] max_samples``: trajectory samples or motion-file rows a run may hold
    max_samples: int = 200_000
    #: ``[limits]`` plausibility of a run's motion and forces: |limb rate| [m/s], |limb
    #: acceleration| [m/s^2], |actuator force| [N], motion duration [s] (``docs/file_formats.md``)
    max_limb_speed_m_s: float = 1.0
    max_limb_acceleration_m_s2: float = 20.0
    max_actuator_force_N: float = 5000.0
    max_duration_s: float = 1e6

    def __post_init__(self) -> None:
        for name in ("R1", "R4", "S", "U_local", "R3_local", "U1_local", "P_local",
                     "home_lengths", "cylinder_com", "piston_com", "gravity", "mass", "inertia",
                     "layer_z", "section_outer", "section_inner", "body_length"):
            getattr(self, name).setflags(write=False)


def default_params_path() -> Path:
    """Path of the built-in ``default.toml``."""
    return Path(str(resources.files("pkmdyn.machines.pdm4").joinpath("default.toml")))


def _validate(raw: dict[str, Any], name: str) -> _Description:
    return validate(_Description, raw, name)


def crank_angle(R1: Array, R3: Array, r2: float, r3: float, branch: Array) -> tuple[Array, Array]:
    """Crank angle theta_1i closing the loop R1i-R2i-R3i, Eq. 5-7 and App. B.

    Solves ``a cos(theta) + b sin(theta) = d`` (Eq. 6) with ``a = r2 dx``, ``b = r2 dy``,
    ``d = (dx^2 + dy^2 + r2^2 - r3^2) / 2``, ``(dx, dy) = R3i - R1i`` (App. B), as
    ``theta = atan2(b, a) + branch * atan2(sqrt(a^2 + b^2 - d^2), d)`` (Eq. 7).
    ``R1, R3`` (..., 3) [m]; ``branch`` broadcasts (+1 or -1). Returns ``theta`` [rad] and the
    discriminant ``a^2 + b^2 - d^2`` [m^4]; a negative one means the loop cannot close (the
    returned angle then uses a clipped root and must not be used). It lives with the parameters,
    which check the home pose with it, below the kinematics, which use it along a motion.
    """
    dx = R3[..., 0] - R1[..., 0]
    dy = R3[..., 1] - R1[..., 1]
    a, b = r2 * dx, r2 * dy
    d = 0.5 * (dx * dx + dy * dy + r2 * r2 - r3 * r3)
    disc = a * a + b * b - d * d
    theta = np.arctan2(b, a) + branch * np.arctan2(np.sqrt(np.maximum(disc, 0.0)), d)
    return theta, disc


def _unit(deg: float) -> Array:
    a = math.radians(deg)
    return np.array([math.cos(a), math.sin(a), 0.0])


def _build(d: _Description, name: str) -> PdmModel:
    g, lim = d.geometry, d.limbs
    r1, r2, r3, r4 = g.crank_pivot_spacing_m, g.crank_length_m, g.coupler_length_m, g.output_link_length_m
    side = np.array([-1.0, 1.0])
    R1 = np.stack([side * r1 / 2, np.full(2, g.crank_pivot_y_m), np.zeros(2)], axis=-1)
    R3_local = np.stack([side * r4 / 2, np.zeros(2), np.zeros(2)], axis=-1)
    branch = np.array(g.assembly_branch, dtype=float)
    theta1, disc = crank_angle(R1[None], R3_local[None], r2, r3, branch)
    if np.any(disc[0] < 0):
        raise ParameterError(
            f"{name}: [geometry] crank_pivot_y_m: the six-bar cannot close at the home pose "
            f"(|R1i R3i| = {abs(g.crank_pivot_y_m):g} m, crank + coupler = {r2 + r3:g} m)"
        )
    R2_home = R1 + r2 * np.stack([np.cos(theta1[0]), np.sin(theta1[0]), np.zeros(2)], axis=-1)
    rpr_dir = np.stack([_unit(a) for a in g.rpr_home_direction_deg])
    R4 = R2_home - g.rpr_home_length_m * rpr_dir
    U_local = np.stack([side * g.u_joint_half_spacing_m, np.zeros(2), np.full(2, g.u_joint_height_m)], axis=-1)
    el = math.radians(g.spu_home_elevation_deg)
    spu_dir = np.stack([_unit(a) * math.cos(el) + np.array([0.0, 0.0, math.sin(el)]) for a in g.spu_home_azimuth_deg])
    S = U_local - g.spu_home_length_m * spu_dir
    t, w = d.trajectory, d.workspace
    if w.gamma_max_deg < w.gamma_min_deg:
        raise ParameterError(f"{name}: [workspace] gamma_max_deg: must be >= gamma_min_deg")
    caps = d.limits
    check_limit(t.samples, caps.max_samples, f"{name}: [trajectory] samples", "max_samples", option=False)
    points = w.gamma_layers * w.directions * (math.floor(w.max_radius_m / w.radial_step_m + 0.5) + 1)
    check_limit(points, caps.max_workspace_points,
                f"{name}: [workspace] gamma_layers x directions x (max_radius_m / radial_step_m + 1)",
                "max_workspace_points", option=False)
    gammas = np.radians(np.linspace(w.gamma_min_deg, w.gamma_max_deg, w.gamma_layers))
    props = body_inertia(d, name, r2=r2, r3=r3, r4=r4)
    return PdmModel(
        r0=g.platform_offset_m, r1=r1, r2=r2, r3=r3, r4=r4, n1=g.crank_pivot_y_m,
        branch=(int(branch[0]), int(branch[1])),
        R1=R1, R4=R4, S=S, U_local=U_local, R3_local=R3_local,
        U1_local=np.array([1.0, 0.0, 0.0]),
        P_local=np.array([0.0, 0.0, g.platform_offset_m]),
        home_lengths=np.array([g.rpr_home_length_m] * 2 + [g.spu_home_length_m] * 2),
        stroke_limit=lim.stroke_limit_m,
        cylinder_com=np.array([lim.rpr_cylinder_com_m] * 2 + [lim.spu_cylinder_com_m] * 2),
        piston_com=np.array([lim.rpr_piston_com_m] * 2 + [lim.spu_piston_com_m] * 2),
        min_transmission=math.radians(lim.min_transmission_angle_deg),
        youngs_modulus_Pa=d.material.youngs_modulus_Pa,
        poisson_ratio=d.material.poisson_ratio,
        section_diameters=tuple(d.material.section_diameters_m),  # type: ignore[arg-type]
        trajectory=TrajectorySettings(
            strokes=(t.stroke_x_m, t.stroke_y_m, math.radians(t.stroke_alpha_deg), math.radians(t.stroke_gamma_deg)),
            period_s=t.period_s, samples=t.samples,
        ),
        workspace=WorkspaceSettings(
            alpha_rad=math.radians(w.alpha_deg), gamma_rad=tuple(float(x) for x in gammas),
            directions=w.directions, radial_step_m=w.radial_step_m, max_radius_m=w.max_radius_m,
        ),
        source=name,
        max_samples=caps.max_samples,
        max_limb_speed_m_s=caps.max_limb_speed_m_s,
        max_limb_acceleration_m_s2=caps.max_limb_acceleration_m_s2,
        max_actuator_force_N=caps.max_actuator_force_N,
        max_duration_s=caps.max_duration_s,
        **props,
    )


def load_params(path: str | Path | None = None) -> PdmModel:
    """Read, validate and build a :class:`PdmModel`; ``None`` reads the built-in defaults.

    Raises :class:`~pkmdyn.errors.ParameterError` naming the file by its full path, the
    section and the key, e.g. ``"/home/me/params.toml: [geometry] crank_length_m: must be > 0"``.
    """
    p = (default_params_path() if path is None else Path(path)).absolute()
    name = str(p)
    return _build(_validate(read_toml(p), name), name)


def params_from_dict(raw: dict[str, Any], name: str = "<dict>") -> PdmModel:
    """Build a model from an already parsed description (same validation as :func:`load_params`)."""
    return _build(_validate(raw, name), name)
