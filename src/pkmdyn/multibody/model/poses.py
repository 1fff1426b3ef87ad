"""Body poses of a compiled mechanism at one configuration (the kernels' positions pass).

Below the modules that need it (topology's joint-centre Jacobian, the explicit legs'
reference geometry): it imports the kernels only.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..model._tree_kernels import forward_positions

__all__ = ["body_poses", "positions_args"]

Array = NDArray[np.float64]


def positions_args(model, R: Array, p: Array, S: Array) -> tuple:
    """The model's arguments of :func:`pkmdyn.multibody.model._tree_kernels.forward_positions` (and ``place_legs``) after
    ``q``, up to ``reuse``, with the outputs ``R, p, S`` and fresh work space."""
    return (model.body_parent, model.body_joint, model.joint_q0, model.joint_nq, model.coord_motion,
            model.coord_offset, model.coord_sign, model.tree_R_parent, model.tree_p_parent, model.tree_R_child,
            model.tree_p_child, R, p, S, np.empty((5, 3, 3)), np.empty((20, 3)), np.empty((model.nq, 3)), False)


def body_poses(model, q: Array) -> tuple[Array, Array, Array]:
    """Body rotations ``(nb, 3, 3)``, origins ``(nb, 3)`` [m] and coordinate twists ``(nq, 6)``
    (base frame) at the tree coordinates ``q (nq,)``."""
    R, p, S = np.empty((model.nb, 3, 3)), np.empty((model.nb, 3)), np.empty((model.nq, 6))
    forward_positions(np.ascontiguousarray(q, dtype=float), *positions_args(model, R, p, S),
                      np.full(model.nb, -1, dtype=np.int64), False)
    return R, p, S
