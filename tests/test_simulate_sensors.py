"""The sensor chain of the closed loop: encoder quantisation, the lag of the differenced and
filtered rate, the attitude sensor's delay and noise - on the toy machine under feedforward on
its exact model (the plant then follows the reference closely, so the encoders see a known
signal)."""

from __future__ import annotations

import numpy as np
import pytest

import toy_machine as toy
from pkmdyn.simulate import LoopSettings, track

T = 1e-3
FC = 20.0  # Hz


@pytest.fixture(scope="module")
def run():
    settings = LoopSettings(cycle_s=T, step_s=T / 4, effort_limit=np.full(2, 100.0), divergence_limit=np.full(2, 1.0),
                            encoder_resolution=1e-5, velocity_cutoff_Hz=FC, acceleration_cutoff_Hz=0.0,
                            pose_noise=np.array([1e-3, 2e-3]), pose_delay_cycles=3, seed=7)
    m = toy.ToyModel()
    return track(toy.verbs(True), m, m, toy.motion, 1.0, "feedforward", _zero_gains(), settings, True)


def _zero_gains():
    from pkmdyn.control import Gains

    return Gains(np.zeros(2), np.zeros(2), np.zeros(2))


def test_encoder_counts(run):
    r = run.result
    counts = r.s_enc / 1e-5
    np.testing.assert_allclose(counts, np.round(counts), atol=1e-6)
    assert np.all((r.s - r.s_enc >= -1e-12) & (r.s - r.s_enc < 1e-5 + 1e-12))


def test_rate_lag_is_the_filters(run):
    """Backward difference (half a cycle) plus the discrete first-order filter
    ``y += a (x - y)``: on the 1 Hz component the delay is
    ``T/2 + atan((1 - a) sin wT / (1 - (1 - a) cos wT)) / w`` (about ``1 / (2 pi f_c)`` for
    slow signals). Fourier phases over the whole second (1 and 2 Hz complete)."""
    r, j = run.result, run.joint
    K = r.t.shape[0]
    f = 1.0
    w = 2 * np.pi * f
    a = 1 - np.exp(-2 * np.pi * FC * T)
    expect = T / 2 + np.arctan((1 - a) * np.sin(w * T) / (1 - (1 - a) * np.cos(w * T))) / w
    assert expect == pytest.approx(1 / (2 * np.pi * FC), rel=0.1)
    e = np.exp(-1j * w * r.t)
    for c in range(2):
        lag = ((np.angle(np.sum(j.sd[:K, c] * e)) - np.angle(np.sum(r.sd_enc[:, c] * e))) % (2 * np.pi)) / w
        assert lag == pytest.approx(expect, rel=0.03)


def test_attitude_sensor_delay_and_noise(run):
    r = run.result
    d = 3
    noise = r.q_att[d:] - r.q[:-d]
    np.testing.assert_allclose(noise.std(axis=0), [1e-3, 2e-3], rtol=0.1)
    assert np.all(np.abs(noise.mean(axis=0)) < 3 * np.array([1e-3, 2e-3]) / np.sqrt(noise.shape[0]) * 3)
    # the controller's pose comes from the encoders by default, not from the noisy sensor
    assert np.abs(r.q_s - r.q).max() < 1e-3
