"""Identification says when a fit means nothing: all-zero, sign-flipped or unrelated measured
torques are refused with one line naming the file, and nothing is written; a good fit reports
the share of each torque it explains; ``residual_rms_percent`` is never 0 for a non-zero residual."""

from __future__ import annotations

import json

import numpy as np
import pytest

from pkmdyn.cli import main
from pkmdyn.identify._report import _percent, explained_percent

from test_fuzz_new_commands import _measured_text


def _measured(tmp_path, change=None, name="m.csv"):
    lines = _measured_text().splitlines()
    header = lines[0].split(",")
    cols = [header.index(f"tau{i}_Nm") for i in (1, 2, 3)]
    rng = np.random.default_rng(0)
    out = [lines[0]]
    for line in lines[1:]:
        cells = line.split(",")
        if change is not None:
            for c in cols:
                cells[c] = repr(float(change(float(cells[c]), rng)))
        out.append(",".join(cells))
    p = tmp_path / name
    p.write_text("\n".join(out) + "\n")
    return p


@pytest.mark.parametrize("which", ["friction", "all"])
@pytest.mark.parametrize("change, words", [
    (lambda x, rng: 0.0, ("'tau1_Nm' is zero in every row",)),
    (lambda x, rng: -x, ("identification failed", "bound")),
    (lambda x, rng: rng.normal() * 0.1, ("identification failed",)),
])
def test_a_meaningless_fit_is_an_error_and_writes_nothing(tmp_path, capsys, which, change, words):
    m = _measured(tmp_path, change)
    out = tmp_path / "id"
    assert main(["hip", "identify", "--no-plots", "--identify", which, "--measured", str(m), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith(f"pkmdyn: error: {m}"), err
    for w in words:
        assert w in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.csv"]


def test_a_good_fit_reports_the_share_it_explains(tmp_path, capsys):
    m = _measured(tmp_path)
    out = tmp_path / "id"
    assert main(["hip", "identify", "--no-plots", "--measured", str(m), "--out", str(out)]) == 0
    doc = json.loads((out / "identification.json").read_text())
    assert doc["minimum_explained_percent"] == 50.0
    assert all(v > 99.9 for v in doc["explained_percent"].values())


def test_residual_percent_is_never_zero_for_a_nonzero_residual():
    assert _percent(0.1, 0.0) is None and _percent(0.0, 0.0) == 0.0 and _percent(1.0, 4.0) == 25.0
    share = explained_percent(np.array([[1.0, 0.0], [-1.0, 0.0]]), np.array([[2.0, 0.5], [-2.0, 0.0]]))
    assert share[0] == -300.0 and share[1] == -np.inf
