"""Analyses over the kinematics and dynamics: stiffness and natural frequencies (:mod:`.stiffness`),
the workspace on a grid of task poses (:mod:`.workspace`, :mod:`.task_grid`), wear of spherical
joints (:mod:`.wear`), the identification regressor (:mod:`.regressor`), and the metrics of one
design for sweeps (:mod:`.designs`).

Every public name of these modules is importable from here; each is imported on first use."""

from __future__ import annotations

from ..._lazy import attach

__getattr__, __dir__ = attach(__name__, {
    **dict.fromkeys(("DescribedSweep", "DescribedSweepContext", "DesignState", "GeneratedMotion", "GeneratedSweep",
                     "GeneratedSweepContext", "evaluate_model"), ".designs"),
    **dict.fromkeys(("BODY_PARAMETERS", "Regressor", "inertial_parameters"), ".regressor"),
    **dict.fromkeys(("Stiffness", "StiffnessDataMissing", "compliance_sources", "deflection", "reaction_route"),
                     ".stiffness"),
    **dict.fromkeys(("MAX_GRID_POINTS", "grid_poses", "parse_grid", "parse_pose", "parse_ranges"), ".task_grid"),
    **dict.fromkeys(("ASPECT_CAP", "ASPECT_LIMIT", "MarkerGrid", "SlideTracks", "WEAR_FACTOR_MM3_N_M", "WearOptions", "geographic", "head_radius", "joint_wear",
                     "joint_index", "joint_slide_tracks", "marker_grid", "motion_axis", "pole_rotation",
                     "slide_tracks"), ".wear"),
    **dict.fromkeys(("MAX_RANGE_POSES", "MAX_REFINE", "Workspace", "refined_size"), ".workspace"),
})
