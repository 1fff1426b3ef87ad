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
