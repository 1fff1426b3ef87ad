"""docs/pdm4.md and docs/pdm4_schematic.png match the code's default parameters."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import numpy as np

from pkmdyn.machines.pdm4 import default_params_path, inverse_position, load_params

DOCS = Path(__file__).resolve().parents[1] / "docs"


def test_joint_table_matches_the_model():
    text = (DOCS / "pdm4.md").read_text(encoding="utf-8")
    m = load_params()
    pos = inverse_position(m, np.zeros((1, 4)))
    expected = {"R11": m.R1[0], "R12": m.R1[1], "R21": pos.R2[0, 0], "R22": pos.R2[0, 1],
                "R31": pos.R3[0, 0], "R32": pos.R3[0, 1], "R41": m.R4[0], "R42": m.R4[1],
                "S23": m.S[0], "S24": m.S[1], "U23": pos.U[0, 0], "U24": pos.U[0, 1],
                "C": pos.C[0], "P": pos.P[0]}
    num = r"\s*([−-]?\d+\.\d+)\s*"
    found = 0
    for name, value in expected.items():
        match = re.search(rf"^\|\s*{name}\s*\|{num}\|{num}\|{num}\|", text, re.MULTILINE)
        assert match, name
        doc = np.array([float(g.replace("−", "-")) for g in match.groups()]) * 1e-3
        assert np.allclose(doc, value, atol=6e-7), name
        found += 1
    assert found == 14


def test_every_parameter_key_is_documented():
    text = (DOCS / "pdm4.md").read_text(encoding="utf-8")
    raw = tomllib.loads(default_params_path().read_text(encoding="utf-8"))
    for section, keys in raw.items():
        for key in keys:
            assert key in text, f"[{section}] {key}"


def test_schematic_is_present():
    assert (DOCS / "pdm4_schematic.png").stat().st_size > 10_000
