"""Self-contained HTML reports: the mechanism animated in 3D, interactive plots, the run's summary.

A report is one file (``report.html`` in a run's output folder) that opens offline in any
current browser: plotly's JavaScript is inlined once, every figure's data travels with it.
The API knows no machine: a machine (or a described mechanism) gives a :class:`Scene` (joint
points per sample and which points each body joins), :class:`TimePlot` curves, its summary,
parameters and warnings (``docs/report.md``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

if TYPE_CHECKING:
    from ._figures import Curve, TimePlot, decimate_minmax
    from ._collect import FOLD_MAX, PLOT_BINS, PLOT_RAW_MAX, CurveData, Curves, Extremes
    from ._output import SUMMARY_NAME, JobResult, Output, Report, write_output
    from ._page import REPORT_NAME, write_report, write_view
    from ._scene import MAX_FRAMES, FramePicker, Scene, SceneActuator, SceneBody, frame_indices, scene_from_files, scene_from_joints
    from ._topology import Topology, fundamental_loops, layered_layout, topology_from_model

__all__ = [
    "Scene",
    "SceneBody",
    "SceneActuator",
    "scene_from_joints",
    "scene_from_files",
    "frame_indices",
    "FramePicker",
    "Curves",
    "CurveData",
    "Extremes",
    "PLOT_RAW_MAX",
    "PLOT_BINS",
    "FOLD_MAX",
    "MAX_FRAMES",
    "Curve",
    "TimePlot",
    "decimate_minmax",
    "write_report",
    "write_view",
    "REPORT_NAME",
    "Report",
    "Output",
    "JobResult",
    "write_output",
    "SUMMARY_NAME",
    "Topology",
    "topology_from_model",
    "fundamental_loops",
    "layered_layout",
]

#: where each public name lives, imported on first use: ``import pkmdyn.report`` loads
#: nothing heavy until a function is looked up
__getattr__, __dir__ = attach(__name__, {
    **dict.fromkeys(("Curve", "TimePlot", "decimate_minmax"), "._figures"),
    **dict.fromkeys(("REPORT_NAME", "write_report", "write_view"), "._page"),
    **dict.fromkeys(("Curves", "CurveData", "Extremes", "PLOT_RAW_MAX", "PLOT_BINS", "FOLD_MAX"), "._collect"),
    **dict.fromkeys(("Report", "Output", "JobResult", "write_output", "SUMMARY_NAME"), "._output"),
    **dict.fromkeys(("MAX_FRAMES", "FramePicker", "Scene", "SceneActuator", "SceneBody", "frame_indices",
                     "scene_from_files", "scene_from_joints"), "._scene"),
    **dict.fromkeys(("Topology", "fundamental_loops", "layered_layout", "topology_from_model"), "._topology"),
})
