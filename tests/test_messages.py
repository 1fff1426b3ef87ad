"""Messages a person can act on: divergence in the coordinate's name and the settings file's
unit, feedforward on an open-loop unstable plant, help of a group called without a command,
the one note that kernels are being compiled."""

from __future__ import annotations

import pytest

from pkmdyn.cli import main


def _one_error(capsys):
    captured = capsys.readouterr()
    err = captured.err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("pkmdyn: error: "), err
    return err


@pytest.mark.parametrize("machine, controller, table, words", [
    ("hip", "pd", "divergence_limit_deg = [30.0, 30.0, 0.01]", ("gamma (IER)", "deg", "divergence_limit_deg = 0.01 deg")),
    ("pdm", "pid", "divergence_limit_m = [0.00001, 0.01]", ("error of x is", " m,", "divergence_limit_m = 1e-05 m")),
])
def test_divergence_names_the_coordinate_in_the_settings_unit(tmp_path, capsys, machine, controller, table, words):
    g = tmp_path / "g.toml"
    g.write_text(f"[run]\n{table}\n")
    out = tmp_path / "o"
    assert main([machine, "control", "--controller", controller, "--no-plots", "--gains", str(g), "--out", str(out)]) == 2
    err = _one_error(capsys)
    for w in words:
        assert w in err, err
    assert "coordinate 3" not in err and "coordinate 1" not in err and not out.exists()


def test_feedforward_on_the_open_loop_unstable_pdm_says_why(tmp_path, capsys):
    out = tmp_path / "o"
    assert main(["pdm", "control", "--controller", "feedforward", "--no-plots", "--out", str(out)]) == 2
    err = _one_error(capsys)
    assert "open-loop unstable" in err and "feedback controller" in err and "gamma" in err
    assert main(["pdm", "control", "--controller", "feedforward", "--no-plots", "--cycles", "0.05",
                 "--out", str(out)]) == 0
    assert "open-loop unstable" in capsys.readouterr().err


def test_the_stable_hip_gets_no_such_warning(tmp_path, capsys):
    assert main(["hip", "control", "--controller", "feedforward", "--no-plots", "--cycles", "0.05",
                 "--out", str(tmp_path / "o")]) == 0
    assert "unstable" not in capsys.readouterr().err


@pytest.mark.parametrize("args, first", [([], "Usage: pkmdyn [OPTIONS] COMMAND"), (["hip"], "Usage: pkmdyn hip"),
                                         (["pdm"], "Usage: pkmdyn pdm")])
def test_a_group_without_a_command_prints_its_help(capsys, args, first):
    assert main(args) == 0
    captured = capsys.readouterr()
    assert captured.out.startswith(first) and "Commands:" in captured.out and captured.err == ""
