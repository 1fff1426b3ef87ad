"""Independent closed-form kinematic oracles for classic parallel mechanisms.

Every function is pure numpy and batched over a leading sample axis ``n``.
See ``README.md`` in this directory for signatures, frames, units,
conventions and literature sources.
"""

from . import bennett, delta, frame_fe, hip, mobility, rpr3, rrr3, stewart

__all__ = ["bennett", "delta", "frame_fe", "hip", "mobility", "rpr3", "rrr3", "stewart"]
