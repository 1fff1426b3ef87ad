"""Say on stderr when a command compiles pkmdyn's numerical kernels, what and why, once.

An install compiles every kernel the commands use into numba's cache inside the package
(``setup.py``, ``pkmdyn compile``), so a command normally loads them in a fraction of a second.
Where that cache cannot serve (built for another CPU or by another numba, an editable install,
a read-only install whose user cache is empty, a cache cleared), a command compiles what it
misses on first use: up to about a minute on two cores for ``pkmdyn run`` or ``pkmdyn control``
of a six-legged platform (:data:`ESTIMATE`). :func:`install` (called by the command line, never
on import) registers a listener on numba's compile events that says so once, when the first
kernel of pkmdyn starts compiling: its name, why the cache did not serve it (:func:`_why`) and
about how long it takes. :func:`summary` gives the kernels compiled and the time they took, for
the command line to print at the end of a run that succeeded. Both are said whether or not
stderr is a terminal: a wait of a minute is explained in a log too.
"""

from __future__ import annotations

import importlib.abc
import importlib.util
import pickle
import sys
import time
from typing import Any

__all__ = ["install", "reset", "silence", "summary", "ESTIMATE"]

#: what the first use of a command costs where nothing is cached, as said to the user: measured
#: on a two-core machine (``pkmdyn run --machine stewart`` 38 s, a first ``pkmdyn control`` then
#: 13 s more; ``pkmdyn compile`` all of them in about two minutes, two processes)
ESTIMATE = "up to about a minute on two cores, once"

_state: dict[str, Any] = {"listener": None}


def _is_ours(ev) -> bool:
    fn = getattr(ev.data.get("dispatcher"), "py_func", None)
    return str(getattr(fn, "__module__", "")).startswith("pkmdyn")


def _name(ev) -> str:
    fn = getattr(ev.data.get("dispatcher"), "py_func", None)
    return f"{getattr(fn, '__module__', '?')}.{getattr(fn, '__qualname__', '?')}"


def _why(dispatcher: Any) -> str:
    """Why numba's cache did not serve ``dispatcher``: read from its index file (the numba
    version, then the source stamp and each entry's CPU), in words; a general reason where the
    index says nothing more."""
    impl = getattr(getattr(dispatcher, "_cache", None), "_cache_file", None)
    if impl is None:
        return "a kernel not cached on disk"
    try:
        path = impl._index_path
        with open(path, "rb") as f:
            version = pickle.load(f)
            data = f.read()
    except FileNotFoundError:
        return "no cache of it here (an editable install, a cache cleared, or one not writable)"
    except (AttributeError, OSError, pickle.UnpicklingError, EOFError):
        return "the cache could not be read"
    try:
        import numba

        if version != numba.__version__:
            return f"the cache was built by numba {version}, this is numba {numba.__version__}"
        stamp, overloads = pickle.loads(data)
        if stamp != impl._source_stamp:
            return "its source changed since the cache was built"
        from numba.core.registry import cpu_target

        here = cpu_target.target_context.codegen().magic_tuple()
        cpus = {key[1][1] for key in overloads if isinstance(key, tuple) and len(key) > 1}
        if cpus and not any(key[1] == here for key in overloads):
            if here[1] in cpus:
                return f"the cache was built for other features of CPU {here[1]} (NUMBA_CPU_FEATURES)"
            return f"the cache was built for CPU {', '.join(sorted(map(str, cpus)))}, this is {here[1]}"
        return "the cache holds it for other argument types"
    except Exception:  # numba's internals differ: say what is sure
        return "the cache does not hold it"


class _AfterNumba(importlib.abc.MetaPathFinder):
    """Registers the listener once numba is imported (:func:`install` before it): a command that
    compiles nothing, or only prints its help, imports no numba for the notice's sake."""

    def find_spec(self, name, path, target=None):
        if name != "numba":
            return None
        if self in sys.meta_path:
            sys.meta_path.remove(self)
        spec = importlib.util.find_spec(name)
        loader = getattr(spec, "loader", None)
        if loader is None or not hasattr(loader, "exec_module"):
            return spec
        run = loader.exec_module

        def exec_module(module):
            run(module)
            _register()

        loader.exec_module = exec_module
        return spec


def install() -> None:
    """Have the compile listener registered (once per process): now where numba is imported,
    else as soon as it is."""
    if _state["listener"] is not None or any(isinstance(f, _AfterNumba) for f in sys.meta_path):
        return
    if "numba" in sys.modules:
        _register()
    else:
        sys.meta_path.insert(0, _AfterNumba())


def _register() -> None:
    if _state["listener"] is not None:
        return
    from numba.core import event

    class _Notice(event.Listener):
        def __init__(self) -> None:
            self.names: list[str] = []
            self.depth = 0
            self.start = 0.0
            self.seconds = 0.0

        def on_start(self, ev) -> None:
            if not _is_ours(ev):
                return
            name = _name(ev)
            if not self.names:
                try:
                    print(f"pkmdyn: compiling numerical kernels missing from the cache, first {name} "
                          f"({_why(ev.data.get('dispatcher'))}); {ESTIMATE}: `pkmdyn compile` compiles them all",
                          file=sys.stderr, flush=True)
                except OSError:  # pragma: no cover - a closed stderr
                    pass
            if name not in self.names:
                self.names.append(name)
            if self.depth == 0:
                self.start = time.perf_counter()
            self.depth += 1

        def on_end(self, ev) -> None:
            if not _is_ours(ev):
                return
            self.depth -= 1
            if self.depth == 0:
                self.seconds += time.perf_counter() - self.start

    _state["listener"] = _Notice()
    event.register("numba:compile", _state["listener"])


def reset() -> None:
    """Forget what was compiled so far (a command starting in a process that ran others: the
    notice and :func:`summary` speak of its own compilations)."""
    lst = _state["listener"]
    if lst is not None:
        lst.names.clear()
        lst.seconds = 0.0


def silence() -> None:
    """Say nothing of compilations in this process (``pkmdyn compile``, whose work they are)."""
    sys.meta_path[:] = [f for f in sys.meta_path if not isinstance(f, _AfterNumba)]
    lst = _state["listener"]
    if lst is not None:
        from numba.core import event

        event.unregister("numba:compile", lst)
        _state["listener"] = None


def summary() -> str | None:
    """One line with the kernels compiled in this process and the time it took, or None when
    nothing was compiled."""
    lst = _state["listener"]
    if lst is None or not lst.names:
        return None
    return (f"pkmdyn: compiled {len(lst.names)} kernel{'s' if len(lst.names) != 1 else ''} in {lst.seconds:.0f} s "
            "(cached for later runs)")
