"""The interface every machine offers to the layers above it (simulation, control, identification).

A machine is data (its frozen model) plus free functions. The layers that drive a machine
(``pkmdyn.simulate``, ``pkmdyn.control``, ``pkmdyn.identify``) never import a machine's
modules: they receive a :class:`MachineDynamics` - any object that provides the verbs below,
in practice the generic engine's verbs of a machine's description
(:class:`pkmdyn.multibody.dynamics.verbs.MechanismVerbs`) - and the machine's model.

Coordinates. ``q (n, nq)`` are the machine's minimal coordinates and ``qd, qdd`` their first
and second time derivatives (for instance a platform's Euler angles [rad], or positions [m]
and angles [rad] of a planar platform). ``u (n, nu)`` are the actuator efforts (motor
torques [N m], limb forces [N]). ``load (n,)`` is the machine's external load (a test rig's
hydraulic force [N], say); a machine without one accepts ``None``.

Equations of motion, in generalised forces dual to ``qd``:

    M(q) qdd + h(q, qd, load) = B(q) u

with ``M`` symmetric positive definite, ``h`` every velocity, gravity and friction term
(friction with its load dependence), and ``B`` the actuator map. ``inverse_dynamics``
returns the ``u`` that solves this for given ``qdd``; ``forward_dynamics`` the ``qdd`` for
given ``u``. Every verb is batched over a leading sample axis.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

__all__ = ["MachineDynamics"]

Array = NDArray[np.float64]


class MachineDynamics(Protocol):
    """The verbs a machine answers in its own minimal coordinates (see the module docstring)."""

    #: coordinate names with their unit suffix, e.g. ``("alpha_rad", "beta_rad", "gamma_rad")``
    COORDINATES: tuple[str, ...]
    #: actuator names with their unit suffix, e.g. ``("tau1_Nm", "tau2_Nm", "tau3_Nm")``
    ACTUATORS: tuple[str, ...]

    def mass_matrix(self, model: Any, q: Array) -> Array:
        """``M(q) (n, nq, nq)``, symmetric positive definite."""
        ...

    def bias_forces(self, model: Any, q: Array, qd: Array, load: Array | None) -> Array:
        """``h(q, qd, load) (n, nq)``: velocity terms, gravity and friction."""
        ...

    def actuator_map(self, model: Any, q: Array) -> Array:
        """``B(q) (n, nq, nu)``: generalised forces of unit actuator efforts."""
        ...

    def inverse_dynamics(self, model: Any, q: Array, qd: Array, qdd: Array, load: Array | None) -> Array:
        """Actuator efforts ``u (n, nu)`` that produce ``qdd``."""
        ...

    def forward_dynamics(self, model: Any, q: Array, qd: Array, u: Array, load: Array | None) -> Array:
        """Accelerations ``qdd (n, nq)`` under actuator efforts ``u``."""
        ...

    def inverse_dynamics_one(self, model: Any, q: Array, qd: Array, qdd: Array, load: float | None) -> Array:
        """One sample of :meth:`inverse_dynamics`: ``q, qd, qdd (nq,)`` -> ``u (nu,)``, the real-time path."""
        ...

    def forward_dynamics_one(self, model: Any, q: Array, qd: Array, u: Array, load: float | None) -> Array:
        """One sample of :meth:`forward_dynamics`: ``q, qd (nq,), u (nu,)`` -> ``qdd (nq,)``, the real-time path."""
        ...

    def one_sample_kernels(self, model: Any) -> tuple[Array, Any, Any]:
        """Optional: ``(p, inverse, forward)``, the compiled kernels behind the two ``*_one`` verbs
        for callers in a loop (the plant integrator, a controller), where the verbs' input checks
        cost more than the model. ``inverse(p, q, qd, qdd, load, out) -> status`` and
        ``forward(p, q, qd, u, load, out) -> status`` write into ``out``; ``load`` is a float (0.0
        for a machine without one); nothing is checked; a nonzero status means the sample is
        invalid, and the caller repeats it through the checked ``*_one`` verb, which raises the
        machine's own error. None where a machine has no such kernels for this model."""
        ...
