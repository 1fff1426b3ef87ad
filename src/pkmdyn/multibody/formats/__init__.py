"""Other formats at the engine's edge: MJCF, URDF (+ loop sidecar) and SDFormat read into one
import graph and turned into a description (:mod:`.graph`, :mod:`.mjcf_in`, :mod:`.urdf_in`,
:mod:`.sdf_in`, :mod:`.importer`); MJCF and URDF written from a model (:mod:`.mjcf_out`,
:mod:`.urdf_out`). Files are read and text returned; nothing here writes a file.

Every public name of these modules is importable from here; each is imported on first use."""

from __future__ import annotations

from ..._lazy import attach

__getattr__, __dir__ = attach(__name__, {
    **dict.fromkeys(("SOLIMP", "SOLREF", "coordinate_names", "mechanism_mjcf", "mujoco_order", "mujoco_qpos"),
                     ".mjcf_out"),
    **dict.fromkeys(("mechanism_urdf",), ".urdf_out"),
})
