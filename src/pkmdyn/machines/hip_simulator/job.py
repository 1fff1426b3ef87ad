"""``pkmdyn hip run``: parameters + motion -> the engine's kinematics and dynamics of the hip's
description -> the paper's files (results, summary, the five figures, wear, report).

Data flows one way: the parameter file is validated into a :class:`~.params.HipModel`, turned
into its mechanism description (:func:`.description.hip_description`) and compiled by the
engine (:func:`pkmdyn.multibody.load_mechanism`). The motion (the built-in ISO 14242-1 cycle
produced block by block, or a motion file) is solved once, block by block, by the engine
(:func:`pkmdyn.multibody.solve_kinematics`, each block warm-started from the one before,
exactly as :func:`pkmdyn.jobs.run.run_mechanism` does), and the same solution feeds the
efforts with load-dependent friction and their split (:func:`pkmdyn.multibody.dynamics.newton_euler.joint_reactions`,
:func:`pkmdyn.multibody.dynamics.actuators.motor_efforts`), the slide tracks of ``wear.json`` (the
samples of the first cycle kept as they pass) and the report. :mod:`.paper` names the results
as the paper does (its columns, Eq. 2-6 Jacobian measures, the parts of Eq. 14); :mod:`.figures`
draws them. The results stream to the file and the summary's extremes and the plots' data are
kept on the fly, so peak memory does not grow with the number of samples
(``benchmarks/memory.py``). Every input is checked before the output folder is touched; the
files are written into a temporary folder beside ``--out`` that replaces it only when the whole
run succeeded (:func:`pkmdyn.report.write_output`).
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from tqdm import tqdm

from ...errors import ParameterError, PkmdynError, SingularityWarning
from ...io import TABLE_FORMATS, atomic_file, check_output_file, check_table_format, note_table_size, open_table_writer
from ...jobs._files import write_texts
from ...jobs.wear import tracks_figure, write_wear_files
from ...multibody import load_mechanism
from ...multibody.formats import mjcf_out
from ...multibody.analyses.wear import WearOptions, joint_wear
from ...multibody.scene import mechanism_scene
from ...params_util import check_limit, parse_limit_options
from ...profiles.iso14242 import IsoCycle, iso14242_block, iso14242_motion, iso14242_samples, iso14242_times
from ...profiles.orientation import OrientationMotion, read_motion_csv, write_motion_csv
from ...report import MAX_FRAMES, FramePicker, JobResult, Output, Report, write_output
from . import figures, paper
from .description import hip_description
from .params import LIMIT_KEYS, HipLimits, HipModel, check_motion_limits, load_params

__all__ = ["run_hip", "profile_job", "export_job", "RUN_CHUNK", "DEFAULT_SINGULARITY_THRESHOLD", "WEAR_SAMPLES",
           "PLATFORM_MASS_KG"]

Array = NDArray[np.float64]

#: samples per block of :func:`run_hip` (some 15 MiB of working set: the engine's kinematics of
#: every body and joint and the reactions; larger blocks buy no speed)
RUN_CHUNK = 1024
#: warn when 1 / cond(J) falls below this (the pose is near a J_a or J_b singularity)
DEFAULT_SINGULARITY_THRESHOLD = 1e-3
#: the samples of the cycle the hip run's slide tracks are computed on (docs/wear.md)
WEAR_SAMPLES = 1000


def _slice(motion: OrientationMotion, start: int, stop: int) -> OrientationMotion:
    sl = slice(max(start, 0), stop)
    return OrientationMotion(motion.t[sl], motion.angles[sl], motion.rates[sl], motion.accels[sl], motion.load[sl])


def _motion_blocks(motion: OrientationMotion | None, n: int, cycles: float, cycle: IsoCycle,
                   chunk: int) -> Iterator[tuple[int, int, OrientationMotion]]:
    """``(start, lead, block)``: samples ``start - lead .. start + chunk - 1`` (the sample before a
    block is solved again as its first row, so that a run in blocks follows the solution of a
    run solved whole)."""
    for s in range(0, n, chunk):
        lead = 1 if s > 0 else 0
        if motion is None:
            yield s, lead, iso14242_block(iso14242_times(n, cycles, cycle, s - lead, s + chunk), cycle)
        else:
            yield s, lead, _slice(motion, s - lead, s + chunk)


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


def _finite_option(name: str, value: Any, lo: float, hi: float) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ParameterError(f"{name}: expected a number, got {type(value).__name__}")
    if not (math.isfinite(value) and lo <= value <= hi):
        raise ParameterError(f"{name}: must be a finite number in [{lo:g}, {hi:g}], got {value}")
    return float(value)


class _WearSamples:
    """The kinematics and loads of the slide tracks' samples, kept as the run's blocks pass:
    sample indices ``keep`` (increasing) of the whole run."""

    def __init__(self, keep: Array) -> None:
        self.keep = keep
        self.kin: list[Any] = []
        self.load: list[Array] = []

    def add(self, start: int, kin: Any, load: Array) -> None:
        k = len(kin)
        pick = self.keep[(self.keep >= start) & (self.keep < start + k)] - start
        if pick.size:
            self.kin.append(dataclasses.replace(kin, **{f.name: getattr(kin, f.name)[pick]
                                                        for f in dataclasses.fields(kin)
                                                        if getattr(kin, f.name) is not None}))
            self.load.append(load[pick])

    def kinematics(self) -> tuple[Any, Array]:
        first = self.kin[0]
        kin = dataclasses.replace(first, **{f.name: np.concatenate([getattr(k, f.name) for k in self.kin])
                                            for f in dataclasses.fields(first) if getattr(first, f.name) is not None})
        return kin, np.concatenate(self.load)


def _wear_keep(motion: OrientationMotion | None, n: int, samples_per_cycle: int) -> Array:
    """The samples of the slide tracks: one cycle of the built-in motion (its first), or the
    whole motion file taken as one cycle, at most :data:`WEAR_SAMPLES` + 1 evenly spaced samples,
    the first and the last kept."""
    last = min(samples_per_cycle, n - 1) if motion is None else n - 1
    return np.unique(np.linspace(0, last, min(last + 1, WEAR_SAMPLES + 1)).round().astype(int))


def _wear(out: Path, mech: Any, model: HipModel, kin: Any, load: Array, builtin: bool,
          params_path: str | Path | None, plots: bool) -> tuple[dict[str, Path], list]:
    """``wear.json`` and the wear files (docs/wear.md) of both stations' prosthesis pairs over one
    cycle (the engine's kinematics ``kin`` and the loads ``load`` [N] of its samples): the head
    on the platform, the cup on the frame, the head's radius the parameter file's
    ``hip_radius_m``, the load the test load. Returns the files and the report's 3D views of the
    tracks."""

    opts = WearOptions(radius_m=float(model.friction.r_h), load="hydraulic_N")
    results = [(j, *joint_wear(mech, kin, j, opts, {"hydraulic_N": load})) for j in ("S0_upper", "S0_lower")]
    files = write_wear_files(out, mech, results, opts, {
        "motion": "one cycle of the built-in ISO 14242-1 motion" if builtin else "the motion file, as one cycle",
        "euler_sequence": model.geometry.euler_sequence,
        "parameters": str(params_path) if params_path else "built-in"}, plots=plots)
    return files, [(f"{j}: the head's tracks on the cup", tracks_figure(j, c)) for j, c, _, _ in results]


def _wear_cycle(view: Any, collected: _WearSamples, motion: OrientationMotion | None, n: int,
                samples_per_cycle: int, cycle: IsoCycle) -> tuple[Any, Array]:
    """The kinematics and loads of the slide tracks' cycle: the samples the run kept as it went,
    or, for a built-in motion shorter than one cycle, one whole cycle solved apart (at most
    :data:`WEAR_SAMPLES` samples)."""
    if motion is None and n - 1 < samples_per_cycle:
        m = iso14242_motion(cycles=1, samples_per_cycle=min(samples_per_cycle, WEAR_SAMPLES), cycle=cycle)
        return view.solve(m).kin, m.load
    kin, load = collected.kinematics()
    collected.kin.clear()  # the blocks' rows are in ``kin`` now
    return kin, load


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
) -> JobResult:
    """Run the whole job; returns its result: the files written, the summary, the warnings raised
    on the way and the report's content.

    ``fmt``: ``"csv"`` or ``"parquet"`` for ``results``; ``limits``: overrides of the
    ``[limits]`` table (``{key: value}`` or ``("key=value", ...)``); ``motion_model``: the named
    ISO 14242-1 cycle model of the built-in motion (:func:`.paper.iso_cycle_preset`; ``None``:
    the parameter file's ``[motion] iso_cycle``); ``html_report``: also write ``report.html``
    (the machine animated over the plots' window). Every input (parameters, motion, options,
    limits on load and angles) is checked before ``out_dir`` is touched; the slider speed and
    acceleration limits are checked block by block as the kinematics are computed. On any error
    nothing is left at or beside ``out_dir``. ``report`` is called with the files' final paths
    before they move into place (:func:`pkmdyn.report.write_output`), so that a listing that cannot
    be printed leaves ``out_dir`` as it was.
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
    cycle = paper.iso_cycle_preset(motion_model)
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
        check_motion_limits(lambda k: f"{motion_path}: row {k + 1}", motion, lim)
        window = n
        source = str(motion_path)
        note = ""
    check_table_format(fmt)  # pyarrow present? (checked before any work)
    note_table_size(n, len(paper.RESULTS_COLUMNS), fmt)
    view = paper.PaperView(model)  # the engine's model of the description, and the paper's names of it
    summ = paper.SummaryAccumulator()
    collect = figures.PlotCollector(window) if make_plots or html_report else None
    frames = None
    if html_report:
        frames = FramePicker(window, MAX_FRAMES)  # the animation's samples of the plots' window
    wear = _WearSamples(_wear_keep(motion, n, samples_per_cycle))
    near = 0
    worst = (0.0, 0.0, 0)  # cond, t, sample
    other: dict[str, None] = {}
    q_prev: Array | None = None
    messages: list[str] = []

    def make(tmp: Path) -> Output:
        nonlocal near, worst, q_prev
        files = {"results": tmp / ("results.csv" if fmt == "csv" else "results.parquet")}
        blocks = _motion_blocks(motion, n, cycles, cycle, chunk)
        bar = tqdm(blocks, total=-(-n // chunk), desc="hip: kinematics + dynamics", unit="block",
                   disable=not progress or None, leave=False)
        with open_table_writer(files["results"], fmt) as writer:
            for s, lead, mb in bar:
                with warnings.catch_warnings(record=True) as caught:
                    warnings.simplefilter("always")
                    res = view.solve(mb, s - lead + 1, q_prev)  # samples counted from 1 in messages
                for w in caught:
                    if not issubclass(w.category, SingularityWarning) and len(other) < 20:
                        other[str(w.message)[:300]] = None
                q_prev = res.kin.q[-1].copy()
                if lead:
                    res = res.rows(1)
                    mb = _slice(mb, 1, len(mb))
                _check_slider_limits(mb.t, res.Ld, res.Ldd, lim, s)
                low = np.flatnonzero(~(1.0 / res.cond_J >= singularity_threshold))
                if low.size:
                    near += low.size
                    k = int(low[np.argmax(res.cond_J[low])])
                    if not res.cond_J[k] <= worst[0]:
                        worst = (float(res.cond_J[k]), float(mb.t[k]), s + k + 1)
                cols = paper.block_columns(mb.t, res)
                _check_finite_block(mb.t, cols, s)
                writer.write(cols)
                summ.add(mb.t, res)
                wear.add(s, res.kin, mb.load)
                if collect is not None:
                    curves = {"t": mb.t, "angles_deg": np.rad2deg(mb.angles), "load_N": mb.load, "L": res.L,
                              "Ld": res.Ld[:, -1], "Ldd": res.Ldd[:, -1], "tau": res.tau,
                              **{p: res.parts[p] for p in paper.PARTS}}
                    collect.add(s, curves, mb.load, res.parts["friction"])
                if frames is not None:
                    frames.add(s, t=mb.t, joint_point=res.kin.joint_point, tau=res.tau)
        messages.extend(other)
        eps_note = paper.regularisation_note(model)
        if eps_note is not None:
            messages.append(eps_note)
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
        try:
            wear_kin, wear_load = _wear_cycle(view, wear, motion, n, samples_per_cycle, cycle)
            wear_files, wear_views = _wear(tmp, view.mech, model, wear_kin, wear_load, motion is None, params_path,
                                           make_plots)
            del wear_kin, wear_load
            files.update(wear_files)
        except PkmdynError as exc:  # the run's own results stand; the slide tracks are left out, said once
            wear_views = []
            messages.append(f"slide tracks and wear left out: {exc}")
            doc["warnings"] = messages
        if collect is not None:
            data = collect.data(note)
        if make_plots:
            files.update(figures.write_figures(data, tmp))
        rep = None
        if frames is not None:
            f = frames.arrays()
            efforts = {f"P_{i + 1}": (f["tau"][:, i], f"motor {i + 1} torque", "N m") for i in range(3)}
            rep = Report("2(3PUS+S) hip simulator: hip run",
                         scene=mechanism_scene(view.mech, f["t"], f["joint_point"], efforts),
                         plots=figures.report_plots(data), summary=doc,
                         parameters=paper.parameters_text(params_path), warnings=messages,
                         images=[k for k, p in files.items() if p.suffix == ".png"],
                         notes=[f"parameters: {doc['parameters']}", f"motion: {source}"],
                         scene_note=(f"The animation covers the plots' window: {note}." if note else ""),
                         samples=window, figures=wear_views)
        return Output(files, doc, rep)

    final, output = write_output(out_dir, {"--params": params_path, "--motion": motion_path}, make, report)
    return JobResult(final, output.summary or {}, (), tuple(messages), report=output.report)


def profile_job(out_path: str | Path, cycles: float, samples_per_cycle: int, max_samples: int,
                announce: Callable[[dict[str, Path]], None] | None = None) -> JobResult:
    """``pkmdyn hip profile``: ``cycles`` of the built-in ISO 14242-1 motion and load model at
    ``samples_per_cycle`` (at most ``max_samples`` rows) as a motion CSV with every derivative
    column, written whole or not at all (:func:`pkmdyn.io.atomic_file`; ``announce`` is given its
    path before it moves into place)."""
    motion = iso14242_motion(cycles, samples_per_cycle, max_samples=max_samples)
    out = Path(out_path)
    with atomic_file(out) as tmp:
        write_motion_csv(tmp, motion)
        if announce is not None:
            announce({"motion": out})
    return JobResult({"motion": out}, {"samples": len(motion)})


#: the mass [kg] written for a platform of zero mass (the paper gives none; MuJoCo needs a mass on a
#: moving body): its centre of mass sits on the platform's fixed ball joint, so the value changes no
#: dynamics
PLATFORM_MASS_KG = 1e-3


def export_job(fmt: str, params_path: str | Path | None, timestep_s: float, out_path: str | Path,
               announce: Callable[[dict[str, Path]], None] | None = None) -> JobResult:
    """``pkmdyn hip export``: the machine of the parameter file ``params_path`` (None: the paper's
    Tables 1-2) in ``fmt`` (``"mjcf"``: :func:`pkmdyn.multibody.formats.mjcf_out.mechanism_mjcf`, a
    massless platform given :data:`PLATFORM_MASS_KG`) at ``out_path``, written only when the whole
    model is valid (:func:`pkmdyn.jobs._files.write_texts`)."""
    inputs = {"--params": None if params_path is None else Path(params_path)}
    out = Path(out_path)
    check_output_file(out, inputs)
    model = load_mechanism(hip_description(load_params(params_path)))
    light = mjcf_out.massless_bodies(model)
    text = mjcf_out.mechanism_mjcf(model, timestep_s, massless_kg=PLATFORM_MASS_KG if light else None)
    return JobResult(write_texts({fmt: (out, text)}, inputs, announce))
