"""Import direction: the multibody layer sits below machines, simulation, control,
identification and the command line, and imports none of them."""

from __future__ import annotations

import ast
from pathlib import Path

PKG = Path(__file__).resolve().parents[1] / "src" / "pkmdyn"
FORBIDDEN = ("machines", "cli", "simulate", "control", "identify", "validation")


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            mod = node.module or ""
            if node.level >= 2:
                out.add(mod.split(".")[0])
            elif node.level == 0 and mod.startswith("pkmdyn."):
                out.add(mod.split(".")[1])
        elif isinstance(node, ast.Import):
            out |= {a.name.split(".")[1] for a in node.names if a.name.startswith("pkmdyn.")}
    return out


def test_multibody_imports_no_higher_layer():
    files = sorted((PKG / "multibody").glob("*.py"))
    assert len(files) >= 8
    for f in files:
        bad = _imports(f) & set(FORBIDDEN)
        assert not bad, f"{f.name} imports {sorted(bad)}"
