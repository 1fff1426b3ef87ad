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
command's pipe (nothing on the terminal), and is ended when the command ends.

A command starts the child with the stages it surely needs (``sample``, ``one``) and hands it
more on its standard input once it knows them (:func:`request`): the direct kinematics of the
route its mechanism takes, so that the child does not spend seconds on the other one first.

The first stage, ``sample``, is the sample solver (:func:`._kernels.solve_sample`) alone: the
command's batched kinematics and the child's single-sample dynamics both call it, and each
process would compile it (some 6 s of a core) at about the same time. The child compiles it
first and the command waits for it (:func:`wait`) once its mechanism is loaded, before its
first batched kinematics, which then load it; ``pkmdyn run`` starts a child for that too (and
for a later ``pkmdyn control``, which then finds the loop's kernel cached). Where the command
waits for a stage the child has not reported yet, it compiles meanwhile a later stage it will
need (:data:`WHILE_WAITING`: the direct kinematics) rather than wait idle: each stage is
claimed by whichever process starts it first (a file created in a folder the two share,
:func:`_claim`), and the child skips a stage the command has claimed.

Its last stage, ``loop``, is the closed loop's cycles in one compiled call
(:mod:`pkmdyn.simulate._cycles`), which links the kernels above a second time (some 15-30 s):
no command waits for it; the loop takes its Python cycles until it is compiled (:func:`compiled`).
``pkmdyn control`` starts a child for it where the run is long (:data:`LOOP_WORTH_S`).

    python -m pkmdyn.multibody.ahead sample one task direct loop
"""

from __future__ import annotations

import atexit
import importlib
import os
import selectors
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterable
from typing import Any

__all__ = ["STAGES", "LOOP_WORTH_S", "cold", "start", "request", "coming", "wait", "ready", "compiled",
           "worth_compiling_loop", "compile_stages", "signatures"]

#: the stages a child can compile, in this order: the sample solver that the batched kinematics
#: and the single-sample kernels share (``sample``), the closed loop's single-sample dynamics and
#: encoders (``one``), its direct kinematics of the encoders' reading in task space (``task``:
#: the Gough-Stewart platform, the hip), and in tree space (``direct``: any other mechanism),
#: and the loop's cycles in one compiled call (``loop``, :mod:`pkmdyn.simulate._cycles`: some
#: 30 s, which a command does not wait for; until it is compiled the loop runs its cycles in
#: Python)
STAGES = ("sample", "one", "task", "direct", "loop")
#: while the command waits for the stage named (not yet reported by the child), it compiles
#: these itself where the child was given them and has not started them: the direct kinematics,
#: which a closed loop needs later, rather than wait idle for the child to reach them
WHILE_WAITING = {"sample": ("task", "direct"), "one": ("task", "direct")}
#: a run whose cycles in Python would take about this long [s] or more starts a child compiling
#: the ``loop`` stage alone (:func:`worth_compiling_loop`): it is done before the run is, and the
#: rest of the run takes the compiled cycles
LOOP_WORTH_S = 60.0
#: the module of the ``loop`` stage's kernel: the simulation layer's, above this one, so named
#: here rather than imported
_LOOP_MODULE = "pkmdyn.simulate._cycles"


def _kernels(stage: str) -> list[Any]:
    """The compiled functions (numba dispatchers) of ``stage``."""
    if stage == "sample":
        from . import _kernels as K

        return [K.solve_sample]
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
    if stage == "sample":  # solve_sample(xs, xds, xdds, q, q_ref, chord, tree, loops, task, solver, work, info)
        return [tuple(_numba_type(c) for c in _SAMPLE_ARGS)]
    if stage == "one":  # _dynamics(pk, x, xd, v, load, mode, out)
        return [(buf, vec, vec, vec, types.float64, types.int64, vec)]
    if stage == "task":  # direct_task_one(pk, d, s, sd, out)
        return [(buf, buf, vec, vec, vec)]
    if stage == "direct":  # direct_one(b, s, sd, out)
        return [(buf, vec, vec, vec)]
    if stage == "loop":  # run_cycles(...): the types of a run's arguments
        return [importlib.import_module(_LOOP_MODULE).example_signature()]
    raise ValueError(f"compile-ahead stage {stage!r}: unknown (known: {', '.join(STAGES)})")


#: the argument types of :func:`._kernels.solve_sample` as :func:`._one._dynamics` and
#: :func:`._kernels.solve_batch` call it (``fN`` / ``iN``: a C-contiguous float64 / int64 array
#: of N dimensions; ``i`` / ``f`` / ``b`` an int64, a float64, a bool; a tuple: a tuple of
#: those); tests/test_compile_ahead.py checks that both callers then compile no other version
_SAMPLE_ARGS = (*"f1 f1 f1 f1 f1 b".split(),
                (*"i1 i1 i1 i1 i1 f1 f1 f3 f2 f3 f2".split(),  # tree, ending with the explicit legs' table
                 tuple("i1 i1 i2 i1 i1 f2 f3 f3 f2 f2 f2 i2 i2 i2 f2 f2 f3 i1 i1".split())),
                tuple("f3 f2 f3 f2 i2 i1 i1 i1 i1 i1 i1 i1".split()),  # loops
                tuple("i f1 i1 i1 i1".split()),  # task
                tuple("i1 f2 i1 i1 i1 f1 f f i i1 i1 i1".split()),  # solver
                tuple("f3 f2 f2 f1 f1 f2 i1 f1 f1 f1 f1 f1 f2 f2 f2 f1 f2 f3 f2 f2 f2 f2".split()),  # work
                "f1")


def _numba_type(code: str | tuple) -> Any:
    """The numba type of one code of :data:`_SAMPLE_ARGS`."""
    from numba import types

    if isinstance(code, tuple):
        return types.Tuple(tuple(_numba_type(c) for c in code))
    scalar = {"i": types.int64, "f": types.float64, "b": types.boolean}
    if code in scalar:
        return scalar[code]
    return types.Array(types.int64 if code[0] == "i" else types.float64, int(code[1:]), "C")


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
#: the folder of claimed stages that this process shares with its child (:func:`_claim`)
_claims: str | None = None
#: the longest wait for a stage [s] (after what the command compiles meanwhile, :func:`wait`);
#: past it the command compiles the kernel itself
WAIT_S = 600.0


def start(stages: Iterable[str]) -> subprocess.Popen | None:
    """A child compiling the kernels of ``stages`` in that order, or None where it would not help
    (module docstring) or a child of this process still runs. The child ends with this process."""
    global _child, _unread, _claims
    stages = tuple(stages)
    if os.environ.get("PKMDYN_COMPILE_AHEAD", "1") == "0" or (os.cpu_count() or 1) < 2 or not cold(stages):
        return None
    if _child is not None and _child.poll() is None:
        return None
    try:
        claims = tempfile.mkdtemp(prefix="pkmdyn-compile-")
    except OSError:  # pragma: no cover - no writable temporary folder: the command compiles alone
        return None
    _done.clear()
    _unread = b""
    _claims = claims
    atexit.register(shutil.rmtree, claims, True)
    _child = subprocess.Popen([sys.executable, "-m", __name__, "--claims", _claims, "--more", *stages],
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, bufsize=0)
    _queued[:] = stages
    atexit.register(_stop, _child)
    return _child


def _claim(stage: str, folder: str | None) -> bool:
    """Whether this process takes ``stage``: it creates the stage's file in ``folder``, the
    folder it shares with the other process, first (an exclusive create, so one process alone
    succeeds); True without a folder."""
    if folder is None:
        return True
    try:
        os.close(os.open(os.path.join(folder, stage), os.O_CREAT | os.O_EXCL | os.O_WRONLY))
    except FileExistsError:
        return False
    except OSError:  # pragma: no cover - the folder has gone (the command ends): compile it here
        return True
    return True


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
    ``timeout_s`` where that is 0 or more: 0 reads what the child has said so far). Without
    ``timeout_s``, the stages of :data:`WHILE_WAITING` that the child has not started are first
    compiled here (:func:`_compile_meanwhile`)."""
    global _unread
    child = _child
    if child is None or stage in _done or stage not in _queued or child.stdout is None or child.stdout.closed:
        return
    if timeout_s < 0 and WHILE_WAITING.get(stage):
        _compile_meanwhile(stage)
        if stage in _done or child.stdout.closed:  # done, or the child has ended meanwhile
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


def _compile_meanwhile(stage: str) -> None:
    """While the child has not reported ``stage``: compile here each stage of
    ``WHILE_WAITING[stage]`` that it was given and has not started (claimed: :func:`_claim`).
    Such a stage counts as done here even where its compilation failed: the child skips it, and
    the caller compiles it again where first called, which then says why."""
    wait(stage, 0.0)
    for later in WHILE_WAITING[stage]:
        if stage in _done:
            return
        if later in _queued and later not in _done and _claim(later, _claims):
            try:
                compile_stages([later])
            except Exception:  # any failure: the caller's own call compiles it again and says why
                pass
            _done.add(later)
        wait(stage, 0.0)


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


def compile_stages(stages: Iterable[str], report: bool = False, claims: str | None = None) -> None:
    """Compile (or load from the cache) every kernel of ``stages`` for its signatures; with
    ``report`` print each stage's name when it is done; with ``claims`` (the folder of
    :func:`_claim`) skip each stage that the command has taken."""
    for stage in stages:
        if not _claim(stage, claims):
            continue
        for kernel, sig in zip(_kernels(stage), signatures(stage)):
            kernel.compile(sig)
        if report:
            print(stage, flush=True)


def main(argv: list[str]) -> int:
    """The child: compile the stages ``argv``, saying each when done; with ``--claims FOLDER``
    only those the command has not claimed (:func:`_claim`); after ``--more`` (a command's
    child), then each stage named on a line of its standard input (:func:`request`) until that
    closes."""
    claims = None
    if argv[:1] == ["--claims"]:
        claims, argv = argv[1], argv[2:]
    more = bool(argv) and argv[0] == "--more"
    compile_stages(argv[1:] if more else argv, report=True, claims=claims)
    for line in sys.stdin if more else ():
        if line.strip():
            compile_stages([line.strip()], report=True, claims=claims)
    return 0


if __name__ == "__main__":  # pragma: no cover - the child process
    sys.exit(main(sys.argv[1:]))
