"""The one writer of a command's output folder (``--out``): the output rule, the files, the
summary and the report, for every job (the engine's and the machines' alike).

A job hands :func:`write_output` a function ``make(folder)`` that writes its own files (tables,
arrays, figures) into a temporary folder and returns an :class:`Output`: those files, the
summary document and the report's content (:class:`Report`). The writer then

1. writes ``summary.json`` (the summary with ``"files"``, the sorted names of every file of the
   folder) where the output has a summary;
2. renders ``report.html`` (:func:`pkmdyn.report.write_report`) where it has a report, its
   summary table the report's own or else the written summary, its images the output's files
   named by label;
3. announces the files' final paths (the command line's listing, before anything moves) and
   moves the folder into place only when all of this succeeded (:func:`pkmdyn.io.output_dir`:
   a failure, Ctrl-C included, leaves ``--out`` as it was; no input, link, device or folder
   pkmdyn did not write is ever replaced).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..io import output_dir, write_json
from ._figures import TimePlot
from ._page import REPORT_NAME, write_report
from ._scene import MAX_FRAMES, Scene

__all__ = ["Report", "Output", "JobResult", "write_output", "SUMMARY_NAME"]

#: the summary's file name inside an output folder
SUMMARY_NAME = "summary.json"


@dataclass(frozen=True)
class Report:
    """The content of ``report.html`` (:func:`pkmdyn.report.write_report`'s arguments): its
    ``title``; the ``scene`` animated in 3D (None: none) and the time ``plots``; further plotly
    ``figures`` ``(caption, figure)``; ``images``, the labels of the output's PNG files to embed;
    ``notes`` under the title, every ``warnings`` line of the run, the ``parameters`` text;
    ``summary``, the document its summary table shows (None: the output's summary as written);
    ``scene_note``, ``samples`` (the run's samples where the scene holds only some) and
    ``max_frames`` (the animation's frames at most)."""

    title: str
    scene: Scene | None = None
    plots: Sequence[TimePlot] = ()
    figures: Sequence[tuple[str, Any]] = ()
    images: Sequence[str] = ()
    notes: Sequence[str] = ()
    warnings: Sequence[str] = ()
    parameters: str = ""
    summary: Mapping[str, Any] | None = None
    scene_note: str = ""
    samples: int | None = None
    max_frames: int = MAX_FRAMES


@dataclass(frozen=True)
class Output:
    """What a job's ``make(folder)`` wrote and what the writer adds (module docstring): ``files``
    (label -> path inside the folder), the ``summary`` document (written as ``summary.json``; None:
    no summary file) and the ``report`` (None: no ``report.html``)."""

    files: Mapping[str, Path] = field(default_factory=dict)
    summary: Mapping[str, Any] | None = None
    report: Report | None = None


@dataclass(frozen=True)
class JobResult:
    """A job's outcome: ``files`` (label -> the written file's final path; empty where the job
    wrote none), ``summary`` (the document its summary or main JSON file holds), ``lines`` (what
    the command prints on stdout after the files), ``warnings`` (one line each, for stderr) and
    ``notes`` (what the user should know that is not wrong: a default filled in, an element
    approximated; one line each, for stderr) and ``report``, the content of its ``report.html``
    (None: the job wrote none), whose :attr:`scene` and :attr:`plots` a notebook can show."""

    files: Mapping[str, Path] = field(default_factory=dict)
    summary: Mapping[str, Any] = field(default_factory=dict)
    lines: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()
    report: Report | None = None

    @property
    def scene(self) -> Scene | None:
        """The mechanism along the job's motion, as its report animates it (None: none)."""
        return None if self.report is None else self.report.scene

    @property
    def plots(self) -> tuple[TimePlot, ...]:
        """The report's time plots."""
        return () if self.report is None else tuple(self.report.plots)


def write_output(out_dir: str | Path, inputs: Mapping[str, Path | None], make: Callable[[Path], Output],
                 announce: Callable[[Mapping[str, Path]], None] | None = None) -> tuple[dict[str, Path], Output]:
    """Write a job's output folder (module docstring): ``make(folder)`` writes the job's own files
    into a temporary folder beside ``out_dir``; ``inputs`` (option -> path) are the files the job
    read, none of which the output may replace; ``announce`` is given the final paths before the
    folder moves into place. Returns the final paths (label -> path; the summary and the report
    last) and the output, its summary with ``"files"``."""
    final = Path(out_dir)
    with output_dir(out_dir, inputs=inputs) as folder:
        out = make(folder)
        files = dict(out.files)
        summary = out.summary
        if summary is not None:
            files["summary"] = folder / SUMMARY_NAME
        if out.report is not None:
            files["report"] = folder / REPORT_NAME
        if summary is not None:
            summary = {**summary, "files": sorted(p.name for p in files.values())}
            write_json(files["summary"], summary)
        r = out.report
        if r is not None:
            write_report(folder, title=r.title, scene=r.scene, plots=r.plots,
                         summary=r.summary if r.summary is not None else summary, parameters=r.parameters,
                         warnings=r.warnings, images=[files[k] for k in r.images], notes=r.notes,
                         max_frames=r.max_frames, scene_note=r.scene_note, samples=r.samples, figures=r.figures)
        placed = {k: final / v.relative_to(folder) for k, v in files.items()}
        if announce is not None:
            announce(placed)
    return placed, Output(placed, summary, out.report)
