"""Compiling ahead: on a fresh install (an empty numba cache) a command compiles its kernels in
the order it meets them, one after the other on one core. A closed loop meets its
single-sample kernels (:func:`._one._dynamics`, :func:`._direct.direct_task_one`,
:func:`._direct.direct_one`) last, after the
batched kinematics, dynamics and references have compiled and run. :func:`start` hands those
to a child process at the command's start, so that they compile on a second core meanwhile and
the command later loads them from the cache (numba writes each cache file whole, under a new
name that replaces the old, so a reader never sees half a file). The child says each stage on
its standard output when done; :func:`wait`, called where a stage's kernel is first needed,
waits for that line rather than compiling the same kernel a second time.

Those kernels read every number of the mechanism from one packed buffer, so their argument
types do not depend on the mechanism: the child compiles them for their signatures
(:func:`signatures`) without loading a mechanism or running anything. It is started only where
it can help: two cores or more, a cache that lacks a kernel of the stages, and
``PKMDYN_COMPILE_AHEAD`` not ``0``. It writes nothing but the cache and its stage lines to the
command's pipe (nothing on the terminal), and is ended when the command ends. ``pkmdyn run``
starts it too: the single-sample kernel calls the batched kinematics' own compiled sample
solver, so the child compiles that in parallel with the command's first kernels, and a later
``pkmdyn control`` finds the loop's kernel cached.

A command starts the child with the stage it surely needs (``one``) and hands it more on its
standard input once it knows them (:func:`request`): the direct kinematics of the route its
mechanism takes, so that the child does not spend seconds on the other one first.

Its last stage, ``loop``, is the closed loop's cycles in one compiled call
(:mod:`pkmdyn.simulate._cycles`), which links the kernels above a second time (some 15-30 s):
no command waits for it; the loop takes its Python cycles until it is compiled (:func:`compiled`).
``pkmdyn control`` starts a child for it where the run is long (:data:`LOOP_WORTH_S`).

    python -m pkmdyn.multibody.ahead one task direct loop
"""

from __future__ import annotations

import atexit
import importlib
import os
import selectors
import subprocess
import sys
import time
from collections.abc import Iterable
from typing import Any

__all__ = ["STAGES", "LOOP_WORTH_S", "cold", "start", "request", "coming", "wait", "ready", "compiled",
           "worth_compiling_loop", "compile_stages", "signatures"]

#: the stages a child can compile, in this order: the closed loop's single-sample dynamics and
#: encoders (``one``), its direct kinematics of the encoders' reading in task space (``task``:
#: the Gough-Stewart platform, the hip), and in tree space (``direct``: any other mechanism),
#: and the loop's cycles in one compiled call (``loop``, :mod:`pkmdyn.simulate._cycles`: some
#: 30 s, which a command does not wait for; until it is compiled the loop runs its cycles in
#: Python)
STAGES = ("one", "task", "direct", "loop")
#: a run whose cycles in Python would take about this long [s] or more starts a child compiling
#: the ``loop`` stage alone (:func:`worth_compiling_loop`): it is done before the run is, and the
#: rest of the run takes the compiled cycles
LOOP_WORTH_S = 60.0
#: the module of the ``loop`` stage's kernel: the simulation layer's, above this one, so named
#: here rather than imported
_LOOP_MODULE = "pkmdyn.simulate._cycles"


def _kernels(stage: str) -> list[Any]:
    """The compiled functions (numba dispatchers) of ``stage``."""
    if stage == "one":
        from . import _one

        return [_one._dynamics]
    if stage == "task":
        from . import _direct

        return [_direct.direct_task_one]
    if stage == "direct":
        from . import _direct

        return [_direct.direct_one]
    if stage == "loop":
        return [importlib.import_module(_LOOP_MODULE).run_cycles]
    raise ValueError(f"compile-ahead stage {stage!r}: unknown (known: {', '.join(STAGES)})")


def signatures(stage: str) -> list[tuple[Any, ...]]:
    """The argument types each kernel of ``stage`` is called with (a packed int64 buffer, float64
    vectors, C-contiguous; :func:`._one.forward_one`, :meth:`.machine.MechanismVerbs.direct_one`)."""
    from numba import types

    buf, vec = types.Array(types.int64, 1, "C"), types.Array(types.float64, 1, "C")
    if stage == "one":  # _dynamics(pk, x, xd, v, load, mode, out)
        return [(buf, vec, vec, vec, types.float64, types.int64, vec)]
    if stage == "task":  # direct_task_one(pk, d, s, sd, out)
        return [(buf, buf, vec, vec, vec)]
    if stage == "direct":  # direct_one(b, s, sd, out)
        return [(buf, vec, vec, vec)]
    if stage == "loop":  # run_cycles(...): the types of a run's arguments
        return [importlib.import_module(_LOOP_MODULE).example_signature()]
    raise ValueError(f"compile-ahead stage {stage!r}: unknown (known: {', '.join(STAGES)})")


def _cached(dispatcher: Any) -> bool | None:
    """Whether numba's cache holds a compiled version of ``dispatcher`` for its present source
    (None where this numba does not say)."""
    try:
        return bool(dispatcher._cache._cache_file._load_index())
    except (AttributeError, OSError):
        return None


def cold(stages: Iterable[str]) -> bool:
    """Whether a kernel of ``stages`` is missing from the cache (False where numba does not say)."""
    return any(_cached(k) is False for s in stages for k in _kernels(s))


def _stop(child: subprocess.Popen) -> None:
    if child.stdin is not None and not child.stdin.closed:
        try:
            child.stdin.close()
        except OSError:  # pragma: no cover - a child that has gone
            pass
    if child.poll() is None:
        child.terminate()
        try:
            child.wait(timeout=5)
        except subprocess.TimeoutExpired:  # pragma: no cover - a child that ignores the signal
            child.kill()
            child.wait()
    if child.stdout is not None:
        child.stdout.close()


#: the running child of :func:`start`, the stages it was given (in order), those it has
#: reported done and its unread output
_child: subprocess.Popen | None = None
_queued: list[str] = []
_done: set[str] = set()
_unread = b""
#: the longest wait for a stage [s]; past it the command compiles the kernel itself
WAIT_S = 600.0


def start(stages: Iterable[str]) -> subprocess.Popen | None:
    """A child compiling the kernels of ``stages`` in that order, or None where it would not help
    (module docstring) or a child of this process still runs. The child ends with this process."""
    global _child, _unread
    stages = tuple(stages)
    if os.environ.get("PKMDYN_COMPILE_AHEAD", "1") == "0" or (os.cpu_count() or 1) < 2 or not cold(stages):
        return None
    if _child is not None and _child.poll() is None:
        return None
    _done.clear()
    _unread = b""
    _child = subprocess.Popen([sys.executable, "-m", __name__, "--more", *stages], stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, bufsize=0)
    _queued[:] = stages
    atexit.register(_stop, _child)
    return _child


def request(stages: Iterable[str]) -> None:
    """Have ``stages`` compiled ahead: handed to the running child (after what it was given;
    each cold one not given yet), else a child started for them (:func:`start`). A command calls
    it once it knows which kernels it will take (the direct kinematics' route of its mechanism,
    a long closed loop's cycles)."""
    child = _child
    if child is None or child.poll() is not None or child.stdin is None or child.stdin.closed:
        start(stages)
        return
    new = [s for s in stages if s not in _queued and cold((s,))]
    if not new:
        return
    try:
        child.stdin.write("".join(f"{s}\n" for s in new).encode("ascii"))
        child.stdin.flush()
    except OSError:  # pragma: no cover - the child has just ended: the command compiles them itself
        return
    _queued.extend(new)


def coming(stage: str) -> bool:
    """Whether the child compiles ``stage`` next or has (every stage it was given before it is
    done): then waiting for it beats compiling it here."""
    wait(stage, 0.0)
    if _child is None or stage not in _queued:
        return False
    return all(s in _done for s in _queued[:_queued.index(stage)])


def wait(stage: str, timeout_s: float = -1.0) -> None:
    """Return once the child has compiled ``stage``: at once without a child or where it was not
    given ``stage`` (it listens for more until the command ends: it would not say it), once it
    has ended (the caller then compiles what is missing itself), or after :data:`WAIT_S` (or
    ``timeout_s`` where that is 0 or more: 0 reads what the child has said so far)."""
    global _unread
    child = _child
    if child is None or stage in _done or stage not in _queued or child.stdout is None or child.stdout.closed:
        return
    deadline = time.monotonic() + (WAIT_S if timeout_s < 0 else timeout_s)
    with selectors.DefaultSelector() as sel:
        sel.register(child.stdout, selectors.EVENT_READ)
        while stage not in _done:
            if not sel.select(max(deadline - time.monotonic(), 0.0)):
                return
            chunk = os.read(child.stdout.fileno(), 4096)
            if not chunk:  # the child has ended
                child.stdout.close()
                return
            *lines, _unread = (_unread + chunk).split(b"\n")
            _done.update(line.decode("ascii", "replace").strip() for line in lines)


def ready(stage: str) -> bool:
    """Whether ``stage`` is compiled, or no child compiles it (what the child has said so far,
    without waiting)."""
    wait(stage, 0.0)
    child = _child
    return child is None or stage in _done or stage not in _queued or child.stdout is None or child.stdout.closed


def worth_compiling_loop(cycles: int, cycle_cost_s: float = 1e-4) -> bool:
    """Whether a closed loop of ``cycles`` cycles, at about ``cycle_cost_s`` each in Python (0.1 ms:
    a six-legged platform's cycle of two steps), runs long enough (:data:`LOOP_WORTH_S`) to start
    a child compiling the ``loop`` stage."""
    return cycles * cycle_cost_s >= LOOP_WORTH_S


def compiled(stage: str) -> bool:
    """Whether every kernel of ``stage`` is compiled: in this process, in numba's cache, or by
    the child (what it has said so far, without waiting). Unlike :func:`ready`, False where no
    child compiles it and the cache lacks it."""
    wait(stage, 0.0)
    if stage in _done:
        return True
    return all(bool(k.signatures) or _cached(k) is True for k in _kernels(stage))


def compile_stages(stages: Iterable[str], report: bool = False) -> None:
    """Compile (or load from the cache) every kernel of ``stages`` for its signatures; with
    ``report`` print each stage's name when it is done."""
    for stage in stages:
        for kernel, sig in zip(_kernels(stage), signatures(stage)):
            kernel.compile(sig)
        if report:
            print(stage, flush=True)


def main(argv: list[str]) -> int:
    """The child: compile the stages ``argv``, saying each when done; after ``--more`` (a
    command's child), then each stage named on a line of its standard input (:func:`request`)
    until that closes."""
    more = bool(argv) and argv[0] == "--more"
    compile_stages(argv[1:] if more else argv, report=True)
    for line in sys.stdin if more else ():
        if line.strip():
            compile_stages([line.strip()], report=True)
    return 0


if __name__ == "__main__":  # pragma: no cover - the child process
    sys.exit(main(sys.argv[1:]))
