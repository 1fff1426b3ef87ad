"""Compiling ahead (pkmdyn.multibody.ahead): the signatures the child compiles are the ones the
closed loop calls, which kernels a fresh cache lacks, and when no child is started."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from pkmdyn.machines.registry import description_path
from pkmdyn.multibody import ahead, load_mechanism, reference_task
from pkmdyn.multibody.machine import machine_verbs


def _loop_calls():
    """The single-sample calls a closed loop makes: dynamics, encoders, direct kinematics."""
    m = load_mechanism(description_path("stewart"))
    V = machine_verbs(m)
    x, z = reference_task(m), np.zeros(m.nt)
    u = V.inverse_dynamics_one(m, x, z, z)
    V.forward_dynamics_one(m, x, z, u)
    a = V.actuator_coordinates_one(m, x, z, fresh=True)
    V.actuator_coordinates_one(m, x, z)
    V.direct_one(m, a, np.zeros(m.na))
    V.direct_one(m, a, np.zeros(m.na))


@pytest.mark.parametrize("stage", ahead.STAGES)
def test_the_child_compiles_the_signatures_the_loop_calls(stage):
    _loop_calls()
    ahead.compile_stages([stage])
    for kernel, sig in zip(ahead._kernels(stage), ahead.signatures(stage)):
        assert set(kernel.signatures) == {sig}  # the loop's calls compiled nothing else
    assert not ahead.cold([stage])
    with pytest.raises(ValueError, match="unknown"):
        ahead.signatures("no-such-stage")


def test_a_fresh_cache_is_cold(tmp_path):
    code = "from pkmdyn.multibody import ahead; print(ahead.cold(ahead.STAGES), ahead.cold(()))"
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["True", "False"]


def test_no_child_where_it_cannot_help(monkeypatch):
    ahead.compile_stages(ahead.STAGES)
    monkeypatch.setenv("PKMDYN_COMPILE_AHEAD", "1")
    assert ahead.start(ahead.STAGES) is None  # every kernel cached already
    monkeypatch.setattr(ahead, "cold", lambda stages: True)
    monkeypatch.setenv("PKMDYN_COMPILE_AHEAD", "0")
    assert ahead.start(ahead.STAGES) is None  # switched off
    monkeypatch.setenv("PKMDYN_COMPILE_AHEAD", "1")
    monkeypatch.setattr(os, "cpu_count", lambda: 1)
    assert ahead.start(ahead.STAGES) is None  # one core: it would only slow the command


def test_a_started_child_reports_its_stages_and_ends_with_the_command(monkeypatch):
    """A child started on a (pretended) cold cache runs the module (here on the suite's cache:
    it loads the kernels), reports each stage, which ``wait`` reads (``ready`` says so without
    waiting), and ends with status 0; or
    is ended by ``_stop``, after which ``wait`` returns at once."""
    monkeypatch.setattr(ahead, "_child", None)
    ahead.wait("one")  # no child: nothing to wait for
    assert ahead.ready("task")  # nor to hold back for
    monkeypatch.setenv("PKMDYN_COMPILE_AHEAD", "1")
    monkeypatch.setattr(ahead, "cold", lambda stages: True)
    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    child = ahead.start(("one", "task", "direct"))
    assert child is not None and ahead._child is child
    ahead.wait("task")
    assert "task" in ahead._done and ahead.ready("task")
    ahead.wait("direct")
    assert ahead._done == {"one", "task", "direct"}
    ahead.request(("one", "loop"))  # handed to the running child: the stage it was not given
    assert ahead._queued == ["one", "task", "direct", "loop"]
    ahead.wait("loop")
    assert "loop" in ahead._done
    child.stdin.close()  # the command's end: the child stops listening for more
    assert child.wait(timeout=120) == 0
    ahead.wait("one")
    stopped = ahead.start(("one", "direct"))
    assert ahead._done == set()
    ahead._stop(stopped)
    assert stopped.poll() is not None
    ahead.wait("direct")  # the stopped child's output ends: no wait


def test_a_silent_child_is_waited_for_at_most_wait_s(monkeypatch):
    """``wait`` gives up after ``WAIT_S`` on a child that says nothing: it returns while the
    child (asleep for 30 s) still runs, the stage not done."""
    silent = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"], stdout=subprocess.PIPE,
                              bufsize=0)
    try:
        monkeypatch.setattr(ahead, "_child", silent)
        monkeypatch.setattr(ahead, "_queued", ["one"])
        monkeypatch.setattr(ahead, "WAIT_S", 0.3)
        ahead.wait("one")
        assert silent.poll() is None
        assert "one" not in ahead._done
    finally:
        ahead._stop(silent)


def test_no_second_child_while_one_runs_and_the_loop_stage_for_long_runs(monkeypatch):
    """While a child runs no second one starts; a long closed loop is worth a child for the
    loop's cycles, a short one is not."""
    monkeypatch.setenv("PKMDYN_COMPILE_AHEAD", "1")
    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    monkeypatch.setattr(ahead, "_child", None)
    monkeypatch.setattr(ahead, "cold", lambda stages: True)
    child = ahead.start(("one",))
    try:
        assert child is not None and child.args[-1] == "one"
        assert ahead.start(("loop",)) is None  # the running child's
        # not given to the child, which listens for more stages until the command ends: no wait
        # on its output at all (a wait would last until WAIT_S)
        with monkeypatch.context() as m:
            m.setattr(ahead.selectors, "DefaultSelector", None)  # a wait would fail calling it
            ahead.wait("task")
            assert ahead.ready("task") and child.poll() is None
    finally:
        ahead._stop(child)
    second = ahead.start(("task",))  # the first has ended
    try:
        assert second is not None and second is not child
    finally:
        ahead._stop(second)
    assert not ahead.worth_compiling_loop(500) and ahead.worth_compiling_loop(10**7)


def test_a_stage_coming_next_is_waited_for(monkeypatch):
    """``coming``: the child compiles the stage next (every stage given before it done), so a
    command waits for it rather than compiling it itself; not where another stage comes first,
    nor where no child was given it."""
    monkeypatch.setattr(ahead, "_child", subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"],
                                                          stdout=subprocess.PIPE, bufsize=0))
    try:
        monkeypatch.setattr(ahead, "_queued", ["one", "task", "direct"])
        monkeypatch.setattr(ahead, "_done", {"one"})
        assert ahead.coming("task") and not ahead.coming("direct") and not ahead.coming("loop")
        ahead._done.add("task")
        assert ahead.coming("direct")
    finally:
        ahead._stop(ahead._child)


@pytest.mark.parametrize("machine, route", [("stewart", "task"), ("delta", "direct")])
def test_control_hands_the_child_the_direct_kinematics_its_mechanism_takes(machine, route, monkeypatch, tmp_path):
    """``pkmdyn control`` of a described mechanism requests the direct kinematics of the route
    its mechanism takes (the task-space one for the Gough-Stewart platform, the tree-space one
    for the Delta), and the loop's cycles only for a long run (not the default one second)."""
    from pkmdyn.cli import main

    asked = []
    monkeypatch.setattr(ahead, "request", lambda stages: asked.append(tuple(stages)))
    assert main(["control", "--machine", machine, "--out", str(tmp_path / "out")]) == 0
    assert asked == [(route,)]


@pytest.mark.slow
def test_the_sample_stage_is_the_version_both_callers_take(tmp_path):
    """In a fresh cache: the ``sample`` stage compiled first, the single-sample dynamics and
    the batched kinematics then compiled (the loop's calls) take that version of the sample
    solver and compile no other."""
    code = ("import sys; sys.path.insert(0, sys.argv[1]); import test_compile_ahead as t\n"
            "from pkmdyn.multibody import ahead, _kernels as K, solve_kinematics, load_mechanism\n"
            "from pkmdyn.multibody import reference_task\n"
            "from pkmdyn.machines.registry import description_path\n"
            "ahead.compile_stages(['sample'])\n"
            "t._loop_calls()\n"
            "m = load_mechanism(description_path('stewart')); x = reference_task(m)\n"
            "solve_kinematics(m, x[None], 0 * x[None], 0 * x[None])\n"
            "print(len(K.solve_sample.signatures), K.solve_sample.signatures[0] == ahead.signatures('sample')[0])")
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    out = subprocess.run([sys.executable, "-c", code, os.path.dirname(__file__)], env=env, capture_output=True,
                         text=True, check=True)
    assert out.stdout.split() == ["1", "True"]


def test_the_child_skips_a_stage_the_command_has_claimed(tmp_path, capsys):
    """The child (``main``) compiles and reports the stages it claims, and skips one whose
    claim file the command made first; a claim succeeds once."""
    assert ahead._claim("task", str(tmp_path))
    assert not ahead._claim("task", str(tmp_path))  # the second process to ask
    assert ahead._claim("task", None)  # no shared folder: this process compiles it
    assert ahead.main(["--claims", str(tmp_path), "one", "task"]) == 0
    assert capsys.readouterr().out.split() == ["one"]
    assert (tmp_path / "one").exists()


def _silent_child(monkeypatch, tmp_path, code="import time; time.sleep(30)"):
    """A child that says nothing (by default for 30 s), given ``sample``, ``one`` and ``task``,
    ``sample`` reported; the claims' folder ``tmp_path``; waits of at most 0.3 s."""
    child = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, bufsize=0)
    monkeypatch.setattr(ahead, "_child", child)
    monkeypatch.setattr(ahead, "_queued", ["sample", "one", "task"])
    monkeypatch.setattr(ahead, "_done", {"sample"})
    monkeypatch.setattr(ahead, "_claims", str(tmp_path))
    monkeypatch.setattr(ahead, "WAIT_S", 0.3)
    return child


def test_a_command_compiles_the_direct_kinematics_while_it_waits(monkeypatch, tmp_path):
    """While the child has not reported ``one``, ``wait("one")`` compiles the queued direct
    kinematics the child has not started, claimed, and counts it done; not in a wait that only
    reads (timeout 0), nor where the child claimed it first."""
    compiled = []
    child = _silent_child(monkeypatch, tmp_path)
    try:
        monkeypatch.setattr(ahead, "compile_stages", lambda stages, **kw: compiled.append(list(stages)))
        ahead.wait("one", 0.0)
        assert compiled == []
        ahead.wait("one")
        assert compiled == [["task"]] and ahead._done == {"sample", "task"} and (tmp_path / "task").exists()
    finally:
        ahead._stop(child)
    child = _silent_child(monkeypatch, tmp_path / "child-first")
    try:
        (tmp_path / "child-first").mkdir()
        (tmp_path / "child-first" / "task").touch()  # the child's claim
        ahead.wait("one")
        assert compiled == [["task"]] and "task" not in ahead._done
    finally:
        ahead._stop(child)


def test_a_failed_compilation_meanwhile_is_not_waited_for(monkeypatch, tmp_path):
    """Where the command's own compilation of a stage meanwhile fails, the stage counts as done
    (the child skips it, claimed): a later wait for it returns at once, and the caller's call
    compiles it again and says why."""
    def fail(stages, **kw):
        raise RuntimeError("typing failed")

    child = _silent_child(monkeypatch, tmp_path)
    try:
        monkeypatch.setattr(ahead, "compile_stages", fail)
        ahead.wait("one")  # the direct kinematics meanwhile: it fails; then 0.3 s for "one"
        assert "task" in ahead._done and (tmp_path / "task").exists()
        with monkeypatch.context() as m:
            m.setattr(ahead.selectors, "DefaultSelector", None)  # a wait on the child would fail calling it
            ahead.wait("task")
        assert "task" in ahead._done
    finally:
        ahead._stop(child)


@pytest.mark.parametrize("stage", ["sample", "one"])
def test_a_child_that_ends_without_a_word_is_not_waited_for(stage, monkeypatch, tmp_path):
    """A child that ends at once (a compilation that failed in it): the wait returns without
    error (the command then compiles the kernel itself), also where it first compiles a later
    stage meanwhile."""
    compiled = []
    child = _silent_child(monkeypatch, tmp_path, code="pass")
    try:
        child.wait(timeout=60)
        monkeypatch.setattr(ahead, "_done", set())
        monkeypatch.setattr(ahead, "compile_stages", lambda stages, **kw: compiled.append(list(stages)))
        ahead.wait(stage)
        assert stage not in ahead._done and child.stdout.closed
    finally:
        ahead._stop(child)


@pytest.mark.parametrize("command", [["run"], ["control"]])
def test_a_command_waits_for_the_sample_solver_before_its_batched_kinematics(command, monkeypatch, tmp_path):
    """``pkmdyn run`` and ``pkmdyn control`` of a described mechanism wait for the child's
    ``sample`` stage before their first batched kinematics (whose kernel calls the sample
    solver), once each."""
    from pkmdyn.cli import main
    from pkmdyn.multibody import _kernels as K

    calls = []
    batch = K.solve_batch
    monkeypatch.setattr(ahead, "wait", lambda stage, timeout_s=-1.0: calls.append(stage))
    monkeypatch.setattr(ahead, "request", lambda stages: None)
    monkeypatch.setattr(K, "solve_batch", lambda *a: (calls.append("solve_batch"), batch(*a))[1])
    assert main([*command, "--machine", "stewart", "--out", str(tmp_path / "out")]) == 0
    assert calls.index("sample") < calls.index("solve_batch") and calls.count("sample") == 1
