"""The report layer without a browser: scenes agree with the machines' kinematics and exported
poses, decimation keeps what matters, topology loops are cycles, pages are single files that
refuse to replace what pkmdyn did not write; and the PNG fixes of issue 18."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from pkmdyn.cli import main
from pkmdyn.errors import ParameterError, PkmdynError
from pkmdyn.machines.hip_simulator import load_params as hip_params
from pkmdyn.machines.pdm4.paper import JOINTS
from pkmdyn.machines.pdm4.params import load_params as pdm_params
from pkmdyn.machines.pdm4.scene import pdm_scene_from_pose, pdm_topology
from pkmdyn.report import (MAX_FRAMES, Curve, Scene, SceneBody, TimePlot, Topology, decimate_minmax,
                           frame_indices, fundamental_loops, scene_from_files, topology_from_model, write_report)


def _info(page: str) -> dict:
    return json.loads(re.search(r"window\.PKMDYN_REPORT = (\{.*?\});</script>", page).group(1))


# ----------------------------------------------------------------------------- scenes
def test_scene_refuses_inconsistent_shapes_and_points():
    t = np.zeros(2)
    with pytest.raises(ParameterError, match="points must be"):
        Scene(t, np.zeros((3, 2, 3)), ("a", "b"), ())
    with pytest.raises(ParameterError, match="outside"):
        Scene(t, np.zeros((2, 2, 3)), ("a", "b"), (SceneBody("x", (0, 2)),))
    with pytest.raises(PkmdynError, match="not finite"):
        Scene(t, np.full((2, 2, 3), np.nan), ("a", "b"), ())


@pytest.mark.parametrize("n", [1, 2, 299, 300, 301, 10_000_001])
def test_frame_indices_are_evenly_spaced_with_both_ends(n):
    idx = frame_indices(n)
    assert idx.size == min(n, MAX_FRAMES) and idx[0] == 0 and idx[-1] == n - 1
    gaps = np.diff(idx)
    assert np.all(gaps >= 1) and (gaps.size == 0 or gaps.max() - gaps.min() <= 1)


@pytest.mark.parametrize("block", [1, 7, 1000, 50_000])
def test_frame_picker_over_blocks_equals_picking_from_the_whole(block):
    from pkmdyn.report import FramePicker

    n = 12_345
    data = np.arange(3 * n, dtype=float).reshape(n, 3)
    picker = FramePicker(n)
    for s in range(0, n, block):
        picker.add(s, t=data[s:s + block, 0], x=data[s:s + block])
    got = picker.arrays()
    idx = frame_indices(n)
    assert np.array_equal(got["x"], data[idx]) and np.array_equal(got["t"], data[idx, 0])


def _hip_model():
    from pkmdyn.machines.hip_simulator.description import hip_description
    from pkmdyn.multibody import load_mechanism

    return load_mechanism(hip_description(hip_params()))


def _hip_topology():
    from pkmdyn.multibody.columns import model_summary
    from pkmdyn.report import topology_from_model

    return topology_from_model(model_summary(_hip_model()))


def test_hip_scene_closes_every_leg_on_the_lever_length():
    """The hip run's scene (the engine's joint centres of the hip's description): the drawn levers
    join each slider to its platform joint at the lever length, sliders sit on their screws and
    platform joints at the platform radius, whatever the pose: the scene is the machine's geometry."""
    from pkmdyn.multibody import solve_kinematics
    from pkmdyn.multibody.scene import mechanism_scene

    model = hip_params()
    g = model.geometry
    m = _hip_model()
    rng = np.random.default_rng(1)
    angles = rng.uniform(-0.3, 0.3, size=(40, 3))
    kin = solve_kinematics(m, angles, np.zeros_like(angles), np.zeros_like(angles))
    tau = rng.normal(size=(40, 3))
    scene = mechanism_scene(m, np.linspace(0, 1, 40), kin.joint_point,
                            {f"P_{i}": (tau[:, i - 1], f"motor {i} torque", "N m") for i in (1, 2, 3)})
    ix = {n: k for k, n in enumerate(scene.point_names)}
    for j, platform in enumerate(("upper", "lower")):
        for i in (1, 2, 3):
            u, s = scene.points[:, ix[f"U_{platform}_{i}"]], scene.points[:, ix[f"S_{platform}_{i}"]]
            assert np.allclose(np.linalg.norm(s - u, axis=-1), g.l, atol=1e-12)
            assert np.allclose(u[:, :2], g.A[i - 1, :2], atol=1e-12)
            assert np.allclose(np.linalg.norm(s - g.o[j], axis=-1), g.e, atol=1e-12)
    # the carriage of module i is coloured by motor i's torque
    assert [a.label for a in scene.actuators] == ["motor 1 torque", "motor 2 torque", "motor 3 torque"]


def test_pdm_scene_from_poses_matches_the_exported_joint_points(tmp_path):
    """The scene a control run builds from poses equals the joint points ``pdm run`` exports."""
    out = tmp_path / "pdm"
    assert main(["pdm", "run", "--no-plots", "--out", str(out)]) == 0
    with np.load(out / "bodies.npz") as z:
        t, jp = z["t"], z["joint_point"]
    cols = np.genfromtxt(out / "results.csv", delimiter=",", names=True)
    q = np.stack([cols["x_m"], cols["y_m"], cols["alpha_rad"], cols["gamma_rad"]], axis=-1)
    idx = frame_indices(t.size, 40)
    scene = pdm_scene_from_pose(pdm_params(), t[idx], q[idx], np.zeros((idx.size, 4)))
    assert np.allclose(scene.points[:, : len(JOINTS)], jp[idx], atol=1e-9)
    # the generic reader of model.json + bodies.npz (any multibody run) gives the same joint points
    generic = scene_from_files(out / "model.json", out / "bodies.npz")
    assert np.allclose(generic.points[idx], jp[idx])
    chains = {a.name: [generic.point_names[p] for p in a.points] for a in pdm_scene_from_pose(
        pdm_params(), t[:1], q[:1], np.ones((1, 4))).actuators}
    assert chains["P11"] == ["R41", "P11", "R21'"] and chains["P24"] == ["S24", "P24", "U24"]
    # a model.json that marks its actuated and cut joints (a described mechanism's) is read as such
    doc = json.loads((out / "model.json").read_text())
    for j in doc["joints"]:
        j["actuated"] = j["name"] in ("P11", "P12", "P23", "P24")
        j["cut"] = j["name"] in ("R21'", "R22'", "R32", "U23", "U24")
    (out / "model.json").write_text(json.dumps(doc))
    marked = scene_from_files(out / "model.json", out / "bodies.npz")
    assert sorted(a.name for a in marked.actuators) == ["P11", "P12", "P23", "P24"]
    top = topology_from_model(doc)
    assert top.actuated == pdm_topology().actuated and set(top.cuts) == set(pdm_topology().cuts)
    assert len(fundamental_loops(top)) == 5


# ----------------------------------------------------------------------------- decimation, topology
def test_minmax_decimation_keeps_the_extremes_of_every_curve():
    t = np.linspace(0, 1, 100_001)
    rng = np.random.default_rng(2)
    a, b = rng.normal(size=t.size), np.sin(40 * t) + 1e-3 * rng.normal(size=t.size)
    a[77_777] = 50.0
    td, (ad, bd), dropped = decimate_minmax(t, [a, b], max_points=4000)
    assert dropped and td.size <= 4002 and np.all(np.diff(td) > 0)
    assert ad.max() == a.max() and ad.min() == a.min() and bd.max() == b.max() and bd.min() == b.min()


@pytest.mark.parametrize("top, loops", [(pdm_topology(), 5), (_hip_topology(), 6)])
def test_each_cut_joint_closes_one_cycle(top, loops):
    found = fundamental_loops(top)
    assert len(found) == loops == len(top.joints) - len(top.bodies) + 1
    by_name = {j[0]: j for j in top.joints}
    for loop in found:
        body = by_name[loop[0]][3]  # walk the cycle from the cut joint's second body
        for name in loop[1:]:
            _, _, a, b = by_name[name]
            assert body in (a, b)
            body = b if body == a else a
        assert body == by_name[loop[0]][2]
    # without named cuts, a spanning tree's chords give the same number of loops
    assert len(fundamental_loops(Topology(top.joints, top.ground))) == loops


def test_topology_refuses_cuts_that_do_not_leave_a_tree():
    top = pdm_topology()
    with pytest.raises(ParameterError, match="spanning tree"):
        fundamental_loops(Topology(top.joints, "ground", top.actuated, top.cuts[:-1]))


# ----------------------------------------------------------------------------- pages
def test_report_is_one_file_with_one_copy_of_plotly_and_decimated_frames(tmp_path):
    from plotly.offline import get_plotlyjs

    n = 5000
    t = np.linspace(0, 10, n)
    pts = np.zeros((n, 3, 3))
    pts[:, 1, 0] = np.cos(t)
    pts[:, 2, 1] = np.sin(t)
    from pkmdyn.report import SceneActuator

    scene = Scene(t, pts, ("a", "b", "c"), (SceneBody("link", (0, 1, 2), closed=True, filled=True),),
                  (SceneActuator("m", (0, 1), np.sin(t), "motor torque", "N m"),))
    path = write_report(tmp_path, title="test <run>", scene=scene,
                        plots=[TimePlot("y", "y [1]", t, (Curve("sin", np.sin(t)),))], summary={"a": {"b": 1.5}},
                        parameters="[geometry]\nx = 1", warnings=["a warning & more"])
    page = path.read_text(encoding="utf-8")
    assert path.name == "report.html" and page.count(get_plotlyjs()[:200]) == 1
    info = _info(page)
    assert info["frames"] == MAX_FRAMES and info["samples"] == n and len(info["times"]) == MAX_FRAMES
    assert f"Decimated: {MAX_FRAMES} frames" in page
    assert "test &lt;run&gt;" in page and "a warning &amp; more" in page
    assert not re.search(r"<(script|link|img|iframe)[^>]*(src|href)=\"(?!data:)", page)  # nothing fetched from elsewhere


def test_long_hip_run_report_stays_light(tmp_path):
    out = tmp_path / "hip"
    assert main(["hip", "run", "--cycles", "2", "--samples-per-cycle", "30000", "--no-plots", "--out", str(out)]) == 0
    page = (out / "report.html").read_text(encoding="utf-8")
    info = _info(page)
    assert info["frames"] == MAX_FRAMES and info["samples"] == 30_001
    assert "Decimated" in page and "envelope (min-max)" in page
    assert (out / "report.html").stat().st_size < 8_000_000


def test_view_page_is_written_atomically_and_replaces_only_its_own_file(tmp_path):
    page = tmp_path / "sub" / "hip.html"
    assert main(["view", "--machine", "hip", "--out", str(page)]) == 0
    text = page.read_text(encoding="utf-8")
    assert "independent loops" in text and "over-constraints" in text
    assert main(["view", "--machine", "hip", "--out", str(page)]) == 0  # its own page: replaced
    other = tmp_path / "notes.html"
    other.write_text("<html>mine</html>", encoding="utf-8")
    assert main(["view", "--machine", "pdm", "--out", str(other)]) == 2
    assert other.read_text(encoding="utf-8") == "<html>mine</html>"
    assert main(["view", "--machine", "pdm", "--out", str(tmp_path)]) == 2
    link = tmp_path / "link.html"
    link.symlink_to(page)
    assert main(["view", "--machine", "pdm", "--out", str(link)]) == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.html", "notes.html", "sub"]


def test_view_page_of_a_described_mechanism(tmp_path, capsys):
    """``view --machine`` takes every machine the registry knows and any description file: the
    Bennett linkage's page states its rank mobility 1 and its 3 over-constraints, draws its
    four joints at the reference configuration, and holds the description; ``--params``
    belongs to the hand-built machines and an unknown name is refused, nothing written."""
    import re

    from pkmdyn.machines.registry import described_machines
    from pkmdyn.multibody import load_mechanism

    page = tmp_path / "bennett.html"
    assert main(["view", "--machine", "bennett", "--out", str(page)]) == 0
    text = page.read_text(encoding="utf-8")
    rep = load_mechanism(described_machines()["bennett"]).topology
    assert (rep.mobility, rep.overconstraints) == (1, 3)
    assert re.search(r"mobility \(rank, reference configuration\)</th><td>1<", text)
    assert re.search(r"over-constraints</th><td>3<", text)
    assert described_machines()["bennett"].read_text(encoding="utf-8").splitlines()[0] in text
    capsys.readouterr()
    for args in (["--machine", "stewart", "--params", str(page)], ["--machine", "no-such-machine"]):
        out = tmp_path / "refused.html"
        assert main(["view", *args, "--out", str(out)]) == 2
        assert len(capsys.readouterr().err.strip().splitlines()) == 1 and not out.exists()


def test_control_run_report_and_effort_plot_name_the_actuators(tmp_path, monkeypatch):
    """The efforts PNG says "limb l11 force [N]", not the column name ``f1_N``; so does the page."""
    import matplotlib.figure

    seen = {}
    savefig = matplotlib.figure.Figure.savefig

    def spy(fig, fname, *args, **kwargs):
        if str(fname).endswith("efforts.png"):
            ax = fig.axes[0]
            seen["legend"] = [t.get_text() for t in ax.get_legend().get_texts()]
            seen["ylabel"] = ax.get_ylabel()
        return savefig(fig, fname, *args, **kwargs)

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", spy)
    out = tmp_path / "ctl"
    assert main(["pdm", "control", "--controller", "pid", "--cycles", "0.2", "--out", str(out)]) == 0
    assert seen["legend"] == [f"limb {k} force [N]" for k in ("l11", "l12", "l23", "l24")]
    assert seen["ylabel"] == "force [N]"
    page = (out / "report.html").read_text(encoding="utf-8")
    assert "limb l11 force" in page and _info(page)["frames"] > 100


# ----------------------------------------------------------------------------- PNG fixes
def test_schematic_title_fits_and_the_legend_hides_no_label(tmp_path):
    import shutil

    from matplotlib.transforms import Bbox

    from pkmdyn.machines.pdm4.params import default_params_path
    from pkmdyn.machines.pdm4.schematic import schematic_figure

    long_dir = tmp_path.joinpath(*(["a_long_folder_name"] * 12))
    long_dir.mkdir(parents=True)
    params = long_dir / "my_pdm_parameters.toml"
    shutil.copy(default_params_path(), params)
    for model in (pdm_params(), pdm_params(params)):
        fig = schematic_figure(model)
        fig.savefig(tmp_path / "s.png", dpi=110)  # lays the figure out
        r = fig.canvas.get_renderer()
        page = Bbox.from_bounds(0, 0, *fig.canvas.get_width_height())
        title = fig._suptitle.get_window_extent(r)
        assert page.x0 <= title.x0 and title.x1 <= page.x1 and title.y1 <= page.y1, "title clipped"
        legend = fig.legends[0].get_window_extent(r)
        for ax in fig.axes:
            for label in (ax.xaxis.label, ax.yaxis.label):
                assert not legend.overlaps(label.get_window_extent(r)), f"legend over {label.get_text()!r}"


def test_workspace_layers_have_distinct_colours():
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.colors import to_hex

    from pkmdyn.machines.pdm4.plots import workspace_figure
    from pkmdyn.machines.pdm4.workspace import reachable_workspace

    ws = reachable_workspace(pdm_params())
    fig = workspace_figure(ws)
    FigureCanvasAgg(fig)
    layers = int(np.sum(ws.valid))
    assert layers >= 13
    projection = fig.axes[1]
    colours = [to_hex(line.get_color()) for line in projection.get_lines() if line.get_label() != "projection boundary"]
    assert len(colours) == layers and len(set(colours)) == layers


def test_effort_labels_name_the_actuator_not_the_column():
    from pkmdyn.jobs.control import effort_label

    assert effort_label("hip", 0) == ("motor 1 torque", "N m")
    assert effort_label("pdm", 3) == ("limb l24 force", "N")
