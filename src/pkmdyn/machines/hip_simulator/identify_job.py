"""The hip simulator's identification jobs behind ``pkmdyn hip identify`` and ``pkmdyn hip
excite``: files in, every result computed, files out (the fit and the design on the engine's
description of the machine, :mod:`.identify_view`, :mod:`.identify_excite`).

``run_identify``: parameter file + measured run -> identified.toml, identification.json,
torques.csv, torque_fit.png, residuals.png. ``run_excite``: parameter file + limits -> an
excitation motion CSV. Every input is validated and every result computed before anything is
written.
"""

from __future__ import annotations

import copy
import tomllib
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import LimitError, MotionError, ParameterError
from ...identify._report import MIN_EXPLAINED_PERCENT, explained_percent, fit_failure, identification_report
from ...io import atomic_file, check_output_dir, check_output_file, dumps_toml, write_csv, write_json
from ...params_util import read_toml
from ...profiles.orientation import write_motion_csv
from .identify_excite import ExcitationLimits, design_excitation, excitation_motion
from .identify_view import (
    FRICTION_ATTR,
    TORQUE_COLUMNS,
    Which,
    consistency_transform,
    identified_description,
    identify_hip,
    read_measured_csv,
)
from .paper import parameters_text, regularisation_note
from .params import HipModel, default_params_dict, load_params, model_from_dict

__all__ = ["run_identify", "run_excite", "complete_description", "HELD_FIXED", "MAX_EXCITE_ROWS"]

import warnings

from ...identify.plots import plot_residuals, plot_torque_fit
from ...multibody import load_mechanism
from ...multibody.scene import motion_scene
from ...report import MAX_FRAMES, Curve, JobResult, Output, Report, TimePlot, frame_indices, write_output
from .description import hip_description
from .identify_bounds import MAX_EXCITE_ROWS, MAX_SG_ORDER, MAX_SG_WINDOW  # noqa: E402  (the bounds, stated by the CLI)
from .identify_excite import design_work

#: what every identification holds at the parameter file's values
HELD_FIXED = (
    "geometry (every [geometry] key)",
    "gravity_m_s2",
    "hip_radius_m and thrust_radius_m (only products with the coefficients are identified)",
    "platform_mass_kg, unless the identified weight friction needs another value (see bearing_split)",
    "friction_velocity_eps_rad_s, friction_velocity_eps_m_s (written back as they are; the engine's "
    "friction regularisation is 1e-3 rad/s and 1e-4 m/s)",
)

_OPTIONAL_FRICTION = {
    "friction_velocity_eps_rad_s": "eps_w",
    "friction_velocity_eps_m_s": "eps_v",
    **FRICTION_ATTR,
}

#: which parameter-file key each identified parameter writes
_KEY_OF = {
    "bearing_load_coeff_m": "hip_coefficient",
    "bearing_weight_friction_Nm": "thrust_coefficient",
    "lever_Ix_kgm2": "lever_inertia_kgm2",
    "lever_Iy_kgm2": "lever_inertia_kgm2",
    "lever_Iz_kgm2": "lever_inertia_kgm2",
    "platform_Ix_kgm2": "platform_inertia_kgm2",
    "platform_Iy_kgm2": "platform_inertia_kgm2",
    "platform_Iz_kgm2": "platform_inertia_kgm2",
}




def _check_identify_options(which: str, sg_window: int, sg_order: int, rank_tol: float) -> None:
    if which not in ("friction", "inertia", "all"):
        raise ParameterError(f"--identify {which!r}: choose friction, inertia or all")
    if isinstance(sg_window, bool) or int(sg_window) != sg_window or not 3 <= sg_window <= MAX_SG_WINDOW \
            or sg_window % 2 == 0:
        raise ParameterError(f"--sg-window: must be an odd number from 3 to {MAX_SG_WINDOW}, got {sg_window}")
    if isinstance(sg_order, bool) or int(sg_order) != sg_order or not 2 <= sg_order <= min(MAX_SG_ORDER, sg_window - 1):
        raise ParameterError(f"--sg-order: must be from 2 to {MAX_SG_ORDER} and less than the window "
                             f"({sg_window}), got {sg_order}")
    rank_tol = float(rank_tol)
    if not (np.isfinite(rank_tol) and 0 < rank_tol < 1):
        raise ParameterError(f"--rank-tol: must be a finite number in (0, 1), got {rank_tol:g} (1 leaves no rank)")


def complete_description(description: dict[str, Any], model: HipModel) -> dict[str, Any]:
    """The description with every optional key written out (from the model's defaults)."""
    d = copy.deepcopy(description)
    g = d["geometry"]
    g.setdefault("euler_sequence", model.geometry.euler_sequence)
    g.setdefault("lever_spin", model.geometry.lever_spin)
    f = d["friction"]
    for key, attr in _OPTIONAL_FRICTION.items():
        f.setdefault(key, float(getattr(model.friction, attr)))
    return {name: d[name] for name in ("geometry", "inertia", "friction")}


def run_identify(
    out_dir: str | Path,
    measured_path: str | Path,
    params_path: str | Path | None,
    which: Which,
    sg_window: int = 15,
    sg_order: int = 5,
    rank_tol: float = 1e-6,
    make_plots: bool = True,
    report: Callable[[Mapping[str, Path]], None] | None = None,
    html_report: bool = True,
) -> JobResult:
    """Identify and write the output folder (with ``html_report``, also ``report.html``: the machine
    along the measured motion coloured by the measured torques, measured and identified torques,
    residuals); returns the result: the files written, ``identification.json``'s document, the
    summary lines and the warnings (a parameter file's friction regularisation not used).

    The options are checked first (``sg_window`` odd, 3 to :data:`MAX_SG_WINDOW`; ``sg_order``
    2 to :data:`MAX_SG_ORDER` and below the window; ``0 < rank_tol < 1``); the measured
    values by :func:`.identify_view.read_measured_csv`; a fit that still overflows is
    refused, never written. ``out_dir`` must pass the output rule
    (:func:`pkmdyn.io.check_output_dir`), checked first; ``report`` is called with the files' final
    paths before they move into place."""
    _check_identify_options(which, sg_window, sg_order, rank_tol)
    inputs = {"--measured": measured_path, "--params": params_path}
    check_output_dir(out_dir, inputs)
    # the parameter file is read once (it may be a pipe)
    description = read_toml(params_path) if params_path is not None else default_params_dict()
    model = model_from_dict(copy.deepcopy(description), str(params_path) if params_path is not None else
                            "built-in parameters")
    description = complete_description(description, model)
    eps_note = regularisation_note(model)
    motion, tau, deriv = read_measured_csv(measured_path, sg_window, sg_order)
    for i, name in enumerate(TORQUE_COLUMNS):
        if not np.any(tau[:, i]):
            raise MotionError(f"{measured_path}: column {name!r} is zero in every row: no measured torque to "
                              "identify from")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result = identify_hip(model, motion, tau, which, rank_tol, source=str(measured_path))
        except (np.linalg.LinAlgError, FloatingPointError, OverflowError) as exc:
            raise MotionError(f"{measured_path}: the fit failed numerically ({exc}); check the file's values") from None
    ok = np.all(np.isfinite(result.tau_identified)) and np.all(np.isfinite(result.residual_rms))
    if not ok:
        raise MotionError(f"{measured_path}: the fit is not finite (the values overflow); check the file's values")
    for w in caught:  # anything else the solvers said, not printed mid-run
        if not issubclass(w.category, RuntimeWarning):
            warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    failure = fit_failure(result.base, result.estimate, TORQUE_COLUMNS, tau, tau - result.tau_identified)
    if failure is not None:  # a meaningless fit is an error, never a result
        raise MotionError(f"{measured_path}: {failure}")
    identified = identified_description(description, result)
    T, _, _ = consistency_transform(result.names)
    report_doc = identification_report(
        result.base, result.estimate, result.prior, TORQUE_COLUMNS,
        np.sqrt(np.mean(tau**2, axis=0)), result.residual_rms, T,
    )
    report_doc = {
        "measured": str(measured_path),
        "parameters": str(params_path) if params_path is not None else "built-in (paper Tables 1-2)",
        "identify": which,
        "samples": len(motion),
        "derivatives": deriv,
        **report_doc,
        "explained_percent": dict(zip(TORQUE_COLUMNS, explained_percent(tau, tau - result.tau_identified).tolist())),
        "minimum_explained_percent": MIN_EXPLAINED_PERCENT,
        "held_at_parameter_file_values": list(HELD_FIXED),
    }
    notes = {}
    for name in report_doc["not_separable"]:
        notes[_KEY_OF.get(name, name)] = "not separable from the data: only a combination is (identification.json)"
    for name in report_doc["not_excited"]:
        notes[_KEY_OF.get(name, name)] = "not excited by the measured motion: parameter file value"
    if "bearing_load_coeff_m" in result.names:
        split = "share of bearing_load_coeff_m; the data fix the split only through platform_mass_kg"
        notes.setdefault("hip_coefficient", split)
        notes.setdefault("thrust_coefficient", split)
        if identified["inertia"]["platform_mass_kg"] != description["inertia"]["platform_mass_kg"]:
            notes["platform_mass_kg"] = "set to carry the identified bearing_weight_friction_Nm (file value could not)"
    header = (
        f"2(3PUS+S) hip simulator: parameters identified ({which}) from {Path(measured_path).name}\n"
        "by pkmdyn hip identify; estimates, standard errors and base parameters in identification.json.\n"
        "A value marked 'not separable' is one split of a combination that the data fix as a whole."
    )
    text = dumps_toml(identified, header, notes)
    check = model_from_dict(tomllib.loads(text), "identified.toml")  # loadable, as `hip run --params` needs
    del check
    columns: dict[str, Any] = {"t_s": motion.t}
    for i, name in enumerate(TORQUE_COLUMNS):
        stem = name[: -len("_Nm")]
        columns[f"{stem}_measured_Nm"] = tau[:, i]
        columns[f"{stem}_identified_Nm"] = result.tau_identified[:, i]
        columns[f"{stem}_residual_Nm"] = tau[:, i] - result.tau_identified[:, i]
    lines = [f"rank {result.base.rank} of {len(result.names)} parameters, condition number {result.base.condition_number:.4g}"]
    for name, v in report_doc["separable"].items():
        lines.append(f"{name} = {v['estimate']:.6g} +- {v['standard_error']:.2g}")
    for c in report_doc["combinations"]:
        lines.append(f"{c['combination']} = {c['estimate']:.6g} +- {c['standard_error']:.2g}")
    if report_doc["not_excited"]:
        lines.append("not excited: " + ", ".join(report_doc["not_excited"]))
    rms = ", ".join(f"{1e3 * v:.4g}" for v in result.residual_rms)
    lines.append(f"residual RMS per motor [N mm]: {rms}")
    warns = ([str(w.message) for w in caught if not issubclass(w.category, RuntimeWarning)]
             + ([eps_note] if eps_note is not None else []))

    def make(tmp: Path) -> Output:
        files = {"identified": tmp / "identified.toml", "identification": tmp / "identification.json",
                 "torques": tmp / "torques.csv"}
        files["identified"].write_text(text, encoding="utf-8")
        write_json(files["identification"], report_doc)
        write_csv(files["torques"], columns)
        if make_plots:
            files["torque_fit"] = tmp / "torque_fit.png"
            files["residuals"] = tmp / "residuals.png"
            plot_torque_fit(motion.t, tau, result.tau_identified, files["torque_fit"])
            plot_residuals(motion.t, tau - result.tau_identified, files["residuals"])
        rep = None
        if html_report:
            rep = _report(model, motion, tau, result.tau_identified, report_doc, params_path,
                          [k for k, p in files.items() if p.suffix == ".png"], warns)
        return Output(files, report=rep)

    files, output = write_output(out_dir, inputs, make, report)
    return JobResult(files, report_doc, tuple(lines), () if eps_note is None else (eps_note,), report=output.report)


def _report(model: HipModel, motion: Any, tau: np.ndarray, tau_id: np.ndarray, doc: dict[str, Any],
            params_path: str | Path | None, images: list[str], warns: list[str]) -> Report:
    """The content of ``report.html``: the measured motion animated, measured and identified torques."""
    idx = frame_indices(len(motion), MAX_FRAMES)
    scene = motion_scene(load_mechanism(hip_description(model)), motion.t[idx], motion.angles[idx], tau[idx],
                         labels=tuple((f"motor {i + 1} torque", "N m") for i in range(3)))
    t = motion.t
    plots = [TimePlot(f"Motor {i + 1} torque: measured and identified", "torque [N m]", t,
                      (Curve("measured", tau[:, i]), Curve("identified", tau_id[:, i]))) for i in range(3)]
    plots.append(TimePlot("Residuals (measured - identified)", "torque [N m]", t,
                          tuple(Curve(f"motor {i + 1}", tau[:, i] - tau_id[:, i]) for i in range(3))))
    plots.append(TimePlot("Measured motion", "angle [deg]", t, tuple(
        Curve(n, np.degrees(motion.angles[:, c])) for c, n in enumerate(("alpha (FE)", "beta (AA)", "gamma (IER)")))))
    return Report("2(3PUS+S) hip simulator: hip identify", scene=scene, plots=plots, summary=doc,
                  parameters=parameters_text(params_path), warnings=warns, images=images,
                  notes=[f"measured: {doc['measured']}", f"parameters: {doc['parameters']}",
                         f"identify: {doc['identify']}"],
                  scene_note="The measured motion; actuated carriages coloured by the measured motor torques.",
                  samples=len(motion))


def run_excite(
    out_path: str | Path,
    params_path: str | Path | None,
    which: Which,
    limits: ExcitationLimits,
    period_s: float,
    harmonics: int,
    cycles: int,
    samples_per_cycle: int,
    iterations: int,
    starts: int,
    seed: int,
    design_samples: int = 120,
    progress: bool = False,
    report: Callable[[list[str]], None] | None = None,
) -> list[str]:
    """Design the excitation and write it as a motion CSV; returns summary lines.

    Every input is checked before the design starts (``cycles x samples_per_cycle + 1`` rows
    at most :data:`MAX_EXCITE_ROWS`); ``progress`` shows a bar of the cost evaluations on a
    terminal. The file is written atomically (:func:`pkmdyn.io.atomic_file`) and must pass the
    output rule (:func:`pkmdyn.io.check_output_file`), checked first; ``report`` is called with
    the summary lines before the file moves into place."""
    from tqdm import tqdm

    inputs = {"--params": params_path}
    out = Path(out_path)
    check_output_file(out, inputs)
    model = load_params(params_path)
    limits.check()
    for name, v, lo in (("cycles", cycles, 1), ("samples per cycle", samples_per_cycle, 16)):
        if isinstance(v, bool) or int(v) != v or v < lo:
            raise ParameterError(f"{name}: {v} must be a whole number >= {lo}")
    n = int(cycles) * int(samples_per_cycle) + 1
    if n > MAX_EXCITE_ROWS:
        raise LimitError(f"motion: {cycles} cycles x {samples_per_cycle} samples per cycle = {n:,} rows is above "
                         f"the limit {MAX_EXCITE_ROWS:,}")
    total, _ = design_work(harmonics, design_samples, iterations, starts)
    with tqdm(total=total, desc="excitation design", unit="evaluation", disable=not progress or None,
              leave=False) as bar:
        ex = design_excitation(model, which, limits, period_s, harmonics, design_samples, iterations, starts, seed,
                               progress=bar.update)
    t = np.linspace(0.0, cycles * ex.period_s, n)
    motion = excitation_motion(ex.coeffs, ex.period_s, limits, t)
    lines = [
        f"period {ex.period_s:.4g} s, {harmonics} harmonics; condition number {ex.condition_number:.4g} "
        f"over {len(ex.parameters)} parameters: {', '.join(ex.parameters)}"
    ]
    with atomic_file(out, inputs=inputs) as tmp:
        write_motion_csv(tmp, motion)
        if report is not None:
            report([*lines, f"motion: {out}"])
    return lines
