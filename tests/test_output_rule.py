"""The output rule (``docs/file_formats.md``): an output never replaces a link, a device, a pipe,
a socket, an input of the same run, a write-protected file or folder, or anything pkmdyn did not
write; a refused run changes nothing; a replaced earlier run is gone whole and said so."""

from __future__ import annotations

import errno
import io as _io
import os
import socket
import stat
import sys

import pytest

from pkmdyn.cli import main
from pkmdyn.errors import PkmdynError
from pkmdyn.io import RUN_MARKER, atomic_file, check_output_dir, check_output_file, output_dir

from test_fuzz_new_commands import EXCITE_FAST, _measured_text


def _tree(root):
    """Every entry under ``root`` with its mode, size, modification time and content."""
    found = {}
    for dirpath, dirnames, filenames in os.walk(root):
        for name in dirnames + filenames:
            p = os.path.join(dirpath, name)
            st = os.lstat(p)
            body = open(p, "rb").read() if stat.S_ISREG(st.st_mode) else None
            found[os.path.relpath(p, root)] = (st.st_mode, st.st_size, st.st_mtime_ns, body)
    return found


def _one_error(capsys, *words):
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("pkmdyn: error: "), err
    for w in words:
        assert w in err, err
    return err


def _run_into(out, name="a.csv", text="1"):
    with output_dir(out, notify=None) as tmp:
        (tmp / name).write_text(text)


# ----------------------------------------------------------------------------- the library
def test_links_pipes_sockets_and_devices_are_refused_as_file_and_folder(tmp_path):
    (tmp_path / "real").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "real")
    (tmp_path / "flink").symlink_to(tmp_path / "nowhere")
    os.mkfifo(tmp_path / "fifo")
    sock = socket.socket(socket.AF_UNIX)
    sock.bind(str(tmp_path / "sock"))
    try:
        for name, kind in (("link", "symbolic link"), ("flink", "symbolic link"), ("fifo", "named pipe"),
                           ("sock", "socket")):
            with pytest.raises(PkmdynError, match=kind):
                check_output_file(tmp_path / name)
            with pytest.raises(PkmdynError, match=kind):
                check_output_dir(tmp_path / name)
    finally:
        sock.close()
    with pytest.raises(PkmdynError, match="character device"):
        check_output_file("/dev/null")
    with pytest.raises(PkmdynError, match="character device"):
        check_output_dir("/dev/null")
    assert (tmp_path / "link").is_symlink() and stat.S_ISFIFO(os.lstat(tmp_path / "fifo").st_mode)


def test_a_file_pkmdyn_did_not_write_or_that_was_changed_is_not_replaced(tmp_path):
    mine = tmp_path / "mine.csv"
    mine.write_text("t_s\n0\n")
    with pytest.raises(PkmdynError, match="not written by pkmdyn"):
        with atomic_file(mine, notify=None):
            raise AssertionError("not reached")
    assert mine.read_text() == "t_s\n0\n"
    ours = tmp_path / "ours.csv"
    with atomic_file(ours, notify=None) as tmp:
        tmp.write_text("first")
    notes = []
    with atomic_file(ours, notify=notes.append) as tmp:
        tmp.write_text("second")
    assert ours.read_text() == "second" and "replaced" in notes[0]
    with ours.open("a") as fh:
        fh.write(" edited by hand")
    with pytest.raises(PkmdynError, match="changed after pkmdyn wrote it"):
        check_output_file(ours)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine.csv", "ours.csv"]


def test_write_protected_files_and_folders_are_refused_even_for_root(tmp_path):
    f = tmp_path / "f.csv"
    with atomic_file(f, notify=None) as tmp:
        tmp.write_text("x")
    f.chmod(0o444)
    with pytest.raises(PkmdynError, match="write-protected"):
        check_output_file(f)
    run = tmp_path / "run"
    _run_into(run)
    before = _tree(tmp_path)
    for p in (run / "a.csv", run / RUN_MARKER, run):  # chmod -R a-w
        p.chmod(p.stat().st_mode & ~0o222)
    try:
        before = _tree(tmp_path)
        with pytest.raises(PkmdynError, match="write-protected"):
            _run_into(run, "b.csv")
        assert _tree(tmp_path) == before
    finally:
        run.chmod(0o755)
    (run / "a.csv").chmod(0o444)  # one file inside is enough
    with pytest.raises(PkmdynError, match="write-protected"):
        check_output_dir(run)
    empty = tmp_path / "empty"
    empty.mkdir(mode=0o555)
    with pytest.raises(PkmdynError, match="write-protected"):
        _run_into(empty)
    assert stat.S_IMODE(empty.stat().st_mode) == 0o555 and not any(empty.iterdir())
    ro = tmp_path / "ro"
    ro.mkdir(mode=0o555)
    with pytest.raises(PkmdynError, match="write-protected"):
        _run_into(ro / "new")
    with pytest.raises(PkmdynError, match="write-protected"):
        with atomic_file(ro / "deeper" / "m.csv", notify=None):
            raise AssertionError("not reached")
    assert not any(ro.iterdir())


def test_inputs_inside_the_folder_are_never_replaced(tmp_path):
    run = tmp_path / "res"
    _run_into(run, "motion.csv", "input")
    with pytest.raises(PkmdynError, match="input of this run"):
        with output_dir(run, notify=None, inputs={"--motion": run / "motion.csv"}):
            raise AssertionError("not reached")
    elsewhere = tmp_path / "elsewhere.csv"
    os.link(run / "motion.csv", elsewhere)  # the same file under another name: same inode
    with pytest.raises(PkmdynError, match="--motion"):
        check_output_dir(run, {"--motion": elsewhere})
    with pytest.raises(PkmdynError, match="--params"):
        check_output_file(elsewhere, {"--params": run / "motion.csv"})
    assert (run / "motion.csv").read_text() == "input"


def test_files_the_earlier_run_did_not_write_or_that_changed_keep_the_folder(tmp_path):
    run = tmp_path / "res"
    _run_into(run)
    (run / "notes.txt").write_text("mine")
    with pytest.raises(PkmdynError, match="not written by the earlier run"):
        check_output_dir(run)
    (run / "notes.txt").unlink()
    with (run / "a.csv").open("a") as fh:
        fh.write("2")
    with pytest.raises(PkmdynError, match="changed after the earlier run wrote it"):
        check_output_dir(run)
    os.mkfifo(run / "pipe")
    with pytest.raises(PkmdynError, match="named pipe"):
        check_output_dir(run)


def test_a_replaced_run_is_gone_whole_and_the_note_says_what_was_removed(tmp_path):
    run = tmp_path / "res"
    with output_dir(run, notify=None) as tmp:
        (tmp / "a.csv").write_text("1")
        (tmp / "sub").mkdir()
        (tmp / "sub" / "b.csv").write_text("2")
    notes = []
    with output_dir(run, notify=notes.append) as tmp:
        (tmp / "c.csv").write_text("3")
    assert sorted(os.listdir(tmp_path)) == ["res"]  # no hidden .res.old-* left
    assert sorted(os.listdir(run)) == [RUN_MARKER, "c.csv"]
    assert notes == [f"replaced an earlier run in {run}: its 2 file(s) removed"]


class _FullDevice(_io.StringIO):
    def write(self, s):
        raise OSError(errno.ENOSPC, "No space left on device")

    def flush(self):
        raise OSError(errno.ENOSPC, "No space left on device")


def test_a_run_whose_stdout_cannot_be_written_changes_nothing(tmp_path, monkeypatch, capsys):
    run = tmp_path / "res"
    assert main(["hip", "run", "--no-plots", "--samples-per-cycle", "20", "--out", str(run)]) == 0
    capsys.readouterr()
    before = _tree(tmp_path)
    monkeypatch.setattr(sys, "stdout", _FullDevice())
    assert main(["hip", "run", "--no-plots", "--samples-per-cycle", "30", "--out", str(run)]) == 2
    monkeypatch.undo()
    _one_error(capsys, "standard output")
    assert _tree(tmp_path) == before
    monkeypatch.setattr(sys, "stdout", _FullDevice())
    assert main(["hip", "profile", "--samples-per-cycle", "20", "--out", str(tmp_path / "m.csv")]) == 2
    monkeypatch.undo()
    _one_error(capsys, "standard output")
    assert _tree(tmp_path) == before


# ----------------------------------------------------------------------------- every command
def test_hip_run_refuses_a_motion_inside_its_out_folder(tmp_path, capsys):
    res = tmp_path / "res"
    assert main(["hip", "profile", "--samples-per-cycle", "20", "--out", str(tmp_path / "m.csv")]) == 0
    assert main(["hip", "run", "--no-plots", "--motion", str(tmp_path / "m.csv"), "--out", str(res)]) == 0
    os.replace(tmp_path / "m.csv", res / "motion.csv")
    capsys.readouterr()
    before = _tree(tmp_path)
    assert main(["hip", "run", "--no-plots", "--motion", str(res / "motion.csv"), "--out", str(res)]) == 2
    _one_error(capsys, "--motion", "input of this run")
    assert _tree(tmp_path) == before


def test_hip_identify_refuses_a_measurement_inside_its_out_folder(tmp_path, capsys):
    out = tmp_path / "id"
    with output_dir(out, notify=None) as tmp:
        (tmp / "m.csv").write_text(_measured_text())
    before = _tree(tmp_path)
    assert main(["hip", "identify", "--no-plots", "--measured", str(out / "m.csv"), "--out", str(out)]) == 2
    _one_error(capsys, "--measured")
    assert _tree(tmp_path) == before


@pytest.mark.parametrize("command", [["hip", "export", "--format", "mjcf"], EXCITE_FAST, ["view", "--machine", "hip"]])
def test_single_file_commands_refuse_their_own_parameter_file(tmp_path, capsys, command):
    params = tmp_path / "p.toml"
    from pkmdyn.machines.hip_simulator.params import DEFAULT_PARAMS_TEXT

    params.write_text(DEFAULT_PARAMS_TEXT, encoding="utf-8")
    before = _tree(tmp_path)
    assert main([*command, "--params", str(params), "--out", str(params)]) == 2
    _one_error(capsys, "--params", "input of this run")
    assert _tree(tmp_path) == before


@pytest.mark.parametrize("command", [["hip", "profile", "--samples-per-cycle", "10"],
                                     ["hip", "export", "--format", "mjcf"], EXCITE_FAST, ["view", "--machine", "pdm"]])
def test_single_file_commands_refuse_a_device_a_pipe_and_a_link(tmp_path, capsys, command):
    os.mkfifo(tmp_path / "fifo")
    (tmp_path / "target.csv").write_text("mine")
    (tmp_path / "link.csv").symlink_to(tmp_path / "target.csv")
    before = _tree(tmp_path)
    for out, word in (("/dev/null", "character device"), (tmp_path / "fifo", "named pipe"),
                      (tmp_path / "link.csv", "symbolic link"), (tmp_path / "target.csv", "not written by pkmdyn")):
        assert main([*command, "--out", str(out)]) == 2
        _one_error(capsys, word)
    assert _tree(tmp_path) == before and stat.S_ISCHR(os.stat("/dev/null").st_mode)


_FOLDER_COMMANDS = {
    "hip run": ["hip", "run", "--no-plots", "--samples-per-cycle", "20"],
    "pdm run": ["pdm", "run", "--no-plots"],
    "hip control": ["hip", "control", "--controller", "pd", "--no-plots", "--cycles", "0.02"],
    "pdm control": ["pdm", "control", "--controller", "pid", "--no-plots", "--cycles", "0.02"],
}


@pytest.mark.parametrize("command", sorted(_FOLDER_COMMANDS))
def test_folder_commands_refuse_devices_links_and_write_protected_runs(tmp_path, capsys, command):
    args = _FOLDER_COMMANDS[command]
    run = tmp_path / "run"
    assert main([*args, "--out", str(run)]) == 0
    for p in [*run.iterdir(), run]:  # chmod -R a-w
        p.chmod(p.stat().st_mode & ~0o222)
    (tmp_path / "target").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "target")
    capsys.readouterr()
    before = _tree(tmp_path)
    try:
        for out, word in (("/dev/null", "character device"), (tmp_path / "link", "symbolic link"),
                          (run, "write-protected")):
            assert main([*args, "--out", str(out)]) == 2
            _one_error(capsys, word)
        assert _tree(tmp_path) == before
    finally:
        run.chmod(0o755)


def test_another_commands_results_are_refused_unless_told(tmp_path, capsys):
    """A command replaces its own earlier run in --out; another command's results there are
    refused (one line naming both commands and the option), nothing touched; ``pkmdyn --replace``
    replaces them."""
    out = tmp_path / "design"
    assert main(["run", "--machine", "delta", "--out", str(out)]) == 0
    capsys.readouterr()
    before = _tree(out)
    assert main(["stiffness", "--machine", "delta", "--default-motion", "--out", str(out)]) == 2
    _one_error(capsys, "pkmdyn run", "pkmdyn stiffness", "--replace")
    assert _tree(out) == before
    assert main(["run", "--machine", "delta", "--out", str(out)]) == 0  # its own earlier run: replaced
    assert "replaced an earlier run" in capsys.readouterr().err
    assert main(["--replace", "stiffness", "--machine", "delta", "--default-motion", "--out", str(out)]) == 0
    capsys.readouterr()
    assert (out / "stiffness.json").is_file() and not (out / "bodies.npz").exists()
    assert main(["hip", "run", "--no-plots", "--samples-per-cycle", "20", "--out", str(out)]) == 2
    _one_error(capsys, "pkmdyn stiffness", "pkmdyn hip run")
