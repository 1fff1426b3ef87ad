"""Inertia and material model of the PDM's 14 bodies (issue 7 item 1; Table II is missing).

Every body is a homogeneous straight rod or tube of the App. A diameters and the density of
``[inertia] density_kg_m3`` (CHOSEN: aluminium, 2700 kg/m^3), lying along the x axis of the
body's own frame with its centre of mass at mid-length (section 4.2: "their centres of masses
lie at their midlengths"). With outer and inner diameters ``Do, Di`` and length ``L``:

    m = rho pi (Do^2 - Di^2) L / 4,
    I_xx = m (Do^2 + Di^2) / 8,   I_yy = I_zz = m (L^2 / 12 + (Do^2 + Di^2) / 16).

Assignment of the App. A diameters (CHOSEN, docs/pdm4.md section 10):

- D1 (35 mm): cranks r2i and couplers r3i (the paper's one flexibility C1 serves r21 and r31,
  Eq. 74), solid;
- D2 (60 mm): output link r4 (its own flexibility C2, Eq. 75, the link that carries R4 and the
  platform), the platform (a rod of length 2 g1 between the U joints) and the outer diameter of
  the four cylinders (tubes of wall ``[material] cylinder_wall_m``);
- D3 (30 mm): the four piston rods, solid.

Lengths: r2, r3, r4; 2 g1 for the platform; ``2 c1`` for a cylinder and ``2 c3`` for a piston
(so that their centres of mass sit at ``c1`` from the fixed joint and ``c3`` from the moving
joint, as the ``[limbs]`` keys say). ``[material] stiffness_diameters_m`` overrides the outer
diameter of named links for their stiffness only (Eq. 64; mass and inertia stay those of the
D1-D3 rods, so one link's section can change with every mass held); ``[inertia.bodies.<name>]``
overrides ``mass_kg`` (the derived inertia then scales with it) and/or ``inertia_kgm2``
(3 x 3, about the centre of mass, in the body's frame: symmetric, positive definite, and its
principal moments obey the triangle inequality).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...errors import ParameterError

__all__ = ["body_inertia", "rod_properties", "ELASTIC_BODIES"]

Array = NDArray[np.float64]

#: the body order of every per-body array (same as ``kinematics.BODY_NAMES``)
_NAMES = (
    "platform", "link4", "crank1", "crank2", "coupler1", "coupler2",
    "cylinder1", "cylinder2", "cylinder3", "cylinder4", "piston1", "piston2", "piston3", "piston4",
)
#: the links whose elasticity makes the reactions unique (section 5: the operating mechanism
#: and the two RPR limbs; the platform and the SPU limbs carry no redundant reaction)
ELASTIC_BODIES = ("link4", "crank1", "crank2", "coupler1", "coupler2",
                  "cylinder1", "cylinder2", "piston1", "piston2")


def rod_properties(rho: float, Do: float, Di: float, L: float) -> tuple[float, Array]:
    """Mass [kg] and inertia (3, 3) [kg m^2] about the centre of a rod/tube along x."""
    m = rho * math.pi * (Do * Do - Di * Di) * L / 4.0
    ia = m * (Do * Do + Di * Di) / 8.0
    it = m * (L * L / 12.0 + (Do * Do + Di * Di) / 16.0)
    return m, np.diag([ia, it, it])


def _check_tensor(value: Any, where: str) -> Array:
    try:
        J = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"{where}: must be a 3 x 3 table of numbers") from None
    if J.shape != (3, 3) or not np.all(np.isfinite(J)):
        raise ParameterError(f"{where}: must be a 3 x 3 table of finite numbers")
    scale = np.abs(J).max()
    if scale <= 0:
        raise ParameterError(f"{where}: must be positive definite (all zero)")
    if np.abs(J - J.T).max() > 1e-9 * scale:
        raise ParameterError(f"{where}: must be symmetric")
    ev = np.linalg.eigvalsh(J)
    if ev[0] <= 1e-12 * scale:
        raise ParameterError(f"{where}: must be positive definite (smallest principal moment {ev[0]:.6g} kg m^2)")
    if ev[2] > ev[0] + ev[1] + 1e-12 * scale:
        raise ParameterError(
            f"{where}: principal moments {ev[0]:.6g}, {ev[1]:.6g}, {ev[2]:.6g} kg m^2 violate the triangle "
            "inequality (the largest exceeds the sum of the other two)")
    return 0.5 * (J + J.T)


def body_inertia(d: Any, name: str, r2: float, r3: float, r4: float) -> dict[str, Array]:
    """Gravity, masses, inertias, layers and sections of the 14 bodies from a validated description.

    ``d``: the validated description (its ``geometry``, ``limbs``, ``material``, ``inertia``
    tables); ``name``: the file name for messages. Returns the :class:`PdmModel` fields
    ``gravity, mass, inertia, layer_z, section_outer, section_inner, body_length``.
    """
    g, lim, mat, ine = d.geometry, d.limbs, d.material, d.inertia
    D1, D2, D3 = mat.section_diameters_m
    wall = mat.cylinder_wall_m
    lengths = {
        "platform": (2.0 * g.u_joint_half_spacing_m, "[geometry] u_joint_half_spacing_m"),
        "link4": (r4, "[geometry] output_link_length_m"),
        "crank1": (r2, ""), "crank2": (r2, ""), "coupler1": (r3, ""), "coupler2": (r3, ""),
    }
    for k in range(4):
        kind = "rpr" if k < 2 else "spu"
        lengths[f"cylinder{k + 1}"] = (2.0 * getattr(lim, f"{kind}_cylinder_com_m"), f"[limbs] {kind}_cylinder_com_m")
        lengths[f"piston{k + 1}"] = (2.0 * getattr(lim, f"{kind}_piston_com_m"), f"[limbs] {kind}_piston_com_m")
    outer = {"platform": D2, "link4": D2, "crank1": D1, "crank2": D1, "coupler1": D1, "coupler2": D1}
    outer.update({f"cylinder{k}": D2 for k in range(1, 5)})
    outer.update({f"piston{k}": D3 for k in range(1, 5)})
    stiff = dict(outer)
    for body, D in mat.stiffness_diameters_m.items():
        if body not in _NAMES:
            raise ParameterError(f"{name}: [material] stiffness_diameters_m: unknown body {body!r} "
                                 f"(one of {', '.join(_NAMES)})")
        stiff[body] = D
    for body in ine.bodies:
        if body not in _NAMES:
            raise ParameterError(f"{name}: [inertia.bodies] {body}: unknown body (one of {', '.join(_NAMES)})")
    layer = {"crank": g.crank_layer_z_m, "coupler": g.coupler_layer_z_m}
    n = len(_NAMES)
    mass, inertia = np.zeros(n), np.zeros((n, 3, 3))
    Do, Di, Ls, lz = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
    for b, body in enumerate(_NAMES):
        L, key = lengths[body]
        Do[b], inner = stiff[body], 0.0
        if body.startswith("cylinder"):
            if 2.0 * wall >= min(Do[b], outer[body]):
                raise ParameterError(f"{name}: [material] cylinder_wall_m: must be less than half the cylinder "
                                     f"diameter ({min(Do[b], outer[body]):g} m for {body})")
            Di[b] = Do[b] - 2.0 * wall
            inner = outer[body] - 2.0 * wall
        Ls[b] = L
        over = ine.bodies.get(body)
        if L <= 0 and (over is None or over.mass_kg is None or over.inertia_kgm2 is None):
            raise ParameterError(f"{name}: {key}: must be > 0 to derive the mass of {body} "
                                 f"(or give [inertia.bodies.{body}] mass_kg and inertia_kgm2)")
        m, J = rod_properties(ine.density_kg_m3, outer[body], inner, L) if L > 0 else (1.0, np.eye(3))
        if over is not None and over.mass_kg is not None:
            J = J * (over.mass_kg / m)
            m = over.mass_kg
        if over is not None and over.inertia_kgm2 is not None:
            J = _check_tensor(over.inertia_kgm2, f"{name}: [inertia.bodies.{body}] inertia_kgm2")
        mass[b], inertia[b] = m, J
        if body.startswith(("crank", "coupler")):
            lz[b] = layer[body.rstrip("12")]
        elif body in ("cylinder1", "cylinder2", "piston1", "piston2"):
            lz[b] = g.rpr_limb_layer_z_m
    return {
        "gravity": np.array(ine.gravity_m_s2, dtype=float),
        "mass": mass, "inertia": inertia, "layer_z": lz,
        "section_outer": Do, "section_inner": Di, "body_length": Ls,
    }
