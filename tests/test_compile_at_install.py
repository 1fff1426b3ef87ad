"""Kernels compiled at install (pkmdyn compile, setup.py): an installed pkmdyn carries numba's
cache of its kernels for this machine; every exercise of ``pkmdyn compile`` is a command line
the command line takes; a lane says each exercise that failed and still runs the others."""

from __future__ import annotations

import importlib
from pathlib import Path

import click
import pytest

import pkmdyn
from pkmdyn.cli import cli
from pkmdyn.cli import compile as comp
from pkmdyn.multibody._cache import cached

#: a source checkout (``src/pkmdyn`` beside ``pyproject.toml``): the kernels compile on first use
#: there; an installed package carries them
FROM_SOURCE = (Path(pkmdyn.__file__).resolve().parents[2] / "pyproject.toml").is_file()


@pytest.mark.skipif(FROM_SOURCE, reason="pkmdyn runs from its source checkout: the install is what compiles")
@pytest.mark.parametrize("module, kernel", [
    ("pkmdyn.multibody.kinematics._solve_kernels", "solve_sample"), ("pkmdyn.multibody.kinematics._solve_kernels", "solve_batch"),
    ("pkmdyn.multibody.dynamics._sample_kernels", "_dynamics"), ("pkmdyn.multibody.kinematics._direct_kernels", "direct_one"),
    ("pkmdyn.multibody.kinematics._direct_kernels", "direct_task_one"), ("pkmdyn.multibody.dynamics._reaction_kernels", "cut_reactions_batch"),
    ("pkmdyn.multibody.kinematics.singularity._kernels", "measure_bounds"), ("pkmdyn.simulate._cycles", "run_cycles"),
    ("pkmdyn.multibody.kinematics.singularity._kernels", "measure_brackets"),
])
def test_the_installed_package_carries_its_compiled_kernels(module, kernel):
    dispatcher = getattr(importlib.import_module(module), kernel)
    assert cached(dispatcher), f"{module}.{kernel}: not in numba's cache of the installed package"
    index = Path(dispatcher._cache._cache_file._index_path)
    assert Path(pkmdyn.__file__).resolve().parent in index.resolve().parents  # inside the package


@pytest.mark.parametrize("args", [a for lane in comp.LANES for a in lane if not a[0].startswith("@")],
                         ids=lambda a: " ".join(a[:3]))
def test_every_exercise_is_a_command_line(args, tmp_path):
    """Each exercise parses as its command's options (an option renamed or removed would leave
    the install's compilation short, said by one warning in pip's output at most)."""
    (tmp_path / "results.csv").write_text("t_s\n0\n", encoding="utf-8")  # an earlier exercise's file
    line = [str(tmp_path) + a[a.index("}") + 1:] if "{" in a else ("P=1" if a == "@reference" else a) for a in args]
    cmd: click.Command = cli
    while isinstance(cmd, click.Group):  # down to the command itself
        name, line = line[0], line[1:]
        cmd = cmd.get_command(click.Context(cmd), name)
        assert cmd is not None, f"{' '.join(args)}: no command {name!r}"
    with cmd.make_context(name, [*line, "--out", str(tmp_path / "out")]) as ctx:
        assert not ctx.args, f"{' '.join(args)}: arguments left over: {ctx.args}"


def test_a_lane_says_each_failed_exercise_and_runs_the_rest(monkeypatch, capsys):
    monkeypatch.setattr(comp, "LANES", ((("hip", "params"), ("run", "--machine", "no-such-machine"),
                                         ("pdm", "params")),))
    ran = []
    real = comp._exercise

    def spy(args, outs, root):
        status, last = real(args, outs, root)
        ran.append((args[0], status, outs[-1].exists()))
        return status, last

    monkeypatch.setattr(comp, "_exercise", spy)
    assert comp._lane(0) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no-such-machine" in err[0] and "exit 2" in err[0]
    assert [(a, s) for a, s, _ in ran] == [("hip", 0), ("run", 2), ("pdm", 0)]
    assert ran[0][2] and ran[2][2]  # the good ones wrote their file (into the lane's temporary folder)


#: commands beside :data:`pkmdyn.cli.compile.LANES`' own: other machines, controllers and analyses
OTHER_COMMANDS = [
    ["run", "--machine", "bennett"],
    ["run", "--machine", "rrr3"],
    ["control", "--machine", "rrr3", "--duration", "0.02"],
    ["control", "--machine", "stewart", "--controller", "pd", "--duration", "0.02"],
    ["stiffness", "--machine", "stewart"],
    ["workspace", "--machine", "stewart", "--grid", "x=-0.2:0.2:5,y=-0.2:0.2:5", "--pose", "z=1.0"],
    ["hip", "control", "--controller", "pd", "--cycles", "0.02", "--no-plots"],
    ["pdm", "control", "--controller", "computed-torque", "--cycles", "0.02", "--no-plots"],
]


@pytest.mark.slow
@pytest.mark.skipif(FROM_SOURCE, reason="pkmdyn runs from its source checkout: the install is what compiles")
@pytest.mark.parametrize("args", OTHER_COMMANDS, ids=lambda a: " ".join(a[:3]))
def test_commands_after_the_install_compile_nothing(args, tmp_path):
    """The first run of a command the install did not run itself, in a process of its own:
    every kernel it takes is in the installed cache (no compile notice on stderr)."""
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    r = subprocess.run([sys.executable, "-m", "pkmdyn.cli", *args, "--out", str(tmp_path / "out")], env=env,
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "compiling numerical kernels" not in r.stderr and "compiled" not in r.stderr, r.stderr
