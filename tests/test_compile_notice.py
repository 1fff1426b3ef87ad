"""The compile notice (pkmdyn/compile_notice.py): said once, whether or not stderr is a
terminal, when a kernel of pkmdyn compiles, with its name and why the cache did not serve it;
the summary names how many kernels took how long; nothing for other compilations."""

from __future__ import annotations

import importlib
import os
import pickle
import sys

import numba
import pytest
from numba import njit
from numba.core import event

from pkmdyn import compile_notice


@pytest.fixture
def listener(monkeypatch):
    """A listener of this test's own: the process's (a command run earlier in it installed one)
    taken off meanwhile, then put back."""
    earlier = compile_notice._state["listener"]
    if earlier is not None:
        event.unregister("numba:compile", earlier)
    monkeypatch.setattr(compile_notice, "_state", {"listener": None})
    assert not sys.stderr.isatty()  # not a terminal (captured): said all the same
    compile_notice.install()
    lst = compile_notice._state["listener"]
    assert lst is not None
    yield
    event.unregister("numba:compile", lst)
    if earlier is not None:
        event.register("numba:compile", earlier)


def test_notice_once_with_the_kernel_and_the_time(listener, capsys):
    assert compile_notice.summary() is None

    @njit
    def not_ours(x):  # this test module is not pkmdyn's: no notice
        return x + 1

    not_ours(1)
    assert compile_notice.summary() is None and capsys.readouterr().err == ""
    # a function of pkmdyn's, compiled afresh (not from the cache), for two argument types
    g = {"__name__": "pkmdyn.example"}
    exec("def f(x):\n    return 2 * x\n", g)
    njit(cache=False)(g["f"])(1.0)
    njit(cache=False)(g["f"])(2)
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and "pkmdyn.example.f" in err[0] and "pkmdyn compile" in err[0]
    line = compile_notice.summary()
    assert line is not None and "compiled 1 kernel in" in line
    compile_notice.reset()  # a next command in the same process speaks of its own compilations
    assert compile_notice.summary() is None
    njit(cache=False)(g["f"])(3.0)
    assert len(capsys.readouterr().err.splitlines()) == 1 and "compiled 1 kernel" in compile_notice.summary()


def _cached_module(tmp_path, monkeypatch):
    """A module of a cached kernel in ``tmp_path``, compiled once: its dispatcher and index file."""
    (tmp_path / "notice_probe.py").write_text(
        "from numba import njit\n\n@njit(cache=True)\ndef twice(x):\n    return 2 * x\n", encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    mod = importlib.import_module("notice_probe")
    mod.twice(1.0)
    index = mod.twice._cache._cache_file._index_path
    return mod.twice, index


def _rewrite(index, edit):
    with open(index, "rb") as f:
        version = pickle.load(f)
        stamp, overloads = pickle.loads(f.read())
    version, stamp, overloads = edit(version, stamp, overloads)
    with open(index, "wb") as f:
        pickle.dump(version, f, protocol=-1)
        f.write(pickle.dumps((stamp, overloads), protocol=-1))


def test_the_reason_names_the_numba_version_the_cpu_or_a_missing_cache(tmp_path, monkeypatch):
    kernel, index = _cached_module(tmp_path, monkeypatch)
    from numba.core.registry import cpu_target

    here = cpu_target.target_context.codegen().magic_tuple()
    try:
        assert "other argument types" in compile_notice._why(kernel)  # served, but asked for another signature
        _rewrite(index, lambda v, s, o: (v, s, {(k[0], (k[1][0], "some-other-cpu", k[1][2]), k[2]): d
                                                for k, d in o.items()}))
        why = compile_notice._why(kernel)
        assert "some-other-cpu" in why and "built for CPU" in why
        _rewrite(index, lambda v, s, o: (v, s, {(k[0], (k[1][0], here[1], "+other"), k[2]): d for k, d in o.items()}))
        assert "other features of CPU" in compile_notice._why(kernel)
        _rewrite(index, lambda v, s, o: ("0.1.0", s, o))
        why = compile_notice._why(kernel)
        assert "numba 0.1.0" in why and numba.__version__ in why
        _rewrite(index, lambda v, s, o: (numba.__version__, b"another source", o))
        assert "source changed" in compile_notice._why(kernel)
        os.remove(index)
        assert "no cache" in compile_notice._why(kernel)
    finally:
        sys.modules.pop("notice_probe", None)


def test_installed_before_numba_it_listens_from_numbas_import_on():
    """``install`` imports no numba (a command's help, a command that compiles nothing); the
    listener is registered as numba is imported, and says a compilation."""
    import subprocess

    code = ("import sys\nfrom pkmdyn import compile_notice as c\nc.install()\nassert 'numba' not in sys.modules\n"
            "from numba import njit\nassert c._state['listener'] is not None\n"
            "g = {'__name__': 'pkmdyn.example'}\nexec('def f(x):\\n    return x + 1\\n', g)\nnjit(g['f'])(1)\n"
            "print(c.summary())")
    import pkmdyn
    from pathlib import Path

    env = {**os.environ, "PYTHONPATH": str(Path(pkmdyn.__file__).resolve().parents[1])}
    r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert "compiled 1 kernel" in r.stdout and "pkmdyn.example.f" in r.stderr


def test_silenced_it_says_nothing(listener, capsys):
    """``pkmdyn compile`` silences the notice: compiling is its work."""
    lst = compile_notice._state["listener"]
    compile_notice.silence()
    g = {"__name__": "pkmdyn.example"}
    exec("def f(x):\n    return 3 * x\n", g)
    njit(cache=False)(g["f"])(1.0)
    assert capsys.readouterr().err == "" and compile_notice.summary() is None
    event.register("numba:compile", lst)  # the fixture's listener back, for its teardown
