"""The hip simulator's control adapter (:class:`pkmdyn.control_protocol.ControlJob`): its models
and motions, the columns and labels of ``control.csv`` and its plots, the posture-error figure
(the paper's Fig. 7) and the 3D scene of ``pkmdyn hip control``.

The dynamics are the generic engine's (:class:`pkmdyn.multibody.dynamics.verbs.MechanismVerbs`) on the
hip's description (:func:`.description.hip_description`), under the paper's names: coordinates
``alpha_rad, beta_rad, gamma_rad`` (the description's ``euler1_rad .. euler3_rad``, the upper
platform's Euler angles in the parameter file's sequence), efforts ``tau1_Nm .. tau3_Nm`` (the
motors ``motor_1 .. motor_3``), load the hydraulic force [N] (the named load ``hydraulic_N``). A
model is a :class:`pkmdyn.machines.generated.GeneratedModel`: the parameters (for the motion and the report) and their
compiled description. The 3D scene is the engine's drawing of the description (each body
through its joint centres, the actuated sliders as chains coloured by their motor's torque).
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..._lazy import lazy_module
from ...control_protocol import BuiltinMotion, JointColumn, MotionTable
from ...errors import MotionError
from ...profiles.iso14242 import angle_wave, iso_load
from ...profiles.orientation import read_motion_csv
from ...report import TimePlot

if TYPE_CHECKING:
    from ... import multibody as _multibody
    from ... import params_util as _params_util
    from ...multibody import scene as _scene
    from .. import generated as _generated
    from . import description as _description
    from . import paper as _paper
    from . import params as _params
else:  # loaded when a command runs, not on import (nor for --help)
    _description = lazy_module("pkmdyn.machines.hip_simulator.description")
    _paper = lazy_module("pkmdyn.machines.hip_simulator.paper")
    _params = lazy_module("pkmdyn.machines.hip_simulator.params")
    _multibody = lazy_module("pkmdyn.multibody")
    _generated = lazy_module("pkmdyn.machines.generated")
    _scene = lazy_module("pkmdyn.multibody.scene")
    _params_util = lazy_module("pkmdyn.params_util")

NAME = "hip"
CONTROLLERS = ("pd", "augmented-pd", "feedforward", "computed-torque")
SUBJECT = "the hip simulator"
REPORT_NAME = "2(3PUS+S) hip simulator"
HAS_LOAD = True
ATTITUDE_COLUMNS = True
TRAVEL_UNIT = "rad"
EFFORT_QUANTITY = "torque"
EFFORTS_TITLE = "motor torques"
#: clinical names of the Euler angles (FE, AA, IER)
COORDINATE_NAMES = {"alpha": "alpha (FE)", "beta": "beta (AA)", "gamma": "gamma (IER)"}
#: the paper's task coordinates and motor torques, in the description's order
COORDINATES = ("alpha_rad", "beta_rad", "gamma_rad")
ACTUATORS = ("tau1_Nm", "tau2_Nm", "tau3_Nm")


def control_model(params: Any) -> Any:
    """The control model of the parameters ``params`` (their description compiled)."""

    return _generated.GeneratedModel(params, _multibody.load_mechanism(_description.hip_description(params)))


def verbs(model: Any) -> Any:
    return _generated.RenamedVerbs(model.mechanism, COORDINATES, ACTUATORS)


def read_description(params: Path | None) -> tuple[dict[str, Any], str]:

    if params is None:
        return _params.default_params_dict(), "built-in parameters"
    return _params_util.read_toml(params), str(params)


def model_from_dict(description: dict[str, Any], source: str) -> Any:
    return control_model(_params.model_from_dict(copy.deepcopy(description), source))


def load_params(path: Path) -> Any:
    return control_model(_params.load_params(path))


def notes(model: Any) -> list[str]:
    """What the run says of the model's parameter file: its ``friction_velocity_eps_*`` where the
    engine does not use them (:func:`.paper.regularisation_note`, as ``hip run`` says it)."""
    note = _paper.regularisation_note(model.params)
    return [] if note is None else [note]


def builtin_motion(model: Any, cycles: float) -> BuiltinMotion:
    """``cycles`` ISO 14242-1 cycles of the model's cycle model, with the hydraulic load."""
    cyc = _paper.iso_cycle_preset(model.params.motion_model)

    def fn(t: np.ndarray) -> tuple:
        w = [angle_wave(t, cyc.period_s, x) for x in (cyc.fe, cyc.aa, cyc.ier)]
        return (np.stack([a[0] for a in w], -1), np.stack([a[1] for a in w], -1),
                np.stack([a[2] for a in w], -1), iso_load(t, cyc))

    duration = cycles * cyc.period_s
    return BuiltinMotion(fn, duration, f"built-in ISO 14242-1 cycle model ({model.params.motion_model}), {cycles:g} cycle(s)",
                         max(duration, cyc.period_s), cyc.period_s)


def read_motion(model: Any, path: Path) -> MotionTable:
    """A posture-angle motion file (:func:`pkmdyn.profiles.orientation.read_motion_csv`); its
    load may not exceed the model's ``max_load_N``."""
    mo = read_motion_csv(path)
    if mo.load is not None:
        lim = float(model.params.limits.max_load_N)
        big = np.flatnonzero(np.abs(mo.load) > lim)
        if big.size:
            raise MotionError(f"{path}: row {big[0] + 1}, column 'load_N': {mo.load[big[0]]:g} N is above "
                              f"max_load_N = {lim:g} N ([limits] of the parameter file)")
    return MotionTable(mo.t, mo.angles, mo.rates, mo.accels, mo.load)


def joint_columns() -> list[JointColumn]:
    return [(f"motor{a + 1}", 1.0, "rad", "rad_s", "rad_s2") for a in range(3)]


def effort_label(a: int) -> tuple[str, str]:
    return f"motor {a + 1} torque", "N m"


def plot_curves(reference_q: np.ndarray, result: Any, joint: Any) -> dict[str, np.ndarray]:
    return {"err_deg": np.rad2deg(reference_q[:result.t.shape[0]] - result.q)}


def figures(draw: Callable[..., None], t: np.ndarray, first: dict[str, np.ndarray], lo: dict[str, np.ndarray],
            hi: dict[str, np.ndarray], heading: str, folder: Path) -> list[Path]:
    """``posture_errors.png``: the AA, IER and FE errors (the paper's Fig. 7 order)."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(13, 4.2))
    for ax, c, label in zip(axes, (1, 2, 0), ("(a) AA error", "(b) IER error", "(c) FE error")):
        draw(ax, t, first["err_deg"][:, c], lo["err_deg"][:, c], hi["err_deg"][:, c], None, lw=0.8)
        ax.set(xlabel="t [s]", ylabel="error [deg]", title=label)
        ax.grid(alpha=0.3)
    fig.suptitle(f"Posture-angle errors, {heading}")
    fig.tight_layout()
    p = folder / "posture_errors.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    return [p]


def report_plots(curve: Callable[[str, int, str], Any], t: np.ndarray, note: str) -> list[Any]:
    return [TimePlot("Posture-angle errors", "error [deg]", t,
                     tuple(curve("err_deg", c, n) for c, n in enumerate(COORDINATE_NAMES.values())), note)]


def scene(model: Any, t: np.ndarray, q: np.ndarray, u: np.ndarray) -> Any:
    """The engine's scene of the description along the plant's angles ``q``, each slider's
    chain coloured by its motor's torque ``u``."""
    return _scene.motion_scene(model.mechanism, t, q, u, tuple(effort_label(a) for a in range(3)))


def parameters_text(params: str | None) -> str:
    """The parameter file's text (the built-in file when None), headed by where it came from."""
    return _paper.parameters_text(params)
