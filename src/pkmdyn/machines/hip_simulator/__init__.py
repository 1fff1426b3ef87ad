"""The 2(3PUS+S) dual-platform hip-joint wear simulator (Chen, Cheng & Pang 2022): its parameter
file (:mod:`.params`), the mechanism description generated from it (:mod:`.description`), the
paper's view of the engine's results (:mod:`.paper`), and the machine's commands and jobs on the
engine (:mod:`.commands`, :mod:`.job`, :mod:`.control_job`, the ``identify_*`` modules,
:mod:`.described_sweep`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..._lazy import attach

if TYPE_CHECKING:
    from .description import hip_description
    from .paper import PaperView
    from .params import HipModel, load_params, model_from_dict

__all__ = ["HipModel", "load_params", "model_from_dict", "hip_description", "PaperView"]

#: the package's names and their modules, imported on first use (so that the registry and the
#: command line can read the machine's entry without loading the engine)
__getattr__, __dir__ = attach(__name__, {
    **dict.fromkeys(("HipModel", "load_params", "model_from_dict"), ".params"),
    "hip_description": ".description",
    "PaperView": ".paper",
})
