"""Importing pkmdyn costs little: a package import, the command line and its help load none of the
heavy libraries (Numba, SciPy's solvers and filters, the plotting and sweep libraries) until a
function needs them. Checked by which modules a fresh interpreter holds afterwards, never by
time; and every public name of a package that imports its names on first use is still there,
the same object its submodule defines."""

from __future__ import annotations

import ast
import importlib
import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import pytest

import pkmdyn

SRC = Path(pkmdyn.__file__).resolve().parents[1]

#: what no plain import may load
HEAVY = ("numba", "scipy", "scipy.signal", "scipy.stats", "scipy.interpolate", "scipy.optimize", "scipy.linalg",
         "scipy.sparse", "scipy.ndimage", "matplotlib", "plotly", "dask", "distributed", "pyarrow", "pymoo", "tqdm",
         "pydantic", "tomlkit", "yaml")
#: the packages whose public names are imported on first use
LAZY_PACKAGES = ("pkmdyn.multibody", "pkmdyn.simulate", "pkmdyn.control", "pkmdyn.sweep", "pkmdyn.report",
                 "pkmdyn.identify", "pkmdyn.machines.hip_simulator", "pkmdyn.machines.pdm4")


def _loaded(code: str, watch: tuple[str, ...] = HEAVY) -> list[str]:
    """The modules of ``watch`` that a fresh interpreter holds after running ``code``."""
    probe = f"{code}\nimport sys\nprint(' '.join(m for m in {watch!r} if m in sys.modules))"
    env = dict(os.environ, PYTHONPATH=str(SRC))
    out = subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True, text=True, check=True)
    return out.stdout.split()


@pytest.mark.parametrize("module", ("pkmdyn", "pkmdyn.errors", *LAZY_PACKAGES))
def test_a_package_import_loads_nothing_heavy(module):
    assert _loaded(f"import {module}", (*HEAVY, "numpy")) == []


def test_the_command_line_and_its_help_load_nothing_heavy():
    """The command tree and its help, by the group itself and through :func:`pkmdyn.cli.main`
    (which sets up the compile notice, listening on Numba's events, only once the arguments are
    read and a command runs)."""
    assert _loaded("import pkmdyn.cli") == []
    for argv in (["--help"], ["run", "--help"], ["hip", "run", "--help"], ["run"]):  # (the last: a usage error)
        code = ("import contextlib, io\nfrom pkmdyn.cli import main\n"
                "with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):\n"
                f"    main({argv!r})")
        assert _loaded(code) == [], argv
    for argv in (["--help"], ["machines"], ["hip", "--help"], ["run", "--help"], ["sweep", "--help"]):
        code = ("import contextlib, io\nfrom pkmdyn.cli import cli\n"
                "with contextlib.redirect_stdout(io.StringIO()), contextlib.suppress(SystemExit):\n"
                f"    cli.main({argv!r}, prog_name='pkmdyn', standalone_mode=False)")
        assert _loaded(code) == [], argv


def test_a_description_is_read_without_the_kernels_or_scipy():
    assert _loaded("from pkmdyn.multibody import load_description") == ["pydantic"]


def test_the_kinematics_load_the_kernels_but_not_scipys_filters_or_solvers():
    """A model is compiled with SciPy's linear algebra, a motion file derived with its splines or
    filters, each at first use only."""
    loaded = _loaded("from pkmdyn.multibody import solve_kinematics, default_motion")
    assert "numba" in loaded
    assert not {"scipy.linalg", "scipy.signal", "scipy.stats", "scipy.interpolate", "scipy.optimize",
                "matplotlib", "plotly"} & set(loaded)


def _type_checking_imports(package: str) -> dict[str, str]:
    """Public name -> defining module, as the ``if TYPE_CHECKING:`` block of ``package`` imports it."""
    init = SRC / Path(*package.split(".")) / "__init__.py"
    found: dict[str, str] = {}
    for node in ast.parse(init.read_text(encoding="utf-8")).body:
        if isinstance(node, ast.If) and getattr(node.test, "id", None) == "TYPE_CHECKING":
            for imp in node.body:
                assert isinstance(imp, ast.ImportFrom)
                module = importlib.util.resolve_name("." * imp.level + (imp.module or ""), package)
                found.update((a.name, module) for a in imp.names)
    return found


@pytest.mark.parametrize("package", LAZY_PACKAGES)
def test_every_public_name_is_there_and_is_what_type_checkers_see(package):
    """Each name of ``__all__`` is imported by the type checkers' block and, looked up on the
    package, is the object that block names (the table of the first-use imports agrees with it)."""
    mod = importlib.import_module(package)
    seen = _type_checking_imports(package)
    assert set(mod.__all__) <= set(seen) | set(vars(mod))
    for name, module in seen.items():
        assert getattr(mod, name) is getattr(importlib.import_module(module), name), name
    assert set(mod.__all__) <= set(dir(mod))
    with pytest.raises(AttributeError, match="no_such_name"):
        getattr(mod, "no_such_name")


def test_a_lazy_module_imports_at_first_use():
    from pkmdyn._lazy import lazy_module

    probe = "from pkmdyn._lazy import lazy_module\nm = lazy_module('xml.dom.minidom')\nrepr(m)"
    assert _loaded(probe, ("xml", "xml.dom.minidom")) == []
    assert _loaded(probe + "\nm.parseString", ("xml", "xml.dom.minidom")) == ["xml", "xml.dom.minidom"]
    colorsys = lazy_module("colorsys")
    assert colorsys.rgb_to_hsv(1.0, 0.0, 0.0) == (0.0, 1.0, 1.0)
    assert repr(colorsys).endswith("(imported)>")
