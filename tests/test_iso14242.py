"""The ISO 14242-1 cycle model: exact derivatives, key points, periodicity, CSV round trip."""

import numpy as np
import pytest

from pkmdyn.errors import MotionError, ParameterError
from pkmdyn.profiles.iso14242 import AxisWave, IsoCycle, angle_wave, iso14242_motion, iso_load
from pkmdyn.profiles.orientation import read_motion_csv, write_motion_csv

WAVES = [AxisWave(25, 0.0, -18, 0.55), AxisWave(7, 0.32, -4, 0.75), AxisWave(2, 0.9, -10, 0.3), AxisWave(1, 0.5, 0, 0.2)]


@pytest.mark.parametrize("wave", WAVES)
def test_derivatives_against_finite_differences(wave):
    t = np.linspace(0, 2, 97)
    h = 1e-6
    q, qd, qdd = angle_wave(t, 1.3, wave)
    qp, qdp, _ = angle_wave(t + h, 1.3, wave)
    qm, qdm, _ = angle_wave(t - h, 1.3, wave)
    np.testing.assert_allclose((qp - qm) / (2 * h), qd, atol=1e-7 * np.abs(qd).max())
    np.testing.assert_allclose((qdp - qdm) / (2 * h), qdd, atol=1e-7 * np.abs(qdd).max())


@pytest.mark.parametrize("wave", WAVES)
def test_extremes_at_their_phases_and_periodic(wave):
    T = 1.3
    t = np.linspace(0, T, 20001)
    q, qd, _ = angle_wave(t, T, wave)
    assert np.rad2deg(q.max()) == pytest.approx(wave.max_deg, abs=1e-9)
    assert np.rad2deg(q.min()) == pytest.approx(wave.min_deg, abs=1e-9)
    for phase, value in ((wave.max_phase, wave.max_deg), (wave.min_phase, wave.min_deg)):
        qq, qqd, _ = angle_wave(np.array([phase * T]), T, wave)
        assert np.rad2deg(qq[0]) == pytest.approx(value, abs=1e-12)
        assert abs(qqd[0]) < 1e-12
    a0 = angle_wave(np.array([0.2, 0.2 + T]), T, wave)
    np.testing.assert_allclose(a0[0][0], a0[0][1], atol=1e-13)
    np.testing.assert_allclose(a0[2][0], a0[2][1], atol=1e-10)


def test_out_of_range_phases_rejected():
    with pytest.raises(ParameterError, match="fe"):
        angle_wave(np.zeros(1), 1.0, AxisWave(25, 0.0, -18, 0.9), "fe")


def test_load_key_points():
    cyc = IsoCycle()
    t = np.linspace(0, 1, 10001)
    F = iso_load(t, cyc)
    for ph in cyc.peak_phases:
        assert iso_load(np.array([ph]), cyc)[0] == pytest.approx(3000.0, rel=1e-12)
    assert iso_load(np.array([cyc.valley_phase]), cyc)[0] == pytest.approx(cyc.valley_load_N, rel=1e-12)
    swing = t >= cyc.stance_end_phase
    np.testing.assert_allclose(F[swing], 300.0, rtol=1e-12)
    assert F.min() >= 300.0 - 1e-9 and F.max() <= 3000.0 + 1e-9
    # monotone between the key points: rise, fall to the valley, rise, fall to swing
    for a, b, sign in ((0.0, 0.12, 1), (0.12, 0.31, -1), (0.31, 0.50, 1), (0.50, 0.62, -1)):
        seg = F[(t >= a) & (t <= b)]
        assert np.all(sign * np.diff(seg) >= -1e-9)
    with pytest.raises(ParameterError, match="load phases"):
        iso_load(t, IsoCycle(valley_phase=0.6))


def test_default_cycle_ranges_and_csv_round_trip(tmp_path):
    m = iso14242_motion(2, 500)
    deg = np.rad2deg(m.angles)
    np.testing.assert_allclose(deg.max(axis=0), [25, 7, 2], atol=1e-3)
    np.testing.assert_allclose(deg.min(axis=0), [-18, -4, -10], atol=1e-3)
    assert len(m) == 1001 and m.t[-1] == pytest.approx(2.0)
    p = tmp_path / "m.csv"
    write_motion_csv(p, m)
    back = read_motion_csv(p)
    np.testing.assert_allclose(back.angles, m.angles, rtol=1e-9, atol=1e-14)
    np.testing.assert_allclose(back.accels, m.accels, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(back.load, m.load, rtol=1e-9)


def test_csv_without_derivatives_uses_the_spline_fit(tmp_path):
    m = iso14242_motion(1, 400)
    p = tmp_path / "m.csv"
    cols = ["t_s,alpha_deg,beta_deg,gamma_deg"]
    for k in range(len(m)):
        cols.append(",".join(f"{v:.12g}" for v in (m.t[k], *np.rad2deg(m.angles[k]))))
    p.write_text("\n".join(cols) + "\n")
    back = read_motion_csv(p)
    inner = slice(20, -20)
    np.testing.assert_allclose(back.rates[inner], m.rates[inner], atol=1e-4 * np.abs(m.rates).max())
    np.testing.assert_allclose(back.accels[inner], m.accels[inner], atol=1e-3 * np.abs(m.accels).max())
    assert np.all(back.load == 0)


def test_csv_with_rates_only_fits_the_accelerations_to_the_rates(tmp_path):
    m = iso14242_motion(1, 400)
    p = tmp_path / "m.csv"
    rows = ["t_s,alpha_deg,beta_deg,gamma_deg,alpha_dot_deg_s,beta_dot_deg_s,gamma_dot_deg_s"]
    for k in range(len(m)):
        rows.append(",".join(f"{v:.15g}" for v in (m.t[k], *np.rad2deg(m.angles[k]), *np.rad2deg(m.rates[k]))))
    p.write_text("\n".join(rows) + "\n")
    back = read_motion_csv(p)
    np.testing.assert_allclose(back.rates, m.rates, rtol=1e-12, atol=1e-14)
    inner = slice(20, -20)
    np.testing.assert_allclose(back.accels[inner], m.accels[inner], atol=1e-4 * np.abs(m.accels).max())


@pytest.mark.parametrize(
    "text, message",
    [
        ("t_s,alpha_deg,beta_deg\n0,1,2\n", "missing required column 'gamma_deg'"),
        ("t_s,alpha_deg,beta_deg,gamma_deg,alpha_deg_s\n0,1,2,3,4\n", "unknown column 'alpha_deg_s'"),
        ("t_s,alpha_deg,beta_deg,gamma_deg\n0,1,2,3\n1,1,x,3\n", r"row 2, column 'beta_deg': 'x' is not a number"),
        ("t_s,alpha_deg,beta_deg,gamma_deg\n0,1,2,3\n1,1,nan,3\n", r"row 2, column 'beta_deg'.*not finite"),
        ("t_s,alpha_deg,beta_deg,gamma_deg,load_N\n0,1,2,3,5\n1,1,2,3,-5\n", r"row 2, column 'load_N'.*negative"),
        ("t_s,alpha_deg,beta_deg,gamma_deg\n0,1,2,3\n0,1,2,3\n", r"row 2, column 't_s': time must increase strictly"),
        ("t_s,alpha_deg,beta_deg,gamma_deg\n0,1,2,3\n1,2,3\n", r"row 2 has 3 fields"),
        ("t_s,alpha_deg,beta_deg,gamma_deg,alpha_dot_deg_s\n0,1,2,3,4\n", "missing column 'beta_dot_deg_s'"),
        ("t_s,alpha_deg,beta_deg,gamma_deg,alpha_ddot_deg_s2,beta_ddot_deg_s2,gamma_ddot_deg_s2\n0,1,2,3,4,5,6\n",
         "acceleration columns need the rate columns"),
    ],
)
def test_bad_motion_files_name_row_and_column(tmp_path, text, message):
    p = tmp_path / "bad.csv"
    p.write_text(text)
    with pytest.raises(MotionError, match=message):
        read_motion_csv(p)


def test_bad_cycle_arguments():
    with pytest.raises(MotionError, match="cycles"):
        iso14242_motion(0, 100)
