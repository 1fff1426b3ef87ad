"""The PDM's control adapter (:class:`pkmdyn.control_protocol.ControlJob`): its models and
motions, the columns and labels of ``control.csv`` and its plots, the limb-tracking figure (the
paper's Fig. 26) and the 3D scene of ``pkmdyn pdm control``.

The dynamics are the generic engine's (:class:`pkmdyn.multibody.dynamics.verbs.MechanismVerbs`) on the
PDM's description (:func:`.description.pdm_description`), under the paper's names: coordinates
``x_m, y_m, alpha_rad, gamma_rad``, efforts ``f1_N .. f4_N`` (the limbs l11, l12, l23, l24; the
description's ``P11 .. P24`` in the same order). A model is a :class:`pkmdyn.machines.generated.GeneratedModel`: the
parameters (for the motion and the scene) and their compiled description.
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..._lazy import lazy_module
from ...control_protocol import BuiltinMotion, JointColumn, MotionTable
from ...profiles.cycloidal import cycloidal
from ...profiles.pdm_motion import read_pdm_motion
from ...report import TimePlot

if TYPE_CHECKING:
    from ... import multibody as _multibody
    from ... import params_util as _params_util
    from .. import generated as _generated
    from . import description as _description
    from . import params as _params
    from . import report as _report
    from . import scene as _scene
else:  # loaded when a command runs, not on import (nor for --help)
    _description = lazy_module("pkmdyn.machines.pdm4.description")
    _params = lazy_module("pkmdyn.machines.pdm4.params")
    _report = lazy_module("pkmdyn.machines.pdm4.report")
    _scene = lazy_module("pkmdyn.machines.pdm4.scene")
    _multibody = lazy_module("pkmdyn.multibody")
    _generated = lazy_module("pkmdyn.machines.generated")
    _params_util = lazy_module("pkmdyn.params_util")

NAME = "pdm"
CONTROLLERS = ("pid", "feedforward", "computed-torque")
SUBJECT = "the PDM"
REPORT_NAME = "4-DOF PDM"
HAS_LOAD = False
ATTITUDE_COLUMNS = False
TRAVEL_UNIT = "m"
EFFORT_QUANTITY = "force"
EFFORTS_TITLE = "limb forces"
COORDINATE_NAMES: dict[str, str] = {}
#: limb names, in the order of the actuators (``l{k}_m`` columns)
LIMBS = ("l11", "l12", "l23", "l24")
#: the paper's task coordinates (Eq. 2-4) and actuator efforts, in the description's order
COORDINATES = ("x_m", "y_m", "alpha_rad", "gamma_rad")
ACTUATORS = ("f1_N", "f2_N", "f3_N", "f4_N")


def control_model(params: Any) -> Any:

    return _generated.GeneratedModel(params, _multibody.load_mechanism(_description.pdm_description(params)))


def verbs(model: Any) -> Any:
    return _generated.RenamedVerbs(model.mechanism, COORDINATES, ACTUATORS)


def read_description(params: Path | None) -> tuple[dict[str, Any], str]:

    source = (_params.default_params_path() if params is None else Path(params)).absolute()
    return _params_util.read_toml(source), str(source)


def model_from_dict(description: dict[str, Any], source: str) -> Any:
    return control_model(_params.params_from_dict(copy.deepcopy(description), source))


def load_params(path: Path) -> Any:
    return control_model(_params.load_params(path))


def builtin_motion(model: Any, cycles: float) -> BuiltinMotion:
    """``cycles`` strokes of the Eq. 84 cycloidal motion of the model's ``[trajectory]``,
    alternately out and back."""
    tr = model.params.trajectory
    S, P = np.asarray(tr.strokes, dtype=float), float(tr.period_s)
    n_cyc = max(1, int(np.ceil(cycles - 1e-9)))

    def fn(t: np.ndarray) -> tuple:
        t = np.asarray(t, dtype=float)
        c = np.clip(np.floor(t / P), 0, n_cyc - 1)
        tau = np.clip(t - c * P, 0.0, P)
        s, sd, sdd = cycloidal(tau, S, P)
        back = (c % 2 == 1)[:, None]
        return (np.where(back, S - s, s), np.where(back, -sd, sd), np.where(back, -sdd, sdd), None)

    duration = cycles * P
    return BuiltinMotion(fn, duration, f"Eq. 84 cycloidal motion of the parameter file, {cycles:g} stroke(s), "
                         "alternately out and back", max(duration, P), 2.0 * P)


def read_motion(model: Any, path: Path) -> MotionTable:
    """A PDM motion file (:func:`pkmdyn.profiles.pdm_motion.read_pdm_motion`)."""
    mo = read_pdm_motion(path)
    return MotionTable(mo.t, mo.q, mo.qd, mo.qdd, None)


def joint_columns() -> list[JointColumn]:
    return [(n, 1e3, "mm", "mm_s", "mm_s2") for n in LIMBS]


def effort_label(a: int) -> tuple[str, str]:
    return f"limb {LIMBS[a]} force", "N"


def plot_curves(reference_q: np.ndarray, result: Any, joint: Any) -> dict[str, np.ndarray]:
    K = result.t.shape[0]
    out = {}
    for key, th, me in (("s", joint.s, result.s_enc), ("sd", joint.sd, result.sd_enc),
                        ("sdd", joint.sdd, result.sdd_enc)):
        out[f"{key}_th"], out[f"{key}_me"] = th[:K] * 1e3, me * 1e3
    return out


def figures(draw: Callable[..., None], t: np.ndarray, first: dict[str, np.ndarray], lo: dict[str, np.ndarray],
            hi: dict[str, np.ndarray], heading: str, folder: Path) -> list[Path]:
    """``limb_tracking.png``: measured and theoretical limb displacement, velocity and
    acceleration (the paper's Fig. 26)."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 4, figsize=(15, 9.4), sharex=True)
    rows = (("s", "displacement [mm]"), ("sd", "velocity [mm/s]"), ("sdd", "acceleration [mm/s^2]"))
    for i, (key, lab) in enumerate(rows):
        for a in range(4):
            ax = axes[i, a]
            draw(ax, t, first[f"{key}_th"][:, a], lo[f"{key}_th"][:, a], hi[f"{key}_th"][:, a], "theoretical", lw=1.0)
            draw(ax, t, first[f"{key}_me"][:, a], lo[f"{key}_me"][:, a], hi[f"{key}_me"][:, a], "measured", lw=0.8,
                 ls="--")
            ax.grid(alpha=0.3)
            if i == 0:
                ax.set_title(f"limb {LIMBS[a]}")
            if a == 0:
                ax.set_ylabel(lab)
            if i == 2:
                ax.set_xlabel("t [s]")
    axes[0, 0].legend()
    fig.suptitle(f"Measured and theoretical limb motion, {heading}")
    fig.tight_layout()
    p = folder / "limb_tracking.png"
    fig.savefig(p, dpi=100)
    plt.close(fig)
    return [p]


def report_plots(curve: Callable[[str, int, str], Any], t: np.ndarray, note: str) -> list[Any]:
    return [TimePlot(f"Limb {lab}: theoretical and measured", f"{lab} [{unit}]", t, tuple(
        c for a, nm in enumerate(LIMBS) for c in (curve(f"{key}_th", a, f"{nm} theoretical"),
                                                  curve(f"{key}_me", a, f"{nm} measured"))), note)
        for key, lab, unit in (("s", "displacement", "mm"), ("sd", "velocity", "mm/s"),
                               ("sdd", "acceleration", "mm/s^2"))]


def scene(model: Any, t: np.ndarray, q: np.ndarray, u: np.ndarray) -> Any:
    return _scene.pdm_scene_from_pose(model.params, t, q, u)


def parameters_text(params: str | None) -> str:
    return _report.parameters_text(params)
