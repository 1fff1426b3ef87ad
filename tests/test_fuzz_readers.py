"""Fuzzing the readers: hostile TOML and CSV input ends in a pkmdyn error or a finite model.

Generated input: random bytes, byte-order marks, NUL bytes, random TOML types, NaN/inf/huge/
negative values, unknown, shuffled and missing keys and columns. The contract: the reader
raises a :class:`~pkmdyn.errors.PkmdynError` (never another exception), or it returns a model
or motion whose every number is finite. The strategies are shared with ``test_fuzz_cli.py``.
"""

from __future__ import annotations

import copy
import dataclasses
import json
import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pkmdyn.errors import PkmdynError
from pkmdyn.io import read_csv_columns
from pkmdyn.machines.hip_simulator.params import default_params_dict, load_params, model_from_dict
from pkmdyn.machines.pdm4.params import default_params_path, load_params as load_pdm, params_from_dict
from pkmdyn.params_util import read_toml
from pkmdyn.profiles.orientation import MOTION_COLUMNS, read_motion_csv
from pkmdyn.profiles.pdm_motion import ACCEL_COLUMNS, POSE_COLUMNS, RATE_COLUMNS, read_pdm_motion

FUZZ = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True)

SPECIAL_FLOATS = [math.nan, math.inf, -math.inf, 1e308, -1e308, 1e-308, 5e-324, 0.0, -0.0, -1.0, 1e20, -1e20, 1e9]

#: a hostile TOML value: special and random floats, huge integers, strings, booleans, arrays, tables
hostile_value = st.one_of(
    st.sampled_from(SPECIAL_FLOATS),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(10**30), max_value=10**30),
    st.text(max_size=8),
    st.booleans(),
    st.lists(st.one_of(st.sampled_from(SPECIAL_FLOATS), st.floats(-1e3, 1e3), st.integers(-5, 5)), max_size=5),
    st.dictionaries(st.sampled_from(["a", "x", "mass_kg"]), st.floats(-10, 10), max_size=2),
)


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, int):
        return str(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{json.dumps(k)} = {_toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(type(v))


def to_toml(d: dict) -> str:
    """A small TOML writer for descriptions: top-level keys, then one table per dict."""
    lines = [f"{json.dumps(k)} = {_toml_value(v)}" for k, v in d.items() if not isinstance(v, dict)]
    for name, table in d.items():
        if isinstance(table, dict):
            lines.append(f"[{json.dumps(name)}]")
            lines += [f"{json.dumps(k)} = {_toml_value(v)}" for k, v in table.items()]
    return "\n".join(lines) + "\n"


@st.composite
def mutated(draw, base: dict) -> dict:
    """``base`` with 1-3 hostile edits: a key set to a hostile value, removed, added, or a table dropped."""
    d = copy.deepcopy(base)
    for _ in range(draw(st.integers(1, 3))):
        tables = [k for k, v in d.items() if isinstance(v, dict)]
        action = draw(st.sampled_from(["set", "set", "set", "perturb", "perturb", "drop_key", "add_key", "drop_table"]))
        if not tables or action == "drop_table":
            if tables:
                d.pop(draw(st.sampled_from(tables)))
            continue
        table = d[draw(st.sampled_from(tables))]
        keys = sorted(table)
        if action == "perturb" and keys:  # a plausible edit, so that successful runs are fuzzed too
            key = draw(st.sampled_from(keys))
            if isinstance(table[key], float):
                table[key] = table[key] * draw(st.floats(0.9, 1.1))
        elif action == "set" and keys:
            table[draw(st.sampled_from(keys))] = draw(hostile_value)
        elif action == "drop_key" and keys:
            table.pop(draw(st.sampled_from(keys)))
        else:
            table[draw(st.text(min_size=1, max_size=6))] = draw(hostile_value)
    return d


def assert_all_finite(obj, where="model") -> None:
    """Every number in a (frozen dataclass) model is finite."""
    if dataclasses.is_dataclass(obj):
        for f in dataclasses.fields(obj):
            assert_all_finite(getattr(obj, f.name), f"{where}.{f.name}")
    elif isinstance(obj, np.ndarray):
        if obj.dtype.kind in "fc":
            assert np.all(np.isfinite(obj)), where
    elif isinstance(obj, float):
        assert math.isfinite(obj), where
    elif isinstance(obj, (tuple, list)):
        for i, v in enumerate(obj):
            assert_all_finite(v, f"{where}[{i}]")


HIP_BASE = default_params_dict()
PDM_BASE = read_toml(default_params_path())

#: hostile CSV cells
hostile_cell = st.one_of(
    st.sampled_from(["nan", "inf", "-inf", "1e999", "", " ", "abc", "1,2", "0x10", "\x00", "1e308", "-1e308",
                     "1_000", "\u0661", "\ufeff1", "--1", "1e-320"]),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(-(10**30), 10**30).map(str),
    st.text(max_size=4),
)


@st.composite
def hostile_csv(draw, columns: tuple[str, ...]) -> bytes:
    """A CSV with a shuffled subset of ``columns`` (maybe an unknown or repeated one) and hostile cells."""
    header = draw(st.lists(st.sampled_from([*columns, "bogus_m", "t"]), min_size=0, max_size=len(columns) + 1))
    if draw(st.booleans()):
        header = list(dict.fromkeys(header))
    n = draw(st.integers(0, 8))
    rows = []
    for r in range(n):
        width = len(header) + draw(st.sampled_from([0, 0, 0, -1, 1]))
        if draw(st.booleans()):
            row = [repr(float(r) if c.startswith("t") else draw(st.floats(-30, 30))) for c in header][: max(width, 0)]
        else:
            row = [draw(hostile_cell) for _ in range(max(width, 0))]
        rows.append(",".join(row))
    text = "\n".join([",".join(header), *rows]) + "\n"
    prefix = draw(st.sampled_from([b"", b"", b"\xef\xbb\xbf", b"\xff\xfe", b"\x00"]))
    suffix = draw(st.sampled_from([b"", b"", b"\xff\xfe\x80", b"\x00\n"]))
    return prefix + text.encode("utf-8", "surrogatepass") + suffix


@st.composite
def plausible_motion_csv(draw) -> bytes:
    """A hip motion that may well run (smooth small angles, a load), then maybe one hostile edit:
    a cell replaced, a column dropped, the columns shuffled, a row repeated."""
    n = draw(st.integers(6, 25))
    t = np.cumsum(np.full(n, draw(st.floats(0.005, 0.1))))
    amp = np.array([draw(st.floats(0, 25)) for _ in range(3)])
    ang = amp * np.sin(2 * np.pi * t[:, None] / (t[-1] + t[0]) + np.arange(3))
    cols = {"t_s": t, "alpha_deg": ang[:, 0], "beta_deg": ang[:, 1], "gamma_deg": ang[:, 2]}
    if draw(st.booleans()):
        cols["load_N"] = np.full(n, draw(st.floats(0, 3000)))
    names = list(cols)
    rows = [[repr(float(cols[c][r])) for c in names] for r in range(n)]
    edit = draw(st.sampled_from(["none", "none", "cell", "drop", "shuffle", "repeat"]))
    if edit == "cell":
        rows[draw(st.integers(0, n - 1))][draw(st.integers(0, len(names) - 1))] = draw(hostile_cell)
    elif edit == "drop":
        k = draw(st.integers(0, len(names) - 1))
        names.pop(k)
        rows = [r[:k] + r[k + 1:] for r in rows]
    elif edit == "shuffle":
        order = draw(st.permutations(range(len(names))))
        names = [names[k] for k in order]
        rows = [[r[k] for k in order] for r in rows]
    elif edit == "repeat":
        rows.insert(1, rows[0])
    text = "\n".join([",".join(names), *(",".join(r) for r in rows)]) + "\n"
    return text.encode("utf-8", "surrogatepass")


def _write(data: bytes, suffix: str) -> tuple[tempfile.TemporaryDirectory, Path]:
    tmp = tempfile.TemporaryDirectory()
    p = Path(tmp.name) / f"input{suffix}"
    p.write_bytes(data)
    return tmp, p


@FUZZ
@given(st.one_of(st.binary(max_size=300), st.binary(max_size=60).map(lambda b: b"\xef\xbb\xbf[geometry]\n" + b)))
def test_random_bytes_as_toml(data):
    tmp, p = _write(data, ".toml")
    with tmp:
        for loader in (read_toml, load_params, load_pdm):
            try:
                loader(p)
            except PkmdynError as exc:
                assert "\n" not in str(exc).strip() and str(p) in str(exc) or p.name in str(exc)


@FUZZ
@given(mutated(HIP_BASE))
def test_hostile_hip_description(d):
    try:
        model = model_from_dict(d, "p.toml")
    except PkmdynError as exc:
        assert str(exc).startswith("p.toml")
    else:
        assert_all_finite(model)


@FUZZ
@given(mutated(HIP_BASE))
def test_hostile_hip_toml_file(d):
    tmp, p = _write(to_toml(d).encode("utf-8", "surrogatepass"), ".toml")
    with tmp:
        try:
            model = load_params(p)
        except PkmdynError as exc:
            assert str(p) in str(exc)
        else:
            assert_all_finite(model)


@FUZZ
@given(mutated(PDM_BASE))
def test_hostile_pdm_description(d):
    try:
        model = params_from_dict(d, "pdm.toml")
    except PkmdynError as exc:
        assert "pdm.toml" in str(exc)
    else:
        assert_all_finite(model)


@FUZZ
@given(st.one_of(hostile_csv(MOTION_COLUMNS), plausible_motion_csv(), st.binary(max_size=200)))
def test_hostile_hip_motion_csv(data):
    tmp, p = _write(data, ".csv")
    with tmp:
        try:
            m = read_motion_csv(p)
        except PkmdynError as exc:
            assert str(p) in str(exc) or "motion" in str(exc)
        else:
            assert_all_finite(m)
            assert m.angles.shape == (len(m), 3) and np.all(np.diff(m.t) > 0) and np.all(m.load >= 0)


@FUZZ
@given(st.one_of(hostile_csv(("t_s", *POSE_COLUMNS, *RATE_COLUMNS, *ACCEL_COLUMNS)), st.binary(max_size=200)))
def test_hostile_pdm_motion_csv(data):
    tmp, p = _write(data, ".csv")
    with tmp:
        try:
            m = read_pdm_motion(p)
        except PkmdynError as exc:
            assert str(p) in str(exc) or "motion" in str(exc)
        else:
            assert_all_finite(m)


@pytest.mark.parametrize(
    "data, word",
    [
        (b"\xff\xfet\x00_\x00s\x00", "UTF-16"),
        (b"t_s,alpha_deg\n\xe9\n", "not UTF-8"),
        (b"t_s\x00,alpha_deg\n", "NUL"),
        (b"", "empty"),
    ],
)
def test_encoding_problems_name_the_file(tmp_path, data, word):
    p = tmp_path / "m.csv"
    p.write_bytes(data)
    with pytest.raises(PkmdynError, match=word) as info:
        read_csv_columns(p, ("t_s",), ("alpha_deg",))
    assert str(p) in str(info.value)


def test_utf8_bom_is_accepted_in_both_readers(tmp_path):
    p = tmp_path / "m.csv"
    p.write_bytes(b"\xef\xbb\xbft_s,alpha_deg\n0,1\n1,2\n")
    np.testing.assert_array_equal(read_csv_columns(p, ("t_s", "alpha_deg"))["alpha_deg"], [1.0, 2.0])
    q = tmp_path / "p.toml"
    q.write_bytes(b"\xef\xbb\xbf" + to_toml(HIP_BASE).encode())
    assert load_params(q).geometry.l == HIP_BASE["geometry"]["lever_length_m"]


def test_row_limit_is_checked_while_reading(tmp_path):
    p = tmp_path / "m.csv"
    p.write_text("t_s\n" + "".join(f"{k}\n" for k in range(11)))
    assert read_csv_columns(p, ("t_s",), max_rows=11)["t_s"].shape == (11,)
    with pytest.raises(PkmdynError, match=r"more than 10 data rows.*max_samples"):
        read_csv_columns(p, ("t_s",), max_rows=10)
