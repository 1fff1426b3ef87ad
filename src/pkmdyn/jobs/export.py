"""``pkmdyn export``: a machine in another engine's format, MJCF (MuJoCo) or URDF with its loop
sidecar (Pinocchio, Gepetto's Extended-URDF loader), written only when the whole model can be
(:mod:`pkmdyn.multibody.formats.mjcf_out`, :mod:`pkmdyn.multibody.formats.urdf_out`;
``docs/import.md``)."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path

from ..errors import ParameterError
from ..io import check_output_file, dumps_yaml
from ..machines.registry import resolve
from ..multibody.formats.mjcf_out import SOLIMP, SOLREF, massless_bodies, mechanism_mjcf
from ..multibody.formats.urdf_out import mechanism_urdf
from ._files import JobResult, prepare, write_texts

__all__ = ["job"]


def _numbers(text: str | None, n: int, flag: str) -> tuple[float, ...] | None:
    """``"a,b,..."`` -> ``n`` numbers (None for None); one line naming ``flag`` otherwise."""
    if text is None:
        return None
    try:
        vals = tuple(float(x) for x in text.split(","))
    except ValueError:
        vals = ()
    if len(vals) != n:
        raise ParameterError(f"{flag}: {n} numbers, comma-separated")
    return vals


def job(machine: str, fmt: str, out_path: Path, *, solref: str | None = None, solimp: str | None = None,
        timestep_s: float | None = None, massless_kg: float | None = None,
        announce: Callable[[Mapping[str, Path]], None] | None = None) -> JobResult:
    """``machine`` as ``fmt`` (``"mjcf"`` or ``"urdf"``) into ``out_path`` (with ``FILE.yaml``, the
    loop sidecar, beside a URDF); MJCF only: the equality constraints' ``solref``
    (``"timeconst,dampratio"``) and ``solimp`` (five numbers), MuJoCo's ``timestep_s`` and the
    mass ``massless_kg`` given to bodies without one."""
    out_path = Path(out_path)
    if fmt not in ("mjcf", "urdf"):
        raise ParameterError(f"--format {fmt!r}: mjcf or urdf")
    if fmt != "mjcf" and (solref or solimp or massless_kg is not None or timestep_s is not None):
        raise ParameterError("--solref, --solimp, --timestep, --massless-mass-kg: only for --format mjcf")
    side_path = out_path.with_suffix(".yaml")
    if fmt == "urdf" and side_path == out_path:
        raise ParameterError("--out: a URDF file name not ending in .yaml (its sidecar is FILE.yaml)")
    given = {"--machine": resolve(machine)[1]}
    for path in (out_path, side_path) if fmt == "urdf" else (out_path,):
        check_output_file(path, given)  # before the machine is compiled: a bad --out costs nothing
    p = prepare(machine, None)
    model = p.model
    if fmt == "mjcf":
        text = mechanism_mjcf(model, 1e-3 if timestep_s is None else timestep_s,
                              solref=_numbers(solref, 2, "--solref") or SOLREF,
                              solimp=_numbers(solimp, 5, "--solimp") or SOLIMP, massless_kg=massless_kg)
        light = massless_bodies(model)
        notes = (f"bodies without mass given {massless_kg:g} kg: {', '.join(light)}",) if light else ()
        texts = {"mjcf": (out_path, text)}
    else:
        text, sidecar, urdf_notes = mechanism_urdf(model)
        notes = tuple(urdf_notes)
        texts = {"urdf": (out_path, text), "sidecar": (side_path, dumps_yaml(sidecar))}
    files = write_texts(texts, p.inputs, announce)
    return JobResult(files, notes=notes)
