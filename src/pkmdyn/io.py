"""Reading and writing unit-suffixed CSV, Parquet and JSON files, and whole output folders.

File conventions (see ``docs/file_formats.md``): comma-separated, one header row, every
column name carries its unit as a suffix (``t_s``, ``L11_m``, ``tau1_Nm``); JSON keys do the
same. Nothing non-finite is ever written: a NaN or infinity is a bug or a user error, and
writing refuses it with a message that names the column and row. Negative zero is written as
``0``.

Readers turn every decoding problem (not UTF-8, a UTF-16 byte-order mark, a NUL byte, an
over-long field) into one :class:`~pkmdyn.errors.PkmdynError` line that names the file.
Writers never leave a partial file or folder: :func:`output_dir` and :func:`atomic_file`
write beside the target and move into place only on success.
"""

from __future__ import annotations

import csv
import json
import math
import os
import shutil
import signal
import sys
import tempfile
import threading
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .errors import LimitError, MotionError, PkmdynError

__all__ = [
    "output_dir",
    "atomic_file",
    "RUN_MARKER",
    "DEFAULT_MAX_SAMPLES",
    "read_csv_columns",
    "write_csv",
    "write_json",
    "TableWriter",
    "open_table_writer",
    "check_table_format",
    "TABLE_FORMATS",
]

Array = NDArray[np.float64]

#: the file that marks a folder as a pkmdyn run's output (so a rerun may replace it whole)
RUN_MARKER = ".pkmdyn-run"

#: the default cap on the samples of one run and the data rows of one input file; checked
#: before anything of that size is allocated. Raise it with ``[limits] max_samples`` in a
#: parameter file or ``--limit max_samples=N`` on the command line.
DEFAULT_MAX_SAMPLES = 20_000_000

#: output table formats: CSV (text, any tool) and Parquet (binary, columnar; needs pyarrow)
TABLE_FORMATS = ("csv", "parquet")


def _note(message: str) -> None:
    print(f"pkmdyn: note: {message}", file=sys.stderr)


def _os_reason(exc: OSError) -> str:
    return exc.strerror or type(exc).__name__


def _missing_parents(path: Path) -> list[Path]:
    """The ancestors of ``path`` that do not exist yet, outermost first."""
    missing = []
    for p in path.parents:
        if p.exists() or p.is_symlink():
            break
        missing.append(p)
    return missing[::-1]


def _make_parents(path: Path, what: str) -> list[Path]:
    """Create the missing parents of ``path``; returns the folders created (outermost first)."""
    created = _missing_parents(path)
    for p in created:
        if p.exists():
            continue
        try:
            p.mkdir()
        except OSError as exc:
            _remove_created(created)
            raise PkmdynError(f"{what} {path}: cannot create folder {p} ({_os_reason(exc)})") from None
    return created


def _remove_created(created: list[Path]) -> None:
    for p in reversed(created):
        try:
            p.rmdir()
        except OSError:
            break


@contextmanager
def _signals_deferred() -> Iterator[None]:
    """Hold SIGINT/SIGTERM back for a few file-system calls that must not be split."""
    if threading.current_thread() is not threading.main_thread() or not hasattr(signal, "pthread_sigmask"):
        yield
        return
    sigs = {signal.SIGINT, signal.SIGTERM}
    old = signal.pthread_sigmask(signal.SIG_BLOCK, sigs)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def _check_out(out: Path) -> bool:
    """Refuse an ``--out`` that cannot be replaced; True when it holds an earlier run."""
    if out.is_symlink() and not out.exists():
        raise PkmdynError(f"--out {out}: is a broken symbolic link")
    if out.exists() and not out.is_dir():
        raise PkmdynError(f"--out {out}: exists and is a file, not a folder")
    if not out.is_dir():
        for p in out.parents:
            if p.exists():
                if not p.is_dir():
                    raise PkmdynError(f"--out {out}: {p} is a file, not a folder")
                break
        return False
    try:
        entries = list(out.iterdir())
    except OSError as exc:
        raise PkmdynError(f"--out {out}: cannot read folder ({_os_reason(exc)})") from None
    earlier = (out / RUN_MARKER).is_file()
    if entries and not earlier:
        raise PkmdynError(
            f"--out {out}: folder is not empty and holds no earlier pkmdyn run; refusing to overwrite it"
        )
    return earlier


@contextmanager
def output_dir(path: str | Path, notify: Callable[[str], None] | None = _note) -> Iterator[Path]:
    """Write a run's files all at once: ``with output_dir(out) as tmp: write into tmp``.

    The files go into a fresh temporary folder beside ``path`` (missing parent folders are
    created, and removed again if the run fails); only when the block ends without an
    exception is that folder moved into place, replacing an earlier pkmdyn run at ``path``
    whole (``notify`` is told so; by default one note on stderr). A non-empty ``path`` that
    holds no earlier run, a file in the way, or a folder that cannot be written is refused
    before anything is written. On any failure, Ctrl-C included, the temporary folder is
    removed and ``path`` is left as it was. The swap itself runs with SIGINT and SIGTERM held
    back, so an interrupt cannot leave ``path`` missing.
    """
    out = Path(path)
    _check_out(out)
    parent = out.absolute().parent
    created = _make_parents(out.absolute(), "--out")
    try:
        tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.partial-", dir=parent))
    except OSError as exc:
        _remove_created(created)
        raise PkmdynError(f"--out {out}: cannot create a folder in {parent} ({_os_reason(exc)})") from None
    swapped = False
    old: Path | None = None
    try:
        umask = os.umask(0)
        os.umask(umask)
        tmp.chmod(0o777 & ~umask)
        yield tmp
        (tmp / RUN_MARKER).write_text("pkmdyn run output; a rerun into this folder replaces it whole\n", encoding="utf-8")
        earlier = _check_out(out)  # again: something may have appeared there while the run computed
        with _signals_deferred():
            try:
                if out.exists():
                    old = Path(tempfile.mkdtemp(prefix=f".{out.name}.old-", dir=parent))
                    old.rmdir()
                    out.rename(old)
                tmp.rename(out)
                swapped = True
            except OSError as exc:
                if old is not None and old.exists() and not out.exists():
                    old.rename(out)
                    old = None
                raise PkmdynError(f"--out {out}: cannot move the results into place ({_os_reason(exc)})") from None
        if earlier and notify is not None:
            notify(f"replaced an earlier run in {out} (every file of it removed)")
    except BaseException:
        if not swapped:
            shutil.rmtree(tmp, ignore_errors=True)
            _remove_created(created)
        raise
    finally:
        if swapped and old is not None:
            if old.is_symlink():
                old.unlink(missing_ok=True)  # --out was a link to a folder: the link is replaced
            else:
                shutil.rmtree(old, ignore_errors=True)


@contextmanager
def atomic_file(path: str | Path, notify: Callable[[str], None] | None = _note) -> Iterator[Path]:
    """Write one file atomically: ``with atomic_file(p) as tmp: write tmp``.

    The file is written under a temporary name in the target's folder and renamed over
    ``path`` only when the block succeeds; on any failure (Ctrl-C included) the temporary
    file is removed and ``path`` is left as it was. Missing parent folders are created
    (``notify`` says which) and removed again on failure. A folder in the way is refused.
    """
    target = Path(path)
    if target.is_dir():
        raise PkmdynError(f"--out {target}: is a folder, expected a file name")
    for p in target.parents:
        if p.exists():
            if not p.is_dir():
                raise PkmdynError(f"--out {target}: {p} is a file, not a folder")
            break
    created = _make_parents(target.absolute(), "--out")
    try:
        fd, name = tempfile.mkstemp(prefix=f".{target.name}.partial-", dir=target.absolute().parent)
        os.close(fd)
    except OSError as exc:
        _remove_created(created)
        raise PkmdynError(f"--out {target}: cannot write in {target.absolute().parent} ({_os_reason(exc)})") from None
    tmp = Path(name)
    try:
        umask = os.umask(0)
        os.umask(umask)
        tmp.chmod(0o666 & ~umask)
        yield tmp
        try:
            os.replace(tmp, target)
        except OSError as exc:
            raise PkmdynError(f"--out {target}: cannot move the file into place ({_os_reason(exc)})") from None
        if created and notify is not None:
            notify(f"created folder {created[-1] if len(created) == 1 else created[0]}")
    except BaseException:
        tmp.unlink(missing_ok=True)
        _remove_created(created)
        raise


_BOMS = ((b"\x00\x00\xfe\xff", "UTF-32"), (b"\xff\xfe\x00\x00", "UTF-32"), (b"\xfe\xff", "UTF-16"), (b"\xff\xfe", "UTF-16"))


def check_text_encoding(path: Path, head: bytes, error: type[PkmdynError]) -> None:
    """Refuse a UTF-16/32 byte-order mark or a NUL byte at the start of a text file."""
    for bom, name in _BOMS:
        if head.startswith(bom):
            raise error(f"{path}: the file is {name} text (byte-order mark); save it as UTF-8")
    if b"\x00" in head:
        raise error(f"{path}: contains a NUL byte (binary data?); expected UTF-8 text")


def _decode_message(path: Path, exc: UnicodeDecodeError, line: int) -> str:
    bad = exc.object[exc.start : exc.start + 1].hex()
    return f"{path}: not UTF-8 text (byte 0x{bad} near line {line}); save it as UTF-8"


_BLOCK = 65_536


def read_csv_columns(
    path: str | Path, required: Sequence[str], optional: Sequence[str] = (), max_rows: int | None = DEFAULT_MAX_SAMPLES
) -> dict[str, Array]:
    """Read a numeric CSV with a header row into ``{column: (n,) array}``.

    Every required column must be present, unknown columns are errors (they are most often
    a misspelt unit suffix), and every cell must parse as a finite number. Errors name the
    file, the column and the 1-based data row. The text must be UTF-8 (a UTF-8 byte-order
    mark is allowed); more than ``max_rows`` data rows is a :class:`LimitError` raised before
    they are stored. The file is read as a stream, 8 bytes per stored value.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise MotionError(f"expected a file path, got {type(path).__name__}")
    path = Path(path)
    try:
        fh = path.open("r", encoding="utf-8-sig", newline="")
        with path.open("rb") as raw:
            head = raw.read(4096)
    except OSError as exc:
        raise MotionError(f"{path}: cannot read file ({_os_reason(exc)})") from None
    with fh:
        check_text_encoding(path, head, MotionError)
        reader = csv.reader(fh)
        try:
            return _parse_csv(path, reader, required, optional, max_rows)
        except UnicodeDecodeError as exc:
            raise MotionError(_decode_message(path, exc, reader.line_num + 1)) from None
        except csv.Error as exc:
            raise MotionError(f"{path}: line {reader.line_num}: not a readable CSV line ({exc})") from None
        except OSError as exc:
            raise MotionError(f"{path}: cannot read file ({_os_reason(exc)})") from None


def _parse_csv(
    path: Path, reader: Iterator[list[str]], required: Sequence[str], optional: Sequence[str], max_rows: int | None
) -> dict[str, Array]:
    rows = (row for row in reader if any(cell.strip() for cell in row))
    first = next(rows, None)
    if first is None:
        raise MotionError(f"{path}: file is empty, expected a header row")
    header = [h.strip() for h in first]
    known = set(required) | set(optional)
    for name in header:
        if "\x00" in name:
            raise MotionError(f"{path}: contains a NUL byte (binary data?); expected UTF-8 text")
        if name not in known:
            shown = name if len(name) <= 40 else name[:40] + "..."
            raise MotionError(
                f"{path}: unknown column {shown!r} (known columns: {', '.join([*required, *optional])})"
            )
    if len(set(header)) != len(header):
        raise MotionError(f"{path}: a column name appears twice in the header")
    for name in required:
        if name not in header:
            raise MotionError(f"{path}: missing required column {name!r}")
    ncol = len(header)
    blocks: list[Array] = []
    block = np.empty((_BLOCK, ncol))
    k = 0
    r = 0
    for r, row in enumerate(rows, start=1):
        if max_rows is not None and r > max_rows:
            raise LimitError(
                f"{path}: more than {max_rows} data rows, the sample limit (raise it with [limits] "
                "max_samples in the parameter file or --limit max_samples=N)"
            )
        if len(row) != ncol:
            raise MotionError(f"{path}: row {r} has {len(row)} fields, the header has {ncol}")
        for c, cell in enumerate(row):
            try:
                value = float(cell)
            except ValueError:
                shown = cell.strip() if len(cell) <= 40 else cell.strip()[:40] + "..."
                raise MotionError(f"{path}: row {r}, column {header[c]!r}: {shown!r} is not a number") from None
            if not math.isfinite(value):
                raise MotionError(f"{path}: row {r}, column {header[c]!r}: value {cell.strip()!r} is not finite")
            block[k, c] = value
        k += 1
        if k == _BLOCK:
            blocks.append(block)
            block = np.empty((_BLOCK, ncol))
            k = 0
    blocks.append(block[:k])
    if r == 0:
        raise MotionError(f"{path}: no data rows below the header")
    data = np.concatenate(blocks) if len(blocks) > 1 else blocks[0]
    return {name: data[:, c].copy() for c, name in enumerate(header)}


def _finite_columns(path: Any, columns: Mapping[str, Array], row0: int = 0) -> tuple[list[str], list[Array]]:
    """Columns as flat float arrays of one length, -0 turned into 0; refuses non-finite values."""
    names = list(columns)
    arrays = [np.asarray(columns[k], dtype=float).reshape(-1) + 0.0 for k in names]
    n = arrays[0].shape[0] if arrays else 0
    for name, a in zip(names, arrays):
        if a.shape[0] != n:
            raise PkmdynError(f"internal error: column {name!r} has {a.shape[0]} rows, expected {n}")
        bad = np.flatnonzero(~np.isfinite(a))
        if bad.size:
            raise PkmdynError(f"refusing to write {path}: column {name!r} row {row0 + bad[0] + 1} is {a[bad[0]]}")
    return names, arrays


def _csv_lines(arrays: list[Array], precision: int) -> str:
    if not arrays or arrays[0].shape[0] == 0:
        return ""
    table = np.column_stack(arrays)
    row_fmt = ",".join([f"%.{precision}g"] * len(arrays))
    return "\n".join(map(row_fmt.__mod__, map(tuple, table.tolist()))) + "\n"


def write_csv(path: str | Path, columns: Mapping[str, Array], precision: int = 17) -> None:
    """Write ``{column: (n,) array}`` as CSV; refuses non-finite values, naming column and row."""
    names, arrays = _finite_columns(path, columns)
    path = Path(path)
    try:
        with path.open("w", newline="", encoding="utf-8") as fh:
            fh.write(",".join(names) + "\n")
            fh.write(_csv_lines(arrays, precision))
    except OSError as exc:
        raise PkmdynError(f"cannot write {path} ({_os_reason(exc)})") from None


def check_table_format(fmt: str) -> None:
    """``fmt`` is a results-table format that can be written here (Parquet needs pyarrow); call it
    before any work so that a missing optional dependency fails first."""
    if fmt not in TABLE_FORMATS:
        raise PkmdynError(f"--format {fmt}: must be one of {', '.join(TABLE_FORMATS)}")
    if fmt == "parquet":
        try:
            import pyarrow  # noqa: F401
            import pyarrow.parquet  # noqa: F401
        except ImportError:
            raise PkmdynError(
                "--format parquet needs pyarrow: pip install 'pkmdyn[parquet]' (or use --format csv)"
            ) from None


class TableWriter:
    """Writes a results table block by block (CSV or Parquet), so that memory stays bounded.

    ``with open_table_writer(path, "csv") as w: w.write({column: (k,) array}); ...``. Every
    block must have the same columns; non-finite values are refused (column and row named)
    and ``-0`` is written as ``0``.
    """

    def __init__(self, path: Path, fmt: str, precision: int = 17) -> None:
        self.path, self.fmt, self.precision = path, fmt, precision
        self.rows = 0
        self._names: list[str] | None = None
        self._fh: Any = None
        self._pq: Any = None
        self._arrow_csv: Any = None
        self._arrow_options: Any = None
        check_table_format(fmt)
        if fmt == "csv" and precision >= 17:
            # pyarrow, where installed, formats numbers some 3x faster, in the shortest form that
            # reads back to the identical double; the plain path writes %.17g (also exact)
            try:
                import pyarrow.csv as pacsv

                self._arrow_csv = pacsv.write_csv
                self._arrow_options = pacsv.WriteOptions(include_header=False, quoting_style="none")
            except ImportError:
                pass

    def write(self, columns: Mapping[str, Array]) -> None:
        names, arrays = _finite_columns(self.path, columns, self.rows)
        if self._names is None:
            self._names = names
            self._open(names)
        elif names != self._names:
            raise PkmdynError(f"internal error: {self.path}: a block has different columns")
        if self.fmt == "csv" and self._arrow_csv is not None:
            import pyarrow as pa

            self._fh.flush()
            self._arrow_csv(pa.table(dict(zip(names, arrays))), self._fh.buffer, self._arrow_options)
        elif self.fmt == "csv":
            self._fh.write(_csv_lines(arrays, self.precision))
        else:
            import pyarrow as pa

            self._pq.write_table(pa.table(dict(zip(names, arrays))))
        self.rows += arrays[0].shape[0] if arrays else 0

    def _open(self, names: list[str]) -> None:
        if self.fmt == "csv":
            self._fh = self.path.open("w", newline="", encoding="utf-8")
            self._fh.write(",".join(names) + "\n")
            self._fh.flush()
        else:
            import pyarrow as pa
            import pyarrow.parquet as pq

            schema = pa.schema([(n, pa.float64()) for n in names])
            self._pq = pq.ParquetWriter(str(self.path), schema, compression="zstd")

    def close(self) -> None:
        if self._fh is not None:
            self._fh.close()
        if self._pq is not None:
            self._pq.close()

    def __enter__(self) -> "TableWriter":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def open_table_writer(path: str | Path, fmt: str = "csv", precision: int = 17) -> TableWriter:
    """A :class:`TableWriter` for ``path`` in ``fmt`` (``"csv"`` or ``"parquet"``)."""
    return TableWriter(Path(path), fmt, precision)


def _check_finite(obj: Any, where: str) -> None:
    if isinstance(obj, float) and not math.isfinite(obj):
        raise PkmdynError(f"refusing to write a non-finite value at {where}")
    if isinstance(obj, Mapping):
        for k, v in obj.items():
            _check_finite(v, f"{where}.{k}")
    elif isinstance(obj, Iterable) and not isinstance(obj, str):
        for i, v in enumerate(obj):
            _check_finite(v, f"{where}[{i}]")


def _no_negative_zero(obj: Any) -> Any:
    if isinstance(obj, float):
        return obj + 0.0
    if isinstance(obj, dict):
        return {k: _no_negative_zero(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_no_negative_zero(v) for v in obj]
    return obj


def _plain(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, (np.floating, np.integer)):
        return obj.item()
    raise TypeError(f"cannot write {type(obj).__name__} as JSON")


def write_json(path: str | Path, data: Mapping[str, Any]) -> None:
    """Write a JSON document with unit-suffixed keys; refuses non-finite numbers."""
    text = json.dumps(data, indent=2, default=_plain)
    plain = json.loads(text)
    _check_finite(plain, "$")
    try:
        Path(path).write_text(json.dumps(_no_negative_zero(plain), indent=2) + "\n", encoding="utf-8")
    except OSError as exc:
        raise PkmdynError(f"cannot write {path} ({_os_reason(exc)})") from None
