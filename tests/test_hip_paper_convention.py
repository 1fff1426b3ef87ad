"""The hip paper's own convention (docs/hip_simulator.md, "The paper's own convention"): the
built-in ``paper.toml``, the ``[motion] iso_cycle`` key that carries its ISO cycle, and the runs
that take it."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from pkmdyn.cli import main
from pkmdyn.errors import ParameterError
from hip_helpers import engine_kinematics, sliders
from pkmdyn.machines.hip_simulator import load_params, model_from_dict
from pkmdyn.machines.hip_simulator.params import default_params_dict, paper_params_path
from pkmdyn.params_util import read_toml
from pkmdyn.profiles.iso14242 import iso14242_motion
from pkmdyn.machines.hip_simulator.paper import PAPER_SLIDER_MAXIMA, iso_cycle_preset


def _upper_sliders(model, motion):
    """The upper platform's slider positions, velocities and accelerations ``(n, 3)`` by the
    engine (its actuators are the lower sliders; the upper ones ride h1 - h2 above them)."""
    m, kin = engine_kinematics(model, motion.angles, motion.rates, motion.accels, motion.t)
    sl = sliders(m)
    return kin.act_q[:, sl] + (model.geometry.h[0] - model.geometry.h[1]), kin.act_qd[:, sl], kin.act_qdd[:, sl]


def test_paper_file_is_the_same_machine_with_fe_about_the_vertical_axis():
    spec, paper = default_params_dict(), read_toml(paper_params_path())
    assert paper["geometry"].pop("euler_sequence") == "ZXY"
    assert spec["geometry"].pop("euler_sequence") == "XYZ"
    assert paper.pop("motion") == {"iso_cycle": "paper-fit-zxy"}
    assert paper == spec  # nothing else differs
    model = load_params(paper_params_path())
    assert model.motion_model == "paper-fit-zxy" and load_params().motion_model == "default"


def test_paper_convention_reproduces_the_nine_fitted_maxima():
    """The preset's six phases were fitted to the nine §5.1 maxima under ZXY; the fit holds
    within 2 % (it was 1.1 % at 400 samples per cycle)."""
    model = load_params(paper_params_path())
    L, Ld, Ldd = _upper_sliders(model, iso14242_motion(1, 2000, iso_cycle_preset(model.motion_model)))
    got = np.concatenate([L.max(axis=0), np.abs(Ld).max(axis=0), np.abs(Ldd).max(axis=0)])
    assert np.all(np.abs(got / PAPER_SLIDER_MAXIMA - 1) < 0.02)


@pytest.mark.parametrize("value", ["nope", 3])
def test_unknown_iso_cycle_names_the_key(value):
    d = copy.deepcopy(default_params_dict())
    d["motion"] = {"iso_cycle": value}
    with pytest.raises(ParameterError, match=r"\[motion\] iso_cycle"):
        model_from_dict(d)


def test_run_takes_the_parameter_files_cycle(tmp_path):
    """``hip run --params paper.toml`` runs the paper-fit-zxy cycle under ZXY without being told;
    ``--motion-model`` still overrides it."""
    model = load_params(paper_params_path())
    for extra, preset in (([], "paper-fit-zxy"), (["--motion-model", "default"], "default")):
        out = tmp_path / preset
        assert main(["hip", "run", "--params", str(paper_params_path()), "--samples-per-cycle", "100",
                     "--no-plots", "--out", str(out), *extra]) == 0
        data = np.genfromtxt(out / "results.csv", delimiter=",", names=True)
        L, _, _ = _upper_sliders(model, iso14242_motion(1, 100, iso_cycle_preset(preset)))
        for i in range(3):
            np.testing.assert_allclose(data[f"L1{i + 1}_m"], L[:, i], rtol=0, atol=1e-12)


def test_paper_option_is_the_paper_file_on_every_hip_command(tmp_path, capsys):
    """``--paper`` stands for ``--params paper.toml`` (run and export compared file for file)
    and refuses to be combined with ``--params``."""
    for cmd, extra in ((["hip", "run", "--samples-per-cycle", "50", "--no-plots"], "results.csv"),
                       (["hip", "export", "--format", "mjcf"], None)):
        a, b = tmp_path / f"{cmd[1]}_paper", tmp_path / f"{cmd[1]}_params"
        if extra is None:
            a, b = a.with_suffix(".xml"), b.with_suffix(".xml")
        assert main([*cmd, "--paper", "--out", str(a)]) == 0
        assert main([*cmd, "--params", str(paper_params_path()), "--out", str(b)]) == 0
        fa, fb = (a / extra, b / extra) if extra else (a, b)
        assert fa.read_bytes() == fb.read_bytes()
    for cmd in (["hip", "run"], ["hip", "control", "--controller", "pd"], ["hip", "export", "--format", "mjcf"],
                ["hip", "excite"], ["hip", "identify", "--measured", str(paper_params_path())]):
        out = tmp_path / "refused"
        assert main([*cmd, "--paper", "--params", str(paper_params_path()), "--out", str(out)]) == 2
        assert "--paper and --params" in capsys.readouterr().err and not out.exists()
