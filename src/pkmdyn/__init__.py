"""pkmdyn: kinematics, dynamics and trajectory-tracking control of parallel manipulators.

The library's verbs (:mod:`pkmdyn.api`, imported on first use) and its errors::

    import pkmdyn
    m = pkmdyn.load("stewart")
    dyn = pkmdyn.dynamics(m, pkmdyn.kinematics(m))
"""

from typing import TYPE_CHECKING

from ._lazy import attach
from .errors import (
    MotionError,
    ParameterError,
    PkmdynError,
    SingularityError,
    SingularityWarning,
    UnreachablePoseError,
)

if TYPE_CHECKING:
    from .api import (Dynamics, assembly_modes, default_motion, direct_kinematics, dynamics, forward_dynamics,
                      Designs, designs, identification, kinematics, load, retime, stiffness, wear, workspace)

_VERBS = ("load", "default_motion", "kinematics", "Dynamics", "dynamics", "forward_dynamics", "direct_kinematics",
          "assembly_modes", "stiffness", "wear", "workspace", "retime", "identification", "Designs", "designs")

__all__ = [
    *_VERBS,
    "PkmdynError",
    "ParameterError",
    "MotionError",
    "UnreachablePoseError",
    "SingularityError",
    "SingularityWarning",
]

#: the verbs live in :mod:`pkmdyn.api`, imported on first use (``import pkmdyn`` stays light)
__getattr__, __dir__ = attach(__name__, dict.fromkeys(_VERBS, ".api"))
