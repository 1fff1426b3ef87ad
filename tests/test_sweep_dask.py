"""Design sweeps on Dask: rows bit-identical to the serial run, a worker killed mid-run, a batch
that fails once and is retried, Ctrl-C and a rerun."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

pq = pytest.importorskip("pyarrow.parquet")
distributed = pytest.importorskip("distributed")

import sweep_flaky  # noqa: E402  (a test adapter whose first batch fails once)

import pkmdyn  # noqa: E402
from pkmdyn.jobs.sweep import run_sweep  # noqa: E402
from pkmdyn.machines.registry import sweep_adapter  # noqa: E402

#: the folder holding the pkmdyn under test (the installed one, or the checkout's src/), for a
#: command run in a child process: the same package and so the same compiled kernels' cache
SRC = Path(pkmdyn.__file__).resolve().parents[1]

HIP_SPACE = """
[sampling]
method = "lhs"
designs = {designs}
seed = 11
batch_size = {batch}

[motion]
samples_per_cycle = {samples}
workspace_points = 32

[parameters]
"geometry.base_radius_m" = {{ min = 0.22, max = 0.32 }}
"geometry.lever_length_m" = {{ min = 0.15, max = 0.40 }}
"inertia.platform_mass_kg" = {{ min = 0.0, max = 20.0 }}

[constraints]
peak_drive_force_N = {{ max = 300.0 }}

[objectives]
peak_drive_force_N = "min"
max_spherical_angle_deg = "min"
"""


def _space(tmp_path: Path, designs: int, batch: int, samples: int, name: str = "space.toml") -> Path:
    p = tmp_path / name
    p.write_text(textwrap.dedent(HIP_SPACE.format(designs=designs, batch=batch, samples=samples)), encoding="utf-8")
    return p


def _parts(out: Path) -> list[Path]:
    return sorted((out / "parts").glob("part-*.parquet")) if (out / "parts").is_dir() else []


def _table(out: Path):
    return pq.read_table(out / "designs.parquet")


def test_the_first_design_runs_alone_on_one_worker_of_each_host():
    """A kernel missing from a host's cache is compiled by one worker there, never by all of
    them at once into the one cache: the first design of the first batches alone, one worker of
    each host (the rest waits for it)."""
    from pkmdyn.sweep.execute import _one_worker_per_host

    workers = {"tcp://10.0.0.2:4001": {"host": "10.0.0.2"}, "tcp://10.0.0.1:4003": {"host": "10.0.0.1"},
               "tcp://10.0.0.1:4002": {"host": "10.0.0.1"}, "tcp://10.0.0.3:4005": {}}
    assert _one_worker_per_host(workers) == ["tcp://10.0.0.1:4002", "tcp://10.0.0.2:4001", "tcp://10.0.0.3:4005"]
    assert _one_worker_per_host({}) == []


def test_serial_and_dask_rows_bit_identical(tmp_path):
    space = _space(tmp_path, 40, 7, 100)
    ad = sweep_adapter("hip")
    serial = run_sweep(ad, space, tmp_path / "serial", workers=0, plots=False)
    dask = run_sweep(ad, space, tmp_path / "dask", workers=2, batch_size=5, plots=False)
    assert dask.stats.mode == "dask" and dask.stats.workers == 2
    a, b = _table(tmp_path / "serial"), _table(tmp_path / "dask")
    assert a.equals(b)  # every column, nulls and bits included
    assert set(a.column("status").to_pylist()) >= {"ok", "infeasible"}
    assert serial.best_design_id == dask.best_design_id
    assert (tmp_path / "serial" / "best_params.toml").read_bytes() == (tmp_path / "dask" / "best_params.toml").read_bytes()


def test_pdm_serial_and_dask_rows_bit_identical(tmp_path):
    space = tmp_path / "pdm.toml"
    space.write_text(textwrap.dedent("""
        [sampling]
        method = "random"
        designs = 6
        seed = 5
        [parameters]
        "geometry.coupler_length_m" = { min = 0.22, max = 0.26 }
        "geometry.u_joint_height_m" = { min = 0.08, max = 0.12 }
        [objectives]
        peak_force_N = "min"
        gci = "max"
        """), encoding="utf-8")
    ad = sweep_adapter("pdm")
    run_sweep(ad, space, tmp_path / "serial", workers=0, plots=False)
    run_sweep(ad, space, tmp_path / "dask", workers=1, batch_size=2, plots=False)
    assert _table(tmp_path / "serial").equals(_table(tmp_path / "dask"))


@pytest.mark.slow
def test_a_local_cluster_is_silent_when_the_dashboard_port_is_taken(tmp_path):
    # another cluster (or anything) on Dask's default HTTP port 8787: the sweep's own cluster
    # must not warn about it on stderr (a sweep's stderr is its progress and its one-line errors)
    held = socket.socket()
    held.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        held.bind(("0.0.0.0", 8787))
        held.listen()
    except OSError:
        pass  # taken already: the situation under test
    try:
        space = _space(tmp_path, 4, 2, 60)
        env = {**os.environ, "PYTHONPATH": str(SRC) + os.pathsep + os.environ.get("PYTHONPATH", "")}
        cmd = [sys.executable, "-m", "pkmdyn.cli", "sweep", "--machine", "hip", "--space", str(space),
               "--out", str(tmp_path / "out"), "--workers", "1", "--no-plots"]
        done = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=300)
    finally:
        held.close()
    assert done.returncode == 0, done.stderr
    assert "8787" not in done.stderr and "Warning" not in done.stderr, done.stderr
    assert (tmp_path / "out" / "designs.parquet").is_file()


def test_worker_killed_mid_run_every_design_exactly_once(tmp_path):
    from distributed import LocalCluster

    space = _space(tmp_path, 240, 6, 1500)
    ad = sweep_adapter("hip")
    run_sweep(ad, space, tmp_path / "serial", workers=0, plots=False)
    out = tmp_path / "dask"
    killed: dict[str, int] = {}
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        # the worker processes' ids from their nannies (a second client in this process would
        # share the sweep's event loop)
        pids = {name: nanny.process.process.pid for name, nanny in cluster.workers.items()}

        def kill_one() -> None:
            deadline = time.monotonic() + 120
            while time.monotonic() < deadline:
                parts = _parts(out)
                if parts:
                    killed["parts_before"] = len(parts)
                    pid = next(iter(pids.values()))
                    os.kill(pid, signal.SIGKILL)
                    killed["pid"] = pid
                    return
                time.sleep(0.005)

        thread = threading.Thread(target=kill_one)
        thread.start()
        report = run_sweep(ad, space, out, scheduler=cluster.scheduler_address, plots=False)
        thread.join()
    assert "pid" in killed and killed["parts_before"] < 40  # killed while batches were still to come
    assert report.evaluated == 240
    ids = np.concatenate([pq.read_table(p).column("design_id").to_numpy() for p in (out / "parts").iterdir()])
    assert sorted(ids.tolist()) == list(range(240))  # every design exactly once
    assert _table(out).equals(_table(tmp_path / "serial"))


def test_a_failing_batch_is_retried(tmp_path):
    space = _space(tmp_path, 12, 4, 50)
    flag = tmp_path / "failed-once"
    adapter = SimpleNamespace(**{k: getattr(sweep_flaky, k) for k in
                                 ("NAME", "base_description", "check_description", "metrics", "evaluate")},
                              prepare=lambda d, o, b: sweep_flaky.prepare(d, o, b, flag))
    report = run_sweep(adapter, space, tmp_path / "out", workers=1, plots=False)
    assert flag.exists()  # the first attempt did fail
    assert report.evaluated == 12
    run_sweep(sweep_adapter("hip"), space, tmp_path / "plain", workers=0, plots=False)
    assert _table(tmp_path / "out").equals(_table(tmp_path / "plain"))


@pytest.mark.slow
def test_ctrl_c_then_rerun_loses_and_duplicates_nothing(tmp_path):
    space = _space(tmp_path, 300, 5, 1500)
    out = tmp_path / "out"
    env = {**os.environ, "PYTHONPATH": str(SRC) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    cmd = [sys.executable, "-m", "pkmdyn.cli", "sweep", "--machine", "hip", "--space", str(space), "--out", str(out),
           "--workers", "1", "--no-plots"]
    # its own process group, signalled whole, as a Ctrl-C at a terminal reaches the workers too
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and not _parts(out):
        time.sleep(0.01)
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "rerun the same command to resume" in err
    assert err.strip().count("\n") == 0, err  # one line: no worker's traceback
    done = sum(pq.read_metadata(p).num_rows for p in _parts(out))  # (the first part: the first design alone)
    assert 1 <= done < 300
    assert not (out / "designs.parquet").exists()
    report = run_sweep(sweep_adapter("hip"), space, out, workers=0, plots=False)
    assert report.evaluated == 300 - done
    run_sweep(sweep_adapter("hip"), space, tmp_path / "clean", workers=0, plots=False)
    assert _table(out).equals(_table(tmp_path / "clean"))
