"""The one summary accumulator and the one plot collector of the streamed jobs
(pkmdyn.report.Extremes, pkmdyn.report.Curves): gathered in chunks of any size, they hold what
the whole run's arrays give at once."""

from __future__ import annotations

import numpy as np
import pytest

from pkmdyn.report import Curves, Extremes


def _chunks(n, rng):
    s = 0
    while s < n:
        k = int(rng.integers(1, 700))
        yield s, min(n, s + k)
        s += k


def test_extremes_in_chunks_are_the_whole_runs():
    rng = np.random.default_rng(3)
    x = rng.standard_normal((5000, 4))
    e = Extremes()
    for a, b in _chunks(len(x), rng):
        e.max("hi", x[a:b].max(axis=0))
        e.min("lo", x[a:b].min(axis=0))
        e.sum("sq", np.sum(x[a:b] ** 2, axis=0))
        e.sum("n", b - a)
        e.max("peak", np.abs(x[a:b]).max())
        if (x[a:b, 0] > 3.0).any():
            e.first("beyond", a + int(np.flatnonzero(x[a:b, 0] > 3.0)[0]))
    np.testing.assert_array_equal(e["hi"], x.max(axis=0))
    np.testing.assert_array_equal(e["lo"], x.min(axis=0))
    np.testing.assert_allclose(e["sq"], np.sum(x**2, axis=0), rtol=1e-12)
    assert e["n"] == 5000 and e["peak"] == np.abs(x).max()
    assert e.get("beyond") == int(np.flatnonzero(x[:, 0] > 3.0)[0])
    assert e.get("never") is None and e.get("never", 7) == 7 and "never" not in e and "hi" in e and "beyond" in e
    with pytest.raises(KeyError):
        e["never"]


def test_extremes_keep_their_own_copy():
    e = Extremes()
    v = np.array([1.0, 2.0])
    e.max("v", v)
    v[0] = 10.0
    assert e["v"][0] == 1.0


@pytest.mark.parametrize("n, raw_max, mode", [(3000, 5000, "raw"), (3000, None, "raw"), (12_345, 5000, "bins")])
def test_curves_in_chunks(n, raw_max, mode):
    """Every sample where the run is short (or raw_max is None); else the least and largest value
    and the mean time of each of the equal bins; samples beyond n are left out."""
    rng = np.random.default_rng(11)
    t = np.cumsum(rng.uniform(0.5, 1.5, n + 50)) * 1e-3
    x = rng.standard_normal((n + 50, 2, 3))
    c = Curves(n, raw_max=raw_max)
    assert c.mode == mode
    for a, b in _chunks(n + 50, rng):
        c.add(a, t[a:b], {"x": x[a:b]})
    d = c.data()
    flat = x[:n].reshape(n, 6)
    if mode == "raw":
        np.testing.assert_array_equal(d.t, t[:n])
        np.testing.assert_array_equal(d.first["x"], flat)
        assert d.lo["x"] is d.first["x"] and d.note == ""
        return
    bins = np.arange(n) * 1000 // n
    assert d.t.shape == (1000,) and "12345 samples in 1000 bins" in d.note
    for b in (0, 1, 500, 999):
        np.testing.assert_array_equal(d.lo["x"][b], flat[bins == b].min(axis=0))
        np.testing.assert_array_equal(d.hi["x"][b], flat[bins == b].max(axis=0))
        np.testing.assert_allclose(d.t[b], t[:n][bins == b].mean(), rtol=1e-12)
    assert np.isnan(d.first["x"]).all()
