"""What a generated machine provides to its closed-loop control job (the protocol between the
control job, :mod:`pkmdyn.jobs.control`, and the machines; it sits below both, so that a
machine never imports the command and the command never names a machine).

A machine's control adapter is a module (``machines/<machine>/control_job.py``, found by
:func:`pkmdyn.machines.registry.control_adapter`) with the constants and free functions of
:class:`ControlJob`. The command builds the loop (:mod:`pkmdyn.control`, :mod:`pkmdyn.simulate`)
and writes the files; the adapter says what is the machine's own: its models and motions, its
column names and labels, its figures and its 3D scene. A described mechanism has no adapter: the
command uses the generic columns and labels of its description.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np

__all__ = ["ControlJob", "BuiltinMotion", "MotionTable", "JointColumn"]


@dataclass(frozen=True)
class BuiltinMotion:
    """A machine's built-in motion for a run: ``fn(t) -> (q, qd, qdd, load or None)`` at times
    ``t`` [s] (arrays of shape ``(n, nq)``, load ``(n,)`` [N]), the run's duration and source line,
    the whole motion ``span_s`` [s] (a full cycle even for part of one) and the period the plots
    fold the run by (``fold_s`` [s], 0: none)."""

    fn: Callable[[np.ndarray], tuple]
    duration_s: float
    source: str
    span_s: float
    fold_s: float


@dataclass(frozen=True)
class MotionTable:
    """A motion read from a file: samples ``t`` [s] of the coordinates, their rates and
    accelerations (SI, ``(n, nq)``) and the load [N] or None; the command interpolates them
    (:func:`pkmdyn.control.hermite_motion`)."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    load: np.ndarray | None


#: one actuated joint's columns in ``control.csv``: its name, the scale from SI to the file unit,
#: and the units of its displacement, rate and acceleration (``("l11", 1e3, "mm", "mm_s", "mm_s2")``)
JointColumn = tuple[str, float, str, str, str]


class ControlJob(Protocol):
    """The constants and functions of a machine's control adapter."""

    #: the registry name of the machine
    NAME: str
    #: the controllers it runs (:mod:`pkmdyn.control`)
    CONTROLLERS: tuple[str, ...]
    #: the machine in a sentence's subject ("the PDM", "the machine")
    SUBJECT: str
    #: the machine in a report's title
    REPORT_NAME: str
    #: whether its motion carries a load (the loop's ``has_load``)
    HAS_LOAD: bool
    #: whether ``control.csv`` carries the attitude sensor's columns (``<coordinate>_attitude_<unit>``)
    ATTITUDE_COLUMNS: bool
    #: the unit of an actuator's travel (encoder messages)
    TRAVEL_UNIT: str
    #: the actuators' efforts in a plot's axis and title ("torque", "motor torques")
    EFFORT_QUANTITY: str
    EFFORTS_TITLE: str
    #: names of its task coordinates in messages, by their column base (``{"alpha": "alpha (flexion)"}``)
    COORDINATE_NAMES: dict[str, str]

    def verbs(self, model: Any) -> Any:
        """The machine's verbs (:mod:`pkmdyn.simulate`) for ``model`` and models like it (the
        plant's)."""
        ...

    def read_description(self, params: Path | None) -> tuple[dict[str, Any], str]:
        """The parameter file (None: the built-in one) as a dict, read once, and its source line."""
        ...

    def model_from_dict(self, description: dict[str, Any], source: str) -> Any:
        """The machine's model from a parameter dict (errors name the file and key)."""
        ...

    def load_params(self, path: Path) -> Any:
        """The machine's model from a parameter file."""
        ...

    def builtin_motion(self, model: Any, cycles: float) -> BuiltinMotion:
        """``cycles`` of the machine's built-in motion for ``model``."""
        ...

    def read_motion(self, model: Any, path: Path) -> MotionTable:
        """A motion file in the machine's format, checked against ``model``'s limits."""
        ...

    def joint_columns(self) -> list[JointColumn]:
        """Per actuator, the columns of its joint in ``control.csv``."""
        ...

    def effort_label(self, a: int) -> tuple[str, str]:
        """The name and unit of actuator ``a`` (0-based) in plots (``("motor 1 torque", "N m")``)."""
        ...

    def plot_curves(self, reference_q: np.ndarray, result: Any, joint: Any) -> dict[str, np.ndarray]:
        """The curves of the machine's own figures for one span of a run (``reference_q`` is at
        least as long as ``result.t``)."""
        ...

    def figures(self, draw: Callable[..., None], t: np.ndarray, first: dict[str, np.ndarray],
                lo: dict[str, np.ndarray], hi: dict[str, np.ndarray], heading: str, folder: Path) -> list[Path]:
        """The machine's own PNG figures in ``folder`` from the gathered curves; ``draw(ax, t,
        first, lo, hi, label, **kw)`` draws one curve as the run's length calls for."""
        ...

    def report_plots(self, curve: Callable[[str, int, str], Any], t: np.ndarray, note: str) -> list[Any]:
        """The machine's own :class:`pkmdyn.report.TimePlot` list; ``curve(key, column, name)``
        gives one :class:`pkmdyn.report.Curve` of the gathered curves."""
        ...

    def scene(self, model: Any, t: np.ndarray, q: np.ndarray, u: np.ndarray) -> Any:
        """The 3D scene of the plant's motion (efforts ``u`` as colours)."""
        ...

    # optional: ``notes(model) -> list[str]``, what the run says of a model's parameter file
    # (each line a warning of the run, e.g. a value the engine does not use)

    def parameters_text(self, params: str | None) -> str:
        """The parameter file as text for the report (None: the built-in one)."""
        ...
