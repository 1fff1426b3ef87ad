"""The compile notice (pkmdyn/compile_notice.py): said once when a kernel of pkmdyn compiles,
with the time it took; nothing for other compilations."""

from __future__ import annotations

import io
import sys

from numba import njit

from pkmdyn import compile_notice


def test_notice_once_with_the_time(capsys, monkeypatch):
    monkeypatch.setattr(compile_notice, "_state", {"listener": None})
    from numba.core import event

    compile_notice.install(force=True)
    lst = compile_notice._state["listener"]
    try:
        assert compile_notice.summary() is None

        @njit
        def not_ours(x):  # this test module is not pkmdyn's: no notice
            return x + 1

        not_ours(1)
        assert compile_notice.summary() is None and capsys.readouterr().err == ""
        # a function of pkmdyn's, compiled afresh (not from the cache)
        g = {"__name__": "pkmdyn.example"}
        exec("def f(x):\n    return 2 * x\n", g)
        njit(cache=False)(g["f"])(1.0)
        njit(cache=False)(g["f"])(2)
        err = capsys.readouterr().err.splitlines()
        assert err == [compile_notice.MESSAGE]
        line = compile_notice.summary()
        assert line is not None and "compiled the kernels in" in line
    finally:
        event.unregister("numba:compile", lst)


def test_without_a_terminal_only_the_summary_of_what_a_command_compiled(monkeypatch):
    """A script or a pipe reading stderr gets no message while compiling, and the summary
    covers only what was compiled after :func:`compile_notice.mark` (one command's kernels)."""
    monkeypatch.setattr(compile_notice, "_state", {"listener": None})
    fake = io.StringIO()
    monkeypatch.setattr(sys, "stderr", fake)
    from numba.core import event

    compile_notice.install()
    lst = compile_notice._state["listener"]
    try:
        g = {"__name__": "pkmdyn.example2"}
        exec("def f(x):\n    return 3 * x\n", g)
        njit(cache=False)(g["f"])(1.0)
        assert fake.getvalue() == ""
        assert "compiled the kernels in" in compile_notice.summary()
        before = compile_notice.mark()
        assert compile_notice.summary(before) is None  # nothing compiled since
        njit(cache=False)(g["f"])(2)
        assert "compiled the kernels in" in compile_notice.summary(before)
    finally:
        event.unregister("numba:compile", lst)
