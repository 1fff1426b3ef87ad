"""Records to a compiled model: the spanning tree, cut joints and loop records (:mod:`.compiler`),
the flat arrays (:mod:`.records`), mobility and over-constraints (:mod:`.topology`), the explicit
legs (:mod:`.legs`), body poses (:mod:`.poses`) and the tree's compiled kernels (elementary
motions, placement, constraint rows: :mod:`._tree_kernels`).

Every public name of these modules is importable from here; each is imported on first use."""

from __future__ import annotations

from ..._lazy import attach

__getattr__, __dir__ = attach(__name__, {
    **dict.fromkeys(("LoopRecord", "MechanismModel", "ModelStructure", "compile_model", "compile_with",
                     "load_mechanism", "model_structure", "spanning_tree", "structure_key"), ".compiler"),
    **dict.fromkeys(("LEG_PATTERNS", "LegTable", "explicit_legs", "held_coordinates", "newton_only", "place"),
                     ".legs"),
    **dict.fromkeys(("body_poses", "positions_args"), ".poses"),
    **dict.fromkeys(("TopologyReport", "analyse_topology", "block_pattern", "block_structure", "blocks_of_pattern",
                     "column_scale", "constraint_jacobian", "kutzbach_count", "row_labels", "row_scale",
                     "solver_selection", "sparse_basis"), ".topology"),
})
