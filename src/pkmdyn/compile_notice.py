"""Tell the user when pkmdyn's compiled kernels are being compiled, once, on stderr.

The kinematics and dynamics kernels (numba) are compiled on their first use after an
install and cached on disk (beside the package, or in the user's cache folder where that is
not writable); a later run loads them in a fraction of a second. The first run of a command
compiles what that command needs: measured on a 2-core machine with an empty cache, about
40-45 s for ``pkmdyn run --machine stewart`` and 20 s more for the single-sample kernels of a
first ``pkmdyn control`` (about 60 s for ``control`` alone from an empty cache). :func:`install` (called by the command line, never on import) registers
a listener on numba's compile events that says so once, when the first kernel of pkmdyn starts
compiling, and :func:`summary` gives the time it took, for the command line to print at the
end of a run that succeeded. Like the progress bars, both are written where stderr is a
terminal (a person waiting); a script or a pipeline that reads stderr gets only what the
command itself says (one line for an error).
"""

from __future__ import annotations

import sys
import time

__all__ = ["install", "summary", "MESSAGE"]

MESSAGE = ("pkmdyn: compiling the numerical kernels for their first use (up to a minute or so on two cores, "
           "once: they are cached for later runs)")

_state = {"listener": None}


def _is_ours(ev) -> bool:
    fn = getattr(ev.data.get("dispatcher"), "py_func", None)
    return str(getattr(fn, "__module__", "")).startswith("pkmdyn")


def install(force: bool = False) -> None:
    """Register the compile listener (once per process) where stderr is a terminal, or always
    with ``force``."""
    if _state["listener"] is not None:
        return
    try:
        tty = sys.stderr.isatty()
    except (AttributeError, ValueError):  # pragma: no cover - a replaced or closed stderr
        tty = False
    if not (tty or force):
        return
    from numba.core import event

    class _Notice(event.Listener):
        def __init__(self) -> None:
            self.said = False
            self.depth = 0
            self.start = 0.0
            self.seconds = 0.0

        def on_start(self, ev) -> None:
            if not _is_ours(ev):
                return
            if self.depth == 0:
                self.start = time.perf_counter()
                if not self.said:
                    self.said = True
                    try:
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

    _state["listener"] = _Notice()
    event.register("numba:compile", _state["listener"])


def summary() -> str | None:
    """One line with the time spent compiling pkmdyn's kernels in this process, or None when
    nothing was compiled."""
    lst = _state["listener"]
    if lst is None or not lst.said:
        return None
    return f"pkmdyn: compiled the kernels in {lst.seconds:.0f} s; later runs load them from the cache"
