"""Reading and writing unit-suffixed CSV, Parquet, JSON and TOML files, and whole output folders.

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
import io
import json
import math
import os
import shutil
import signal
import stat
import sys
import tempfile
import threading
import zipfile
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .errors import LimitError, MotionError, PkmdynError

__all__ = [
    "note_table_size",
    "output_dir",
    "atomic_file",
    "check_output_dir",
    "check_inputs_outside",
    "check_output_file",
    "RUN_MARKER",
    "DEFAULT_MAX_SAMPLES",
    "read_csv_columns",
    "write_csv",
    "write_json",
    "dumps_toml",
    "TableWriter",
    "open_table_writer",
    "NpzWriter",
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
    try:
        print(f"pkmdyn: note: {message}", file=sys.stderr, flush=True)
    except (OSError, ValueError):
        pass  # the run has succeeded; a standard error that cannot be written does not undo it


#: a results table expected above this many bytes is announced before the run (a note on stderr)
LARGE_TABLE_BYTES = 500_000_000


def note_table_size(rows: int, columns: int, fmt: str, notify: Callable[[str], None] | None = None) -> None:
    """Say before a run how large its results table will be, where that is above
    :data:`LARGE_TABLE_BYTES`: about 20 bytes a value in CSV (shortest round-trip decimals), 8
    in Parquet (before compression)."""
    size = rows * columns * (20 if fmt == "csv" else 8)
    if size > LARGE_TABLE_BYTES:
        (notify or _note)(f"the results table will hold {rows:,} rows of {columns} columns, about {size / 1e9:.1f} GB "
                          f"as {fmt}" + (" (--format parquet writes about a third of it)" if fmt == "csv" else ""))


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


# ----------------------------------------------------------------------------- the output rule
#: extended attribute that marks a single output file as written by pkmdyn: its size and
#: modification time when written, so that a file changed since is no longer pkmdyn's to replace
_FILE_MARK = "user.pkmdyn.output"

Inputs = Mapping[str, "str | Path | None"] | Iterable["str | Path | None"]

_KINDS = ((stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"), (stat.S_ISFIFO, "a named pipe"),
          (stat.S_ISSOCK, "a socket"), (stat.S_ISLNK, "a symbolic link"))


def _kind(mode: int) -> str:
    for test, name in _KINDS:
        if test(mode):
            return name
    return "not a regular file or folder"


def _lstat(path: Path) -> os.stat_result | None:
    try:
        return os.lstat(path)
    except (FileNotFoundError, NotADirectoryError):
        return None  # missing, or under a file: the parent check names the file
    except OSError as exc:
        raise PkmdynError(f"--out {path}: cannot inspect it ({_os_reason(exc)})") from None


def _write_protected(st: os.stat_result) -> bool:
    """The permission bits say no writing: the owner's write bit for the owner and for root (whom
    the operating system would let through), the system's answer for anyone else."""
    uid = os.geteuid() if hasattr(os, "geteuid") else st.st_uid
    if uid in (0, st.st_uid):
        return not st.st_mode & stat.S_IWUSR
    return not st.st_mode & (stat.S_IWGRP | stat.S_IWOTH)


@dataclass(frozen=True)
class _Input:
    label: str
    real: Path
    ident: tuple[int, int]


def _inputs(inputs: Inputs) -> list[_Input]:
    """The run's input files that exist, by resolved path and (device, inode)."""
    items = inputs.items() if isinstance(inputs, Mapping) else ((str(p), p) for p in inputs)
    found = []
    for label, p in items:
        if p is None:
            continue
        try:
            st = os.stat(p)
        except (OSError, ValueError):
            continue  # cannot be read either: the reader says so
        found.append(_Input(label, Path(os.path.realpath(p)), (st.st_dev, st.st_ino)))
    return found


def check_inputs_outside(out: str | Path, inputs: Inputs) -> list[_Input]:
    """No input of the run (``{label: path}``) inside the folder ``out`` or equal to it (by
    resolved path): one :class:`~pkmdyn.errors.PkmdynError` line naming it. Returns the inputs
    that exist."""
    real = Path(os.path.realpath(out))
    given = _inputs(inputs)
    for inp in given:
        if inp.real == real or real in inp.real.parents:
            raise PkmdynError(f"--out {out}: holds {inp.label} ({inp.real.relative_to(real)}), an input of this "
                              "run; refusing to replace it (write to another --out)")
    return given


def _check_parent(target: Path) -> None:
    """The folder that will receive ``target`` (or, when it is missing, its nearest existing
    ancestor) is a folder and is not write-protected."""
    for p in target.absolute().parents:
        try:
            st = os.stat(p)
        except (FileNotFoundError, NotADirectoryError):
            continue
        except OSError as exc:
            raise PkmdynError(f"--out {target}: cannot inspect {p} ({_os_reason(exc)})") from None
        if not stat.S_ISDIR(st.st_mode):
            raise PkmdynError(f"--out {target}: {p} is a file, not a folder")
        if _write_protected(st):
            raise PkmdynError(f"--out {target}: folder {p} is write-protected; refusing to write in it")
        return


def _read_manifest(marker: Path) -> tuple[dict[str, list[int]] | None, str | None]:
    """The files an earlier run wrote, ``{relative path: [size, mtime_ns]}`` (None for a marker of
    an earlier pkmdyn version: plain text, no list), and the command that wrote them (None where
    the marker does not say)."""
    try:
        text = marker.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise PkmdynError(f"--out {marker.parent}: cannot read {marker.name} ({_os_reason(exc)})") from None
    try:
        doc = json.loads(text)
    except ValueError:
        return None, None
    if not isinstance(doc, dict):
        return None, None
    files, command = doc.get("files"), doc.get("command")
    return (files if isinstance(files, dict) else None), (command if isinstance(command, str) else None)


def current_command() -> tuple[str | None, bool]:
    """The pkmdyn command running now (``"run"``, ``"hip run"``; None outside the command line)
    and whether it was told to replace another command's run (``pkmdyn --replace ...``)."""
    click = sys.modules.get("click")
    ctx = click.get_current_context(silent=True) if click is not None else None
    if ctx is None:
        return None, False
    names = []
    root = ctx
    while root.parent is not None:
        names.append(root.info_name)
        root = root.parent
    return (" ".join(reversed(names)) or None), bool((root.obj or {}).get("replace"))


@dataclass(frozen=True)
class _Earlier:
    """What ``--out`` holds now: nothing (``exists`` False), an empty folder, or an earlier run."""

    exists: bool
    files: int
    run: bool = False


def check_output_dir(path: str | Path, inputs: Inputs = ()) -> _Earlier:
    """Apply the output rule to a folder ``--out`` (``docs/file_formats.md``, "The output rule").

    Refused, each with one :class:`~pkmdyn.errors.PkmdynError` line: a symbolic link, a device,
    a pipe, a socket or a file in the way; a write-protected folder (or a write-protected file or
    folder inside it, or a write-protected folder to create it in); a non-empty folder without an
    earlier run's marker; anything in an earlier run that the run did not write or that was
    changed since (where the marker lists the files); an input of this run (same resolved path or
    same device and inode) inside the folder. Call it before the work, so that a refused run
    computes nothing; :func:`output_dir` applies it again.
    """
    out = Path(path)
    st = _lstat(out)
    if st is None:
        _check_parent(out)
        return _Earlier(False, 0)
    if stat.S_ISREG(st.st_mode):
        raise PkmdynError(f"--out {out}: exists and is a file, not a folder")
    if not stat.S_ISDIR(st.st_mode):
        raise PkmdynError(f"--out {out}: is {_kind(st.st_mode)}, not a folder pkmdyn wrote; refusing to replace it")
    if _write_protected(st):
        raise PkmdynError(f"--out {out}: folder is write-protected; refusing to replace it")
    _check_parent(out)
    given = check_inputs_outside(out, inputs)
    entries = _walk(out)
    if not entries:
        return _Earlier(True, 0)
    marker = out / RUN_MARKER
    mst = entries.get(RUN_MARKER)
    if mst is None or not stat.S_ISREG(mst.st_mode):
        raise PkmdynError(
            f"--out {out}: folder is not empty and holds no earlier pkmdyn run; refusing to overwrite it")
    manifest, written_by = _read_manifest(marker)
    command, replace = current_command()
    if written_by is not None and command is not None and written_by != command and not replace:
        raise PkmdynError(f"--out {out}: holds the results of pkmdyn {written_by}; pkmdyn {command} replaces only its "
                          f"own earlier run: choose another --out, or replace them with pkmdyn --replace {command} ...")
    idents = {inp.ident: inp for inp in given}
    files = 0
    for rel, est in entries.items():
        where = out / rel
        if stat.S_ISLNK(est.st_mode) or not (stat.S_ISREG(est.st_mode) or stat.S_ISDIR(est.st_mode)):
            raise PkmdynError(f"--out {out}: {where} is {_kind(est.st_mode)}, which pkmdyn never writes; "
                              "refusing to replace the folder")
        if (est.st_dev, est.st_ino) in idents:
            raise PkmdynError(f"--out {out}: {where} is {idents[(est.st_dev, est.st_ino)].label}, an input of "
                              "this run; refusing to replace it (write to another --out)")
        if _write_protected(est):
            raise PkmdynError(f"--out {out}: {where} is write-protected; refusing to replace the folder")
        if stat.S_ISDIR(est.st_mode) or rel == RUN_MARKER:
            continue
        files += 1
        if manifest is not None:
            known = manifest.get(rel)
            if known is None:
                raise PkmdynError(f"--out {out}: {where} was not written by the earlier run there; refusing to "
                                  "replace the folder (move the file away or choose another --out)")
            if list(known) != [est.st_size, est.st_mtime_ns]:
                raise PkmdynError(f"--out {out}: {where} was changed after the earlier run wrote it; refusing to "
                                  "replace the folder (move the file away or choose another --out)")
    return _Earlier(True, files, run=True)


def _walk(folder: Path) -> dict[str, os.stat_result]:
    """Every entry under ``folder`` (not following links), ``{relative path: lstat}``."""
    found: dict[str, os.stat_result] = {}
    pending = [folder]
    try:
        while pending:
            d = pending.pop()
            with os.scandir(d) as it:
                for e in it:
                    st = e.stat(follow_symlinks=False)
                    rel = Path(e.path).relative_to(folder).as_posix()
                    found[rel] = st
                    if stat.S_ISDIR(st.st_mode):
                        pending.append(Path(e.path))
    except OSError as exc:
        raise PkmdynError(f"--out {folder}: cannot read folder ({_os_reason(exc)})") from None
    return found


def _file_fingerprint(st: os.stat_result) -> bytes:
    return f"{st.st_size} {st.st_mtime_ns}".encode()


def check_output_file(path: str | Path, inputs: Inputs = ()) -> bool:
    """Apply the output rule to a single-file ``--out``; True when it replaces an earlier file.

    Refused: a folder, a symbolic link, a device, a pipe or a socket; an input of this run (same
    resolved path or same device and inode); a write-protected file or a write-protected folder
    to write it in; an existing file that pkmdyn did not write, or that was changed after pkmdyn
    wrote it (pkmdyn marks what it writes with an extended attribute holding its size and
    modification time; where the file system keeps no such attribute, an existing file is never
    replaced).
    """
    target = Path(path)
    st = _lstat(target)
    if st is None:
        _check_parent(target)
        return False
    if stat.S_ISDIR(st.st_mode):
        raise PkmdynError(f"--out {target}: is a folder, expected a file name")
    if not stat.S_ISREG(st.st_mode):
        raise PkmdynError(f"--out {target}: is {_kind(st.st_mode)}, not a file pkmdyn wrote; refusing to replace it")
    real = Path(os.path.realpath(target))
    for inp in _inputs(inputs):
        if inp.real == real or inp.ident == (st.st_dev, st.st_ino):
            raise PkmdynError(f"--out {target}: is {inp.label}, an input of this run; refusing to replace it")
    if _write_protected(st):
        raise PkmdynError(f"--out {target}: file is write-protected; refusing to replace it")
    _check_parent(target)
    try:
        mark = os.getxattr(target, _FILE_MARK, follow_symlinks=False)
    except (OSError, AttributeError):
        mark = None
    if mark != _file_fingerprint(st):
        said = "was changed after pkmdyn wrote it" if mark is not None else "was not written by pkmdyn"
        raise PkmdynError(f"--out {target}: the file exists and {said}; refusing to replace it (remove it or "
                          "choose another --out)")
    return True


def _mark_file(path: Path) -> None:
    try:
        os.setxattr(path, _FILE_MARK, _file_fingerprint(os.stat(path)), follow_symlinks=False)
    except (OSError, AttributeError):
        pass  # no extended attributes here: the file is simply never replaced by a later run


def _write_marker(folder: Path) -> None:
    """The run's marker, listing every file it wrote with its size and modification time."""
    files = {rel: [st.st_size, st.st_mtime_ns] for rel, st in sorted(_walk(folder).items())
             if stat.S_ISREG(st.st_mode)}
    doc = {"pkmdyn_run": "output of one pkmdyn run; a rerun into this folder replaces it whole", "files": files}
    command, _ = current_command()
    if command is not None:
        doc["command"] = command
    (folder / RUN_MARKER).write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")


def _commit_stdout() -> None:
    """Flush what the run said on standard output before anything moves into place: a standard
    output that cannot be written (a full device) fails the run while nothing is changed yet."""
    stream = sys.stdout
    if stream is None:
        return
    try:
        stream.flush()
    except OSError as exc:
        raise PkmdynError(f"standard output: cannot write ({_os_reason(exc)}); --out left as it was") from None
    except ValueError:
        pass  # closed


@contextmanager
def output_dir(path: str | Path, notify: Callable[[str], None] | None = _note, inputs: Inputs = ()) -> Iterator[Path]:
    """Write a run's files all at once: ``with output_dir(out, inputs=...) as tmp: write into tmp``.

    ``--out`` must pass :func:`check_output_dir` (the output rule; ``inputs``, ``{label: path}``,
    are the files this run reads, none of which may be inside ``path``), before the block and
    again before the swap. The files go into a fresh temporary folder beside ``path`` (missing
    parent folders are created, and removed again if the run fails); only when the block ends
    without an exception, and what the run printed on standard output was written, is that
    folder moved into place, replacing an earlier pkmdyn run at ``path`` whole (``notify`` is
    told what was removed; by default one note on stderr). On any failure, Ctrl-C included, the
    temporary folder is removed and ``path`` is left as it was. The swap itself runs with SIGINT
    and SIGTERM held back, so an interrupt cannot leave ``path`` missing. The folder gets the
    marker :data:`RUN_MARKER`, which lists every file written with its size and modification time.
    """
    out = Path(path)
    check_output_dir(out, inputs)
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
        _write_marker(tmp)
        earlier = check_output_dir(out, inputs)  # again: something may have changed while the run computed
        _commit_stdout()
        with _signals_deferred():
            try:
                if earlier.exists:
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
    except BaseException:
        if not swapped:
            shutil.rmtree(tmp, ignore_errors=True)
            _remove_created(created)
        raise
    if old is None:
        return
    problem = ""
    try:
        shutil.rmtree(old)
    except OSError as exc:
        problem = f"{exc.filename}: {_os_reason(exc)}" if exc.filename else _os_reason(exc)
    if notify is None:
        return
    if problem:
        notify(f"replaced an earlier run in {out}, but its old files could not all be removed; they are in "
               f"{old} ({problem}): delete that folder by hand")
    elif earlier.run:
        notify(f"replaced an earlier run in {out}: its {earlier.files} file(s) removed")
    else:
        notify(f"replaced the empty folder {out}")


@contextmanager
def atomic_file(path: str | Path, notify: Callable[[str], None] | None = _note, inputs: Inputs = ()) -> Iterator[Path]:
    """Write one file atomically: ``with atomic_file(p, inputs=...) as tmp: write tmp``.

    ``path`` must pass :func:`check_output_file` (the output rule), before the block and again
    before the rename. The file is written under a temporary name in the target's folder,
    marked as pkmdyn's, and renamed over ``path`` only when the block succeeds and what the run
    printed on standard output was written; on any failure (Ctrl-C included) the temporary file
    is removed and ``path`` is left as it was. Missing parent folders are created (``notify``
    says which) and removed again on failure; ``notify`` also says when an earlier file was
    replaced.
    """
    target = Path(path)
    check_output_file(target, inputs)
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
        replaced = check_output_file(target, inputs)  # again: something may have appeared meanwhile
        _mark_file(tmp)
        _commit_stdout()
        try:
            os.replace(tmp, target)
        except OSError as exc:
            raise PkmdynError(f"--out {target}: cannot move the file into place ({_os_reason(exc)})") from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        _remove_created(created)
        raise
    if notify is not None:
        if created:
            notify(f"created folder {created[-1] if len(created) == 1 else created[0]}")
        if replaced:
            notify(f"replaced {target}, which an earlier pkmdyn run wrote")


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
    path: str | Path, required: Sequence[str], optional: Sequence[str] = (), max_rows: int | None = DEFAULT_MAX_SAMPLES,
    beyond: str = "the sample limit (raise it with [limits] max_samples in the parameter file or --limit max_samples=N)"
) -> dict[str, Array]:
    """Read a numeric CSV with a header row into ``{column: (n,) array}``.

    Every required column must be present, unknown columns are errors (they are most often
    a misspelt unit suffix), and every cell must parse as a finite number; ``beyond`` says what
    the row limit is and how to live with it. Errors name the
    file, the column and the 1-based data row. The text must be UTF-8 (a UTF-8 byte-order
    mark is allowed); more than ``max_rows`` data rows is a :class:`LimitError` raised before
    they are stored. The file is read as a stream, 8 bytes per stored value.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise MotionError(f"expected a file path, got {type(path).__name__}")
    path = Path(path)
    try:
        # opened once and read once: a pipe (``--motion <(cat m.csv)``) can be read only once
        raw = path.open("rb")
    except OSError as exc:
        raise MotionError(f"{path}: cannot read file ({_os_reason(exc)})") from None
    try:
        head = raw.peek(4096)[:4096]
    except OSError as exc:
        raw.close()
        raise MotionError(f"{path}: cannot read file ({_os_reason(exc)})") from None
    fh = io.TextIOWrapper(raw, encoding="utf-8-sig", newline="")
    with fh:
        check_text_encoding(path, head, MotionError)
        reader = csv.reader(fh)
        try:
            return _parse_csv(path, reader, required, optional, max_rows, beyond)
        except UnicodeDecodeError as exc:
            raise MotionError(_decode_message(path, exc, reader.line_num + 1)) from None
        except csv.Error as exc:
            raise MotionError(f"{path}: line {reader.line_num}: not a readable CSV line ({exc})") from None
        except OSError as exc:
            raise MotionError(f"{path}: cannot read file ({_os_reason(exc)})") from None


def _parse_csv(
    path: Path, reader: Iterator[list[str]], required: Sequence[str], optional: Sequence[str], max_rows: int | None,
    beyond: str
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
            raise LimitError(f"{path}: more than {max_rows} data rows, {beyond}")
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


#: rows of a Parquet row group (TableWriter)
PARQUET_ROW_GROUP = 32_768


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
        self._pending: list[list[Array]] = []
        self._pending_rows = 0
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
            # the system allocator: arrow's own pool keeps its buffers (some 10 MiB) after a block
            self._arrow_csv(pa.table(dict(zip(names, arrays))), self._fh.buffer, self._arrow_options,
                            memory_pool=pa.system_memory_pool())
        elif self.fmt == "csv":
            self._fh.write(_csv_lines(arrays, self.precision))
        else:
            # blocks gathered into row groups of about PARQUET_ROW_GROUP rows: each row group keeps
            # its metadata in memory until the file closes, so small groups add up over a long run
            self._pending.append([np.array(a, copy=True) for a in arrays])
            self._pending_rows += arrays[0].shape[0] if arrays else 0
            if self._pending_rows >= PARQUET_ROW_GROUP:
                self._flush()
        self.rows += arrays[0].shape[0] if arrays else 0

    def _flush(self) -> None:
        if not self._pending:
            return
        import pyarrow as pa

        cols = [np.concatenate([blk[k] for blk in self._pending]) for k in range(len(self._names or []))]
        self._pq.write_table(pa.table(dict(zip(self._names or [], cols))))
        self._pending, self._pending_rows = [], 0

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
            self._flush()
            self._pq.close()

    def __enter__(self) -> "TableWriter":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def open_table_writer(path: str | Path, fmt: str = "csv", precision: int = 17) -> TableWriter:
    """A :class:`TableWriter` for ``path`` in ``fmt`` (``"csv"`` or ``"parquet"``)."""
    return TableWriter(Path(path), fmt, precision)


class NpzWriter:
    """Writes a NumPy ``.npz`` archive whose per-sample arrays arrive block by block along their
    first axis, so that memory stays bounded: each array streams into its own ``.npy`` file
    beside ``path`` (its header written first, with the final ``rows``), and :meth:`close` packs
    them into the archive and removes them. The members are stored, not deflated: the bodies'
    floating-point arrays shrink by about a third under deflate at its fastest level, which
    took longer than computing them (21 s of a 47 s run of 20,000 Stewart samples). ``write({name: (k, ...) array})`` takes the
    next ``k`` rows of every per-sample array (the same names each block); ``put(name, array)``
    an array stored whole. Non-finite values are refused, naming the array and the row."""

    def __init__(self, path: str | Path, rows: int) -> None:
        self.path, self.rows = Path(path), int(rows)
        self._files: dict[str, tuple[Path, Any]] = {}
        self._done: dict[str, int] = {}
        self._whole: list[tuple[str, Path]] = []

    def _member(self, name: str) -> Path:
        return self.path.with_name(f".{self.path.name}.{name}.npy")

    def put(self, name: str, array: Array) -> None:
        tmp = self._member(name)
        np.save(tmp, np.asarray(array), allow_pickle=False)
        self._whole.append((name, tmp))

    def write(self, arrays: Mapping[str, Array]) -> None:
        for name, a in arrays.items():
            a = np.ascontiguousarray(a)
            if a.dtype.kind == "f" and not np.all(np.isfinite(a)):
                row = int(np.flatnonzero(~np.isfinite(a.reshape(a.shape[0], -1)).all(axis=1))[0])
                raise PkmdynError(f"{self.path.name}: {name} has a non-finite value at sample "
                                  f"{self._done.get(name, 0) + row}; refusing to write it")
            if name not in self._files:
                tmp = self._member(name)
                fh = tmp.open("wb")
                np.lib.format.write_array_header_2_0(fh, {"descr": np.lib.format.dtype_to_descr(a.dtype),
                                                          "fortran_order": False,
                                                          "shape": (self.rows, *a.shape[1:])})
                self._files[name] = (tmp, fh)
                self._done[name] = 0
            if self._done[name] + a.shape[0] > self.rows:
                raise PkmdynError(f"internal error: {self.path.name}: {name} gets more than {self.rows} rows")
            self._files[name][1].write(a.tobytes())
            self._done[name] += a.shape[0]

    def close(self) -> None:
        """Pack the archive (every per-sample array must have its ``rows``) and remove the parts."""
        for _, fh in self._files.values():
            fh.close()
        short = [n for n, k in self._done.items() if k != self.rows]
        if short:
            raise PkmdynError(f"internal error: {self.path.name}: {short[0]} has {self._done[short[0]]} of "
                              f"{self.rows} rows")
        try:
            with zipfile.ZipFile(self.path, "w", compression=zipfile.ZIP_STORED, allowZip64=True) as zf:
                for name, tmp in [*self._whole, *((n, f[0]) for n, f in self._files.items())]:
                    zf.write(tmp, arcname=f"{name}.npy")
        except OSError as exc:
            raise PkmdynError(f"{self.path}: cannot write file ({_os_reason(exc)})") from None
        finally:
            self.discard()

    def discard(self) -> None:
        """Remove the parts (after :meth:`close`, or when the run failed)."""
        for _, fh in self._files.values():
            fh.close()
        for tmp in [t for _, t in self._whole] + [f[0] for f in self._files.values()]:
            tmp.unlink(missing_ok=True)


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


def _check_toml_values(value: Any, where: str) -> None:
    """Refuse what a parameter file cannot hold: non-finite numbers, and types other than
    tables, strings, booleans, integers, floats and lists of them."""
    if isinstance(value, Mapping):
        for k, v in value.items():
            _check_toml_values(v, f"{where}.{k}" if where else str(k))
    elif isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            _check_toml_values(v, f"{where}[{i}]")
    elif isinstance(value, float):
        if not math.isfinite(value):
            raise PkmdynError(f"{where}: refusing to write the non-finite value {value} into a TOML file")
    elif not isinstance(value, (str, bool, int)):
        raise PkmdynError(f"{where}: cannot write a {type(value).__name__} into a TOML file")


def dumps_toml(data: Mapping[str, Any], header: str = "", notes: Mapping[str, str] | None = None) -> str:
    """TOML text (written by ``tomlkit``) of nested tables of strings, booleans, numbers and
    lists: ``header`` lines become comments at the top, ``notes[key]`` a comment after every
    ``key`` of that name. Floats are written in their shortest round-trip form, so reading
    the file back gives the same doubles; a non-finite number is refused."""
    import tomlkit

    _check_toml_values(data, "")
    notes = notes or {}

    def table(values: Mapping[str, Any]) -> Any:
        t = tomlkit.table()
        for k, v in values.items():
            t.add(k, table(v) if isinstance(v, Mapping) else v)
            if k in notes and not isinstance(v, Mapping):
                t[k].comment(notes[k])
        return t

    doc = tomlkit.document()
    for line in header.splitlines():
        doc.add(tomlkit.comment(line))
    for k, v in data.items():
        doc.add(k, table(v) if isinstance(v, Mapping) else v)
    return tomlkit.dumps(doc)


def dumps_yaml(data: Mapping[str, Any]) -> str:
    """YAML text (written by PyYAML, keys in the given order) of tables, lists, strings and
    numbers; a non-finite number is refused."""
    import yaml

    _check_toml_values(data, "")
    return yaml.safe_dump(dict(data), sort_keys=False, default_flow_style=None)


def write_json(path: str | Path, data: Mapping[str, Any]) -> None:
    """Write a JSON document with unit-suffixed keys; refuses non-finite numbers."""
    text = json.dumps(data, indent=2, default=_plain)
    plain = json.loads(text)
    _check_finite(plain, "$")
    try:
        Path(path).write_text(json.dumps(_no_negative_zero(plain), indent=2) + "\n", encoding="utf-8")
    except OSError as exc:
        raise PkmdynError(f"cannot write {path} ({_os_reason(exc)})") from None
