"""The 4-DOF parallel driving mechanism's entry in the machine registry
(:mod:`pkmdyn.machines.registry`): its name, built-in files, description and default motion."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..._lazy import lazy_module
from ...profiles.pdm_motion import cycloidal_motion
from ...report import write_view

if TYPE_CHECKING:
    from ... import multibody as _multibody
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

NAME = "pdm"
TITLE = "4-DOF over-constrained parallel driving mechanism (Huang et al. 2023); see pkmdyn pdm --help"
#: the built-in control settings (``--gains``; :mod:`pkmdyn.control`)
CONTROL_SETTINGS = Path(__file__).with_name("control.toml")


def default_params_text() -> str:
    """The built-in parameter file, to edit and pass as ``--params``."""
    return _params.default_params_path().read_text(encoding="utf-8")


def description(params: Path | None = None) -> dict[str, Any]:
    """The machine of the parameter file ``params`` (default: the built-in one) as a mechanism
    description (:mod:`pkmdyn.multibody`)."""

    return _description.pdm_description(_params.load_params(params))


def default_motion() -> Any:
    """The Eq. 84 cycloidal motion of the built-in parameters' ``[trajectory]``, as a
    :class:`pkmdyn.multibody.TaskMotion`."""

    tr = _params.load_params().trajectory
    m = cycloidal_motion(tr.strokes, tr.period_s, tr.samples)
    return _multibody.TaskMotion(m.t, m.q, m.qd, m.qdd)


def view_page(params: Path | None, out: Path, listing: Any) -> Path:
    """The ``pkmdyn view`` page of this machine (:func:`pkmdyn.report.write_view`) at its home pose."""
    import numpy as np  # deferred: the registry reads this module, and `pkmdyn machines` loads no numpy

    model = _params.load_params(params)
    scene = _scene.pdm_scene_from_pose(model, np.zeros(1), np.zeros((1, 4)), np.zeros((1, 4)))
    return write_view(out, title="4-DOF PDM: machine view", scene=scene, topology=_scene.pdm_topology(),
                      mobility=_scene.pdm_mobility(model), parameters=_report.parameters_text(params),
                      notes=[f"parameters: {model.source}", "home pose: x = y = 0, alpha = gamma = 0"],
                      inputs={"--params": params}, listing=listing)
