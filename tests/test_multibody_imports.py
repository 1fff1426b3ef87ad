"""Import direction: the multibody layer (the engine) sits below the jobs, machines, simulation,
control, identification, sweeps and the command line, and imports none of them; and it writes no
files and starts no processes (the jobs write)."""

from __future__ import annotations

import ast
from pathlib import Path

PKG = Path(__file__).resolve().parents[1] / "src" / "pkmdyn"
FORBIDDEN = ("machines", "cli", "jobs", "simulate", "control", "identify", "sweep", "validation")


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            mod = node.module or ""
            if node.level >= 2:
                # relative to the file's own package: up to pkmdyn, then the first name
                depth = len(path.relative_to(PKG).parts) - 1
                if node.level > depth:
                    out.add(mod.split(".")[0])
            elif node.level == 0 and mod.startswith("pkmdyn."):
                out.add(mod.split(".")[1])
        elif isinstance(node, ast.Import):
            out |= {a.name.split(".")[1] for a in node.names if a.name.startswith("pkmdyn.")}
    return out


def test_multibody_imports_no_higher_layer():
    files = sorted((PKG / "multibody").rglob("*.py"))
    assert len(files) >= 40
    for f in files:
        bad = _imports(f) & set(FORBIDDEN)
        assert not bad, f"{f.name} imports {sorted(bad)}"


#: calls that write a file or start a process
WRITES = ("subprocess", "multiprocessing", "concurrent.futures", "os.system", "Popen", ".write_text(",
          ".write_bytes(", "savez", "savefig", "write_json(", "write_csv(", "output_dir(", "atomic_file(",
          "to_csv(", "to_parquet(")


def test_the_engine_writes_no_files_and_starts_no_processes():
    """No engine module calls a writer or starts a process; numba's cache markers (``_cache.py``,
    beside the compiled kernels, never among the user's files) are the one exception."""
    for f in sorted((PKG / "multibody").rglob("*.py")):
        if f.name == "_cache.py":
            continue
        text = f.read_text(encoding="utf-8")
        code = "\n".join(line.split("#")[0] for line in text.splitlines())
        found = [w for w in WRITES if w in code]
        assert not found, f"{f.relative_to(PKG)} calls {found}"
        assert not any(m in ("w", "a", "x") for m in _open_modes(text)), f"{f.relative_to(PKG)} opens a file to write"


def _open_modes(text: str) -> list[str]:
    """The mode arguments of every ``open(...)`` call in ``text``."""
    modes = []
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.Call) and getattr(node.func, "id", getattr(node.func, "attr", None)) == "open":
            args = [*node.args[1:2], *(k.value for k in node.keywords if k.arg == "mode")]
            modes += [a.value[0] for a in args if isinstance(a, ast.Constant) and isinstance(a.value, str) and a.value]
    return modes


PACKAGES = ("pkmdyn", "pkmdyn.multibody", "pkmdyn.multibody.description", "pkmdyn.multibody.model",
            "pkmdyn.multibody.kinematics", "pkmdyn.multibody.dynamics", "pkmdyn.multibody.analyses",
            "pkmdyn.multibody.formats", "pkmdyn.jobs", "pkmdyn.identify", "pkmdyn.sweep", "pkmdyn.control",
            "pkmdyn.simulate", "pkmdyn.report", "pkmdyn.profiles", "pkmdyn.analysis")


def test_every_name_a_package_lists_resolves():
    """Each package's ``dir()`` (its lazily attached names included) names only what it gives: a
    name left behind by a move fails here, not at a user's first lookup."""
    import importlib

    for package in PACKAGES:
        module = importlib.import_module(package)
        for name in dir(module):
            if not name.startswith("_"):
                getattr(module, name)  # raises AttributeError or ImportError for a stale entry


def _resolves(dotted: str) -> bool:
    import importlib

    parts = dotted.split(".")
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
        except ModuleNotFoundError:
            continue
        try:
            for attr in parts[k:]:
                obj = getattr(obj, attr)
        except AttributeError:
            return False
        return True
    return False


def test_every_engine_path_the_docs_and_docstrings_name_exists():
    """``pkmdyn.multibody.<...>`` and ``multibody.<...>`` in the docs, the README and the source's
    docstrings and comments name a module or a name that exists (the engine's layers moved its
    modules; a reference to the old place misleads a reader)."""
    import re

    root = Path(__file__).resolve().parents[1]
    files = [root / "README.md", *sorted((root / "docs").glob("*.md")), *sorted((root / "src").rglob("*.py"))]
    pattern = re.compile(r"(?<![\w/])(?:pkmdyn\.)?(multibody(?:\.[A-Za-z_]\w*)+)")
    stale = set()
    for f in files:
        for ref in pattern.findall(f.read_text(encoding="utf-8")):
            if not _resolves("pkmdyn." + ref):
                stale.add(f"{f.relative_to(root)}: {ref}")
    assert not stale, sorted(stale)
