"""Model files that attack the readers: FIFOs and devices where a file is expected, a 2 kB MJCF
asking for a million bodies through nested replicates, a URDF chain of 10,000 links (it crashed
the C++ parser's recursion), SDFormat chains of 60,000 links and of 3,000 ``relative_to`` poses;
each refused in one line, exit status 2, nothing written, before a parser builds it."""

from __future__ import annotations

import os

import pytest

from pkmdyn.cli import main

pytest.importorskip("mujoco")


def _refused(tmp_path, capsys, src, words, *extra):
    out = tmp_path / "out.toml"
    assert main(["import", "--from", str(src), "--out", str(out), *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0], err
    assert not out.exists()


MJCF = """<mujoco model="m">
  <worldbody>
    <body name="a" pos="0 0 1">
      <joint name="j" type="hinge" axis="0 0 1"/>
      <inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/>
    </body>{extra}
  </worldbody>
  <actuator><motor joint="j"/></actuator>
</mujoco>
"""


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")
def test_a_fifo_include_or_mesh_is_not_opened(tmp_path, capsys):
    fifo = tmp_path / "pipe.xml"
    os.mkfifo(fifo)
    src = tmp_path / "inc.xml"
    src.write_text(MJCF.format(extra='\n    <include file="pipe.xml"/>'))
    _refused(tmp_path, capsys, src, "include pipe.xml: not a regular file")
    os.mkfifo(tmp_path / "part.stl")
    src.write_text(MJCF.format(extra="").replace("<worldbody>", '<asset><mesh name="m" file="part.stl"/></asset>'
                                                               "<worldbody>"))
    _refused(tmp_path, capsys, src, "mesh file part.stl: not a regular file")
    _refused(tmp_path, capsys, fifo, "pipe.xml: not a regular file")


def test_nested_replicates_are_counted_before_mujoco_compiles(tmp_path, capsys):
    bomb = ('\n    <replicate count="1000" offset="0.1 0 0"><replicate count="1000" offset="0 0.1 0">'
            '<body name="b"><inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/></body></replicate></replicate>')
    src = tmp_path / "bomb.xml"
    src.write_text(MJCF.format(extra=bomb))
    assert src.stat().st_size < 2000
    _refused(tmp_path, capsys, src, "more than 300 bodies (replicates counted out) before MuJoCo compiles it")


def test_a_urdf_chain_of_ten_thousand_links(tmp_path, capsys):
    parts = ['<robot name="chain">', '<link name="l0"/>']
    for k in range(1, 10_001):
        parts.append(f'<link name="l{k}"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" '
                     'iyz="0"/></inertial></link>')
        parts.append(f'<joint name="j{k}" type="revolute"><parent link="l{k - 1}"/><child link="l{k}"/>'
                     '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>')
    src = tmp_path / "chain.urdf"
    src.write_text("\n".join(parts) + "</robot>")
    pytest.importorskip("pinocchio")
    _refused(tmp_path, capsys, src, "10,001 links and 10,000 joints; a description holds at most 300 bodies",
             "--actuated", "j1")


@pytest.mark.parametrize("links, frames, words", [(60_000, 0, "more than 200,000 elements"),
                                                  (1_000, 0, "1,000 links"), (2, 3_000, "3,000 frames")])
def test_long_sdformat_chains(tmp_path, capsys, links, frames, words):
    body = []
    for k in range(links):
        body.append(f'<link name="l{k}"><pose>0 0 {k * 0.01} 0 0 0</pose></link>')
    for k in range(1, links):
        body.append(f'<joint name="j{k}" type="revolute"><parent>l{k - 1}</parent><child>l{k}</child>'
                    '<axis><xyz>0 0 1</xyz></axis></joint>')
    for k in range(frames):
        body.append(f'<frame name="f{k}" attached_to="l0"><pose relative_to="{"f" + str(k - 1) if k else "l0"}">'
                    '0 0 0.001 0 0 0</pose></frame>')
    src = tmp_path / "chain.sdf"
    src.write_text('<sdf version="1.9"><model name="m">' + "".join(body) + "</model></sdf>")
    _refused(tmp_path, capsys, src, words, "--actuated", "j1")


@pytest.mark.parametrize("args, made", [
    (["export", "--machine", "stewart", "--format", "urdf"], ("e.urdf", "e.yaml")),
    (["export", "--machine", "stewart", "--format", "mjcf"], ("e.urdf",)),
])
def test_a_full_standard_output_leaves_no_file(tmp_path, capsys, monkeypatch, args, made):
    """The listing is printed before the files move into place: when it cannot be written (a
    full device), nothing is left, the URDF's sidecar included."""
    import errno

    import click

    echo = click.echo

    def full(*a, err=False, **k):
        if err:
            return echo(*a, err=True, **k)
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(click, "echo", full)
    out = tmp_path / "e.urdf"
    assert main([*args, "--out", str(out)]) == 2
    assert "standard output: cannot write" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == []
    monkeypatch.undo()
    assert main([*args, "--out", str(out)]) == 0
    assert all((tmp_path / m).is_file() for m in made)
