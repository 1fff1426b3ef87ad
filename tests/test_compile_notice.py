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


def test_no_notice_without_a_terminal(monkeypatch):
    """A script or a pipe reading stderr gets only what the command says (one line for an
    error): no listener where stderr is not a terminal."""
    monkeypatch.setattr(compile_notice, "_state", {"listener": None})
    monkeypatch.setattr(sys, "stderr", io.StringIO())
    compile_notice.install()
    assert compile_notice._state["listener"] is None and compile_notice.summary() is None
