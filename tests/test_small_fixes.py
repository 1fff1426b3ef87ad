"""A motion read through a pipe is read once; the excitation's progress total is a true bound;
the default parameter files can be written to edit."""

from __future__ import annotations

import os
import tomllib

import numpy as np
import pytest

from pkmdyn.cli import main
from pkmdyn.identify._excite import max_evaluations, minimize_excitation
from pkmdyn.machines.hip_simulator.identify_excite import design_excitation, design_work
from pkmdyn.io import read_csv_columns
from pkmdyn.machines.hip_simulator import load_params


def _pipe_path(text: str) -> tuple[str, int]:
    """A pipe holding ``text`` (its write end closed), as a ``/dev/fd/N`` path, as a shell's
    process substitution gives it."""
    r, w = os.pipe()
    os.write(w, text.encode())
    os.close(w)
    return f"/dev/fd/{r}", r


def test_a_csv_from_a_pipe_is_read_once(tmp_path):
    text = "t_s,x_m\n" + "".join(f"{k},{k * 0.5}\n" for k in range(200))
    path, fd = _pipe_path(text)
    try:
        cols = read_csv_columns(path, ("t_s", "x_m"))
    finally:
        os.close(fd)
    assert cols["t_s"].shape == (200,) and cols["x_m"][-1] == 99.5


def test_hip_run_reads_its_motion_through_a_pipe(tmp_path, capsys):
    m = tmp_path / "m.csv"
    assert main(["hip", "profile", "--samples-per-cycle", "60", "--out", str(m)]) == 0
    path, fd = _pipe_path(m.read_text())
    try:
        assert main(["hip", "run", "--no-plots", "--motion", path, "--out", str(tmp_path / "o")]) == 0
    finally:
        os.close(fd)
    assert (tmp_path / "o" / "results.csv").read_text().count("\n") == 62


def test_minimize_excitation_never_exceeds_its_evaluation_bound():
    calls = [0]

    def cost(z):  # rough: L-BFGS-B would line-search past its own maxfun
        calls[0] += 1
        return float(np.sum(np.abs(z)) + np.sin(40 * z).sum())

    for starts, iterations in ((1, 1), (2, 3), (1, 7)):
        calls[0] = 0
        minimize_excitation(cost, 9, np.random.default_rng(3), starts=starts, iterations=iterations)
        assert calls[0] <= max_evaluations(9, starts, iterations)


@pytest.mark.parametrize("harmonics, samples, iterations, starts", [(1, 16, 2, 1), (2, 32, 4, 2)])
def test_the_excitation_progress_total_is_a_true_bound(harmonics, samples, iterations, starts):
    ticks = [0]

    def progress(k):
        ticks[0] += k

    design_excitation(load_params(), "friction", period_s=2.0, harmonics=harmonics, samples=samples,
                      iterations=iterations, starts=starts, seed=1, progress=progress)
    assert 0 < ticks[0] <= design_work(harmonics, samples, iterations, starts)[0]


@pytest.mark.parametrize("machine, extra, table", [("hip", [], "geometry"), ("pdm", [], "geometry"),
                                                   ("hip", ["--control"], "timing"), ("pdm", ["--control"], "sensors")])
def test_params_writes_the_default_file_to_edit(tmp_path, capsys, machine, extra, table):
    p = tmp_path / "p.toml"
    assert main([machine, "params", *extra, "--out", str(p)]) == 0
    assert table in tomllib.loads(p.read_text())
    assert main([machine, "params", *extra, "--out", str(p)]) == 0  # its own earlier file: replaced
    with p.open("a") as fh:
        fh.write("# edited\n")
    capsys.readouterr()
    assert main([machine, "params", *extra, "--out", str(p)]) == 2  # now the user's: kept
    assert p.read_text().endswith("# edited\n") and "changed after pkmdyn wrote it" in capsys.readouterr().err


def test_edited_parameter_file_runs(tmp_path):
    p = tmp_path / "p.toml"
    assert main(["hip", "params", "--out", str(p)]) == 0
    p.write_text(p.read_text().replace("slider_mass_kg = 3.00", "slider_mass_kg = 3.50"))
    assert main(["hip", "run", "--no-plots", "--params", str(p), "--samples-per-cycle", "20",
                 "--out", str(tmp_path / "o")]) == 0
