"""The 4-DOF parallel driving mechanism's entry in the machine registry
(:mod:`pkmdyn.machines.registry`): its name, built-in files, description and default motion."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ...profiles.pdm_motion import cycloidal_motion
from ...report import write_view

NAME = "pdm"
TITLE = "4-DOF over-constrained parallel driving mechanism (Huang et al. 2023); see pkmdyn pdm --help"
#: the built-in control settings (``--gains``; :mod:`pkmdyn.control`)
CONTROL_SETTINGS = Path(__file__).with_name("control.toml")


def default_params_text() -> str:
    """The built-in parameter file, to edit and pass as ``--params``."""
    from .params import default_params_path

    return default_params_path().read_text(encoding="utf-8")


def description() -> dict[str, Any]:
    """The built-in machine as a mechanism description (:mod:`pkmdyn.multibody`)."""
    from .description import pdm_description
    from .params import load_params

    return pdm_description(load_params())


def default_motion() -> Any:
    """The Eq. 84 cycloidal motion of the built-in parameters' ``[trajectory]``, as a
    :class:`pkmdyn.multibody.TaskMotion`."""
    from ...multibody import TaskMotion
    from .params import load_params

    tr = load_params().trajectory
    m = cycloidal_motion(tr.strokes, tr.period_s, tr.samples)
    return TaskMotion(m.t, m.q, m.qd, m.qdd)


def view_page(params: Path | None, out: Path, listing: Any) -> Path:
    """The ``pkmdyn view`` page of this machine (:func:`pkmdyn.report.write_view`) at its home pose."""
    import numpy as np

    from .params import load_params
    from .report import parameters_text
    from .scene import pdm_mobility, pdm_scene_from_pose, pdm_topology

    model = load_params(params)
    scene = pdm_scene_from_pose(model, np.zeros(1), np.zeros((1, 4)), np.zeros((1, 4)))
    return write_view(out, title="4-DOF PDM: machine view", scene=scene, topology=pdm_topology(),
                      mobility=pdm_mobility(model), parameters=parameters_text(params),
                      notes=[f"parameters: {model.source}", "home pose: x = y = 0, alpha = gamma = 0"],
                      inputs={"--params": params}, listing=listing)
