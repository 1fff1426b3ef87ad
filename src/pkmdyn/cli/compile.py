"""``pkmdyn compile``: fill numba's on-disk cache with every kernel the commands use, now.

``python -m pip install .`` runs it once while it builds pkmdyn (``setup.py``), so that the
installed package carries its compiled kernels and the first command after an install starts
as a later one does. A user runs it again where the cache cannot serve: after numba was
upgraded, on another CPU (a shared install, a copied environment), or after clearing the
cache; a command meeting a missing kernel compiles it itself and says so on stderr
(:mod:`pkmdyn.compile_notice`).

The kernels are compiled by running the commands themselves on the built-in machines with
small inputs (:data:`LANES`), into a temporary folder that is removed afterwards: a kernel is
compiled for the argument types its callers pass, and running the callers is the one way that
stays true as the code changes. The exercises are split in lanes of about equal compile time,
one process a lane (``--jobs``, default the cores, at most the lanes), so that a two-core
machine compiles in about half the time. Lanes share few kernels; a kernel two lanes need is
compiled by both (numba writes each cache file whole under a new name, so neither reads half
a file).
"""

from __future__ import annotations

import contextlib
import io
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import TYPE_CHECKING

import click

from .._lazy import lazy_module
from ..compile_notice import silence
from ..errors import PkmdynError
from ..machines.registry import generated_machines, resolve
from ._groups import cli, echo

if TYPE_CHECKING:
    from .. import multibody as _multibody
    from ..multibody.kinematics import direct as _direct
    from ..multibody.kinematics.singularity import measures as _measures
    from ..simulate import _cycles
else:  # loaded when a command runs, not on import (nor for --help)
    _multibody = lazy_module("pkmdyn.multibody")
    _direct = lazy_module("pkmdyn.multibody.kinematics.direct")
    _measures = lazy_module("pkmdyn.multibody.kinematics.singularity.measures")
    _cycles = lazy_module("pkmdyn.simulate._cycles")

__all__ = ["LANES", "compile_kernels"]

#: each lane: the exercises one process runs in order, each a command line without ``--out``
#: (``{k}`` names the folder of the lane's k-th exercise: its files as an input; ``@reference``
#: the actuators a little off their reference), or ``@cycles``: the closed loop's compiled cycles
#: (:func:`pkmdyn.simulate._cycles.compile_for_runs`), which no short run takes, or ``@bounds``: the
#: singularity measures' level bounds (:func:`pkmdyn.multibody.kinematics.singularity.measures.least_measure_bounds`),
#: which a sweep's workspace takes and no command.
#: Lane 0 takes the closed loops (the single-sample kernels and the loop's cycles, the longest
#: compilations), lane 1 the batched kinematics, dynamics and analyses.
_GENERIC_LANES: tuple[tuple[tuple[str, ...], ...], ...] = (
    (
        ("@cycles",),  # the closed loop's cycles in one compiled call (a long run's route)
        ("control", "--machine", "stewart", "--controller", "computed-torque", "--duration", "0.02"),
        ("control", "--machine", "delta", "--controller", "pid", "--duration", "0.02"),
        ("control", "--machine", "bennett", "--duration", "0.02"),  # one actuator: other array types
        ("pdm", "control", "--controller", "pid", "--cycles", "0.01", "--no-plots"),
        ("assemble", "--machine", "stewart", "--actuators", "@reference", "--starts", "8"),
        ("assemble", "--machine", "delta", "--actuators", "@reference", "--starts", "8"),
    ),
    (
        ("run", "--machine", "stewart", "--samples-per-cycle", "64"),
        ("identify", "--machine", "stewart", "--measured", "{0}/results.csv"),
        ("run", "--machine", "delta", "--samples-per-cycle", "64"),
        ("run", "--machine", "pdm"),
        ("stiffness", "--machine", "delta", "--default-motion"),
        ("workspace", "--machine", "delta", "--grid", "x=-0.6:0.6:5,y=-0.6:0.6:5", "--pose", "z=-1.2"),
        ("pdm", "run", "--no-plots"),
        ("@bounds",),
    ),
)


def _lanes() -> tuple[tuple[tuple[str, ...], ...], ...]:
    """The generic exercises, each generated machine's own (``COMPILE_EXERCISES`` of its registry
    entry: ``(lane, command line)`` pairs) appended to their lanes."""
    lanes = [list(lane) for lane in _GENERIC_LANES]
    for entry in generated_machines().values():
        for lane, args in getattr(entry, "COMPILE_EXERCISES", ()):
            lanes[lane].append(tuple(args))
    return tuple(tuple(lane) for lane in lanes)


#: every lane's exercises (the generic ones and the generated machines' own)
LANES = _lanes()


def _reference_actuators(machine: str) -> str:
    """``NAME=VALUE,...`` of ``machine``'s actuators a little off their reference: an
    ``assemble`` input that every built-in machine reaches."""

    _, path = resolve(machine)
    model = _multibody.load_mechanism(path)
    ref = _direct.actuator_reference(model)
    return ",".join(f"{a}={v + 0.01:.12g}" for a, v in zip(model.actuator_names, ref))


def _exercise(args: tuple[str, ...], outs: list[Path], root: Path) -> tuple[int, str]:
    """Run one exercise in this process (the command tree of :mod:`._groups`, every command
    registered by then); its exit status and what it said last."""
    if args == ("@cycles",):
        _cycles.compile_for_runs()
        return 0, ""
    if args == ("@bounds",):
        model = _multibody.load_mechanism(resolve("delta")[1])
        for tight in (False, True):
            _measures.least_measure_bounds(model, model.coord_offset[None, :], 1e-3, tight=tight)
        return 0, ""
    line = [a.format(*outs) if "{" in a else a for a in args]
    if "@reference" in line:
        line[line.index("@reference")] = _reference_actuators(line[line.index("--machine") + 1])
    out = root / f"x{len(outs)}"
    outs.append(out)
    err = io.StringIO()
    try:
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
            cli.main([*line, "--out", str(out)], prog_name="pkmdyn", standalone_mode=False)
    except click.exceptions.Exit as exc:
        return int(exc.exit_code), ""
    except (click.ClickException, PkmdynError) as exc:
        return 2, " ".join(str(exc).split())
    lines = err.getvalue().strip().splitlines()
    return 0, lines[-1] if lines else ""


def _lane(index: int) -> int:
    """Run lane ``index`` in this process; one line a failed exercise on stderr."""
    failed = 0
    with tempfile.TemporaryDirectory(prefix="pkmdyn-compile-") as tmp:
        outs: list[Path] = []
        for args in LANES[index]:
            status, last = _exercise(args, outs, Path(tmp))
            if status != 0:
                failed += 1
                print(f"pkmdyn compile: {' '.join(args)}: exit {status}: {last}", file=sys.stderr, flush=True)
    return 1 if failed else 0


def compile_kernels(jobs: int | None = None, log=print) -> int:
    """Run every lane of :data:`LANES`, ``jobs`` processes at a time (default: the cores, at
    most the lanes); the number of lanes that failed."""
    jobs = max(1, min(len(LANES), jobs or os.cpu_count() or 1))
    t0 = time.perf_counter()
    pending = list(range(len(LANES)))
    running: dict[int, subprocess.Popen] = {}
    failed = 0
    try:
        while pending or running:
            while pending and len(running) < jobs:
                k = pending.pop(0)
                running[k] = subprocess.Popen([sys.executable, "-m", "pkmdyn.cli", "compile", "--lane", str(k)])
            for k, proc in list(running.items()):
                if proc.poll() is not None:
                    del running[k]
                    failed += proc.returncode != 0
                    log(f"pkmdyn compile: lane {k + 1} of {len(LANES)} done ({time.perf_counter() - t0:.0f} s)")
            if running:
                time.sleep(0.2)
    finally:
        for proc in running.values():
            proc.terminate()
            proc.wait()
    return failed


@cli.command("compile")
@click.option("--jobs", type=click.IntRange(1, 64), default=None,
              help="Processes compiling at once (default: the cores, at most the lanes).")
@click.option("--lane", type=click.IntRange(0, len(LANES) - 1), default=None, hidden=True)
def compile_command(jobs: int | None, lane: int | None) -> None:
    """Compile every numerical kernel into numba's cache now (done by the install; again after
    numba was upgraded or on another CPU). Writes nothing but the cache."""
    silence()  # compiling is this command's work: no notice of it
    if lane is not None:
        click.get_current_context().exit(_lane(lane))
    if compile_kernels(jobs, log=echo):
        raise click.ClickException("some kernels were not compiled (the lines above); "
                                   "the commands compile them on their first use")
