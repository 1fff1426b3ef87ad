"""Plausibility limits of every machine: PDM limb speeds, accelerations and forces, platforms
closer than the hardware allows, motions of one sample or of absurd duration, sensor settings
that cannot work in the control cycle. Each is refused with one line and nothing written, and
each limit can be raised."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from pkmdyn.cli import main
from pkmdyn.errors import LimitError
from pkmdyn.io import write_csv
from pkmdyn.machines.hip_simulator import model_from_dict
from pkmdyn.machines.hip_simulator.params import DEFAULT_PARAMS_TEXT


def _refused(capsys, args, out, *words):
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("pkmdyn: error: "), err
    for w in words:
        assert w in err, err
    assert not out.exists() and not [p for p in out.parent.iterdir() if ".partial-" in p.name]
    return err


def test_pdm_run_refuses_a_motion_squeezed_into_a_millisecond(tmp_path, capsys):
    out = tmp_path / "o"
    base = ["pdm", "run", "--no-plots", "--period-s", "0.001"]
    _refused(capsys, [*base, "--out", str(out)], out, "max_limb_speed_m_s", "m/s", "l11")
    _refused(capsys, [*base, "--limit", "max_limb_speed_m_s=100", "--out", str(out)], out, "max_limb_acceleration_m_s2")
    _refused(capsys, [*base, "--limit", "max_limb_speed_m_s=100", "--limit", "max_limb_acceleration_m_s2=1e6",
                      "--out", str(out)], out, "max_actuator_force_N", "N")
    raised = ["--limit", "max_limb_speed_m_s=100", "--limit", "max_limb_acceleration_m_s2=1e6",
              "--limit", "max_actuator_force_N=1e7"]
    assert main([*base, *raised, "--out", str(out)]) == 0


def test_pdm_limits_can_be_raised_in_the_parameter_file(tmp_path, capsys):
    from pkmdyn.machines.pdm4.params import default_params_path

    text = default_params_path().read_text()
    d = tomllib.loads(text)
    assert "limits" not in d or "max_limb_speed_m_s" not in d["limits"]
    p = tmp_path / "p.toml"
    p.write_text(text + "\n[limits]\nmax_limb_speed_m_s = 0.001\n" if "[limits]" not in text else
                 text.replace("[limits]", "[limits]\nmax_limb_speed_m_s = 0.001"))
    _refused(capsys, ["pdm", "run", "--no-plots", "--params", str(p), "--out", str(tmp_path / "o")], tmp_path / "o",
             "max_limb_speed_m_s = 0.001")


def test_hip_platforms_closer_than_a_slider_are_refused_unless_the_file_allows_it():
    d = tomllib.loads(DEFAULT_PARAMS_TEXT)
    d["geometry"]["platform_heights_m"] = [0.50, 0.49]
    with pytest.raises(LimitError, match="min_platform_gap_m"):
        model_from_dict(d)
    d["limits"] = {"min_platform_gap_m": 0.005}
    assert model_from_dict(d).limits.min_platform_gap_m == 0.005


def _hip_motion(path, t, deriv=True):
    n = len(t)
    cols = {"t_s": np.asarray(t, dtype=float)}
    for a in ("alpha", "beta", "gamma"):
        cols[f"{a}_deg"] = np.zeros(n)
        if deriv:
            cols[f"{a}_dot_deg_s"] = np.zeros(n)
            cols[f"{a}_ddot_deg_s2"] = np.zeros(n)
    write_csv(path, cols)
    return path


def _pdm_motion(path, t, deriv=True):
    n = len(t)
    cols = {"t_s": np.asarray(t, dtype=float)}
    for c in ("x_m", "y_m", "alpha_rad", "gamma_rad"):
        cols[c] = np.zeros(n)
    if deriv:
        for c in ("xd_m_s", "yd_m_s", "alphad_rad_s", "gammad_rad_s", "xdd_m_s2", "ydd_m_s2", "alphadd_rad_s2",
                  "gammadd_rad_s2"):
            cols[c] = np.zeros(n)
    write_csv(path, cols)
    return path


@pytest.mark.parametrize("machine, writer", [("hip", _hip_motion), ("pdm", _pdm_motion)])
def test_a_motion_of_one_sample_is_refused(tmp_path, capsys, machine, writer):
    m = writer(tmp_path / "m.csv", [0.0])
    out = tmp_path / "o"
    _refused(capsys, [machine, "run", "--no-plots", "--motion", str(m), "--out", str(out)], out, "at least 2 data rows",
             "m.csv")


@pytest.mark.parametrize("machine, writer, key", [("hip", _hip_motion, "max_duration_s"),
                                                 ("pdm", _pdm_motion, "max_duration_s")])
def test_a_motion_of_absurd_duration_is_refused_and_the_limit_raised(tmp_path, capsys, machine, writer, key):
    m = writer(tmp_path / "m.csv", np.linspace(0.0, 1e9, 8), deriv=False)
    out = tmp_path / "o"
    _refused(capsys, [machine, "run", "--no-plots", "--motion", str(m), "--out", str(out)], out, key, "duration")
    if machine == "hip":
        assert main([machine, "run", "--no-plots", "--motion", str(m), "--limit", f"{key}=2e9", "--out", str(out)]) == 0


def test_hip_built_in_motion_of_absurd_duration_is_refused_before_allocating(tmp_path, capsys):
    out = tmp_path / "o"
    _refused(capsys, ["hip", "run", "--no-plots", "--cycles", "3e7", "--samples-per-cycle", "2", "--limit",
                      "max_samples=100000000", "--out", str(out)], out, "max_duration_s")


@pytest.mark.parametrize("machine, controller, table, word", [
    ("hip", "pd", "velocity_cutoff_Hz = 500.0", "Nyquist"),
    ("hip", "pd", "acceleration_cutoff_Hz = 900.0", "Nyquist"),
    ("pdm", "pid", "velocity_cutoff_Hz = 250.0", "Nyquist"),
    ("hip", "pd", "encoder_counts_per_turn = 1\nencoder_travel_per_turn_rad = 1000.0", "encoder_counts_per_turn"),
    ("pdm", "pid", "encoder_counts_per_turn = 1", "encoder_counts_per_turn"),
])
def test_sensor_settings_that_cannot_work_in_the_control_cycle_are_refused(tmp_path, capsys, machine, controller,
                                                                             table, word):
    g = tmp_path / "g.toml"
    g.write_text(f"[sensors]\n{table}\n")
    out = tmp_path / "o"
    _refused(capsys, [machine, "control", "--controller", controller, "--no-plots", "--cycles", "0.01", "--gains", str(g),
                      "--out", str(out)], out, word, "g.toml")
