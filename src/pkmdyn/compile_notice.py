"""Tell the user when pkmdyn's compiled kernels are being compiled, once, on stderr.

The kinematics and dynamics kernels (numba) are compiled on their first use after an
install and cached on disk (beside the package, or in the user's cache folder where that is
not writable); a later run loads them in a fraction of a second. The first run of a command
compiles what that command needs: measured on a 2-core machine with an empty cache, about
25-30 s for ``pkmdyn run --machine stewart`` and 10 s more for the single-sample kernels of a
first ``pkmdyn control``. :func:`install` (called by the command line, never on import)
registers a listener on numba's compile events; where stderr is a terminal (a person waiting)
it says so at once, when the first kernel of pkmdyn starts compiling. :func:`summary` gives
the time it took, one line that the command line prints at the end of a run that succeeded,
terminal or not (a run that failed keeps to its one error line).
"""

from __future__ import annotations

import sys
import time

__all__ = ["install", "mark", "summary", "MESSAGE"]

MESSAGE = ("pkmdyn: compiling the numerical kernels for their first use (up to a minute or so on two cores, "
           "once: they are cached for later runs)")

_state = {"listener": None}


def _is_ours(ev) -> bool:
    fn = getattr(ev.data.get("dispatcher"), "py_func", None)
    return str(getattr(fn, "__module__", "")).startswith("pkmdyn")


def _terminal() -> bool:
    try:
        return bool(sys.stderr.isatty())
    except (AttributeError, ValueError):  # pragma: no cover - a replaced or closed stderr
        return False


def install(force: bool = False) -> None:
    """Register the compile listener (once per process); its first message is printed where
    stderr is a terminal, or with ``force``."""
    if _state["listener"] is not None:
        return
    from numba.core import event

    class _Notice(event.Listener):
        def __init__(self) -> None:
            self.said = False
            self.depth = 0
            self.start = 0.0
            self.seconds = 0.0
            self.count = 0

        def on_start(self, ev) -> None:
            if not _is_ours(ev):
                return
            if self.depth == 0:
                self.start = time.perf_counter()
                if not self.said:
                    self.said = True
                    try:
                        if force or _terminal():
                            print(MESSAGE, file=sys.stderr, flush=True)
                    except OSError:  # pragma: no cover - a closed stderr
                        pass
            self.depth += 1

        def on_end(self, ev) -> None:
            if not _is_ours(ev):
                return
            self.depth -= 1
            if self.depth == 0:
                self.seconds += time.perf_counter() - self.start
                self.count += 1

    _state["listener"] = _Notice()
    event.register("numba:compile", _state["listener"])


def mark() -> tuple[int, float]:
    """The kernels compiled and the seconds spent so far in this process, for :func:`summary`
    of what a command compiled after it."""
    lst = _state["listener"]
    return (0, 0.0) if lst is None else (lst.count, lst.seconds)


def summary(since: tuple[int, float] = (0, 0.0)) -> str | None:
    """One line with the time spent compiling pkmdyn's kernels in this process since ``since``
    (:func:`mark`; default: since the start), or None when none was compiled."""
    count, seconds = mark()
    if count <= since[0]:
        return None
    return (f"pkmdyn: compiled the kernels in {seconds - since[1]:.0f} s; later runs load them "
            "from the cache")
