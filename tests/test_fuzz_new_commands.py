"""Fuzzing the newer commands: ``hip control``, ``pdm control``, ``hip export``, ``hip identify``
and ``hip excite``, fed generated and hand-picked hostile input.

The contract (as ``test_fuzz_cli``): exit status 2 with exactly one ``pkmdyn: error:`` line on
stderr (no traceback, no warning lines) and ``--out`` exactly as it was, or exit status 0 with
finite output; never a temporary ``.partial``/``.old`` entry left beside ``--out``. The success
cases use small sizes (a fraction of a cycle, a few design samples) to stay fast.
"""

from __future__ import annotations

import functools
import re
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pkmdyn.io import write_csv
from test_fuzz_cli import _earlier_run, _run, _snapshot
from test_fuzz_cli import check_contract as _check_contract
from test_fuzz_readers import HIP_BASE, PDM_BASE, hostile_csv, mutated, plausible_motion_csv, to_toml

FAST = settings(max_examples=60, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])

#: fast, valid option values for each command (overridden one option at a time)
EXCITE_FAST = ["hip", "excite", "--iterations", "0", "--harmonics", "1", "--design-samples", "16", "--cycles", "1",
               "--samples-per-cycle", "16"]
CONTROL_FAST = {"hip": ["hip", "control", "--controller", "pd", "--no-plots"],
                "pdm": ["pdm", "control", "--controller", "pid", "--no-plots"]}

hostile_number = st.sampled_from(["inf", "-inf", "nan", "1e400", "-1e400", "1e300", "-1e300", "1e-300", "0", "-0",
                                  "-1", "abc", "", " ", "0x10", "1e9", "99999999999999999999999"])


def _shown(w: warnings.WarningMessage) -> bool:
    """Whether Python's default filters print this warning on stderr (they hide these)."""
    return not issubclass(w.category, (DeprecationWarning, PendingDeprecationWarning, ImportWarning, ResourceWarning))


def check_contract(args: list[str], out: Path) -> int:
    """``test_fuzz_cli.check_contract``, and no warning emitted (on a terminal it would be a
    stderr line beside the error line, or a stray line of a successful run)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rc = _check_contract(args, out)
    shown = [f"{w.category.__name__}: {w.message}" for w in caught if _shown(w)]
    assert not shown, shown
    return rc


def _set(args: list[str], option: str, value: str | tuple[str, ...]) -> list[str]:
    """``args`` with ``option`` given ``value`` (replacing an earlier value)."""
    out = list(args)
    n = 1 if isinstance(value, str) else len(value)
    if option in out:
        i = out.index(option)
        del out[i:i + 1 + n]
    return out + [option, *([value] if isinstance(value, str) else value)]


def _one_error_line(args: list[str], out: Path) -> str:
    """Run a case that must fail (the contract's failure half); returns its single error line."""
    before = _snapshot(out)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rc, err = _run(args + ["--out", str(out)])
    assert not [w for w in caught if _shown(w)], [str(w.message) for w in caught]
    lines = err.strip().splitlines()
    assert rc == 2 and len(lines) == 1 and lines[0].startswith("pkmdyn: error: "), err
    assert _snapshot(out) == before
    if out.parent.is_dir():
        assert not [p.name for p in out.parent.iterdir() if ".partial" in p.name or ".old-" in p.name]
    return lines[0]


@functools.cache
def _measured_text() -> str:
    """A measured run: a quarter of the ISO 14242-1 cycle with the default machine's torques."""
    from pkmdyn.machines.hip_simulator import load_params
    from pkmdyn.machines.hip_simulator.paper import PaperView
    from pkmdyn.profiles.iso14242 import iso14242_motion

    model = load_params(None)
    motion = iso14242_motion(0.25, 400)
    tau = PaperView(model).solve(motion).tau
    cols = {"t_s": motion.t}
    for k, a in enumerate(("alpha", "beta", "gamma")):
        cols[f"{a}_deg"] = np.rad2deg(motion.angles[:, k])
    cols["load_N"] = motion.load
    for i in range(3):
        cols[f"tau{i + 1}_Nm"] = tau[:, i]
    with tempfile.TemporaryDirectory() as d:
        write_csv(Path(d) / "m.csv", cols)
        return (Path(d) / "m.csv").read_text()


# ----------------------------------------------------------------------------- generated options
@FAST
@given(option=st.sampled_from(["--period-s", "--harmonics", "--cycles", "--samples-per-cycle", "--iterations",
                               "--starts", "--design-samples", "--seed", "--max-slider-speed-m-s",
                               "--max-slider-accel-m-s2", "--max-cond-j", "--alpha-range-deg", "--load-range-N"]),
       value=hostile_number | st.sampled_from(["1", "2", "16", "0.5", "-5"]),
       second=hostile_number | st.sampled_from(["5", "100"]))
def test_excite_hostile_numbers(option, value, second):
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "m.csv"
        v = (value, second) if option.endswith(("range-deg", "range-N")) else value
        check_contract(_set(EXCITE_FAST, option, v) + ["--out", str(out)], out)


@FAST
@given(machine=st.sampled_from(["hip", "pdm"]), cycles=hostile_number | st.sampled_from(["0.01", "0.02"]),
       out_kind=st.sampled_from(["missing", "earlier", "foreign", "file"]))
def test_control_hostile_cycles_and_out(machine, cycles, out_kind):
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "out"
        if out_kind == "earlier":
            _earlier_run(out)
        elif out_kind == "foreign":
            out.mkdir()
            (out / "notes.txt").write_text("mine\n")
        elif out_kind == "file":
            out.write_text("a file\n")
        rc = check_contract(CONTROL_FAST[machine] + ["--cycles", cycles, "--out", str(out)], out)
        if out_kind in ("foreign", "file"):
            assert rc == 2


_gain_values = st.sampled_from([float("inf"), float("nan"), -1.0, 0.0, 1e300, 1e-300, 0.5, 3, True, "x", [1.0],
                                [1e308, 1e308, 1e308]])


@FAST
@given(machine=st.sampled_from(["hip", "pdm"]), data=st.data())
def test_control_hostile_gains_file(machine, data):
    from pkmdyn.control import default_settings_text
    import tomllib

    base = tomllib.loads(default_settings_text(machine))
    table = data.draw(st.sampled_from(sorted(base)))
    key = data.draw(st.sampled_from(sorted(base[table])))
    value = data.draw(_gain_values)
    d = {table: {key: value}}
    with tempfile.TemporaryDirectory() as tmp:
        g = Path(tmp) / "g.toml"
        g.write_text(to_toml(d))
        out = Path(tmp) / "out"
        check_contract(CONTROL_FAST[machine] + ["--cycles", "0.01", "--gains", str(g), "--out", str(out)], out)


@FAST
@given(window=hostile_number | st.sampled_from(["3", "4", "15", "10001", "10003"]),
       order=hostile_number | st.sampled_from(["2", "5", "20", "21"]),
       tol=hostile_number | st.sampled_from(["1e-6", "1", "1.5"]),
       which=st.sampled_from(["friction", "inertia", "all", "bogus"]))
def test_identify_hostile_options(window, order, tol, which):
    with tempfile.TemporaryDirectory() as d:
        m = Path(d) / "m.csv"
        m.write_text(_measured_text())
        out = Path(d) / "out"
        check_contract(["hip", "identify", "--measured", str(m), "--no-plots", "--sg-window", window, "--sg-order", order,
                        "--rank-tol", tol, "--identify", which, "--out", str(out)], out)


@FAST
@given(row=st.integers(1, 100), column=st.integers(0, 7),
       value=st.sampled_from(["nan", "inf", "1e300", "-1e300", "1e-300", "x", "", "1e5"]))
def test_identify_hostile_measured_values(row, column, value):
    lines = _measured_text().splitlines()
    cells = lines[row].split(",")
    cells[column] = value
    lines[row] = ",".join(cells)
    with tempfile.TemporaryDirectory() as d:
        m = Path(d) / "m.csv"
        m.write_text("\n".join(lines) + "\n")
        out = Path(d) / "out"
        check_contract(["hip", "identify", "--measured", str(m), "--no-plots", "--out", str(out)], out)


@FAST
@given(step=hostile_number | st.sampled_from(["1e-3", "1e-6", "1"]), d=mutated(HIP_BASE))
def test_export_hostile(step, d):
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "p.toml"
        p.write_text(to_toml(d))
        out = Path(tmp) / "machine.xml"
        # the MJCF file is XML, not a table: the contract is checked by hand here
        before = _snapshot(out)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            rc, err = _run(["hip", "export", "--format", "mjcf", "--params", str(p), "--timestep", step, "--out", str(out)])
        assert not [w for w in caught if _shown(w)]
        assert "Traceback" not in err
        if rc:
            assert rc == 2 and len(err.strip().splitlines()) == 1 and err.startswith("pkmdyn: error: "), err
            assert _snapshot(out) == before
        else:
            assert not re.search(r"\b(nan|inf)\b", out.read_text().lower())
        assert not [q for q in Path(tmp).iterdir() if ".partial" in q.name]


@FAST
@given(d=mutated(HIP_BASE))
def test_excite_hostile_parameter_file(d):
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "p.toml"
        p.write_text(to_toml(d))
        out = Path(tmp) / "m.csv"
        check_contract(EXCITE_FAST + ["--params", str(p), "--out", str(out)], out)


@FAST
@given(machine=st.sampled_from(["hip", "pdm"]), which=st.sampled_from(["--params", "--plant-params"]), data=st.data())
def test_control_hostile_parameter_file(machine, which, data):
    d = data.draw(mutated(HIP_BASE if machine == "hip" else PDM_BASE))
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "p.toml"
        p.write_text(to_toml(d))
        out = Path(tmp) / "out"
        check_contract(CONTROL_FAST[machine] + ["--cycles", "0.01", which, str(p), "--out", str(out)], out)


@FAST
@given(machine=st.sampled_from(["hip", "pdm"]), data=st.data())
def test_control_hostile_motion_file(machine, data):
    from pkmdyn.profiles.pdm_motion import ACCEL_COLUMNS, POSE_COLUMNS, RATE_COLUMNS
    from pkmdyn.profiles.orientation import MOTION_COLUMNS

    if machine == "hip":
        text = data.draw(plausible_motion_csv() | hostile_csv(MOTION_COLUMNS))
    else:
        text = data.draw(hostile_csv(("t_s", *POSE_COLUMNS, *RATE_COLUMNS, *ACCEL_COLUMNS)))
    with tempfile.TemporaryDirectory() as tmp:
        m = Path(tmp) / "m.csv"
        m.write_bytes(text)
        out = Path(tmp) / "out"
        check_contract(CONTROL_FAST[machine] + ["--motion", str(m), "--out", str(out)], out)


@FAST
@given(data=st.data())
def test_identify_hostile_measured_file(data):
    from pkmdyn.machines.hip_simulator.identify_view import TORQUE_COLUMNS
    from pkmdyn.profiles.orientation import MOTION_COLUMNS

    text = data.draw(hostile_csv((*MOTION_COLUMNS, *TORQUE_COLUMNS)))
    with tempfile.TemporaryDirectory() as tmp:
        m = Path(tmp) / "m.csv"
        m.write_bytes(text)
        out = Path(tmp) / "out"
        _earlier_run(out)
        check_contract(["hip", "identify", "--no-plots", "--measured", str(m), "--sg-window", "3", "--sg-order", "2",
                        "--out", str(out)], out)


# ----------------------------------------------------------------------------- every file option
def _bad_files(root: Path) -> dict[str, Path]:
    files = {
        "missing": root / "nope.toml",
        "binary": root / "bin.dat",
        "latin1": root / "latin.txt",
        "bom_only": root / "bom.txt",
        "empty": root / "empty.txt",
        "folder": root / "folder",
        "broken_link": root / "link",
        "hip_params": root / "hip.toml",
        "pdm_params": root / "pdm.toml",
        "shuffled_columns": root / "cols.csv",
    }
    files["binary"].write_bytes(bytes(range(256)) * 4)
    files["latin1"].write_bytes("t_s,caf\xe9\n1,2\n".encode("latin-1"))
    files["bom_only"].write_bytes(b"\xef\xbb\xbf")
    files["empty"].write_bytes(b"")
    files["folder"].mkdir()
    files["broken_link"].symlink_to(root / "gone")
    files["hip_params"].write_text(to_toml(HIP_BASE))
    files["pdm_params"].write_text(to_toml(PDM_BASE))
    files["shuffled_columns"].write_text("tau3_Nm,b,t_s\n1,2,3\n4,5,6\n")
    return files


_FILE_OPTIONS = [
    ("hip control", "--params"), ("hip control", "--plant-params"), ("hip control", "--motion"),
    ("hip control", "--gains"), ("pdm control", "--params"), ("pdm control", "--plant-params"),
    ("pdm control", "--motion"), ("pdm control", "--gains"), ("hip export", "--params"),
    ("hip identify", "--measured"), ("hip identify", "--params"), ("hip excite", "--params"),
]


def _command_args(command: str, root: Path) -> tuple[list[str], Path]:
    if command == "hip export":
        return ["hip", "export", "--format", "mjcf"], root / "machine.xml"
    if command == "hip excite":
        return list(EXCITE_FAST), root / "m.csv"
    if command == "hip identify":
        m = root / "measured.csv"
        m.write_text(_measured_text())
        return ["hip", "identify", "--no-plots", "--measured", str(m)], root / "out"
    machine = command.split()[0]
    return CONTROL_FAST[machine] + ["--cycles", "0.01"], root / "out"


@pytest.mark.parametrize("command, option", _FILE_OPTIONS)
def test_every_file_option_refuses_bad_files(tmp_path, command, option):
    files = _bad_files(tmp_path)
    args, out = _command_args(command, tmp_path)
    machine = command.split()[0]
    if option == "--motion":  # --cycles applies to the built-in motion only
        args = [x for x in args if x not in ("--cycles", "0.01")]
    for kind, path in files.items():
        if kind == f"{machine}_params" and option in ("--params", "--plant-params"):
            continue  # the machine's own file is valid
        if kind in ("empty", "bom_only") and option == "--gains":
            continue  # an empty settings file overrides nothing: valid
        rc = check_contract(_set(args, option, str(path)) + ["--out", str(out)], out)
        assert rc == 2, (kind, option, command)


# ----------------------------------------------------------------------------- regressions
def test_excite_negative_seed_is_one_error_line(tmp_path):
    err = _one_error_line(_set(EXCITE_FAST, "--seed", "-1"), tmp_path / "m.csv")
    assert "--seed" in err


@pytest.mark.parametrize("value", ["inf", "1e400", "nan"])
def test_excite_infinite_period_is_one_error_line_without_warnings(tmp_path, value):
    err = _one_error_line(_set(EXCITE_FAST, "--period-s", value), tmp_path / "m.csv")
    assert "--period-s" in err and "Warning" not in err


@pytest.mark.parametrize("option, value, words", [
    ("--load-range-N", ("0", "1e300"), "--load-range-N"),
    ("--max-slider-speed-m-s", "1e-300", "excitation"),
    ("--max-slider-accel-m-s2", "inf", "--max-slider-accel-m-s2"),
    ("--alpha-range-deg", ("-1e300", "1e300"), "--alpha-range-deg"),
    ("--samples-per-cycle", "1000000", "rows"),
    ("--iterations", "200", "design effort"),
])
def test_excite_bad_limits_are_one_error_line(tmp_path, option, value, words):
    args = _set(EXCITE_FAST, option, value)
    if option == "--samples-per-cycle":
        args = _set(args, "--cycles", "10")
    if option == "--iterations":
        args = _set(_set(args, "--harmonics", "6"), "--design-samples", "1000")
    assert words in _one_error_line(args, tmp_path / "m.csv")


def test_excite_effort_is_bounded():
    """The optimiser's cost evaluations never exceed the bound the command line states."""
    from pkmdyn.machines.hip_simulator.identify_excite import ExcitationLimits, design_excitation, design_work
    from pkmdyn.machines.hip_simulator import load_params

    calls = []
    design_excitation(load_params(None), "friction", ExcitationLimits(), 2.0, 1, 16, 3, 2, 0, progress=calls.append)
    n, work = design_work(1, 16, 3, 2)
    assert 0 < len(calls) <= n and work == 16 * n


def test_excite_library_entry_checks_sizes():
    from pkmdyn.errors import ParameterError
    from pkmdyn.machines.hip_simulator.identify_excite import ExcitationLimits, design_excitation
    from pkmdyn.machines.hip_simulator import load_params

    model = load_params(None)
    for kw, words in (({"seed": -1}, "seed"), ({"period_s": float("inf")}, "period"), ({"starts": 50}, "starts"),
                      ({"harmonics": 7, "samples": 100}, "harmonics")):
        with pytest.raises(ParameterError, match=words):
            design_excitation(model, "friction", ExcitationLimits(), **{"harmonics": 1, "samples": 16, "iterations": 0, **kw})


@pytest.mark.parametrize("machine", ["hip", "pdm"])
@pytest.mark.parametrize("cycles", ["1e300", "1e9"])
def test_control_huge_cycles_is_one_error_line(tmp_path, machine, cycles):
    assert "--cycles" in _one_error_line(CONTROL_FAST[machine] + ["--cycles", cycles], tmp_path / "out")


def test_control_long_motion_file_is_refused_before_allocating(tmp_path):
    m = tmp_path / "m.csv"
    m.write_text("t_s,x_m,y_m,alpha_rad,gamma_rad\n" + "".join(f"{k * 1e8:g},0,0,0,0\n" for k in range(7)))
    err = _one_error_line(["pdm", "control", "--controller", "pid", "--no-plots", "--motion", str(m)], tmp_path / "out")
    assert "control cycles" in err


@pytest.mark.parametrize("text, words", [
    ("[sensors]\npose_delay_cycles = 1e300\n", "pose_delay_cycles"),
    ("[sensors]\npose_feedback_from_sensor = 7\n", "pose_feedback_from_sensor"),
])
def test_control_settings_bounds(tmp_path, text, words):
    g = tmp_path / "g.toml"
    g.write_text(text)
    assert words in _one_error_line(CONTROL_FAST["hip"] + ["--cycles", "0.01", "--gains", str(g)], tmp_path / "out")


@pytest.mark.parametrize("extra, words", [
    (["--rank-tol", "nan"], "--rank-tol"),
    (["--rank-tol", "1"], "--rank-tol"),
    (["--sg-window", "-1"], "--sg-window"),
    (["--sg-window", "4"], "--sg-window"),
    (["--sg-order", "99"], "--sg-order"),
])
def test_identify_bad_options_are_one_error_line(tmp_path, extra, words):
    m = tmp_path / "m.csv"
    m.write_text(_measured_text())
    assert words in _one_error_line(["hip", "identify", "--measured", str(m), "--no-plots", *extra], tmp_path / "out")


def test_identify_huge_torque_is_one_error_line(tmp_path):
    lines = _measured_text().splitlines()
    header = lines[0].split(",")
    cells = lines[3].split(",")
    cells[header.index("tau2_Nm")] = "1e300"
    lines[3] = ",".join(cells)
    m = tmp_path / "m.csv"
    m.write_text("\n".join(lines) + "\n")
    err = _one_error_line(["hip", "identify", "--measured", str(m), "--no-plots"], tmp_path / "out")
    assert "tau2_Nm" in err and "row 3" in err


@pytest.mark.parametrize("step", ["nan", "inf", "1e-300"])
def test_export_bad_timestep_is_one_error_line(tmp_path, step):
    out = tmp_path / "machine.xml"
    assert "--timestep" in _one_error_line(["hip", "export", "--format", "mjcf", "--timestep", step], out)


def test_control_motion_load_above_the_limit_is_one_error_line(tmp_path):
    m = tmp_path / "m.csv"
    m.write_text("t_s,alpha_deg,beta_deg,gamma_deg,load_N\n"
                 + "".join(f"{0.01 * k:g},0,0,0,{1e300 if k == 3 else 100}\n" for k in range(7)))
    err = _one_error_line(CONTROL_FAST["hip"] + ["--motion", str(m)], tmp_path / "out")
    assert "load_N" in err and "row 4" in err


def test_control_integration_steps_are_bounded(tmp_path):
    g = tmp_path / "g.toml"
    g.write_text("[timing]\nintegration_step_s = 1e-300\ncontrol_cycle_s = 0.001\n")
    err = _one_error_line(CONTROL_FAST["pdm"] + ["--cycles", "0.01", "--gains", str(g)], tmp_path / "out")
    assert "integration_step_s" in err


def test_identify_derivatives_that_overflow_are_one_error_line(tmp_path):
    lines = _measured_text().splitlines()
    header = lines[0].split(",")
    k = header.index("t_s")
    rows = [r.split(",") for r in lines[1:]]
    for r in rows:
        r[k] = repr(float(r[k]) * 1e-300)
    m = tmp_path / "m.csv"
    m.write_text("\n".join([lines[0], *(",".join(r) for r in rows)]) + "\n")
    err = _one_error_line(["hip", "identify", "--measured", str(m), "--no-plots"], tmp_path / "out")
    assert "t_s" in err


def test_export_into_a_file_path_is_one_error_line(tmp_path):
    (tmp_path / "afile").write_text("x")
    err = _one_error_line(["hip", "export", "--format", "mjcf"], tmp_path / "afile" / "m.xml")
    assert "is a file" in err


def test_identify_shuffled_columns_give_the_same_result_and_replace_an_earlier_run(tmp_path):
    lines = [r.split(",") for r in _measured_text().splitlines()]
    order = np.random.default_rng(3).permutation(len(lines[0]))
    assert list(order) != sorted(order)
    (tmp_path / "a.csv").write_text(_measured_text())
    (tmp_path / "b.csv").write_text("\n".join(",".join(r[k] for k in order) for r in lines) + "\n")
    texts = []
    for name in ("a", "b"):
        out = tmp_path / f"out_{name}"
        _earlier_run(out)
        assert check_contract(["hip", "identify", "--no-plots", "--measured", str(tmp_path / f"{name}.csv"),
                               "--out", str(out)], out) == 0
        texts.append((out / "identified.toml").read_text().replace(f"{name}.csv", ""))
    assert texts[0] == texts[1]


@FAST
@given(d=mutated(HIP_BASE))
def test_identify_hostile_parameter_file(d):
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "p.toml"
        p.write_text(to_toml(d))
        m = Path(tmp) / "m.csv"
        m.write_text(_measured_text())
        out = Path(tmp) / "out"
        check_contract(["hip", "identify", "--no-plots", "--measured", str(m), "--params", str(p), "--identify", "all",
                        "--out", str(out)], out)


def test_base_parameters_refuses_a_rank_tolerance_outside_0_1():
    from pkmdyn.errors import ParameterError
    from pkmdyn.identify._base import base_parameters

    W = np.random.default_rng(0).normal(size=(20, 3))
    assert base_parameters(W, ("a", "b", "c"), 0.5).rank >= 1
    for tol in (1.0, 0.0, float("nan"), -1.0):
        with pytest.raises(ParameterError, match="rank tolerance"):
            base_parameters(W, ("a", "b", "c"), tol)


def test_pdm_control_with_an_implausible_crank_length_is_one_error_line(tmp_path):
    import copy

    d = copy.deepcopy(PDM_BASE)
    d["geometry"]["crank_length_m"] = 1e308
    p = tmp_path / "p.toml"
    p.write_text(to_toml(d))
    err = _one_error_line(CONTROL_FAST["pdm"] + ["--cycles", "0.01", "--params", str(p)], tmp_path / "out")
    assert "crank_length_m" in err


@pytest.mark.parametrize("command", [["hip", "control", "--controller", "pd"], ["hip", "run"]])
def test_motion_whose_spline_is_singular_is_one_error_line(tmp_path, command):
    """Times 1e308 s apart: the derivative spline's matrix is singular (the shared motion reader)."""
    m = tmp_path / "m.csv"
    m.write_text("t_s,alpha_deg,beta_deg,gamma_deg\n-1e308,0,0,0\n" + "".join(f"{k / 16},0,0,0\n" for k in range(2, 7)))
    err = _one_error_line([*command, "--no-plots", "--motion", str(m)], tmp_path / "out")
    assert "t_s" in err
