"""Keep numba's on-disk cache of cross-module kernels in step with the code they compile in.

Numba keys a cached compiled function on its own source file only (its time stamp and size).
A kernel that inlines or links functions of other modules (:mod:`pkmdyn.multibody.dynamics._sample_kernels` uses the kinematics,
dynamics and friction kernels) would then keep serving the code it was compiled against after
those modules change, e.g. in a development checkout. :func:`refresh` writes a marker with a
hash of the modules' sources beside each kernel's cache and flushes the cache when the hash
differs; where the marker cannot be written, the kernel is compiled afresh in each process.
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterable
from pathlib import Path
from types import ModuleType
from typing import Any

__all__ = ["refresh", "cached"]


def _stamp(modules: Iterable[ModuleType]) -> str:
    h = hashlib.sha256()
    for mod in modules:
        h.update(Path(str(mod.__file__)).read_bytes())
    return h.hexdigest()[:20]


def refresh(dispatchers: Iterable[Any], modules: Iterable[ModuleType]) -> None:
    """Flush the on-disk cache of each numba dispatcher compiled against other ``modules``
    whose sources changed since (module docstring)."""
    stamp = _stamp(modules)
    for fn in dispatchers:
        cache = getattr(fn, "_cache", None)
        path = getattr(cache, "cache_path", None)
        if not path:
            continue
        marker = Path(path) / f"{fn.py_func.__module__}.{fn.__name__}.deps"
        try:
            if marker.is_file() and marker.read_text(encoding="ascii") == stamp:
                continue
            cache.flush()
            marker.parent.mkdir(parents=True, exist_ok=True)
            marker.write_text(stamp, encoding="ascii")
        except OSError:
            cache.disable()


def cached(dispatcher: Any) -> bool:
    """Whether numba's cache holds a compiled version of ``dispatcher`` for its present source
    (False where this numba's cache cannot be read so)."""
    try:
        return bool(dispatcher._cache._cache_file._load_index())
    except (AttributeError, OSError):
        return False
