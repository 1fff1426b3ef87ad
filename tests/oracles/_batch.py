"""The one input convention every oracle shares: a sample, or a batch of samples along a
leading axis."""

from __future__ import annotations

import numpy as np


def as_batch(x, width):
    """``x`` as a float array ``(n, width)`` (one sample ``(width,)`` becomes ``(1, width)``)."""
    x = np.asarray(x, dtype=float)
    if x.ndim == 1:
        x = x[None, :]
    if x.shape[-1] != width:
        raise ValueError(f"expected trailing dimension {width}, got {x.shape}")
    return x
