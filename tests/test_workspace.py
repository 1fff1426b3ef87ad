"""The workspace of any described mechanism on a grid (pkmdyn.multibody.analyses.workspace), against the
closed-form inverse kinematics of the Stewart platform and the Delta robot (tests/oracles) with
the descriptions' joint limits; the size's error estimate against a finer grid; the command."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import ndimage

from oracles import delta, stewart
from pkmdyn.cli import main
from pkmdyn.multibody import load_mechanism
from pkmdyn.multibody.kinematics.inverse import reference_task, solve_kinematics
from pkmdyn.multibody.analyses.workspace import workspace

from multibody_examples import MACHINES


def _stewart_inside(x, margin):
    """Every leg within [0.9, 1.6] m (the description's limits_m), and which poses lie within
    ``margin`` of a limit (undecidable by rounding: left out of the comparison)."""
    a, b, _ = stewart.default_geometry()
    L = stewart.inverse_kinematics(a, b, x[:, :3], x[:, 3:], "XYZ")["L"]
    inside = np.all((L >= 0.9) & (L <= 1.6), axis=1)
    near = np.any((np.abs(L - 0.9) < margin) | (np.abs(L - 1.6) < margin), axis=1)
    return inside, near


def test_stewart_constant_orientation_workspace_against_the_closed_form():
    m = load_mechanism(MACHINES / "stewart" / "stewart.toml")
    axes = [(0, np.linspace(-0.5, 0.5, 11)), (1, np.linspace(-0.5, 0.5, 11)), (2, np.linspace(0.7, 1.5, 9))]
    base = reference_task(m)
    base[5] = 0.15  # a constant orientation away from the reference
    ws = workspace(m, axes, base, threshold=0.0)
    ref, near = _stewart_inside(ws.x, 1e-9)
    assert ref.sum() > 50 and (~ref).sum() > 50  # the grid crosses the boundary
    assert np.array_equal(ws.reached[~near], ref[~near])
    cell = 0.1 * 0.1 * 0.1
    assert ws.size == pytest.approx(ws.inside.sum() * cell)
    assert ws.size_error > 0


def test_delta_workspace_against_the_closed_form():
    m = load_mechanism(MACHINES / "delta" / "delta.toml")
    axes = [(0, np.linspace(-0.85, 0.85, 18)), (1, np.linspace(-0.85, 0.85, 18))]
    base = np.array([0.0, 0.0, -1.25])
    ws = workspace(m, axes, base, threshold=0.0)
    g = delta.williams_irb360_geometry()
    with np.errstate(invalid="ignore"):
        th = delta.inverse_kinematics(ws.x, g["R_b"], g["R_p"], g["L_A"], g["L_B"])
    ok = np.all(np.isfinite(th), axis=1)
    ref = ok & np.all((np.nan_to_num(th) >= -1.2) & (np.nan_to_num(th) <= 1.5), axis=1)
    near = np.any((np.abs(np.nan_to_num(th) + 1.2) < 1e-9) | (np.abs(np.nan_to_num(th) - 1.5) < 1e-9), axis=1)
    assert ref.sum() > 20 and (~ref).sum() > 20
    assert np.array_equal(ws.reached[~near], ref[~near])


@pytest.mark.parametrize("name, axes", [
    ("stewart", [(0, np.linspace(-0.5, 0.5, 6)), (1, np.linspace(-0.5, 0.5, 6)), (2, np.linspace(0.7, 1.5, 5))]),
    ("rrr3", [(0, np.linspace(-0.4, 0.4, 9)), (2, np.linspace(-1.5, 1.5, 9))]),
])
def test_grid_continuation_gives_each_pose_as_solved_alone(name, axes):
    """Every inside pose's joint coordinates by continuation over the grid equal those of the
    pose solved by itself from the reference configuration (the first sample of a motion)."""
    m = load_mechanism(MACHINES / name / f"{name}.toml")
    ws = workspace(m, axes, threshold=1e-3)
    assert ws.inside.sum() > 20
    for k in np.flatnonzero(ws.inside):
        alone = solve_kinematics(m, ws.x[k:k + 1])
        assert np.max(np.abs(alone.q[0] - ws.q[k])) < 1e-9


@pytest.mark.parametrize("name, grid", [
    ("delta", "x=-1.5:1.5:13,y=-1.5:1.5:13,z=-2.2:-0.2:9"),
    ("rrr3", "x=-0.4:0.4:41,euler1=-1.5:1.5:41"),
])
def test_giving_up_on_stalled_poses_leaves_the_grid_as_it_was(name, grid):
    """A grid pose whose Newton iteration stalls is given up after a few steps (``stall``)
    instead of ``MAX_ITER``: the same poses are reached, with the same coordinates, as
    without giving up; wide grids, so that many poses lie out of reach (a Stewart platform's
    unlimited legs reach every pose)."""
    from pkmdyn.multibody.kinematics.inverse import GRID_STALL, solve_grid
    from pkmdyn.multibody.analyses.task_grid import parse_grid
    from pkmdyn.multibody.analyses.workspace import _roots, grid_poses

    m = load_mechanism(MACHINES / name / f"{name}.toml")
    axes = parse_grid(m, grid, max_axes=4, max_points=10**5)
    base = reference_task(m)
    x = grid_poses(m, axes, base)
    shape = tuple(len(v) for _, v in axes)
    kin, reached = solve_grid(m, x, shape, _roots(axes, base), stall=GRID_STALL)
    kin0, reached0 = solve_grid(m, x, shape, _roots(axes, base), stall=0)
    assert 20 < reached0.sum() < 0.9 * len(x)
    assert np.array_equal(reached, reached0)
    assert np.max(np.abs(kin.q[reached] - kin0.q[reached])) < 1e-12


def test_the_workspace_is_the_part_connected_to_the_start():
    """A planar 3-RRR over position and orientation: the poses away from every singularity fall
    in several parts; the workspace is the one about the held pose, the others (reached only
    across a singularity) are outside."""
    m = load_mechanism(MACHINES / "rrr3" / "rrr3.toml")
    axes = [(0, np.linspace(-0.4, 0.4, 41)), (2, np.linspace(-1.5, 1.5, 41))]
    thr = 0.01
    ws = workspace(m, axes, threshold=thr)
    good = (ws.reached & (ws.measure >= thr)).reshape(41, 41)
    labels, count = ndimage.label(good)
    assert count >= 2
    start = labels[20, 20]  # the reference pose (x = 0, phi = 0) is a grid pose
    assert start > 0
    assert np.array_equal(ws.inside.reshape(41, 41), labels == start)
    assert ws.inside.sum() < good.sum()


def test_total_orientation_workspace_against_the_closed_form():
    """Over a range of orientations (two values of each Euler angle: eight orientations), a
    position is reached where every orientation of the range reaches it within the strokes
    (Merlet's total orientation workspace); it lies inside each constant-orientation workspace."""
    m = load_mechanism(MACHINES / "stewart" / "stewart.toml")
    axes = [(0, np.linspace(-0.5, 0.5, 9)), (1, np.linspace(-0.5, 0.5, 9)), (2, np.linspace(0.7, 1.5, 7))]
    ranges = [(3, np.array([-0.1, 0.1])), (4, np.array([-0.1, 0.1])), (5, np.array([0.05, 0.25]))]
    ws = workspace(m, axes, threshold=0.0, ranges=ranges)
    every, near_any = np.ones(len(ws.x), dtype=bool), np.zeros(len(ws.x), dtype=bool)
    for a in ranges[0][1]:
        for b in ranges[1][1]:
            for c in ranges[2][1]:
                x = ws.x.copy()
                x[:, 3:] = a, b, c
                ref, near = _stewart_inside(x, 1e-9)
                every &= ref
                near_any |= near
                one = workspace(m, axes, x[0], threshold=0.0)
                assert np.all(one.inside[ws.inside])
    assert every.sum() > 30 and (~every).sum() > 30
    assert np.array_equal(ws.reached[~near_any], every[~near_any])
    assert ws.q is None and ws.size == pytest.approx(ws.inside.sum() * 0.125 * 0.125 * (0.8 / 6))


def test_the_size_error_estimate_covers_a_finer_grid():
    """The Stewart platform's constant-orientation area at one height on a coarse and a 4x finer
    grid: the two sizes differ by less than the sum of their error estimates, and the finer
    estimate is smaller."""
    m = load_mechanism(MACHINES / "stewart" / "stewart.toml")
    base = reference_task(m)
    base[2] = 1.3
    sizes = []
    for count in (13, 49):
        axes = [(0, np.linspace(-0.6, 0.6, count)), (1, np.linspace(-0.6, 0.6, count))]
        ws = workspace(m, axes, base, threshold=0.0)
        assert ws.unit == "m2"
        sizes.append((ws.size, ws.size_error))
    (a, ea), (b, eb) = sizes
    assert abs(a - b) <= ea + eb
    assert eb < ea


def test_inscribed_shapes_and_the_singularity_threshold():
    m = load_mechanism(MACHINES / "delta" / "delta.toml")
    axes = [(0, np.linspace(-0.8, 0.8, 17)), (1, np.linspace(-0.8, 0.8, 17))]
    base = np.array([0.0, 0.0, -1.25])
    loose = workspace(m, axes, base, threshold=0.0)
    strict = workspace(m, axes, base, threshold=float(np.quantile(loose.measure[loose.inside], 0.5)))
    assert strict.inside.sum() < loose.inside.sum()
    assert np.all(strict.measure[strict.inside] >= strict.threshold)
    # every pose within the inscribed disc about the centre is inside
    r = loose.cylinder_radius
    d = np.linalg.norm(loose.x[:, :2], axis=1)
    assert r > 0.1 and np.all(loose.inside[d <= r])
    a = loose.cube_half_width
    assert np.all(loose.inside[np.max(np.abs(loose.x[:, :2]), axis=1) <= a])


def test_workspace_command(tmp_path):
    out = tmp_path / "ws"
    assert main(["workspace", "--machine", "delta", "--grid", "x=-0.6:0.6:7,y=-0.6:0.6:7", "--pose", "z=-1.2",
                 "--out", str(out)]) == 0
    doc = json.loads((out / "workspace.json").read_text())
    assert doc["poses"] == 49 and 0 < doc["inside"] <= 49
    assert doc["fixed"]["z_m"] == -1.2 and doc["size_m2"] == pytest.approx(doc["inside"] * 0.04)
    rows = (out / "workspace.csv").read_text().splitlines()
    assert len(rows) == 50 and (out / "workspace.png").stat().st_size > 0
    # over a range of heights: fewer poses inside, the range in the file, z no longer fixed
    wide = tmp_path / "wide"
    assert main(["workspace", "--machine", "delta", "--grid", "x=-0.6:0.6:7,y=-0.6:0.6:7",
                 "--orientation-range", "z=-1.6:-0.8:3", "--out", str(wide)]) == 0
    both = json.loads((wide / "workspace.json").read_text())
    assert both["orientation_range"] == {"z_m": {"low": -1.6, "high": -0.8, "count": 3}} and "z_m" not in both["fixed"]
    assert both["inside"] < doc["inside"]
    # the refined size: the same poses, the size from the boundary's crossings, the method named
    folders = (tmp_path / "coarse", tmp_path / "fine")
    for refine, folder in zip((0, 4), folders):
        assert main(["workspace", "--machine", "delta", "--grid", "x=-1.4:1.4:8,y=-1.4:1.4:8", "--pose", "z=-1.2",
                     "--refine", str(refine), "--out", str(folder)]) == 0
    coarse, ref = (json.loads((f / "workspace.json").read_text()) for f in folders)
    assert 0 < ref["inside"] == coarse["inside"] < 64 and ref["size_method"].endswith("4 steps an edge")
    assert coarse["size_method"] == "inside poses times the cell" and ref["size_error_m2"] < coarse["size_error_m2"]
    assert abs(ref["size_m2"] - coarse["size_m2"]) <= coarse["size_error_m2"]


@pytest.mark.parametrize("args, words", [
    (["--grid", "q=0:1:3"], "'q'"),
    (["--grid", "x=1:0:3"], "LOW < HIGH"),
    (["--grid", "x=0:1:3", "--threshold", "2"], "--threshold"),
    (["--grid", "x=0:1:3,y=0:1:3", "--centre", "0.1"], "--centre"),
    (["--grid", "x=0:1:3", "--orientation-range", "x=0:1:3"], "--orientation-range"),
    (["--grid", "x=0:1:3", "--orientation-range", "z=-1:1"], "--orientation-range"),
    (["--grid", "x=0:1:3", "--orientation-range", "z=-1:1:3", "--refine", "4"], "--refine"),
    (["--grid", "x=0:1:3", "--refine", "65"], "--refine"),
    (["--grid", "x=0:1:3", "--pose", "z=1e308"], "--pose z: 1e+308 m is beyond the limit max_length_m = 1000"),
    (["--grid", "x=-1e300:0:3"], "--grid x: -1e+300 m is beyond the limit max_length_m"),
    (["--grid", "x=-2000:0:3", "--limit", "max_length_m=1500"], "--grid x: -2000 m is beyond the limit max_length_m = "
                                                                 "1500"),
])
def test_bad_workspace_input(tmp_path, capsys, args, words):
    out = tmp_path / "ws"
    assert main(["workspace", "--machine", "delta", *args, "--out", str(out)]) == 2
    assert words in capsys.readouterr().err
    assert not out.exists()


def _stewart_sweep(tmp_path, rest):
    """The rows (by design id) of a serial grid sweep of the Stewart platform without reactions,
    its space file's ``[motion]`` table continued by ``rest``."""
    pq = pytest.importorskip("pyarrow.parquet")
    tmp_path.mkdir(exist_ok=True)
    space = tmp_path / "space.toml"
    space.write_text('[sampling]\nmethod = "grid"\n[motion]\nreactions = false\n' + rest)
    out = tmp_path / "out"
    assert main(["sweep", "--machine", "stewart", "--space", str(space), "--workers", "0", "--no-plots",
                 "--out", str(out)]) == 0
    return sorted(pq.read_table(out / "designs.parquet").to_pylist(), key=lambda r: r["design_id"])


def test_sweep_reports_the_workspace_of_every_design(tmp_path):
    """The Stewart platform's constant-orientation workspace on a grid, per design of a sweep over
    its base radius: each row's size is the workspace computed for that design alone."""
    rows = _stewart_sweep(tmp_path, 'workspace_grid = "x=-0.4:0.4:5,y=-0.4:0.4:5,z=0.9:1.3:3"\n'
                                    '[parameters]\n"parameters.base_radius_m" = { values = [0.8, 1.1] }\n'
                                    '[objectives]\nworkspace_size_m3 = "max"\n')
    assert [r["status"] for r in rows] == ["ok", "ok"]
    from pkmdyn.multibody.analyses.task_grid import parse_grid

    for r, radius in zip(rows, (0.8, 1.1)):
        import multibody_examples as ex

        d = ex.builtin_dict("stewart", parametric=True)
        d["parameters"]["base_radius_m"] = radius
        m = load_mechanism(d)
        ws = workspace(m, parse_grid(m, "x=-0.4:0.4:5,y=-0.4:0.4:5,z=0.9:1.3:3", max_axes=3), threshold=1e-3)
        assert r["workspace_size_m3"] == pytest.approx(ws.size, rel=1e-12)
        assert r["workspace_inside_share"] == pytest.approx(ws.inside.mean())
        assert r["workspace_min_measure"] == pytest.approx(ws.measure[ws.inside].min(), rel=1e-12)
        assert r["workspace_size_error_m3"] == pytest.approx(ws.size_error, rel=1e-12)
        cube = ws.inside.reshape(5, 5, 3)  # an inside pose on a face of the grid: the size is a lower bound
        on_edge = any(np.take(cube, e, axis=a).any() for a in range(3) for e in (0, -1))
        assert r["workspace_at_grid_edge"] == (1.0 if on_edge else 0.0)
    assert rows[0]["workspace_size_m3"] != rows[1]["workspace_size_m3"]


def test_a_sweep_without_the_workspace_measure(tmp_path):
    """``workspace_measure = false``: the same workspace size, no ``workspace_min_measure``."""
    grid = 'workspace_grid = "x=-0.4:0.4:5,y=-0.4:0.4:5,z=0.9:1.3:3"\n'
    rest = '[parameters]\n"parameters.base_radius_m" = { values = [0.8] }\n[objectives]\nworkspace_size_m3 = "max"\n'
    with_measure = _stewart_sweep(tmp_path / "a", grid + rest)
    without = _stewart_sweep(tmp_path / "b", grid + "workspace_measure = false\n" + rest)
    assert "workspace_min_measure" in with_measure[0] and "workspace_min_measure" not in without[0]
    assert without[0]["workspace_size_m3"] == with_measure[0]["workspace_size_m3"] > 0


def test_a_sweep_with_the_refined_size(tmp_path):
    """``workspace_refine = 4``: each row's size (the sweep's route, the measures bounded
    cheaply) is the refined size of that design's workspace with every measure computed, and
    the share inside is the count's."""
    grid = "x=-0.4:0.4:5,y=-0.4:0.4:5,z=0.9:1.3:3"
    rows = _stewart_sweep(tmp_path, f'workspace_grid = "{grid}"\nworkspace_refine = 4\n'
                                    '[parameters]\n"parameters.base_radius_m" = { values = [0.8, 1.1] }\n'
                                    '[objectives]\nworkspace_size_m3 = "max"\n')
    from pkmdyn.multibody.analyses.task_grid import parse_grid

    import multibody_examples as ex

    for r, radius in zip(rows, (0.8, 1.1)):
        d = ex.builtin_dict("stewart", parametric=True)
        d["parameters"]["base_radius_m"] = radius
        m = load_mechanism(d)
        ws = workspace(m, parse_grid(m, grid, max_axes=3), threshold=1e-3, refine=4)
        count = workspace(m, parse_grid(m, grid, max_axes=3), threshold=1e-3)
        assert r["status"] == "ok" and r["workspace_size_m3"] == pytest.approx(ws.size, rel=1e-12)
        assert r["workspace_inside_share"] == pytest.approx(count.inside.mean())
        assert ws.size != pytest.approx(count.size, rel=1e-6)


@pytest.mark.parametrize("motion, words", [
    ('workspace_refine = 4\n', "workspace_refine"),
    ('workspace_grid = "x=-0.4:0.4:5"\nworkspace_refine = 65\n', "workspace_refine"),
    ('workspace_grid = "x=-0.4:0.4:5"\nworkspace_orientation_range = "euler3=-0.3:0.3:3"\nworkspace_refine = 4\n',
     "workspace_refine"),
])
def test_bad_refine_in_a_sweep(tmp_path, capsys, motion, words):
    """A refined size without a grid, beyond 64 steps, or over an orientation range: one line
    naming the key, exit status 2, nothing written."""
    space = tmp_path / "space.toml"
    space.write_text('[sampling]\nmethod = "grid"\n[motion]\nreactions = false\n' + motion
                     + '[parameters]\n"parameters.base_radius_m" = { values = [1.0] }\n'
                       '[objectives]\npeak_effort_N = "min"\n')
    out = tmp_path / "out"
    assert main(["sweep", "--machine", "stewart", "--space", str(space), "--workers", "0", "--no-plots",
                 "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert words in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_sweep_reports_the_total_orientation_workspace(tmp_path):
    """``workspace_orientation_range``: each row's size is that design's workspace over the range."""
    grid, turn = "x=-0.4:0.4:5,y=-0.4:0.4:5,z=0.9:1.3:3", "euler3=-0.3:0.3:3"
    rows = _stewart_sweep(tmp_path, f'workspace_grid = "{grid}"\nworkspace_orientation_range = "{turn}"\n'
                                    '[parameters]\n"parameters.base_radius_m" = { values = [1.0] }\n'
                                    '[objectives]\nworkspace_size_m3 = "max"\n')
    from pkmdyn.multibody.analyses.task_grid import parse_grid

    m = load_mechanism(MACHINES / "stewart" / "stewart.toml")
    ws = workspace(m, parse_grid(m, grid, max_axes=3), threshold=1e-3, ranges=parse_grid(m, turn))
    fixed = workspace(m, parse_grid(m, grid, max_axes=3), threshold=1e-3)
    assert rows[0]["workspace_size_m3"] == pytest.approx(ws.size, rel=1e-12) and ws.size < fixed.size


def test_a_required_region_constrains_a_sweep(tmp_path):
    """[requirements]: the share of a required task region inside each design's workspace, a
    constraint like any metric: a Stewart platform with a wider base needs longer legs than its
    strokes allow for the region's lowest poses, covers less of it and breaks the constraint."""
    grid = "x=-0.1:0.1:3,y=-0.1:0.1:3,z=0.9:1.3:3"
    rows = _stewart_sweep(tmp_path, f'[requirements]\ngrid = "{grid}"\n'
                                    '[parameters]\n"parameters.base_radius_m" = { values = [1.0, 1.3] }\n'
                                    '[constraints]\nrequired_region_coverage = { min = 1.0 }\n'
                                    '[objectives]\npeak_effort_N = "min"\n')
    from pkmdyn.multibody.analyses.task_grid import parse_grid

    m = load_mechanism(MACHINES / "stewart" / "stewart.toml")  # base radius 1.0: the oracle's geometry
    ws = workspace(m, parse_grid(m, grid, max_axes=3), threshold=1e-3)
    ref, _ = _stewart_inside(ws.x, 0.0)
    assert rows[0]["required_region_coverage"] == pytest.approx(ref.mean()) == 1.0
    assert rows[1]["required_region_coverage"] < 1.0
    assert [r["status"] for r in rows] == ["ok", "infeasible"]


def _least(m, q):
    from pkmdyn.multibody.kinematics.singularity.measures import singularity_measures

    sm = singularity_measures(m, q)
    least = np.minimum(sm.inverse, sm.constraint)
    return np.minimum(least, sm.direct) if m.na == m.nt else least


@pytest.mark.parametrize("name", ["stewart", "delta", "rrr3", "bennett"])
def test_the_cheap_measure_bounds_hold_and_decide(name):
    """``least_measure_bounds``: where it proves the least singularity measure above a level, the
    singular values agree; its upper bound is never below the measure; and at a level below the
    measure by the factor its proof may lose (the square root of the coordinates, twice over)
    it proves every pose; with ``tight``, at 0.9 of each pose's own measure."""
    from pkmdyn.multibody import default_motion
    from pkmdyn.multibody.kinematics.singularity.measures import least_measure_bounds

    m = load_mechanism(MACHINES / name / f"{name}.toml")
    mo = default_motion(m)
    q = solve_kinematics(m, mo.x, mo.xd, mo.xdd, mo.t).q
    least = _least(m, q)
    for f in (0.25, 0.5, 0.9, 1.0, 1.1, 2.0):
        level = f * float(np.median(least))
        for tight in (False, True):
            passed, upper = least_measure_bounds(m, q, level, tight=tight)
            assert np.all(least[passed] > level)
            assert np.all(upper >= least * (1.0 - 1e-12))
    passed, _ = least_measure_bounds(m, q, float(least.min()) / (2.0 * np.sqrt(m.nq)))
    assert passed.all()
    # tight: the largest singular values bounded within 12 % at worst (a proof at 1.25 times
    # a lower bound of the largest eigenvalue at the most), so every pose is proven above 0.9
    # of its own measure
    for k in range(0, len(q), max(1, len(q) // 25)):
        assert least_measure_bounds(m, q[k:k + 1], 0.9 * float(least[k]), tight=True)[0][0]


@pytest.mark.parametrize("name, axes, base", [
    ("stewart", [(0, np.linspace(-0.4, 0.4, 8)), (1, np.linspace(-0.4, 0.4, 8)), (2, np.linspace(0.7, 1.3, 8))], None),
    ("delta", [(0, np.linspace(-0.85, 0.85, 14)), (1, np.linspace(-0.85, 0.85, 14))], [0.0, 0.0, -1.25]),
    ("rrr3", [(0, np.linspace(-0.4, 0.4, 9)), (2, np.linspace(-1.5, 1.5, 9))], None),
])
def test_the_least_measure_route_gives_the_workspace_of_every_measure(name, axes, base):
    """``measures="least"`` and ``"none"`` (a sweep's workspace): the same reached and inside
    poses and size as every pose's singular values give, and (``"least"``) the same least
    measure over the inside poses, at the default threshold and at one that cuts through the
    measures (where the bounds decide nothing and the measures are computed)."""
    m = load_mechanism(MACHINES / name / f"{name}.toml")
    base = None if base is None else np.array(base)
    full = workspace(m, axes, base, threshold=1e-3)
    cut = float(np.quantile(full.measure[full.reached], 0.3))
    for threshold in (1e-3, cut):
        ref = workspace(m, axes, base, threshold=threshold)
        assert ref.inside.sum() > 5
        for mode in ("least", "none"):
            ws = workspace(m, axes, base, threshold=threshold, measures=mode)
            assert np.array_equal(ws.reached, ref.reached) and np.array_equal(ws.inside, ref.inside)
            assert ws.size == ref.size and ws.measure is None
        assert workspace(m, axes, base, threshold=threshold, measures="least").least_measure == pytest.approx(
            ref.measure[ref.inside].min(), rel=1e-12)
        assert ws.least_measure is None


def _delta_inside(p):
    """Which positions ``p (n, 3)`` the Delta robot reaches with every arm within its limits
    ([-1.2, 1.5] rad, the description's), by its closed-form arm angles."""
    g = delta.williams_irb360_geometry()
    with np.errstate(invalid="ignore"):
        th = delta.inverse_kinematics(p, g["R_b"], g["R_p"], g["L_A"], g["L_B"])
    return np.all(np.isfinite(th) & (np.nan_to_num(th) >= -1.2) & (np.nan_to_num(th) <= 1.5), axis=1)


def _size_and_error(inside, cell):
    """An oracle grid's size (inside points times the cell) and its error estimate (half the
    cells with a neighbour of the other state along an axis), ``inside`` shaped as the grid."""
    edge = np.zeros_like(inside)
    for ax in range(inside.ndim):
        d = np.diff(inside.astype(np.int8), axis=ax) != 0
        lo, hi = [slice(None)] * inside.ndim, [slice(None)] * inside.ndim
        lo[ax], hi[ax] = slice(0, -1), slice(1, None)
        edge[tuple(lo)] |= d
        edge[tuple(hi)] |= d
    return inside.sum() * cell, 0.5 * edge.sum() * cell


def _oracle_area(name, base, half, count):
    """The constant-orientation area at ``base``'s other coordinates over the square of
    half-width ``half`` by the closed-form inverse kinematics (every actuated joint within its
    limits; the Delta's arms also within reach) on a fine ``count x count`` grid, with its own
    error estimate (half the boundary's cells)."""
    v = np.linspace(-half, half, count)
    X, Y = np.meshgrid(v, v, indexing="ij")
    x = np.tile(base, (count * count, 1))
    x[:, 0], x[:, 1] = X.reshape(-1), Y.reshape(-1)
    inside = _stewart_inside(x, 0.0)[0] if name == "stewart" else _delta_inside(x[:, :3])
    return _size_and_error(inside.reshape(count, count), (v[1] - v[0]) ** 2)


@pytest.mark.parametrize("name, half, pose", [
    ("stewart", 0.6, {2: 0.95}),
    ("stewart", 0.6, {2: 1.15, 5: 0.2}),
    ("delta", 1.2, {2: -1.25}),  # its boundary partly the arms' limits, partly their reach
])
def test_the_refined_size_against_the_closed_form(name, half, pose):
    """A constant-orientation area on a coarse 13 x 13 grid, refined by the boundary's
    crossings of its edges (8 steps an edge), against the area of the closed-form inverse
    kinematics on a 601 x 601 grid: within the two error estimates, and the refined estimate
    far below the count's (which covers the same area)."""
    m = load_mechanism(MACHINES / name / f"{name}.toml")
    base = reference_task(m)
    for i, v in pose.items():
        base[i] = v
    axes = [(0, np.linspace(-half, half, 13)), (1, np.linspace(-half, half, 13))]
    count = workspace(m, axes, base, threshold=0.0)
    refined = workspace(m, axes, base, threshold=0.0, refine=8)
    step = 2 * half / 12
    area, area_error = _oracle_area(name, base, half + step / 2, 601)  # the cells reach half a step beyond
    assert refined.refine == 8 and np.array_equal(refined.inside, count.inside)
    assert 40 < count.inside.sum() < 13 * 13 - 20  # the boundary lies inside the grid
    assert abs(refined.size - area) <= refined.size_error + area_error
    assert abs(count.size - area) <= count.size_error + area_error
    assert refined.size_error < 0.25 * count.size_error


def test_the_refined_volume_of_the_delta_against_the_closed_form():
    """The Delta robot's volume on the 13 x 13 x 9 grid of the sweep benchmark (singularity
    threshold 0: reach and arm limits), refined (4 steps an edge), against the volume of its
    closed-form arm angles within their limits on a 121 x 121 x 121 grid of the same box (the
    coarse cells' extent), with that grid's own error estimate (half its boundary cells):
    within the two estimates, the refined estimate under half the count's."""
    m = load_mechanism(MACHINES / "delta" / "delta.toml")
    axes = [(0, np.linspace(-1.5, 1.5, 13)), (1, np.linspace(-1.5, 1.5, 13)), (2, np.linspace(-2.2, -0.2, 9))]
    count = workspace(m, axes, threshold=0.0, measures="none")
    refined = workspace(m, axes, threshold=0.0, measures="none", refine=4)
    xs, zs = np.linspace(-1.625, 1.625, 121), np.linspace(-2.325, -0.075, 121)
    X, Y, Z = np.meshgrid(xs, xs, zs, indexing="ij")
    inside = _delta_inside(np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])).reshape(X.shape)
    volume, volume_error = _size_and_error(inside, (xs[1] - xs[0]) ** 2 * (zs[1] - zs[0]))
    assert 100 < count.inside.sum() < 1000  # the boundary lies inside the grid
    assert abs(refined.size - volume) <= refined.size_error + volume_error
    assert abs(count.size - volume) <= count.size_error + volume_error
    assert refined.size_error < 0.5 * count.size_error


def test_the_refined_size_of_a_segment_and_a_box():
    """The refined size's sum on given crossings, against the lengths they put the boundary
    at: a segment of three inside poses whose ends cross at fractions t1, t2 of the edges out
    is (2 + t1 + t2) steps long; a box of 3 x 2 x 1 inside poses whose faces along axis d cross
    at fraction t_d is, along each axis's lines, its length (the poses' extent plus 2 t_d steps)
    times the lines' cross-section (the other axes' inside cells), and the size their mean."""
    from pkmdyn.multibody.analyses.workspace import _edges, refined_size

    inside = np.array([False, True, True, True, False])
    a, _, axis = _edges(inside, (5,))
    frac = np.where(a == 1, 0.3, 0.8)
    size, error = refined_size(inside, (5,), a, axis, frac, 0.1, 8)
    assert size == pytest.approx(0.1 * (2 + 0.3 + 0.8), rel=1e-12)
    assert error == pytest.approx(0.1 * 2 / (2 * 8), rel=1e-12)  # a line's length has no quadrature error

    shape, cell = (5, 4, 3), 0.1 * 0.2 * 0.3
    box = np.zeros(shape, dtype=bool)
    box[1:4, 1:3, 1:2] = True
    a, _, axis = _edges(box.reshape(-1), shape)
    t = np.array([0.3, 0.6, 0.2])
    size, error = refined_size(box.reshape(-1), shape, a, axis, t[axis], cell, 8)
    counts = np.array([3, 2, 1])
    extent = counts - 1 + 2 * t  # in steps
    per_axis = [extent[d] * np.prod(np.delete(counts, d)) * cell for d in range(3)]
    assert len(a) == 2 * (2 * 1 + 3 * 1 + 3 * 2)
    assert size == pytest.approx(np.mean(per_axis), rel=1e-12)
    # the error estimate: the lines along d are all extent[d] long over the box's cross-section
    # and empty around it, so along each transverse axis e each row of lines has second
    # differences summing to 4 extent[d]; there are as many rows as the third axis's count
    quad = [sum(4 * extent[d] * np.prod(np.delete(counts, [d, e])) for e in range(3) if e != d) / 8 for d in range(3)]
    assert error == pytest.approx(cell * (np.mean(quad) + len(a) / (2 * 8 * 3)), rel=1e-12)


def test_the_refined_size_moves_with_the_boundary():
    """As the Stewart platform's height changes in steps of 0.2 mm (the area by some 6 % of a
    cell a step), the count of inside poses jumps by whole cells; the refined size moves by a
    small part of a cell at each step (each crossing moving by one step of its edge changes it
    by 1/16 of a cell over two axes)."""
    m = load_mechanism(MACHINES / "stewart" / "stewart.toml")
    axes = [(0, np.linspace(-0.6, 0.6, 13)), (1, np.linspace(-0.6, 0.6, 13))]
    cell = 0.1 * 0.1
    counts, sizes = [], []
    for h in np.arange(1.20, 1.22, 0.0002):
        base = reference_task(m)
        base[2] = h
        counts.append(workspace(m, axes, base, threshold=0.0).size)
        sizes.append(workspace(m, axes, base, threshold=0.0, refine=8).size)
    jumps, moves = np.abs(np.diff(counts)), np.abs(np.diff(sizes))
    assert jumps.max() >= cell * (1 - 1e-9)  # the count moves in whole cells
    assert moves.max() < 0.25 * cell


def test_a_workspace_that_reaches_the_grids_edge_is_a_lower_bound(tmp_path, capsys):
    """Inside poses on the grid's edge: the size is said to be a lower bound (workspace.json and
    one warning line naming the coordinates); a grid wide enough says nothing of the kind."""
    import json

    from pkmdyn.cli import main

    assert main(["workspace", "--machine", "delta", "--grid", "x=-0.1:0.1:5,y=-0.1:0.1:5", "--pose", "z=-1.0",
                 "--out", str(tmp_path / "small")]) == 0
    err = capsys.readouterr().err
    doc = json.loads((tmp_path / "small" / "workspace.json").read_text())
    assert doc["size_is_lower_bound"] and doc["inside_at_grid_edge"] == ["x_m", "y_m"]
    assert "lower bound" in err and "x_m, y_m" in err
    assert main(["workspace", "--machine", "delta", "--grid", "x=-2:2:9,y=-2:2:9", "--pose", "z=-1.0",
                 "--out", str(tmp_path / "wide")]) == 0
    doc = json.loads((tmp_path / "wide" / "workspace.json").read_text())
    assert not doc["size_is_lower_bound"] and doc["inside_at_grid_edge"] == []
    assert "lower bound" not in capsys.readouterr().err


def test_the_grids_pose_cap_is_a_limit_like_the_others(tmp_path, capsys):
    """``max_workspace_poses`` (``[limits]``, ``--limit``): a grid over it is refused naming the
    limit and how to raise it, nothing written; raised by ``--limit`` or by the description, the
    same grid runs."""
    import tomllib

    from pkmdyn.io import dumps_toml
    from pkmdyn.machines.registry import description_path

    grid = ["--grid", "x=-0.1:0.1:6,y=-0.1:0.1:5", "--pose", "z=-1.0"]  # 30 poses
    out = tmp_path / "ws"
    d = tomllib.loads(description_path("delta").read_text(encoding="utf-8"))
    d.setdefault("limits", {})["max_workspace_poses"] = 29
    capped = tmp_path / "capped.toml"
    capped.write_text(dumps_toml(d), encoding="utf-8")
    assert main(["workspace", "--machine", str(capped), *grid, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "more than 29 poses" in err and "--limit max_workspace_poses=N" in err and err.count("\n") == 1
    assert not out.exists()
    assert main(["workspace", "--machine", str(capped), *grid, "--limit", "max_workspace_poses=30",
                 "--out", str(out)]) == 0
    assert json.loads((out / "workspace.json").read_text())["poses"] == 30
    capsys.readouterr()
    assert main(["workspace", "--machine", "delta", *grid, "--limit", "max_workspace_poses=29",
                 "--out", str(tmp_path / "b")]) == 2
    assert "more than 29 poses" in capsys.readouterr().err


def test_the_slices_titles_clear_the_labels_of_the_row_above():
    """A three-axis grid drawn as six slices in two rows: no slice's title box meets an axis
    label box of the row above, and every box lies inside the figure."""
    import matplotlib.pyplot as plt

    from pkmdyn.jobs.workspace import workspace_figure

    model = load_mechanism(MACHINES / "stewart" / "stewart.toml")
    z = reference_task(model)[2]
    axes = [(0, np.linspace(-0.2, 0.2, 4)), (3, np.linspace(-0.3, 0.3, 4)), (2, z + np.linspace(-0.1, 0.1, 6))]
    fig = workspace_figure(model, workspace(model, axes))
    try:
        fig.canvas.draw()
        r = fig.canvas.get_renderer()
        axs = [a for a in fig.axes if a.get_title()]
        assert len(axs) == 6
        whole = fig.bbox
        for upper in axs[:3]:
            label = upper.xaxis.label.get_window_extent(r)
            ticks = upper.xaxis.get_tightbbox(r)
            for lower in axs[3:]:
                title = lower.title.get_window_extent(r)
                assert not title.overlaps(label) and not title.overlaps(ticks)
        for a in axs:
            for box in (a.title.get_window_extent(r), a.xaxis.label.get_window_extent(r),
                        a.yaxis.label.get_window_extent(r)):
                assert whole.x0 - 1 <= box.x0 and box.x1 <= whole.x1 + 1
                assert whole.y0 - 1 <= box.y0 and box.y1 <= whole.y1 + 1
    finally:
        plt.close(fig)
