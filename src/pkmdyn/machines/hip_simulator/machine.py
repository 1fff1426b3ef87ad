"""The hip simulator's entry in the machine registry (:mod:`pkmdyn.machines.registry`).

What the machine-independent layers need to know of this machine, in one place: its name,
its built-in parameter and control settings files, its description for the multibody layer
and its default motion.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..._lazy import lazy_module
from ...profiles.iso14242 import iso14242_motion

if TYPE_CHECKING:
    from ... import multibody as _multibody
    from . import description as _description
    from . import paper as _paper
    from . import params as _params
else:  # loaded when a command runs, not on import (nor for --help)
    _description = lazy_module("pkmdyn.machines.hip_simulator.description")
    _paper = lazy_module("pkmdyn.machines.hip_simulator.paper")
    _params = lazy_module("pkmdyn.machines.hip_simulator.params")
    _multibody = lazy_module("pkmdyn.multibody")

NAME = "hip"
TITLE = "2(3PUS+S) dual-platform hip-joint wear simulator (Chen, Cheng & Pang 2022); see pkmdyn hip --help"
#: the built-in control settings (``--gains``; :mod:`pkmdyn.control`)
CONTROL_SETTINGS = Path(__file__).with_name("control.toml")
#: the machine's commands for ``pkmdyn compile`` (:data:`pkmdyn.cli.compile.LANES`): ``(lane, command
#: line without --out)``; lane 0 the closed loops, lane 1 the batched kinematics and dynamics
COMPILE_EXERCISES = (
    (0, ("hip", "control", "--controller", "augmented-pd", "--cycles", "0.01", "--no-plots")),
    (0, ("hip", "control", "--controller", "feedforward", "--cycles", "0.01", "--no-plots")),
    (0, ("hip", "control", "--controller", "computed-torque", "--cycles", "0.01", "--no-plots")),
    (1, ("wear", "--machine", "hip", "--joint", "S0_upper", "--radius-m", "0.014")),
    (1, ("hip", "run", "--samples-per-cycle", "64", "--no-plots")),
)


def default_params_text() -> str:
    """The built-in parameter file, to edit and pass as ``--params``."""
    return _params.DEFAULT_PARAMS_TEXT


def description(params: Path | None = None) -> dict[str, Any]:
    """The machine of the parameter file ``params`` (default: the built-in one) as a mechanism
    description (:mod:`pkmdyn.multibody`)."""

    return _description.hip_description(_params.load_params(params))


def default_motion() -> Any:
    """One ISO 14242-1 cycle of the built-in parameters' cycle model (1000 samples), as a
    :class:`pkmdyn.multibody.TaskMotion` in the description's task order, with its hydraulic
    load as the description's named load ``hydraulic_N``."""

    m = iso14242_motion(cycles=1, samples_per_cycle=1000, cycle=_paper.iso_cycle_preset(_params.load_params().motion_model))
    return _multibody.TaskMotion(m.t, m.angles, m.rates, m.accels, {"hydraulic_N": m.load})


def parameters_text(params: Path | None) -> str:
    """The parameter file's text (the built-in file when None), headed by where it came from."""
    return _paper.parameters_text(params)
