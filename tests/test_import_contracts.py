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
