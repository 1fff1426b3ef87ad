"""The hip simulator's main job: parameters + motion -> kinematics -> dynamics -> files.

Data flows one way: file -> validated model -> motion -> kinematics -> dynamics -> results ->
files and plots. ``run_hip`` streams: the motion is produced (or sliced) block by block, each
block's results are checked and appended to the results file, and the summary's extremes and
the plots' data are accumulated on the fly, so peak memory does not grow with the number of
samples (``benchmarks/memory.py``). Every input is validated before the output folder is
touched; the files are written into a temporary folder beside ``--out`` that replaces it only
when the whole run succeeded (:func:`pkmdyn.io.output_dir`).
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from tqdm import tqdm

from ...errors import ParameterError, PkmdynError, SingularityWarning
from ...io import TABLE_FORMATS, check_table_format, open_table_writer, output_dir, write_json
from ...params_util import check_limit, parse_limit_options
from .iso_fit import iso_cycle_preset
from ...profiles.iso14242 import IsoCycle, iso14242_block, iso14242_samples, iso14242_times
from ...profiles.orientation import OrientationMotion, read_motion_csv
from ...spatial import euler_kinematics
from .dynamics import PARTS, HipTorques, inverse_dynamics
from .kinematics import DEFAULT_SINGULARITY_THRESHOLD, HipKinematics, _platform_kinematics, platform_kinematics
from .params import LIMIT_KEYS, HipLimits, HipModel, load_params

__all__ = [
    "HipResults",
    "torques_batched",
    "simulate",
    "results_columns",
    "block_columns",
    "summary",
    "SummaryAccumulator",
    "run_hip",
    "DEFAULT_CHUNK",
    "RUN_CHUNK",
]

Array = NDArray[np.float64]

DEFAULT_CHUNK = 4096  # samples per block: keeps the working set of a block in cache
RUN_CHUNK = 16_384  # samples per block of ``run_hip`` (a few tens of MiB of working set)
PLOT_RAW_MAX = 5000  # up to this many samples a plot shows every sample, beyond it an envelope
PLOT_BINS = 1000  # bins of an envelope plot
SCATTER_MAX = 20_000  # points of the friction-against-load scatter


def torques_batched(
    model: HipModel, t: Array, R: Array, omega: Array, omega_dot: Array, load: Array, chunk: int = DEFAULT_CHUNK
) -> Array:
    """Motor torques ``(n, 3)`` [N m] from the platform motion, in blocks of ``chunk`` samples.

    The lean path for controllers and sweeps: no conditioning check, only the total torque.
    """
    out = np.empty((t.shape[0], 3))
    for s in range(0, t.shape[0], chunk):
        sl = slice(s, s + chunk)
        kin = platform_kinematics(model, t[sl], R[sl], omega[sl], omega_dot[sl], check_conditioning=False)
        out[sl] = inverse_dynamics(model, kin, load[sl]).tau
    return out


@dataclass(frozen=True)
class HipResults:
    """Everything a run writes, per sample; shapes as in :class:`HipKinematics` and :class:`HipTorques`.

    ``det_Ja``, ``det_Jb`` [m^3] and ``cond_J`` are ``(n,)``: equal for both platforms.
    """

    t: Array
    L: Array  #: (n, 2, 3) [m]
    Ld: Array  #: (n, 2, 3) [m/s]
    Ldd: Array  #: (n, 2, 3) [m/s^2]
    det_Ja: Array  #: (n,)
    det_Jb: Array  #: (n,) [m^3]
    cond_J: Array  #: (n,)
    torques: HipTorques


def _block(model: HipModel, motion: OrientationMotion, threshold: float) -> tuple[HipKinematics, HipTorques]:
    R, w, wd = euler_kinematics(model.geometry.euler_sequence, motion.angles, motion.rates, motion.accels)
    kin = _platform_kinematics(model, motion.t, R, w, wd, threshold)
    return kin, inverse_dynamics(model, kin, motion.load)


def simulate(
    model: HipModel,
    motion: OrientationMotion,
    chunk: int = 20_000,
    progress: bool = False,
    singularity_threshold: float = DEFAULT_SINGULARITY_THRESHOLD,
) -> HipResults:
    """Kinematics and dynamics along ``motion``, ``chunk`` samples at a time, all kept in memory.

    For long runs use :func:`run_hip`, which streams the results to a file instead.
    """
    n = len(motion)
    pieces: list[tuple] = []
    bar = tqdm(range(0, n, chunk), desc="hip: kinematics + dynamics", unit="chunk", disable=not progress or None, leave=False)
    for s in bar:
        kin, tq = _block(model, _slice(motion, s, s + chunk), singularity_threshold)
        pieces.append((kin.L, kin.Ld, kin.Ldd, kin.det_Ja, kin.det_Jb, kin.cond_J, tq))
    cat = lambda k: np.concatenate([p[k] for p in pieces])  # noqa: E731
    torques = HipTorques(**{f: np.concatenate([getattr(p[6], f) for p in pieces]) for f in HipTorques.__dataclass_fields__})
    return HipResults(t=motion.t, L=cat(0), Ld=cat(1), Ldd=cat(2), det_Ja=cat(3), det_Jb=cat(4), cond_J=cat(5), torques=torques)


def _slice(motion: OrientationMotion, start: int, stop: int) -> OrientationMotion:
    sl = slice(start, stop)
    return OrientationMotion(motion.t[sl], motion.angles[sl], motion.rates[sl], motion.accels[sl], motion.load[sl])


def block_columns(t: Array, L: Array, Ld: Array, Ldd: Array, det_Ja: Array, det_Jb: Array, cond_J: Array,
                  tq: HipTorques) -> dict[str, Array]:
    """The results-file columns (``docs/file_formats.md``), in order, for one block of samples."""
    cols: dict[str, Array] = {"t_s": t}
    for j in range(L.shape[1]):
        for i in range(3):
            cols[f"L{j + 1}{i + 1}_m"] = L[:, j, i]
            cols[f"Ld{j + 1}{i + 1}_m_s"] = Ld[:, j, i]
            cols[f"Ldd{j + 1}{i + 1}_m_s2"] = Ldd[:, j, i]
    cols["detJa"] = det_Ja
    cols["detJb_m3"] = det_Jb
    for i in range(3):
        cols[f"tau{i + 1}_Nm"] = tq.tau[:, i]
        for part in PARTS:
            cols[f"tau{i + 1}_{part}_Nm"] = getattr(tq, part)[:, i]
    cols["condJ"] = cond_J
    return cols


def results_columns(res: HipResults) -> dict[str, Array]:
    """The spec's results-file columns (``docs/file_formats.md``), in order."""
    return block_columns(res.t, res.L, res.Ld, res.Ldd, res.det_Ja, res.det_Jb, res.cond_J, res.torques)


class SummaryAccumulator:
    """Per-slider and per-motor extremes, updated block by block (the summary without the data)."""

    def __init__(self) -> None:
        self.samples = 0
        self.t0 = math.nan
        self.t1 = math.nan
        self.ext: dict[str, Array] = {}

    def _max(self, key: str, value: Array) -> None:
        old = self.ext.get(key)
        self.ext[key] = value if old is None else np.maximum(old, value)

    def add(self, t: Array, L: Array, Ld: Array, Ldd: Array, det_Ja: Array, det_Jb: Array, cond_J: Array,
            tq: HipTorques) -> None:
        if self.samples == 0:
            self.t0 = float(t[0])
        self.t1 = float(t[-1])
        self.samples += int(t.shape[0])
        self._max("L_max", L.max(axis=0))
        self._max("L_negmin", -L.min(axis=0))
        self._max("Ld", np.abs(Ld).max(axis=0))
        self._max("Ldd", np.abs(Ldd).max(axis=0))
        for f in ("tau", *PARTS, "hip_friction"):
            self._max(f, np.abs(getattr(tq, f)).max(axis=0))
        self._max("neg_detJa", -np.abs(det_Ja).min(keepdims=True))
        self._max("neg_detJb", -np.abs(det_Jb).min(keepdims=True))
        self._max("condJ", np.asarray([cond_J.max()]))
        self._max("power", np.asarray([np.abs(tq.power).max()]))

    def result(self) -> dict[str, Any]:
        """The summary document (JSON-ready, unit-suffixed keys)."""
        e = self.ext
        sliders = {}
        for j in range(e["L_max"].shape[0]):
            for i in range(3):
                sliders[f"S{j + 1}{i + 1}"] = {
                    "max_position_m": float(e["L_max"][j, i]),
                    "min_position_m": float(-e["L_negmin"][j, i]),
                    "max_abs_velocity_m_s": float(e["Ld"][j, i]),
                    "max_abs_acceleration_m_s2": float(e["Ldd"][j, i]),
                }
        motors = {}
        for i in range(3):
            m = {"max_abs_tau_Nm": float(e["tau"][i])}
            for part in PARTS:
                m[f"max_abs_tau_{part}_Nm"] = float(e[part][i])
            m["max_abs_tau_hip_friction_Nm"] = float(e["hip_friction"][i])
            motors[f"motor{i + 1}"] = m
        return {
            "samples": self.samples,
            "duration_s": self.t1 - self.t0,
            "sliders": sliders,
            "motors": motors,
            "min_abs_detJa": float(-e["neg_detJa"][0]),
            "min_abs_detJb_m3": float(-e["neg_detJb"][0]),
            "max_condJ": float(e["condJ"][0]),
            "max_abs_power_W": float(e["power"][0]),
        }


def summary(res: HipResults) -> dict:
    """Per-slider and per-motor maxima (JSON-ready, unit-suffixed keys)."""
    acc = SummaryAccumulator()
    acc.add(res.t, res.L, res.Ld, res.Ldd, res.det_Ja, res.det_Jb, res.cond_J, res.torques)
    return acc.result()


class _PlotCollector:
    """The plots' data, gathered block by block with bounded memory.

    The plots cover samples ``[0, window)`` (one cycle of the built-in motion, or the whole of
    a motion file). Up to ``PLOT_RAW_MAX`` samples every sample is kept; beyond, ``PLOT_BINS``
    equal bins of samples keep the minimum and maximum of every curve (an envelope). The
    friction-against-load scatter keeps every k-th sample of the window, at most ``SCATTER_MAX``.
    """

    def __init__(self, window: int) -> None:
        self.window = window
        self.envelope = window > PLOT_RAW_MAX
        self.bins = PLOT_BINS if self.envelope else window
        self.lo: dict[str, Array] = {}
        self.hi: dict[str, Array] = {}
        self.scatter_step = max(1, -(-window // SCATTER_MAX))
        self.scatter: list[Array] = []

    def add(self, start: int, curves: dict[str, Array], load: Array, friction: Array) -> None:
        k = next(iter(curves.values())).shape[0]
        idx = np.arange(start, start + k)
        keep = idx < self.window
        if not keep.any():
            return
        idx = idx[keep]
        curves = {key: v[keep] for key, v in curves.items()}
        pick = (idx % self.scatter_step) == 0
        self.scatter.append(np.column_stack([load[keep][pick], friction[keep][pick]]))
        b = idx * self.bins // self.window
        starts = np.concatenate(([0], np.flatnonzero(np.diff(b)) + 1))
        target = b[starts]
        for key, v in curves.items():
            v2 = v.reshape(v.shape[0], -1)
            if key not in self.lo:
                self.lo[key] = np.full((self.bins, v2.shape[1]), np.inf)
                self.hi[key] = np.full((self.bins, v2.shape[1]), -np.inf)
            self.lo[key][target] = np.minimum(self.lo[key][target], np.minimum.reduceat(v2, starts, axis=0))
            self.hi[key][target] = np.maximum(self.hi[key][target], np.maximum.reduceat(v2, starts, axis=0))

    def data(self, note: str) -> Any:
        from .plots import PlotData

        used = np.isfinite(self.lo["t"][:, 0])
        lo = {k: v[used] for k, v in self.lo.items()}
        hi = {k: v[used] for k, v in self.hi.items()}
        t = 0.5 * (lo.pop("t")[:, 0] + hi.pop("t")[:, 0])
        if self.envelope:
            note = (note + "; " if note else "") + f"envelope (min-max) of {self.window} samples in {self.bins} bins"
        sc = np.concatenate(self.scatter)
        return PlotData(t=t, lo=lo, hi=hi, envelope=self.envelope, note=note, scatter_load=sc[:, 0], scatter_friction=sc[:, 1:])


def _check_motion_limits(where: Callable[[int], str], motion: OrientationMotion, limits: HipLimits) -> None:
    """Load and angles of a motion against the plausibility limits (before anything is computed)."""
    if motion.load.size:
        k = int(np.argmax(motion.load))
        check_limit(float(motion.load[k]), limits.max_load_N, f"{where(k)}: load", "max_load_N", "N")
        a = np.abs(np.rad2deg(motion.angles))
        r, c = np.unravel_index(int(np.argmax(a)), a.shape)
        name = ("alpha", "beta", "gamma")[c]
        check_limit(float(a[r, c]), limits.max_abs_angle_deg, f"{where(int(r))}: |{name}|", "max_abs_angle_deg", "deg")


def _check_slider_limits(t: Array, Ld: Array, Ldd: Array, limits: HipLimits, row0: int) -> None:
    for arr, key, what, unit in ((Ld, "max_slider_speed_m_s", "slider speed", "m/s"),
                                 (Ldd, "max_slider_acceleration_m_s2", "slider acceleration", "m/s^2")):
        a = np.abs(arr[:, -1])
        r, i = np.unravel_index(int(np.argmax(a)), a.shape)
        check_limit(float(a[r, i]), getattr(limits, key),
                    f"t = {t[r]:.6g} s (sample {row0 + r + 1}): slider {i + 1} {what}", key, unit)


def _check_finite_block(t: Array, cols: dict[str, Array], row0: int) -> None:
    for name, v in cols.items():
        bad = np.flatnonzero(~np.isfinite(v))
        if bad.size:
            r = int(bad[0])
            raise PkmdynError(
                f"t = {t[r]:.6g} s (sample {row0 + r + 1}): {name} is not finite; the parameters or the "
                "motion are outside what the model can represent"
            )


def _motion_blocks(motion: OrientationMotion | None, n: int, cycles: float, cycle: IsoCycle,
                   chunk: int) -> Iterator[tuple[int, OrientationMotion]]:
    for s in range(0, n, chunk):
        if motion is None:
            yield s, iso14242_block(iso14242_times(n, cycles, cycle, s, s + chunk), cycle)
        else:
            yield s, _slice(motion, s, s + chunk)


def _finite_option(name: str, value: Any, lo: float, hi: float) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ParameterError(f"{name}: expected a number, got {type(value).__name__}")
    if not (math.isfinite(value) and lo <= value <= hi):
        raise ParameterError(f"{name}: must be a finite number in [{lo:g}, {hi:g}], got {value}")
    return float(value)


#: the samples of the cycle the hip run's slide tracks are computed on (docs/wear.md)
WEAR_SAMPLES = 1000


def _wear(out: Path, model: HipModel, motion: OrientationMotion | None, cycle: Any, samples_per_cycle: int,
          params_path: str | Path | None, plots: bool) -> tuple[dict[str, Path], list]:
    """``wear.json`` (and the wear files, docs/wear.md) of both stations' prosthesis pairs over one
    cycle of the built-in motion (or the whole motion file, taken as one cycle), at most
    :data:`WEAR_SAMPLES` samples (evenly spaced), through the
    generic engine's kinematics of the hip's description: the head on the platform, the cup on
    the frame, the head's radius the parameter file's ``hip_radius_m``, the load the test load.
    Returns the files and the report's 3D views of the tracks."""
    from ...multibody import load_mechanism, solve_kinematics
    from ...multibody.wear_run import WearOptions, joint_wear, tracks_figure, write_wear_files
    from ...profiles.iso14242 import iso14242_motion
    from .description import hip_description

    if motion is None:
        m = iso14242_motion(cycles=1, samples_per_cycle=min(samples_per_cycle, WEAR_SAMPLES), cycle=cycle)
    else:  # a long motion file: evenly spaced rows, the first and the last kept
        keep = np.unique(np.linspace(0, len(motion) - 1, min(len(motion), WEAR_SAMPLES + 1)).round().astype(int))
        m = OrientationMotion(motion.t[keep], motion.angles[keep], motion.rates[keep], motion.accels[keep],
                              motion.load[keep])
    mech = load_mechanism(hip_description(model))
    kin = solve_kinematics(mech, m.angles, m.rates, m.accels, m.t)
    opts = WearOptions(radius_m=float(model.friction.r_h), load="hydraulic_N")
    loads = {"hydraulic_N": m.load}
    results = [(j, *joint_wear(mech, kin, j, opts, loads)) for j in ("S0_upper", "S0_lower")]
    files = write_wear_files(out, mech, results, opts, {
        "motion": "one cycle of the built-in ISO 14242-1 motion" if motion is None else "the motion file, as one cycle",
        "euler_sequence": model.geometry.euler_sequence,
        "parameters": str(params_path) if params_path else "built-in"}, plots=plots)
    return files, [(f"{j}: the head's tracks on the cup", tracks_figure(j, c)) for j, c, _, _ in results]


def run_hip(
    out_dir: str | Path,
    params_path: str | Path | None = None,
    motion_path: str | Path | None = None,
    cycles: float = 1.0,
    samples_per_cycle: int = 1000,
    make_plots: bool = True,
    progress: bool = False,
    singularity_threshold: float = DEFAULT_SINGULARITY_THRESHOLD,
    fmt: str = "csv",
    limits: dict[str, Any] | tuple[str, ...] | None = None,
    chunk: int = RUN_CHUNK,
    motion_model: str | None = None,
    report: Callable[[dict[str, Path]], None] | None = None,
    html_report: bool = True,
) -> tuple[dict[str, Path], list[str]]:
    """Run the whole job; returns the files written and the warnings raised on the way.

    ``fmt``: ``"csv"`` or ``"parquet"`` for ``results``; ``limits``: overrides of the
    ``[limits]`` table (``{key: value}`` or ``("key=value", ...)``); ``motion_model``: the named
    ISO 14242-1 cycle model of the built-in motion (:func:`pkmdyn.machines.hip_simulator.iso_fit.iso_cycle_preset`;
    ``None``: the parameter file's ``[motion] iso_cycle``); ``html_report``: also write ``report.html``
    (the machine animated over the plots' window). Every input (parameters,
    motion, options, limits on load and angles) is checked before ``out_dir`` is touched; the
    slider speed and acceleration limits are checked block by block as the kinematics are
    computed. On any error nothing is left at or beside ``out_dir``. ``report`` is called with
    the files' final paths before they move into place (:func:`pkmdyn.io.output_dir`), so that a
    listing that cannot be printed leaves ``out_dir`` as it was.
    """
    singularity_threshold = _finite_option("--singularity-threshold", singularity_threshold, 0.0, 1.0)
    if fmt not in TABLE_FORMATS:
        raise ParameterError(f"--format {fmt!r}: must be one of {', '.join(TABLE_FORMATS)}")
    if isinstance(chunk, bool) or not isinstance(chunk, int) or chunk < 1:
        raise ParameterError(f"chunk: must be an integer >= 1, got {chunk!r}")
    model = load_params(params_path)
    if limits:
        items = [f"{k}={v}" for k, v in limits.items()] if isinstance(limits, dict) else list(limits)
        given = parse_limit_options(items, LIMIT_KEYS)
        model = dataclasses.replace(model, limits=dataclasses.replace(model.limits, **given))
    lim = model.limits
    if motion_path is not None and motion_model is not None:
        raise ParameterError("--motion-model names a built-in motion; it cannot be combined with --motion")
    if motion_model is None:
        motion_model = model.motion_model
    cycle = iso_cycle_preset(motion_model)
    if motion_path is None:
        n = iso14242_samples(cycles, samples_per_cycle, lim.max_samples)
        motion = None
        # the cycle model's extremes are its key values (iso14242): check them, not the samples
        peak = max(cycle.peak_load_N, cycle.valley_load_N, cycle.swing_load_N)
        check_limit(peak, lim.max_load_N, "built-in motion: load", "max_load_N", "N")
        for name, w in (("alpha", cycle.fe), ("beta", cycle.aa), ("gamma", cycle.ier)):
            check_limit(max(abs(w.max_deg), abs(w.min_deg)), lim.max_abs_angle_deg, f"built-in motion: |{name}|",
                        "max_abs_angle_deg", "deg")
        check_limit(cycles * cycle.period_s, lim.max_duration_s, "built-in motion: duration", "max_duration_s", "s")
        window = min(n, samples_per_cycle + 1)
        source = f"built-in ISO 14242-1 model ({motion_model}), {cycles:g} cycle(s)"
        note = f"first cycle of {cycles:g} (every cycle is the same)" if cycles > 1 else ""
    else:
        motion = read_motion_csv(motion_path, max_rows=lim.max_samples)
        n = len(motion)
        check_limit(float(motion.t[-1] - motion.t[0]), lim.max_duration_s, f"{motion_path}: duration",
                    "max_duration_s", "s")
        _check_motion_limits(lambda k: f"{motion_path}: row {k + 1}", motion, lim)
        window = n
        source = str(motion_path)
        note = ""
    check_table_format(fmt)  # pyarrow present? (checked before any work)

    summ = SummaryAccumulator()
    collect = _PlotCollector(window) if make_plots or html_report else None
    frames = None
    if html_report:
        from ...report import MAX_FRAMES, FramePicker

        frames = FramePicker(window, MAX_FRAMES)  # the animation's samples of the plots' window
    near = 0
    worst = (0.0, 0.0, 0)  # cond, t, sample
    other: dict[str, None] = {}
    with output_dir(out_dir, inputs={"--params": params_path, "--motion": motion_path}) as tmp:
        files = {"results": tmp / ("results.csv" if fmt == "csv" else "results.parquet"), "summary": tmp / "summary.json"}
        blocks = _motion_blocks(motion, n, cycles, cycle, chunk)
        bar = tqdm(blocks, total=-(-n // chunk), desc="hip: kinematics + dynamics", unit="block",
                   disable=not progress or None, leave=False)
        with open_table_writer(files["results"], fmt) as writer:
            for s, mb in bar:
                with warnings.catch_warnings(record=True) as caught:
                    warnings.simplefilter("always")
                    kin, tq = _block(model, mb, singularity_threshold)
                for w in caught:
                    if not issubclass(w.category, SingularityWarning) and len(other) < 20:
                        other[str(w.message)[:300]] = None
                _check_slider_limits(mb.t, kin.Ld, kin.Ldd, lim, s)
                low = np.flatnonzero(~(1.0 / kin.cond_J >= singularity_threshold))
                if low.size:
                    near += low.size
                    k = int(low[np.argmax(kin.cond_J[low])])
                    if not kin.cond_J[k] <= worst[0]:
                        worst = (float(kin.cond_J[k]), float(mb.t[k]), s + k + 1)
                cols = block_columns(mb.t, kin.L, kin.Ld, kin.Ldd, kin.det_Ja, kin.det_Jb, kin.cond_J, tq)
                _check_finite_block(mb.t, cols, s)
                writer.write(cols)
                summ.add(mb.t, kin.L, kin.Ld, kin.Ldd, kin.det_Ja, kin.det_Jb, kin.cond_J, tq)
                if collect is not None:
                    curves = {"t": mb.t, "angles_deg": np.rad2deg(mb.angles), "load_N": mb.load, "L": kin.L,
                              "Ld": kin.Ld[:, -1], "Ldd": kin.Ldd[:, -1], "tau": tq.tau,
                              **{p: getattr(tq, p) for p in PARTS}}
                    collect.add(s, curves, mb.load, tq.friction)
                if frames is not None:
                    frames.add(s, t=mb.t, R=kin.R, L=kin.L, tau=tq.tau)
        messages = list(other)
        if near:
            cond, tw, kw = worst
            messages.insert(0, f"{near} sample(s) near a singularity (1/cond(J) < {singularity_threshold:g}); the "
                               f"worst at t = {tw:.6g} s (sample {kw}): cond(J) = {cond:.3g}")
        doc = summ.result()
        doc["results_format"] = fmt
        doc["parameters"] = str(params_path) if params_path else "built-in (paper Tables 1-2)"
        doc["motion"] = source
        doc["limits"] = dataclasses.asdict(lim)
        doc["warnings"] = messages
        if html_report:
            files["report"] = tmp / "report.html"
        try:
            wear_files, wear_views = _wear(tmp, model, motion, cycle, samples_per_cycle, params_path, make_plots)
            files.update(wear_files)
        except PkmdynError as exc:  # the run's own results stand; the slide tracks are left out, said once
            wear_views = []
            messages.append(f"slide tracks and wear left out: {exc}")
            doc["warnings"] = messages
        write_json(files["summary"], doc)
        if collect is not None:
            from . import plots

            data = collect.data(note)
        if make_plots:
            files["motion_plot"] = plots.plot_motion_and_load(data, tmp / "motion_load.png")
            files["slider_plot"] = plots.plot_slider_motion(data, tmp / "slider_motion.png")
            files["torque_parts_plot"] = plots.plot_torque_parts(data, tmp / "torque_parts.png")
            files["torque_plot"] = plots.plot_torques(data, tmp / "torques.png")
            files["friction_plot"] = plots.plot_friction_vs_load(data, tmp / "friction_vs_load.png")
        if frames is not None:
            from .report import run_plots, write_run_report
            from .scene import hip_scene

            f = frames.arrays()
            write_run_report(tmp, title="2(3PUS+S) hip simulator: hip run",
                             scene=hip_scene(model, f["t"], f["R"], f["L"], f["tau"]),
                             plots=run_plots(data), summary=doc, params_path=params_path, warnings=messages,
                             images=[p for p in files.values() if p.suffix == ".png"],
                             notes=[f"parameters: {doc['parameters']}", f"motion: {source}"],
                             scene_note=(f"The animation covers the plots' window: {note}." if note else ""),
                             samples=window, figures=wear_views)
        final = {k: Path(out_dir) / p.name for k, p in files.items()}
        if report is not None:
            report(final)
    return final, messages

