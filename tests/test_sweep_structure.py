"""A sweep over a described mechanism compiles its structure once and each design's numbers
(:func:`pkmdyn.multibody.model.compiler.compile_with`): every design's model is the one compiled from
scratch, field by field to the last bit (the Stewart platform, the Delta robot with its idle rod
spins, the planar 3-RRR with explicit legs and over-constraints, the over-constrained Bennett
linkage); numbers that change the rank-based topology, the idle rows, the block order or which
legs are solved in closed form are computed again, a design of another structure is compiled
in full; and a sweep's rows, NSGA-II generations included, are those of designs each compiled
from scratch."""

from __future__ import annotations

import copy
import dataclasses
import pickle

import multibody_examples as ex
import numpy as np
import pytest

from pkmdyn.errors import PkmdynError
from pkmdyn.io import dumps_toml
from pkmdyn.jobs.sweep import run_sweep
from pkmdyn.machines.registry import sweep_adapter
from pkmdyn.multibody import load_mechanism
from pkmdyn.multibody.analyses.designs import DescribedSweep
from pkmdyn.multibody.description.schema import load_description
from pkmdyn.multibody.model.compiler import (
    compile_model,
    compile_with,
    model_structure,
    structure_key,
)

pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")


def _differences(a, b, where="model"):
    """Where two compiled models (or any of their parts) differ: arrays by dtype, shape and
    bytes, floats by their bits, records field by field, containers item by item."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        same = (isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and a.dtype == b.dtype
                and a.shape == b.shape and a.tobytes() == b.tobytes())
        return [] if same else [where]
    if dataclasses.is_dataclass(a) and not isinstance(a, type):
        if type(a) is not type(b):
            return [f"{where} (type)"]
        return [d for f in dataclasses.fields(a) for d in _differences(getattr(a, f.name), getattr(b, f.name),
                                                                        f"{where}.{f.name}")]
    if isinstance(a, dict):
        if not isinstance(b, dict) or list(a) != list(b):
            return [f"{where} (keys)"]
        return [d for k in a for d in _differences(a[k], b[k], f"{where}[{k!r}]")]
    if isinstance(a, (tuple, list)):
        if type(a) is not type(b) or len(a) != len(b):
            return [f"{where} (length)"]
        return [d for i, (x, y) in enumerate(zip(a, b)) for d in _differences(x, y, f"{where}[{i}]")]
    if isinstance(a, float) and isinstance(b, float):
        return [] if np.float64(a).tobytes() == np.float64(b).tobytes() else [where]
    return [] if type(a) is type(b) and a == b else [where]


def _designs(name, n, seed):
    """Random designs of a built-in mechanism as written (with its [parameters]): every number
    of [parameters] scaled by U(0.85, 1.15), every top-level body's mass by U(0.5, 2)."""
    base = ex.builtin_dict(name, parametric=True)
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        d = copy.deepcopy(base)
        for k, v in d["parameters"].items():
            if isinstance(v, float):
                d["parameters"][k] = float(v * rng.uniform(0.85, 1.15))
        for b in d.get("bodies", []):
            b["mass_kg"] = float(b["mass_kg"] * rng.uniform(0.5, 2.0))
        out.append(d)
    return out


def _outcome(make):
    """A compiled model, or the error's text."""
    try:
        return make()
    except PkmdynError as exc:
        return f"{type(exc).__name__}: {exc}"


def _structure(description):
    """The compiled structure of a description (the sweep's template) and its model."""
    desc = load_description(copy.deepcopy(description))
    structure = model_structure(structure_key(desc))
    return structure, compile_with(structure, desc)


def _fast_and_scratch(base, design):
    """The design compiled with the structure of ``base`` (and whether that structure was
    taken), and compiled from scratch (``load_mechanism``)."""
    structure, _ = _structure(base)
    desc = load_description(copy.deepcopy(design))
    reused = structure_key(desc) == structure.key
    return _outcome(lambda: compile_with(structure, desc)), reused, _outcome(lambda: load_mechanism(copy.deepcopy(design)))


@pytest.mark.parametrize("name, seed", [("stewart", 1), ("delta", 2), ("rrr3", 3), ("bennett", 4)])
def test_a_designs_model_is_the_one_compiled_from_scratch(name, seed):
    base = ex.builtin_dict(name, parametric=True)
    structure, model0 = _structure(base)
    assert _differences(model0, load_mechanism(copy.deepcopy(base))) == []
    features = {"stewart": model0.legs.count == 6, "delta": model0.topology.idle == 6,
                "rrr3": model0.legs.count == 2 and model0.topology.overconstraints == 6,
                "bennett": model0.topology.overconstraints == 3}
    assert features[name]  # what each mechanism is here to cover
    for design in _designs(name, 5, seed):
        desc = load_description(copy.deepcopy(design))
        assert structure_key(desc) == structure.key  # the structure is reused
        fast = compile_with(structure, desc)
        scratch = load_mechanism(copy.deepcopy(design))
        assert _differences(fast, scratch) == []
        assert _differences(fast, compile_model(desc)) == []
        assert not np.array_equal(fast.joint_p_parent, model0.joint_p_parent)  # the numbers did change


def test_numbers_that_change_the_topology_are_not_taken_from_the_template():
    """The same structure, other numbers: a Bennett linkage whose link lengths break Bennett's
    condition has no mobility left, a tilted axis of the planar 3-RRR leaves the plane, a leg
    whose universal joint turns about the leg gains idle freedoms: each is refused as its
    compilation from scratch refuses it."""
    bennett = ex.builtin_dict("bennett", parametric=True)
    broken = copy.deepcopy(bennett)
    broken["parameters"]["b_m"] = 0.3
    fast, reused, scratch = _fast_and_scratch(bennett, broken)
    assert reused and isinstance(scratch, str) and "0 degree(s) of freedom" in scratch and fast == scratch

    rrr3 = ex.builtin_dict("rrr3", parametric=True)
    tilted = copy.deepcopy(rrr3)
    tilted["legs"][0]["joints"][1]["axis"] = [0.0, 0.05, 1.0]
    fast, reused, scratch = _fast_and_scratch(rrr3, tilted)
    assert reused and isinstance(scratch, str) and "degree(s) of freedom" in scratch and fast == scratch

    stewart = ex.builtin_dict("stewart")
    spun = copy.deepcopy(stewart)
    u, p, s = spun["legs"][0]["joints"]
    leg = np.subtract(s["point_m"], u["point_m"])
    first = np.cross([0.0, 0.0, 1.0], leg)
    u["axes"] = [list(first / np.linalg.norm(first)), list(leg / np.linalg.norm(leg))]
    fast, reused, scratch = _fast_and_scratch(stewart, spun)
    assert reused and isinstance(scratch, str) and "idle" in scratch and fast == scratch


def test_idle_rows_block_order_and_explicit_legs_are_those_of_the_design():
    """Numbers alone change the idle rows' pattern, and with it the Newton system's blocks and
    which legs are solved in closed form: a Delta robot's elbow balls turned off the rods, a
    Stewart platform on base balls whose frames no longer lie along the legs. The template's
    blocks and legs would be wrong here; the design's own are computed."""
    delta = ex.builtin_dict("delta", parametric=True)
    turned = copy.deepcopy(delta)
    for j in turned["legs"][0]["joints"][1:]:
        j["axis"] = [0.0, 0.0, 1.0]
    _, base = _structure(delta)
    fast, reused, scratch = _fast_and_scratch(delta, turned)
    assert reused and _differences(fast, scratch) == []
    assert not np.array_equal(fast.solver_blocks, base.solver_blocks)

    sps = ex.stewart_sps()
    turned = copy.deepcopy(sps)
    turned["legs"][0]["joints"][0]["axis"] = [0.0, 0.0, 1.0]
    _, base = _structure(sps)
    fast, reused, scratch = _fast_and_scratch(sps, turned)
    assert reused and _differences(fast, scratch) == []
    assert fast.legs.count < base.legs.count and not np.array_equal(fast.solver_blocks, base.solver_blocks)


def test_a_design_of_another_structure_is_compiled_in_full():
    """Another structure (a body and a fixed joint more, another mechanism, more legs) is not
    the template's: its key differs and it is compiled from scratch."""
    stewart = ex.builtin_dict("stewart")
    for other in (ex.stewart_with_tool(), ex.builtin_dict("delta"), ex.stewart_sps()):
        fast, reused, scratch = _fast_and_scratch(stewart, other)
        assert not reused and _differences(fast, scratch) == []
    counted = _counted_delta()
    more = copy.deepcopy(counted)
    more["legs"][0]["count"] = 4
    fast, reused, scratch = _fast_and_scratch(counted, more)  # four legs: redundantly actuated
    assert not reused and _differences(fast, scratch) == [] and fast.na == 4


def _counted_delta():
    """The Delta robot with its legs given by a count (3) rather than their angles."""
    d = ex.builtin_dict("delta", parametric=True)
    del d["legs"][0]["angles_deg"]
    d["legs"][0]["count"] = 3
    return d


def _rows(out):
    return pq.read_table(out / "designs.parquet")


def _same_table(a, b):
    """Two result tables the same, column by column, floats to the last bit."""
    assert a.schema == b.schema and a.num_rows == b.num_rows
    for name in a.column_names:
        x, y = a.column(name), b.column(name)
        assert x.is_null().to_pylist() == y.is_null().to_pylist(), name
        if pa.types.is_floating(x.type):
            assert x.fill_null(0.0).to_numpy().tobytes() == y.fill_null(0.0).to_numpy().tobytes(), name
        else:
            assert x.to_pylist() == y.to_pylist(), name


def _sweep_both_ways(monkeypatch, tmp_path, machine, space_text):
    """The sweep's designs.parquet with the structure compiled once, and with every design
    compiled from scratch (the context without its template)."""
    space = tmp_path / "space.toml"
    space.write_text(space_text, encoding="utf-8")
    fast = run_sweep(sweep_adapter(str(machine)), space, tmp_path / "fast", workers=0, plots=False, progress=False)
    prepare = DescribedSweep.prepare
    monkeypatch.setattr(DescribedSweep, "prepare",
                        lambda self, *a, **k: dataclasses.replace(prepare(self, *a, **k), template=None))
    slow = run_sweep(sweep_adapter(str(machine)), space, tmp_path / "scratch", workers=0, plots=False, progress=False)
    return fast, _rows(tmp_path / "fast"), slow, _rows(tmp_path / "scratch")


GEOMETRY = """
[sampling]
method = "grid"

[motion]
workspace_grid = "x=-0.2:0.2:3,y=-0.2:0.2:3,z=0.9:1.1:3"

[parameters]
"parameters.base_radius_m" = { values = [0.85, 1.15] }
"parameters.platform_half_angle_deg" = { values = [42.0, 53.0] }
"parameters.height_m" = { values = [1.05] }
"bodies[platform].mass_kg" = { values = [-1.0, 12.5] }

[objectives]
peak_effort_N = "min"
"""


def test_a_sweeps_rows_are_those_of_designs_compiled_from_scratch(monkeypatch, tmp_path):
    """The Stewart platform's geometry and platform mass (a negative mass: an invalid row, said
    as the full validation says it), with every metric, the workspace's included."""
    machine = tmp_path / "stewart.toml"
    machine.write_text(dumps_toml(ex.builtin_dict("stewart", parametric=True)), encoding="utf-8")
    fast, a, slow, b = _sweep_both_ways(monkeypatch, tmp_path, machine, GEOMETRY)
    statuses = a.column("status").to_pylist()
    assert "ok" in statuses and "invalid" in statuses
    _same_table(a, b)


COUNT = """
[sampling]
method = "grid"

[motion]
reactions = false
stiffness = false

[parameters]
"legs[0].count" = { values = [3, 4] }
"parameters.forearm_m" = { min = 1.1, max = 1.3, points = 2 }

[objectives]
peak_effort_Nm = "min"
"""


def test_a_swept_count_of_legs_changes_the_structure_and_is_compiled_in_full(monkeypatch, tmp_path):
    machine = tmp_path / "delta.toml"
    machine.write_text(dumps_toml(_counted_delta()), encoding="utf-8")
    fast, a, slow, b = _sweep_both_ways(monkeypatch, tmp_path, machine, COUNT)
    rows = a.to_pylist()
    # four legs: a redundantly actuated Delta, a design of its own with every metric
    assert {r["legs[0].count"]: r["status"] for r in rows} == {3: "ok", 4: "ok"}
    _same_table(a, b)


NSGA2 = """
[sampling]
method = "nsga2"
designs = 6
generations = 2
seed = 7

[motion]
reactions = false
stiffness = false

[parameters]
"parameters.base_side_m" = { min = 0.45, max = 0.70 }
"parameters.upper_arm_m" = { min = 0.40, max = 0.65 }
"parameters.forearm_m" = { min = 1.0, max = 1.4 }

[constraints]
min_direct_measure = { min = 0.02 }

[objectives]
gci = "max"
peak_effort_Nm = "min"
"""


def test_nsga2_generations_are_those_of_designs_compiled_from_scratch(monkeypatch, tmp_path):
    """Each generation is bred from the rows before it: the same rows, the same generations."""
    machine = tmp_path / "delta.toml"
    machine.write_text(dumps_toml(ex.builtin_dict("delta", parametric=True)), encoding="utf-8")
    fast, a, slow, b = _sweep_both_ways(monkeypatch, tmp_path, machine, NSGA2)
    assert a.num_rows == 6 * 3 and fast.counts == slow.counts
    _same_table(a, b)


def test_the_template_travels_with_the_context():
    """The context goes to every worker once: its template pickles, and the structure it
    carries is the base description's."""
    adapter = sweep_adapter("rrr3")
    ctx = adapter.prepare(adapter.raw, {"reactions": False}, adapter.path.parent)
    again = pickle.loads(pickle.dumps(ctx))
    key = structure_key(load_description(copy.deepcopy(adapter.raw)))
    assert again.template.key == key == ctx.template.key
