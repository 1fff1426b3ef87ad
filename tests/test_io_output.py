"""Output folders and files written whole, streaming table writers, CSV reading in blocks."""

from __future__ import annotations

import json
import os

import numpy as np
import pyarrow.parquet as pq
import pytest

from pkmdyn import io as pio
from pkmdyn.errors import PkmdynError
from pkmdyn.io import RUN_MARKER, atomic_file, open_table_writer, output_dir, read_csv_columns, write_json


def _leftovers(folder):
    return [p.name for p in folder.iterdir() if ".partial-" in p.name or ".old-" in p.name]


def test_output_dir_moves_into_place_and_marks_the_run(tmp_path):
    out = tmp_path / "o"
    with output_dir(out, notify=None) as tmp:
        assert tmp.parent == tmp_path and not out.exists()
        (tmp / "a.csv").write_text("x")
    assert sorted(p.name for p in out.iterdir()) == [RUN_MARKER, "a.csv"]
    assert not _leftovers(tmp_path)


def test_earlier_run_is_replaced_whole_and_said_so(tmp_path):
    out = tmp_path / "o"
    with output_dir(out, notify=None) as tmp:
        (tmp / "old_plot.png").write_text("old")
    notes = []
    with output_dir(out, notify=notes.append) as tmp:
        (tmp / "new.csv").write_text("new")
    assert sorted(p.name for p in out.iterdir()) == [RUN_MARKER, "new.csv"]
    assert len(notes) == 1 and "replaced an earlier run" in notes[0]
    assert not _leftovers(tmp_path)


@pytest.mark.parametrize("exc", [RuntimeError("boom"), KeyboardInterrupt(), PkmdynError("bad")])
@pytest.mark.parametrize("earlier", [False, True])
def test_failure_or_interrupt_leaves_out_as_it_was(tmp_path, exc, earlier):
    out = tmp_path / "o"
    if earlier:
        with output_dir(out, notify=None) as tmp:
            (tmp / "kept.csv").write_text("earlier")
    before = sorted(p.name for p in out.iterdir()) if earlier else None
    with pytest.raises(type(exc)):
        with output_dir(out, notify=None) as tmp:
            (tmp / "partial.csv").write_text("half")
            raise exc
    if earlier:
        assert sorted(p.name for p in out.iterdir()) == before and (out / "kept.csv").read_text() == "earlier"
    else:
        assert not out.exists()
    assert not _leftovers(tmp_path)


def test_foreign_folder_and_file_in_the_way_are_refused_before_writing(tmp_path):
    foreign = tmp_path / "f"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("mine")
    with pytest.raises(PkmdynError, match="holds no earlier pkmdyn run"):
        with output_dir(foreign, notify=None):
            raise AssertionError("not reached")
    (tmp_path / "file").write_text("x")
    with pytest.raises(PkmdynError, match="is a file"):
        with output_dir(tmp_path / "file", notify=None):
            raise AssertionError("not reached")
    with pytest.raises(PkmdynError, match="is a file, not a folder"):
        with output_dir(tmp_path / "file" / "sub", notify=None):
            raise AssertionError("not reached")
    assert (foreign / "notes.txt").read_text() == "mine" and not _leftovers(tmp_path)


def test_missing_parents_are_created_and_removed_again_on_failure(tmp_path):
    out = tmp_path / "a" / "b" / "o"
    with pytest.raises(RuntimeError):
        with output_dir(out, notify=None):
            assert (tmp_path / "a" / "b").is_dir()
            raise RuntimeError
    assert not (tmp_path / "a").exists()
    with output_dir(out, notify=None) as tmp:
        (tmp / "x").write_text("1")
    assert (out / "x").exists()


def test_an_earlier_run_appearing_meanwhile_is_not_overwritten_by_a_foreign_folder(tmp_path):
    out = tmp_path / "o"
    with pytest.raises(PkmdynError, match="holds no earlier pkmdyn run"):
        with output_dir(out, notify=None) as tmp:
            out.mkdir()
            (out / "someone_else.txt").write_text("x")
            (tmp / "r.csv").write_text("1")
    assert sorted(p.name for p in out.iterdir()) == ["someone_else.txt"] and not _leftovers(tmp_path)


@pytest.mark.skipif(os.geteuid() == 0, reason="permissions do not bind root")
def test_unwritable_parent_is_one_error(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        with pytest.raises(PkmdynError, match="cannot"):
            with output_dir(ro / "o", notify=None):
                pass
    finally:
        ro.chmod(0o700)


def test_atomic_file_replaces_only_on_success(tmp_path):
    target = tmp_path / "m.csv"
    with atomic_file(target, notify=None) as tmp:
        tmp.write_text("old")
    with pytest.raises(KeyboardInterrupt):
        with atomic_file(target, notify=None) as tmp:
            tmp.write_text("half")
            raise KeyboardInterrupt
    assert target.read_text() == "old" and len(list(tmp_path.iterdir())) == 1
    with atomic_file(target, notify=None) as tmp:
        tmp.write_text("new")
    assert target.read_text() == "new" and len(list(tmp_path.iterdir())) == 1
    (tmp_path / "d").mkdir()
    with pytest.raises(PkmdynError, match="is a folder"):
        with atomic_file(tmp_path / "d", notify=None):
            pass
    notes = []
    with atomic_file(tmp_path / "new" / "deeper" / "m.csv", notify=notes.append) as tmp:
        tmp.write_text("x")
    assert (tmp_path / "new" / "deeper" / "m.csv").read_text() == "x" and "created folder" in notes[0]


def _table(rng, n):
    cols = {"t_s": np.arange(n, dtype=float), "x_m": rng.standard_normal(n) * 10.0 ** rng.integers(-30, 30, n)}
    cols["x_m"][::7] = -0.0
    return cols


@pytest.mark.parametrize("arrow", [True, False])
def test_streamed_csv_reads_back_exactly_without_negative_zero(tmp_path, arrow):
    rng = np.random.default_rng(3)
    blocks = [_table(rng, k) for k in (5, 1, 17)]
    path = tmp_path / "r.csv"
    with open_table_writer(path, "csv") as w:
        if not arrow:
            w._arrow_csv = None
        for b in blocks:
            w.write(b)
    text = path.read_text()
    assert text.splitlines()[0] == "t_s,x_m"
    assert not any(c in ("-0", "-0.0") for line in text.splitlines()[1:] for c in line.split(","))
    back = read_csv_columns(path, ("t_s", "x_m"))
    np.testing.assert_array_equal(back["x_m"], np.concatenate([b["x_m"] for b in blocks]))


def test_parquet_holds_the_same_numbers(tmp_path):
    rng = np.random.default_rng(4)
    blocks = [_table(rng, k) for k in (3, 9)]
    with open_table_writer(tmp_path / "r.parquet", "parquet") as w:
        for b in blocks:
            w.write(b)
    t = pq.read_table(tmp_path / "r.parquet")
    assert t.column_names == ["t_s", "x_m"]
    np.testing.assert_array_equal(t.column("x_m").to_numpy(), np.concatenate([b["x_m"] for b in blocks]))


def test_writer_refuses_non_finite_naming_column_and_row(tmp_path):
    with pytest.raises(PkmdynError, match=r"column 'x_m' row 5 is nan"):
        with open_table_writer(tmp_path / "r.csv", "csv") as w:
            w.write({"x_m": np.zeros(3)})
            w.write({"x_m": np.array([0.0, np.nan])})


def test_csv_read_in_blocks_matches_whole(tmp_path, monkeypatch):
    rng = np.random.default_rng(5)
    x = rng.standard_normal(23)
    p = tmp_path / "m.csv"
    p.write_text("t_s,x_m\n" + "".join(f"{k},{float(v)!r}\n" for k, v in enumerate(x)))
    monkeypatch.setattr(pio, "_BLOCK", 4)
    np.testing.assert_array_equal(read_csv_columns(p, ("t_s", "x_m"))["x_m"], x)


def test_json_has_no_negative_zero_and_refuses_nan(tmp_path):
    write_json(tmp_path / "a.json", {"v_m": -0.0, "w": [np.float64(-0.0)]})
    assert "-0" not in (tmp_path / "a.json").read_text()
    assert json.loads((tmp_path / "a.json").read_text()) == {"v_m": 0.0, "w": [0.0]}
    with pytest.raises(PkmdynError, match="non-finite"):
        write_json(tmp_path / "b.json", {"v": float("nan")})


def test_refused_folder_creation_is_one_error_and_leaves_nothing(tmp_path, monkeypatch):
    """A parent that refuses new folders (as without write permission) is one PkmdynError."""
    import tempfile

    def refuse(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(tempfile, "mkdtemp", refuse)
    with pytest.raises(PkmdynError, match="Permission denied"):
        with output_dir(tmp_path / "a" / "o", notify=None):
            pass
    assert not (tmp_path / "a").exists()


def test_a_large_results_table_is_announced():
    """Above 500 MB a run says how large its table will be (rows, columns, size, the format), before
    it starts; below, nothing."""
    from pkmdyn.io import note_table_size

    said = []
    note_table_size(800_000, 40, "csv", said.append)
    assert len(said) == 1 and "800,000 rows of 40 columns" in said[0] and "0.6 GB as csv" in said[0]
    assert "parquet" in said[0]
    note_table_size(800_000, 40, "parquet", said.append)
    assert len(said) == 1  # 0.26 GB: nothing said
    note_table_size(10_000, 40, "csv", said.append)
    assert len(said) == 1


def _png(path):
    """A one-pixel PNG written by matplotlib (a figure the report embeds)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(0.1, 0.1))
    fig.savefig(path)
    plt.close(fig)


def test_the_one_writer_adds_the_summary_and_the_report(tmp_path):
    """write_output: the job's files, then summary.json (the summary and every file's name,
    itself and the report included) and report.html (its images the output's PNG files named by
    label, the summary shown), announced at their final paths before the folder moves."""
    from pkmdyn.report import Output, Report, write_output

    out = tmp_path / "o"
    seen = {}

    def make(folder):
        (folder / "a.csv").write_text("x_m\n1\n")
        _png(folder / "fig.png")
        return Output({"table": folder / "a.csv", "figure": folder / "fig.png"}, {"samples": 1},
                      Report("a title", images=["figure"], notes=["a note"]))

    def announce(placed):
        seen.update(placed)
        assert not out.exists()  # before the move

    files, output = write_output(out, {}, make, announce)
    assert list(files) == ["table", "figure", "summary", "report"]
    assert files == seen and all(p.parent == out and p.exists() for p in files.values())
    doc = json.loads((out / "summary.json").read_text())
    assert doc == output.summary == {"samples": 1, "files": ["a.csv", "fig.png", "report.html", "summary.json"]}
    assert sorted(p.name for p in out.iterdir()) == sorted([RUN_MARKER, *doc["files"]])
    page = (out / "report.html").read_text()
    assert "a title" in page and "a note" in page and "data:image/png;base64," in page and "fig.png" in page
    assert not _leftovers(tmp_path)


def test_the_one_writer_without_summary_or_report_writes_the_files_alone(tmp_path):
    from pkmdyn.report import Output, write_output

    def make(folder):
        (folder / "t.csv").write_text("a\n")
        return Output({"t": folder / "t.csv"})

    files, output = write_output(tmp_path / "o", {}, make)
    assert list(files) == ["t"] and output.summary is None and output.report is None
    assert sorted(p.name for p in (tmp_path / "o").iterdir()) == [RUN_MARKER, "t.csv"]


@pytest.mark.parametrize("where", ["make", "report"])
def test_a_failing_job_or_report_leaves_nothing(tmp_path, where):
    """A failure while the job writes, or while the report is rendered (an image label the
    output lacks), leaves no folder and nothing beside it."""
    from pkmdyn.report import Output, Report, write_output

    def make(folder):
        (folder / "a.csv").write_text("x")
        if where == "make":
            raise PkmdynError("bad")
        return Output({"a": folder / "a.csv"}, {"n": 1}, Report("t", images=["missing"]))

    with pytest.raises((PkmdynError, KeyError)):
        write_output(tmp_path / "o", {}, make)
    assert not (tmp_path / "o").exists() and not _leftovers(tmp_path)
