"""What a streamed run gathers for its summary and its plots as the chunks go by, with memory
bounded whatever the run's length: one summary accumulator (:class:`Extremes`) and one plot
collector (:class:`Curves`); the animation's frames are picked by
:class:`pkmdyn.report.FramePicker`. Every streamed job (``run``, ``control``, ``hip run``) uses
these three."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["Extremes", "Curves", "CurveData", "PLOT_RAW_MAX", "PLOT_BINS", "FOLD_MAX"]

Array = NDArray[np.float64]

#: up to this many samples a plot shows every one; beyond, the first cycle of a periodic motion
#: with the band of every cycle (folded by the period), or an envelope of bins
PLOT_RAW_MAX = 5000
#: bins of an envelope; the longest period (in samples) a plot folds by
PLOT_BINS, FOLD_MAX = 1000, 20_000


class Extremes:
    """Named running extremes and sums over a run's chunks: :meth:`max` and :meth:`min` keep the
    elementwise largest and least value seen under a name (a scalar or an array of a fixed
    shape), :meth:`sum` adds up; :meth:`first` keeps the first value given under a name (a
    message naming the first sample beyond a limit). Reading a name never given is an error
    (:meth:`get` with a default is not)."""

    def __init__(self) -> None:
        self._v: dict[str, NDArray] = {}
        self._first: dict[str, object] = {}

    def _keep(self, key: str, value: ArrayLike, op) -> None:
        v = np.asarray(value)
        old = self._v.get(key)
        self._v[key] = v.copy() if old is None else op(old, v)

    def max(self, key: str, value: ArrayLike) -> None:
        """Keep the elementwise largest of ``value`` and what ``key`` holds."""
        self._keep(key, value, np.maximum)

    def min(self, key: str, value: ArrayLike) -> None:
        """Keep the elementwise least of ``value`` and what ``key`` holds."""
        self._keep(key, value, np.minimum)

    def sum(self, key: str, value: ArrayLike) -> None:
        """Add ``value`` to what ``key`` holds."""
        self._keep(key, value, np.add)

    def first(self, key: str, value: object) -> None:
        """Keep ``value`` under ``key`` unless something not None is there already."""
        if self._first.get(key) is None:
            self._first[key] = value

    def __getitem__(self, key: str) -> NDArray:
        return self._v[key]

    def __contains__(self, key: str) -> bool:
        return key in self._v or self._first.get(key) is not None

    def get(self, key: str, default: object = None) -> object:
        """What ``key`` holds (a kept value, or a :meth:`first` one), else ``default``."""
        if key in self._v:
            return self._v[key]
        return self._first.get(key, default)


@dataclass(frozen=True)
class CurveData:
    """A :class:`Curves` collection's result: ``t (m,)`` [s] the slots' times; per curve ``first
    (m, c)`` (every sample, or the first cycle of a fold; NaN for an envelope), ``lo`` and
    ``hi`` (m, c) the least and largest value of each slot (equal to ``first`` where every
    sample is a slot); ``mode`` ``"raw"``, ``"fold"`` or ``"bins"``; ``note`` what the plots
    show, for their captions (empty for ``"raw"``)."""

    t: Array
    first: dict[str, Array]
    lo: dict[str, Array]
    hi: dict[str, Array]
    mode: str
    note: str


class Curves:
    """A run's plot curves, gathered chunk by chunk: the samples ``0 .. n - 1`` (later ones are
    left out) in ``slots`` of one of three kinds:

    - ``"raw"``: every sample, where ``n <= raw_max`` (``raw_max`` None: always);
    - ``"fold"``: where ``0 < fold <= fold_max``, a periodic motion of ``fold`` samples a period:
      the first period's samples, and at each phase the least and largest value over every period
      (a band);
    - ``"bins"``: otherwise, ``bins`` equal bins of samples, the least and largest value of each (an
      envelope), the time the bin's mean.

    ``unit`` names the samples in the note (``"samples"``, ``"control cycles"``)."""

    def __init__(self, n: int, *, fold: int = 0, raw_max: int | None = PLOT_RAW_MAX, bins: int = PLOT_BINS,
                 fold_max: int = FOLD_MAX, unit: str = "samples") -> None:
        self.n, self.unit = int(n), unit
        if raw_max is None or n <= raw_max:
            self.mode, self.size = "raw", self.n
        elif 0 < fold <= fold_max:
            self.mode, self.size = "fold", min(int(fold), self.n)
        else:
            self.mode, self.size = "bins", int(bins)
        self.first: dict[str, Array] = {}
        self.lo: dict[str, Array] = {}
        self.hi: dict[str, Array] = {}
        self.t_sum = np.zeros(self.size)
        self.t_n = np.zeros(self.size)

    def add(self, start: int, t: Array, curves: dict[str, Array]) -> None:
        """The chunk of samples ``start, start + 1, ...``: its times ``t (k,)`` [s] and ``curves``
        (name -> ``(k, ...)``, each flattened to columns)."""
        g = np.arange(start, start + t.shape[0])
        keep = g < self.n
        if not keep.any():
            return
        g, t = g[keep], t[keep]
        curves = {key: np.asarray(v)[keep].reshape(g.shape[0], -1) for key, v in curves.items()}
        if self.mode == "raw":
            self.t_sum[g] = t
            self.t_n[g] = 1.0
            for key, v in curves.items():
                if key not in self.first:
                    self.first[key] = np.full((self.size, v.shape[1]), np.nan)
                self.first[key][g] = v
            return
        where = g % self.size if self.mode == "fold" else g * self.size // self.n
        head = g < self.size if self.mode == "fold" else np.zeros(g.shape[0], dtype=bool)  # (none for bins)
        if self.mode == "bins":
            np.add.at(self.t_sum, where, t)
            np.add.at(self.t_n, where, 1.0)
        else:
            self.t_sum[g[head]] = t[head]
            self.t_n[g[head]] = 1.0
        for key, v in curves.items():
            if key not in self.lo:
                m = v.shape[1]
                self.first[key] = np.full((self.size, m), np.nan)
                self.lo[key] = np.full((self.size, m), np.inf)
                self.hi[key] = np.full((self.size, m), -np.inf)
            self.first[key][g[head]] = v[head]
            np.minimum.at(self.lo[key], where, v)
            np.maximum.at(self.hi[key], where, v)

    def data(self) -> CurveData:
        """The slots filled so far (:class:`CurveData`)."""
        used = self.t_n > 0
        t = self.t_sum[used] / self.t_n[used]
        first = {k: v[used] for k, v in self.first.items()}
        if self.mode == "raw":
            return CurveData(t, first, first, first, "raw", "")
        lo = {k: v[used] for k, v in self.lo.items()}
        hi = {k: v[used] for k, v in self.hi.items()}
        if self.mode == "fold":
            note = f"first of {self.n / self.size:.4g} motion cycles; band: every cycle (min-max at each phase)"
            return CurveData(t, first, lo, hi, "fold", note)
        return CurveData(t, first, lo, hi, "bins", f"envelope (min-max) of {self.n} {self.unit} in {self.size} bins")
