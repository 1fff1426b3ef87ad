"""The ``report.html`` of ``pdm run``: the mechanism animated from ``bodies.npz``'s joint points,
limb motion, actuator forces and over-constrained reactions against time, the PNG figures, the
summary and the parameters."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ...report import Curve, Report, TimePlot
from .paper import REDUNDANT_LABELS
from .params import PdmModel, default_params_path
from .scene import pdm_scene

__all__ = ["run_report", "run_plots", "parameters_text"]

Array = NDArray[np.float64]
_LIMBS = ("l11", "l12", "l23", "l24")


def parameters_text(params_path: str | Path | None) -> str:
    """The parameter file's text (the built-in file when None), headed by where it came from."""
    path = Path(params_path) if params_path is not None else default_params_path()
    head = f"# {path}" if params_path is not None else "# built-in parameters (pkmdyn/machines/pdm4/default.toml)"
    try:
        return head + "\n" + path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return head + "\n# (the file could not be read again for the report)"


def run_plots(cols: dict[str, Array]) -> list[TimePlot]:
    """The time plots of a run from its ``results.csv`` columns."""
    t = cols["t_s"]

    def limbs(prefix: str, scale: float) -> tuple[Curve, ...]:
        return tuple(Curve(_LIMBS[k], cols[f"{prefix}{k + 1}{'_m' if prefix == 's' else ''}"] * scale)
                     for k in range(4))

    return [
        TimePlot("Platform pose: position of P", "position [mm]", t,
                 (Curve("x", cols["x_m"] * 1e3), Curve("y", cols["y_m"] * 1e3), Curve("z (parasitic)", cols["z_m"] * 1e3))),
        TimePlot("Platform pose: angles", "angle [deg]", t,
                 (Curve("alpha", np.degrees(cols["alpha_rad"])), Curve("gamma", np.degrees(cols["gamma_rad"])))),
        TimePlot("Limb extension l - l_home", "extension [mm]", t,
                 tuple(Curve(_LIMBS[k], cols[f"s{k + 1}_m"] * 1e3) for k in range(4))),
        TimePlot("Limb velocity", "velocity [mm/s]", t,
                 tuple(Curve(_LIMBS[k], cols[f"ld{k + 1}_m_s"] * 1e3) for k in range(4))),
        TimePlot("Limb acceleration", "acceleration [mm/s^2]", t,
                 tuple(Curve(_LIMBS[k], cols[f"ldd{k + 1}_m_s2"] * 1e3) for k in range(4))),
        TimePlot("Actuator forces", "force [N]", t, tuple(Curve(f"limb {_LIMBS[k]}", cols[f"f{k + 1}_N"])
                                                           for k in range(4))),
        TimePlot("Over-constrained reactions: forces along z", "force [N]", t,
                 tuple(Curve(lab, cols[lab]) for lab in REDUNDANT_LABELS if lab.endswith("_fz_N"))),
        TimePlot("Over-constrained reactions: moments about x and y", "moment [N m]", t,
                 tuple(Curve(lab, cols[lab]) for lab in REDUNDANT_LABELS if not lab.endswith("_fz_N"))),
        TimePlot("U-joint constraint torques", "torque [N m]", t,
                 (Curve("U23", cols["U23_torque_Nm"]), Curve("U24", cols["U24_torque_Nm"]))),
    ]


def run_report(model: PdmModel, params_path: str | Path | None, motion_source: str, cols: dict[str, Array],
               npz: dict[str, Array], images: list[str]) -> Report:
    """The content of a run's ``report.html`` (``images``: the labels of the run's PNG files)."""
    force = np.stack([cols[f"f{k}_N"] for k in range(1, 5)], axis=-1)
    P = np.stack([cols["x_m"], cols["y_m"], cols["z_m"]], axis=-1)
    scene = pdm_scene(npz["t"], npz["joint_point"], force, P)
    return Report(
        "4-DOF PDM: pdm run", scene=scene, plots=run_plots(cols), parameters=parameters_text(params_path),
        images=images, notes=[f"parameters: {model.source}", f"motion: {motion_source}"],
        scene_note="Joint centres as in bodies.npz (joint_point); the orange line is the path of the platform point P.")
