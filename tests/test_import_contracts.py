"""Import directions, as the contracts in pyproject.toml ([tool.importlinter]) state them: the
command line on top; identification, simulation and control above the machines; the machines
above the multibody layer and the motion and analysis helpers; no machine imports another."""

from __future__ import annotations

from pathlib import Path

import pytest

importlinter_cli = pytest.importorskip("importlinter.cli")

ROOT = Path(__file__).resolve().parents[1]


def _lint(config: Path) -> int:
    return importlinter_cli.lint_imports(config_filename=str(config), no_cache=True, no_logo=True)


def test_the_projects_contracts_are_kept():
    assert _lint(ROOT / "pyproject.toml") == 0


def test_a_broken_contract_is_caught(tmp_path):
    """The checker does bite: the command line below the machines is reported broken."""
    bad = tmp_path / "bad.toml"
    bad.write_text('[tool.importlinter]\nroot_package = "pkmdyn"\n\n[[tool.importlinter.contracts]]\n'
                   'name = "upside down"\ntype = "layers"\nlayers = ["pkmdyn.machines", "pkmdyn.cli"]\n',
                   encoding="utf-8")
    assert _lint(bad) == 1



def _machine_compares(text: str, where: str) -> list[str]:
    """``where:line`` of every comparison with the string "hip" or "pdm" in the module ``text``."""
    import ast

    found = []
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.Compare):
            for side in (node.left, *node.comparators):
                names = [side] if isinstance(side, ast.Constant) else list(getattr(side, "elts", []))
                if any(isinstance(c, ast.Constant) and c.value in ("hip", "pdm") for c in names):
                    found.append(f"{where}:{node.lineno}")
    return found


def test_no_layer_outside_the_machines_compares_a_machine_name():
    """Outside the machines' own folders no module routes by the strings "hip" or "pdm" (a
    machine comes from the registry)."""
    src = ROOT / "src" / "pkmdyn"
    found = [f for p in sorted(src.rglob("*.py")) if p.relative_to(src).parts[0] != "machines"
             for f in _machine_compares(p.read_text(encoding="utf-8"), str(p.relative_to(src)))]
    assert found == []


def test_the_machine_name_scan_finds_a_comparison():
    probe = 'def f(m):\n    a = "hip"\n    return 1 if m == "hip" else (2 if m in ("x", "pdm") else 3)\n'
    assert _machine_compares(probe, "probe") == ["probe:3", "probe:3"]
    assert _machine_compares('a = "hip"\nb = a + "pdm"\n', "probe") == []


def _import_graph(files: dict[str, str], packages: set[str]) -> dict[str, set[str]]:
    """Module -> the project's modules it imports, function-local imports and ``if
    TYPE_CHECKING:`` blocks included (a circle through annotations is still a circle for the
    reader); ``files``: module name -> source (a package under its own name, from its
    ``__init__``), ``packages`` the packages' names. ``from . import x`` names the submodule
    ``x`` where there is one, else the package."""
    import ast

    graph: dict[str, set[str]] = {m: set() for m in files}
    for mod, text in files.items():
        pkg = mod if mod in packages else mod.rsplit(".", 1)[0]
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    parts = pkg.split(".")[: len(pkg.split(".")) - node.level + 1]
                    target = ".".join(parts + ([node.module] if node.module else []))
                else:
                    target = node.module or ""
                subs = [f"{target}.{a.name}" for a in node.names if f"{target}.{a.name}" in files]
                names = subs if len(subs) == len(node.names) else [target, *subs]
            elif isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            else:
                continue
            graph[mod] |= {t for t in names if t in files and t != mod}
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan's algorithm)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_module_imports_itself_through_others():
    """No import circle between the project's modules, counting the imports inside functions
    and those for annotations only (which hide a circle from the import system but not from
    the reader)."""
    src = ROOT / "src"
    files, packages = {}, set()
    for p in sorted((src / "pkmdyn").rglob("*.py")):
        parts = p.relative_to(src).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
            packages.add(".".join(parts))
        files[".".join(parts)] = p.read_text(encoding="utf-8")
    assert _cycles(_import_graph(files, packages)) == []


def test_the_circle_check_finds_a_function_local_circle():
    files = {"p": "", "p.a": "from .b import f\n", "p.b": "def f():\n    from .a import g\n",
             "p.c": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .d import g\n",
             "p.d": "from . import c\n"}
    graph = _import_graph(files, {"p"})
    assert _cycles(graph) == [["p.a", "p.b"], ["p.c", "p.d"]]
    assert graph["p.d"] == {"p.c"} and graph["p.c"] == {"p.d"}


def _calls_of(text: str, names: tuple[str, ...]) -> list[int]:
    """Lines of the calls of any of ``names`` (as a bare name or an attribute) in the module ``text``."""
    import ast

    return [node.lineno for node in ast.walk(ast.parse(text)) if isinstance(node, ast.Call)
            and getattr(node.func, "id", getattr(node.func, "attr", None)) in names]


def test_one_writer_of_output_folders():
    """A job's folder, its summary and its report are written by one writer
    (pkmdyn.report.write_output): no other module calls write_report or output_dir."""
    src = ROOT / "src" / "pkmdyn"
    callers = sorted(str(p.relative_to(src)) for p in src.rglob("*.py")
                     if _calls_of(p.read_text(encoding="utf-8"), ("write_report", "output_dir")))
    assert callers == ["report/_output.py"]


def test_the_call_scan_finds_a_call():
    probe = "from x import write_report\nimport io\nwrite_report(1)\nio.output_dir(2)\nf = output_dir\n"
    assert _calls_of(probe, ("write_report", "output_dir")) == [3, 4]


def test_the_commands_write_nothing_themselves():
    """The command line (cli/ and each machine's commands.py) parses, calls one job and prints:
    it calls none of the writers."""
    src = ROOT / "src" / "pkmdyn"
    writers = ("atomic_file", "output_dir", "write_output", "write_report", "write_view", "write_json", "write_csv",
               "open_table_writer", "write_text", "write_bytes", "savefig", "write_motion_csv")
    modules = [*sorted((src / "cli").glob("*.py")), *sorted((src / "machines").glob("*/commands.py"))]
    assert len(modules) > 10
    found = {str(p.relative_to(src)): lines for p in modules
             if (lines := _calls_of(p.read_text(encoding="utf-8"), writers))}
    assert found == {}
