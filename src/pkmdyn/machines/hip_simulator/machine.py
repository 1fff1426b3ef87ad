"""The hip simulator's entry in the machine registry (:mod:`pkmdyn.machines.registry`).

What the machine-independent layers need to know of this machine, in one place: its name,
its built-in parameter and control settings files, its description for the multibody layer
and its default motion.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ...profiles.iso14242 import iso14242_motion

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
    from .params import DEFAULT_PARAMS_TEXT

    return DEFAULT_PARAMS_TEXT


def description(params: Path | None = None) -> dict[str, Any]:
    """The machine of the parameter file ``params`` (default: the built-in one) as a mechanism
    description (:mod:`pkmdyn.multibody`)."""
    from .description import hip_description
    from .params import load_params

    return hip_description(load_params(params))


def default_motion() -> Any:
    """One ISO 14242-1 cycle of the built-in parameters' cycle model (1000 samples), as a
    :class:`pkmdyn.multibody.TaskMotion` in the description's task order, with its hydraulic
    load as the description's named load ``hydraulic_N``."""
    from ...multibody import TaskMotion
    from .paper import iso_cycle_preset
    from .params import load_params

    m = iso14242_motion(cycles=1, samples_per_cycle=1000, cycle=iso_cycle_preset(load_params().motion_model))
    return TaskMotion(m.t, m.angles, m.rates, m.accels, {"hydraulic_N": m.load})


def parameters_text(params: Path | None) -> str:
    """The parameter file's text (the built-in file when None), headed by where it came from."""
    from .paper import parameters_text as text

    return text(params)
