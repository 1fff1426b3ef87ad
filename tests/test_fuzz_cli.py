"""Fuzzing the command line: every command and option fed generated hostile input.

The contract of every command: either exit status 2 with exactly one line on stderr (no
traceback) and ``--out`` exactly as it was (missing, or the earlier run's files unchanged),
or exit status 0 with finite output in which no file of an earlier run survives. In both
cases no temporary ``.partial``/``.old`` folder is left beside ``--out``.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import tempfile
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
from hypothesis import event, given
from hypothesis.control import currently_in_test_context
from hypothesis import strategies as st

from pkmdyn.cli import cli, main
from pkmdyn.io import RUN_MARKER
from test_fuzz_readers import FUZZ, HIP_BASE, PDM_BASE, hostile_csv, hostile_value, mutated, plausible_motion_csv, to_toml

from pkmdyn.profiles.orientation import MOTION_COLUMNS


def _run(args: list[str]) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        rc = main(args)
    return rc, err.getvalue()


def _snapshot(path: Path) -> dict[str, bytes] | bytes | None:
    if not path.exists():
        return None
    if path.is_file():
        return path.read_bytes()
    return {p.name: p.read_bytes() for p in sorted(path.iterdir())}


def _earlier_run(folder: Path) -> None:
    """An earlier run's folder: the marker and a stale plot that must not survive a rerun."""
    folder.mkdir()
    (folder / RUN_MARKER).write_text("earlier\n")
    (folder / "stale_plot.png").write_bytes(b"old")


def _finite_table(path: Path) -> None:
    if path.suffix == ".parquet":
        table = pq.read_table(path)
        data = np.column_stack([table.column(i).to_numpy() for i in range(table.num_columns)])
    else:
        text = path.read_text()
        assert "nan" not in text.lower() and "inf" not in text.lower()
        assert not any(cell.strip() == "-0" for line in text.splitlines()[1:] for cell in line.split(","))
        data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    assert data.size and np.all(np.isfinite(data))


def _finite_json(path: Path) -> None:
    def walk(x):
        if isinstance(x, float):
            assert math.isfinite(x)
        elif isinstance(x, dict):
            for v in x.values():
                walk(v)
        elif isinstance(x, list):
            for v in x:
                walk(v)

    walk(json.loads(path.read_text()))


def check_contract(args: list[str], out: Path) -> int:
    """Run ``args`` (which write to ``out``) and assert the contract; returns the exit status."""
    before = _snapshot(out)
    rc, err = _run(args)
    if currently_in_test_context():
        event(f"exit status {rc}")  # shown by --hypothesis-show-statistics
    assert "Traceback" not in err
    if rc != 0:
        lines = err.strip().splitlines()
        assert rc == 2, err
        assert len(lines) == 1 and lines[0].startswith("pkmdyn: error: "), err
        assert _snapshot(out) == before
    else:
        if out.is_dir():
            assert not (out / "stale_plot.png").exists()
            for f in out.iterdir():
                if f.suffix in (".csv", ".parquet"):
                    _finite_table(f)
                elif f.suffix == ".json":
                    _finite_json(f)
        else:
            _finite_table(out)
    if out.parent.is_dir():
        leftovers = [p.name for p in out.parent.iterdir() if ".partial-" in p.name or ".old-" in p.name]
        assert not leftovers
    return rc


def _scratch():
    tmp = tempfile.TemporaryDirectory()
    return tmp, Path(tmp.name)


numbers_as_text = st.one_of(
    st.sampled_from(["1", "0.5", "2", "2.5", "20", "50", "0.001", "0.01"]),
    st.sampled_from(["inf", "-inf", "nan", "1e9", "1e400", "0", "-0", "0.0001", "-1", "1e-300", "abc", "", " 2",
                     "0x10", "1_0", "2"]),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(-(10**25), 10**25).map(str),
)


@FUZZ
@given(
    cycles=st.none() | numbers_as_text,
    spc=st.none() | numbers_as_text,
    thr=st.none() | numbers_as_text,
    fmt=st.none() | st.sampled_from(["csv", "parquet", "xlsx", ""]),
    limit=st.none() | st.tuples(st.sampled_from(["max_samples", "max_load_N", "max_slider_speed_m_s", "bogus", ""]),
                                numbers_as_text).map("=".join),
    earlier=st.booleans(),
)
def test_hip_run_options(cycles, spc, thr, fmt, limit, earlier):
    tmp, root = _scratch()
    with tmp:
        out = root / "out"
        if earlier:
            _earlier_run(out)
        args = ["hip", "run", "--no-plots", "--out", str(out)]
        for opt, v in (("--cycles", cycles), ("--samples-per-cycle", spc), ("--singularity-threshold", thr),
                       ("--format", fmt), ("--limit", limit)):
            if v is not None:
                args += [opt, v]
        if cycles is None and spc is None:
            args += ["--samples-per-cycle", "20"]  # keep successful runs small
        try:
            n = float(cycles or 1) * float(spc or 1000)
        except ValueError:
            n = 0.0
        if not n <= 50_000:  # a valid but large request: make the sample limit refuse it
            args += ["--limit", "max_samples=50000"]
        check_contract(args, out)


@FUZZ
@given(d=mutated(HIP_BASE), earlier=st.booleans())
def test_hip_run_hostile_parameters(d, earlier):
    tmp, root = _scratch()
    with tmp:
        params = root / "p.toml"
        params.write_bytes(to_toml(d).encode("utf-8", "surrogatepass"))
        out = root / "out"
        if earlier:
            _earlier_run(out)
        check_contract(["hip", "run", "--params", str(params), "--samples-per-cycle", "20", "--no-plots",
                        "--out", str(out)], out)


@FUZZ
@given(data=st.one_of(hostile_csv(MOTION_COLUMNS), plausible_motion_csv(), plausible_motion_csv(), st.binary(max_size=200)),
       fmt=st.sampled_from(["csv", "parquet"]))
def test_hip_run_hostile_motion(data, fmt):
    tmp, root = _scratch()
    with tmp:
        motion = root / "m.csv"
        motion.write_bytes(data)
        out = root / "out"
        check_contract(["hip", "run", "--motion", str(motion), "--format", fmt, "--no-plots", "--out", str(out)], out)


@FUZZ
@given(
    cycles=st.none() | numbers_as_text,
    spc=st.none() | numbers_as_text,
    limit=st.none() | st.tuples(st.sampled_from(["max_samples", "max_load_N", "x"]), numbers_as_text).map("=".join),
    where=st.sampled_from(["plain", "missing_parent", "folder_in_the_way", "file_as_parent", "existing_file"]),
)
def test_hip_profile_options_and_paths(cycles, spc, limit, where):
    tmp, root = _scratch()
    with tmp:
        out = {"plain": root / "m.csv", "missing_parent": root / "a" / "b" / "m.csv",
               "folder_in_the_way": root / "d", "file_as_parent": root / "f" / "m.csv",
               "existing_file": root / "old.csv"}[where]
        if where == "folder_in_the_way":
            out.mkdir()
        if where == "file_as_parent":
            (root / "f").write_text("x")
        if where == "existing_file":
            out.write_text("t_s\n0\n")
        args = ["hip", "profile", "--out", str(out)]
        for opt, v in (("--cycles", cycles), ("--samples-per-cycle", spc), ("--limit", limit)):
            if v is not None:
                args += [opt, v]
        if spc is None:
            args += ["--samples-per-cycle", "10"]
        args += ["--limit", "max_samples=20000"] if limit is None or not limit.startswith("max_samples") else []
        before = sorted(p.relative_to(root) for p in root.rglob("*"))
        rc = check_contract(args, out)
        if rc != 0:
            assert sorted(p.relative_to(root) for p in root.rglob("*")) == before  # no parent folder left behind


PDM_SMALL = {**PDM_BASE, "trajectory": {**PDM_BASE["trajectory"], "samples": 11},
             "workspace": {**PDM_BASE["workspace"], "gamma_layers": 1, "directions": 8, "radial_step_m": 0.05}}


@FUZZ
@given(d=mutated(PDM_SMALL), earlier=st.booleans())
def test_pdm_run_hostile_parameters(d, earlier):
    tmp, root = _scratch()
    with tmp:
        params = root / "p.toml"
        params.write_bytes(to_toml(d).encode("utf-8", "surrogatepass"))
        out = root / "out"
        if earlier:
            _earlier_run(out)
        check_contract(["pdm", "run", "--params", str(params), "--no-plots", "--out", str(out)], out)


def test_pdm_rerun_leaves_no_file_of_the_earlier_run(tmp_path):
    params = tmp_path / "p.toml"
    params.write_text(to_toml(PDM_SMALL))
    out = tmp_path / "out"
    _earlier_run(out)
    assert check_contract(["pdm", "run", "--params", str(params), "--no-plots", "--out", str(out)], out) == 0


@FUZZ
@given(
    cmd=st.sampled_from(sorted(
        [name, sub] for name, group in cli.commands.items() for sub in getattr(group, "commands", {})
    )),
    opt=st.text(alphabet="-abcdefghijklmnopqrstuvwxyz", min_size=1, max_size=12),
    value=st.one_of(numbers_as_text, hostile_value.map(str)),
)
def test_every_command_refuses_unknown_and_hostile_options(cmd, opt, value):
    """Every registered command (those of other modules included): an unknown option, or an
    option given a hostile value, is one line and status 2 (or a success with finite files)."""
    tmp, root = _scratch()
    with tmp:
        out = root / "out"
        command = cli.commands[cmd[0]].commands[cmd[1]]
        names = [o for p in command.params for o in p.opts if o.startswith("--") and o != "--out"]
        option = names[len(opt) % len(names)] if names and opt.startswith("-") else f"--{opt.strip('-') or 'x'}x"
        flag = any(option in p.opts and getattr(p, "is_flag", False) for p in command.params)
        args = [*cmd, option] + ([] if flag else [value]) + ["--out", str(out)]
        rc, err = _run(args)
        assert "Traceback" not in err
        if rc != 0:
            assert rc == 2 and len(err.strip().splitlines()) == 1, err
            assert not out.exists()


def test_rerun_into_an_earlier_run_leaves_none_of_its_files(tmp_path):
    out = tmp_path / "o"
    assert _run(["hip", "run", "--samples-per-cycle", "20", "--out", str(out)])[0] == 0
    assert (out / "torques.png").exists()
    rc, err = _run(["hip", "run", "--no-plots", "--samples-per-cycle", "20", "--format", "parquet", "--out", str(out)])
    assert rc == 0 and "replaced an earlier run" in err
    wear = ["wear.json", "tracks.npz"] + [f"markers_S0_{p}_on_{s}.csv" for p in ("upper", "lower") for s in ("cup", "head")]
    assert sorted(p.name for p in out.iterdir()) == sorted([RUN_MARKER, "report.html", "results.parquet", "summary.json",
                                                            *wear])


def test_foreign_folder_is_refused_and_untouched(tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "thesis.tex").write_text("precious")
    check_contract(["hip", "run", "--no-plots", "--samples-per-cycle", "20", "--out", str(out)], out)
    assert (out / "thesis.tex").read_text() == "precious" and len(list(out.iterdir())) == 1


@pytest.mark.parametrize("cmd", [["hip", "run", "--no-plots", "--samples-per-cycle", "20"], ["pdm", "run", "--no-plots"]])
def test_both_runs_refuse_a_file_in_the_way(tmp_path, cmd):
    out = tmp_path / "o"
    out.write_text("x")
    rc = check_contract([*cmd, "--out", str(out)], out)
    assert rc == 2 and out.read_text() == "x"


def _edit_text(text: str, table: str, key: str, value: str) -> str:
    """``text`` (a TOML description) with ``key`` of ``[table]`` set to the raw TOML ``value``."""
    out, current, done = [], None, False
    for line in text.splitlines():
        s = line.strip()
        if s.startswith("[") and s.endswith("]") or (s.startswith("[") and "]" in s and "=" not in s):
            current = s[1:s.index("]")]
        if current == table and s.split("=")[0].strip() == key:
            line, done = f"{key} = {value}", True
        out.append(line)
    assert done, (table, key)
    return "\n".join(out) + "\n"


ISSUE_SAMPLE = [  # the issue's sample of hostile parameter values, and neighbours
    ("hip", "geometry", "lever_length_m", "inf", "finite"),
    ("hip", "inertia", "slider_mass_kg", "1e308", "<= 10000"),
    ("hip", "geometry", "screw_lead_m", "1e-300", ">= 0.0001"),
    ("hip", "friction", "friction_velocity_eps_rad_s", "5e-324", ">= 1e-09"),
    ("hip", "geometry", "module_angles_deg", "[nan, 0.0, 1.0]", "finite"),
    ("pdm", "geometry", "crank_pivot_y_m", "nan", "finite"),
    ("pdm", "workspace", "alpha_deg", "nan", "finite"),
    ("pdm", "trajectory", "samples", "1000000000", "max_samples"),
    ("pdm", "workspace", "directions", "100000000", "<= 3600"),
    ("pdm", "workspace", "max_radius_m", "1e6", "<= 10"),
    ("pdm", "workspace", "radial_step_m", "1e-6", "max_workspace_points"),
    ("pdm", "workspace", "gamma_layers", "100000", "<= 361"),
]


@pytest.mark.parametrize("machine, table, key, value, word", ISSUE_SAMPLE)
def test_issue_sample_of_hostile_parameters(tmp_path, machine, table, key, value, word):
    from pkmdyn.machines.hip_simulator.params import DEFAULT_PARAMS_TEXT
    from pkmdyn.machines.pdm4.params import default_params_path

    base = DEFAULT_PARAMS_TEXT if machine == "hip" else default_params_path().read_text()
    p = tmp_path / "p.toml"
    p.write_text(_edit_text(base, table, key, value))
    out = tmp_path / "out"
    rc, err = _run([machine, "run", "--params", str(p), "--no-plots", "--out", str(out)])
    assert rc == 2 and len(err.strip().splitlines()) == 1 and word in err and key in err, err
    assert sorted(x.name for x in tmp_path.iterdir()) == ["p.toml"]


@pytest.mark.parametrize("data", [b"\xff\xfe[\x00g\x00", "[geometry]\nlever_length_m = 0.3 # \xe9\n".encode("latin-1"),
                                  b"[geometry]\x00\n", b"a = " + b"[" * 5000 + b"]" * 5000])
@pytest.mark.parametrize("machine", ["hip", "pdm"])
def test_undecodable_parameter_files_are_one_line(tmp_path, data, machine):
    p = tmp_path / "p.toml"
    p.write_bytes(data)
    rc, err = _run([machine, "run", "--params", str(p), "--no-plots", "--out", str(tmp_path / "o")])
    assert rc == 2 and len(err.strip().splitlines()) == 1 and "p.toml" in err, err
    assert not (tmp_path / "o").exists()
