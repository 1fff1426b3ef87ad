"""``pkmdyn identify``: a machine and a measured file in; ``identification.json`` (the report of
``docs/identification.md``) and ``efforts.csv`` (measured and identified efforts) out. The fit is
:func:`pkmdyn.identify.described.fit_described`."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path

from ..identify._base import DEFAULT_RANK_TOL
from ..identify.described import fit_described, identification_document, read_measured
from ..io import write_csv, write_json
from ..multibody.kinematics.inverse import solve_kinematics
from ..report import Output, write_output
from ._files import JobResult, prepare

__all__ = ["job"]


def job(machine: str, measured_path: Path, out_dir: Path, *, rank_tol: float = DEFAULT_RANK_TOL,
        sg_window: int = 15, sg_order: int = 5,
        announce: Callable[[Mapping[str, Path]], None] | None = None) -> JobResult:
    """Identify ``machine``'s inertial parameters and joint friction coefficients from the efforts
    measured in ``measured_path`` (its columns: :mod:`pkmdyn.identify.described`); ``sg_window``,
    ``sg_order``: the differentiator of a log in actuator coordinates without rate columns."""
    path = Path(measured_path).absolute()
    p = prepare(machine, out_dir, {"--measured": path})
    model = p.model
    t, x, xd, xdd, u, named = read_measured(model, path, sg_window, sg_order)
    kin = solve_kinematics(model, x, xd, xdd, t)
    fit = fit_described(model, kin, u, named, rank_tol, source=str(path))
    doc = identification_document(model, fit)
    cols = fit.columns(t)

    def make(out: Path) -> Output:
        files = {"identification": out / "identification.json", "efforts": out / "efforts.csv"}
        write_csv(files["efforts"], cols)
        write_json(files["identification"], doc)
        return Output(files)

    files, _ = write_output(out_dir, p.inputs, make, announce)
    worst = min((v for v in doc["explained_percent"].values() if v is not None), default=None)
    line = (f"rank {doc['rank']} of {len(doc['parameters_asked'])} parameters; "
            + (f"least explained actuator {worst:.4g} %" if worst is not None else "no effort explained"))
    return JobResult(files, doc, (line,))
