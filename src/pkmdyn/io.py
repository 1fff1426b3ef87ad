"""Reading and writing unit-suffixed CSV and JSON files.

File conventions (see ``docs/file_formats.md``): comma-separated, one header row, every
column name carries its unit as a suffix (``t_s``, ``L11_m``, ``tau1_Nm``); JSON keys do the
same. Nothing non-finite is ever written: a NaN or infinity is a bug or a user error, and
writing refuses it with a message that names the column and row.
"""

from __future__ import annotations

import csv
import json
import math
import shutil
import tempfile
from contextlib import contextmanager
from collections.abc import Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .errors import MotionError, PkmdynError

__all__ = ["output_dir", "RUN_MARKER", "make_out_dir", "read_csv_columns", "write_csv", "write_json"]

Array = NDArray[np.float64]


#: the file that marks a folder as a pkmdyn run's output (so a rerun may replace it whole)
RUN_MARKER = ".pkmdyn-run"


@contextmanager
def output_dir(path: str | Path) -> Iterator[Path]:
    """Write a run's files all at once: ``with output_dir(out) as tmp: write into tmp``.

    The files go into a fresh temporary folder beside ``path``; only when the block ends
    without an exception (Ctrl-C included) is that folder moved into place, replacing an
    earlier pkmdyn run at ``path`` whole. A non-empty ``path`` that holds no earlier run is
    refused before anything is written. On any failure the temporary folder is removed and
    ``path`` is left as it was.
    """
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise PkmdynError(f"--out {out}: exists and is not a folder")
    if out.is_dir() and any(out.iterdir()) and not (out / RUN_MARKER).is_file():
        raise PkmdynError(f"--out {out}: folder is not empty and holds no earlier pkmdyn run; refusing to overwrite it")
    parent = out.absolute().parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.partial-", dir=parent))
    except OSError as exc:
        raise PkmdynError(f"--out {out}: cannot create folder ({exc.strerror or exc})") from None
    try:
        yield tmp
        (tmp / RUN_MARKER).write_text("pkmdyn run output; a rerun into this folder replaces it whole\n", encoding="utf-8")
        old = None
        if out.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{out.name}.old-", dir=parent))
            old.rmdir()
            out.rename(old)
        tmp.rename(out)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def make_out_dir(path: str | Path) -> Path:
    """Create the output folder (and its parents); a file in the way or a refused creation is a
    :class:`PkmdynError` naming the folder. Call it only once every result is computed, so that
    a user error leaves nothing behind."""
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise PkmdynError(f"--out {out}: exists and is not a folder")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise PkmdynError(f"--out {out}: cannot create folder ({exc.strerror or exc})") from None
    return out


def read_csv_columns(
    path: str | Path, required: Sequence[str], optional: Sequence[str] = ()
) -> dict[str, Array]:
    """Read a numeric CSV with a header row into ``{column: (n,) array}``.

    Every required column must be present, unknown columns are errors (they are most often
    a misspelt unit suffix), and every cell must parse as a finite number. Errors name the
    file, the column and the 1-based data row.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except OSError as exc:
        raise MotionError(f"{path}: cannot read file ({exc.strerror or exc})") from None
    rows = list(csv.reader(line for line in text.splitlines() if line.strip()))
    if not rows:
        raise MotionError(f"{path}: file is empty, expected a header row")
    header = [h.strip() for h in rows[0]]
    known = set(required) | set(optional)
    for name in header:
        if name not in known:
            raise MotionError(
                f"{path}: unknown column {name!r} (known columns: {', '.join([*required, *optional])})"
            )
    if len(set(header)) != len(header):
        raise MotionError(f"{path}: a column name appears twice in the header")
    for name in required:
        if name not in header:
            raise MotionError(f"{path}: missing required column {name!r}")
    data = np.empty((len(rows) - 1, len(header)))
    for r, row in enumerate(rows[1:], start=1):
        if len(row) != len(header):
            raise MotionError(f"{path}: row {r} has {len(row)} fields, the header has {len(header)}")
        for c, cell in enumerate(row):
            try:
                value = float(cell)
            except ValueError:
                raise MotionError(f"{path}: row {r}, column {header[c]!r}: {cell.strip()!r} is not a number") from None
            if not math.isfinite(value):
                raise MotionError(f"{path}: row {r}, column {header[c]!r}: value {cell.strip()!r} is not finite")
            data[r - 1, c] = value
    if data.shape[0] == 0:
        raise MotionError(f"{path}: no data rows below the header")
    return {name: data[:, c].copy() for c, name in enumerate(header)}


def write_csv(path: str | Path, columns: Mapping[str, Array], precision: int = 17) -> None:
    """Write ``{column: (n,) array}`` as CSV; refuses non-finite values, naming column and row."""
    names = list(columns)
    arrays = [np.asarray(columns[k], dtype=float).reshape(-1) for k in names]
    n = arrays[0].shape[0] if arrays else 0
    for name, a in zip(names, arrays):
        if a.shape[0] != n:
            raise PkmdynError(f"internal error: column {name!r} has {a.shape[0]} rows, expected {n}")
        bad = np.flatnonzero(~np.isfinite(a))
        if bad.size:
            raise PkmdynError(f"refusing to write {path}: column {name!r} row {bad[0] + 1} is {a[bad[0]]}")
    table = np.column_stack(arrays) if arrays else np.empty((0, 0))
    path = Path(path)
    with path.open("w", newline="", encoding="utf-8") as fh:
        fh.write(",".join(names) + "\n")
        np.savetxt(fh, table, delimiter=",", fmt=f"%.{precision}g")


def _check_finite(obj: Any, where: str) -> None:
    if isinstance(obj, float) and not math.isfinite(obj):
        raise PkmdynError(f"refusing to write a non-finite value at {where}")
    if isinstance(obj, Mapping):
        for k, v in obj.items():
            _check_finite(v, f"{where}.{k}")
    elif isinstance(obj, Iterable) and not isinstance(obj, str):
        for i, v in enumerate(obj):
            _check_finite(v, f"{where}[{i}]")


def _plain(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, (np.floating, np.integer)):
        return obj.item()
    raise TypeError(f"cannot write {type(obj).__name__} as JSON")


def write_json(path: str | Path, data: Mapping[str, Any]) -> None:
    """Write a JSON document with unit-suffixed keys; refuses non-finite numbers."""
    text = json.dumps(data, indent=2, default=_plain)
    _check_finite(json.loads(text), "$")
    Path(path).write_text(text + "\n", encoding="utf-8")
