"""Cycloidal motion (Eq. 84) and PDM motion CSV files."""

from __future__ import annotations

import numpy as np
import pytest

from pkmdyn.errors import MotionError
from pkmdyn.profiles.cycloidal import cycloidal
from pkmdyn.profiles.pdm_motion import cycloidal_motion, read_pdm_motion, write_pdm_motion

S = (0.02, -0.015, 0.08, 0.2)


def test_cycloidal_derivatives_and_end_conditions():
    T, h = 1.7, 1e-6
    t = np.linspace(0.01, T - 0.01, 50)
    s, sd, sdd = cycloidal(t, np.array(S), T)
    sp, sdp, _ = cycloidal(t + h, np.array(S), T)
    sm, sdm, _ = cycloidal(t - h, np.array(S), T)
    assert np.abs((sp - sm) / (2 * h) - sd).max() < 1e-8
    assert np.abs((sdp - sdm) / (2 * h) - sdd).max() < 1e-7
    e, ed, edd = cycloidal(np.array([0.0, T]), np.array(S), T)
    assert np.allclose(e, [[0, 0, 0, 0], S], atol=1e-15)
    assert np.allclose(ed, 0, atol=1e-15) and np.allclose(edd, 0, atol=1e-14)
    with pytest.raises(MotionError, match="outside"):
        cycloidal(np.array([T * 1.01]), np.array(S), T)


def test_csv_round_trip_keeps_given_derivatives(tmp_path):
    m = cycloidal_motion(S, 2.0, 41)
    path = tmp_path / "m.csv"
    write_pdm_motion(path, m)
    back = read_pdm_motion(path)
    for a, b in ((m.t, back.t), (m.q, back.q), (m.qd, back.qd), (m.qdd, back.qdd)):
        assert np.allclose(a, b, rtol=1e-13, atol=1e-15)


def test_missing_derivatives_come_from_a_quintic_spline(tmp_path):
    m = cycloidal_motion(S, 2.0, 201)
    path = tmp_path / "m.csv"
    write_pdm_motion(path, m, derivatives=False)
    back = read_pdm_motion(path)
    scale_d, scale_dd = np.abs(m.qd).max(0), np.abs(m.qdd).max(0)
    assert np.all(np.abs(back.qd - m.qd).max(0) < 1e-5 * scale_d)
    assert np.all(np.abs(back.qdd - m.qdd).max(0) < 1e-3 * scale_dd)
    # only first derivatives given: the second ones are the spline derivative of those
    cols = ["t_s,x_m,y_m,alpha_rad,gamma_rad,xd_m_s,yd_m_s,alphad_rad_s,gammad_rad_s"]
    cols += [",".join(f"{v:.15g}" for v in (t, *q, *qd)) for t, q, qd in zip(m.t, m.q, m.qd)]
    path.write_text("\n".join(cols) + "\n", encoding="utf-8")
    back = read_pdm_motion(path)
    assert np.allclose(back.qd, m.qd, rtol=1e-13, atol=1e-17)  # given rates are used as they are
    assert np.all(np.abs(back.qdd - m.qdd).max(0) < 1e-4 * scale_dd)


@pytest.mark.parametrize(
    "text, message",
    [
        ("t_s,x_m,y_m,alpha_rad\n0,0,0,0\n", "missing required column 'gamma_rad'"),
        ("t_s,x_m,y_m,alpha_rad,gamma_rad\n0,0,0,0,0\n0,0,0,0,0\n", r"row 2, column 't_s': time must increase"),
        ("t_s,x_m,y_m,alpha_rad,gamma_rad\n0,0,0,0,0\n1,0,0,x,0\n", r"row 2, column 'alpha_rad'"),
        ("t_s,x_m,y_m,alpha_rad,gamma_rad,xd_m_s\n0,0,0,0,0,0\n", "missing column 'yd_m_s'"),
        ("t_s,x_m,y_m,alpha_rad,gamma_rad\n0,0,0,0,0\n1,0,0,0,0\n", "at least 6 rows"),
        ("t_s,x_m,y_m,alpha_deg,gamma_rad\n0,0,0,0,0\n", "unknown column 'alpha_deg'"),
    ],
)
def test_bad_motion_files_name_row_and_column(tmp_path, text, message):
    path = tmp_path / "bad.csv"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(MotionError, match=message):
        read_pdm_motion(path)
