"""Evaluating the designs in batches, in this process or on Dask, with Parquet part files.

A *batch* is a list of design ids; one task evaluates one batch and returns its rows as a
pyarrow table, which this process writes as one part file ``parts/part-<first id>.parquet``
(atomically: written under a temporary name and renamed, so an interrupted run never leaves
half a part). A rerun on the same output folder reads the design ids of the parts already
there and evaluates only the others, so no design is lost or evaluated into the results twice.

Rows depend on the design alone: each design is evaluated by itself from the same
description, never vectorised across the designs of a batch, so the same design gives a
bit-identical row whatever batch, worker or process computed it.
"""

from __future__ import annotations

import importlib
import logging
import math
import os
import signal
import threading
import time
import uuid
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import CancelledError
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import PkmdynError
from ..io import atomic_file
from ..sweep_protocol import STATUSES, DesignOutcome, MetricInfo
from .space import Bound, Parameter, design_description

__all__ = ["BatchJob", "run_batch", "make_batches", "finished_ids", "execute", "Executor", "part_schema",
           "PARTS_DIR", "default_batch_size", "ExecutionStats"]

Array = NDArray[np.float64]
PARTS_DIR = "parts"
#: statuses whose motion was followed to its end (every pose reached, no singularity)
_REACHED = ("ok", "infeasible", "limit")


@dataclass(frozen=True)
class BatchJob:
    """Everything a worker needs besides the batch itself; sent once to every worker."""

    evaluate: Callable[[Sequence[Mapping[str, Any]], Any], list[DesignOutcome]]
    context: Any
    base: Mapping[str, Any]
    parameters: tuple[Parameter, ...]
    metrics: tuple[MetricInfo, ...]
    constraints: tuple[Bound, ...]
    #: designs of the first sample and of each refinement round (for the ``round`` column)
    sample_designs: int = 0
    round_designs: int = 0

    def rounds(self, ids: Array) -> Array:
        """The round that made each design: 0 the sample, 1.. the refinement rounds."""
        ids = np.asarray(ids, dtype=np.int64)
        if self.round_designs == 0:
            return np.zeros_like(ids)
        return np.where(ids < self.sample_designs, 0, 1 + (ids - self.sample_designs) // self.round_designs)


def part_schema(job: BatchJob) -> Any:
    """The Arrow schema of every part file and of ``designs.parquet``."""
    import pyarrow as pa

    fields = [pa.field("design_id", pa.int64(), nullable=False), pa.field("round", pa.int64(), nullable=False)]
    fields += [pa.field(p.key, pa.int64() if p.integer else pa.float64(), nullable=False) for p in job.parameters]
    fields += [pa.field("status", pa.string(), nullable=False), pa.field("reason", pa.string(), nullable=False),
               pa.field("reachable", pa.bool_(), nullable=False), pa.field("feasible", pa.bool_(), nullable=False)]
    fields += [pa.field(m.name, pa.float64()) for m in job.metrics]
    return pa.schema(fields)


def _checked(job: BatchJob, outcome: DesignOutcome) -> tuple[str, str, list[float | None]]:
    """Status, reason and metric values of one design after the sweep's own checks: every
    metric of a usable design finite, then the constraints."""
    status, reason = outcome.status, outcome.reason
    if status not in STATUSES or status == "infeasible":
        raise PkmdynError(f"internal error: a machine adapter returned the status {status!r}")
    values: list[float | None] = []
    bad = ""
    for m in job.metrics:
        v = outcome.metrics.get(m.name)
        v = None if v is None else float(v)
        if v is not None and not math.isfinite(v):
            bad = bad or m.name
            v = None
        elif v is None and status == "ok":
            bad = bad or m.name
        values.append(v)
    if status == "ok" and bad:
        return "nonfinite", f"{bad} is not finite", [None] * len(values)
    if status == "ok":
        by_name = dict(zip((m.name for m in job.metrics), values))
        broken = [v for v in (b.violation(by_name[b.metric]) for b in job.constraints) if v]  # type: ignore[arg-type]
        if broken:
            return "infeasible", "; ".join(broken), values
    return status, reason, values


def run_batch(job: BatchJob, ids: Array, X: Array) -> Any:
    """Evaluate one batch of designs (ids ``(k,)``, values ``(k, d)``) -> a pyarrow table of rows."""
    import pyarrow as pa

    descriptions = [design_description(job.base, job.parameters, row) for row in X]
    outcomes = job.evaluate(descriptions, job.context)
    if len(outcomes) != len(descriptions):
        raise PkmdynError(f"internal error: {len(outcomes)} outcomes for {len(descriptions)} designs")
    rows = [_checked(job, o) for o in outcomes]
    cols: dict[str, Any] = {"design_id": np.asarray(ids, dtype=np.int64), "round": job.rounds(ids)}
    for j, p in enumerate(job.parameters):
        cols[p.key] = X[:, j].astype(np.int64) if p.integer else X[:, j].astype(np.float64)
    cols["status"] = [r[0] for r in rows]
    cols["reason"] = [" ".join(r[1].split()) for r in rows]
    cols["reachable"] = [r[0] in _REACHED for r in rows]
    cols["feasible"] = [r[0] == "ok" for r in rows]
    for k, m in enumerate(job.metrics):
        cols[m.name] = [r[2][k] for r in rows]
    return pa.table(cols, schema=part_schema(job))


def default_batch_size(todo: int, workers: int) -> int:
    """About eight tasks per worker (load balance, cheap retries), 10 to 250 designs each."""
    return max(10, min(250, math.ceil(todo / (8 * max(workers, 1)))))


def make_batches(todo: Array, size: int) -> list[Array]:
    """Consecutive runs of ``size`` ids of the sorted ``todo``."""
    return [todo[s:s + size] for s in range(0, todo.shape[0], size)]


def _part_name(ids: Array) -> str:
    return f"part-{int(ids[0]):09d}.parquet"


def finished_ids(parts: Path) -> Array:
    """Sorted design ids held by the part files of an earlier run (empty when none).

    Leftover temporary files of a killed run are removed; a part file that cannot be read is
    an error naming it (it can only come from outside: parts are written atomically).
    """
    import pyarrow.parquet as pq

    if not parts.is_dir():
        return np.zeros(0, dtype=np.int64)
    found = []
    for p in sorted(parts.iterdir()):
        if p.name.startswith(".") and ".partial-" in p.name:
            p.unlink(missing_ok=True)
            continue
        if not (p.name.startswith("part-") and p.name.endswith(".parquet")):
            continue
        try:
            found.append(pq.read_table(p, columns=["design_id"]).column(0).to_numpy())
        except Exception as exc:  # pyarrow raises several types for a damaged file
            raise PkmdynError(f"{p}: cannot read this part file ({type(exc).__name__}); delete it to "
                              "evaluate its designs again") from None
    if not found:
        return np.zeros(0, dtype=np.int64)
    return np.sort(np.concatenate(found))


def _write_part(parts: Path, table: Any) -> None:
    import pyarrow.parquet as pq

    ids = table.column("design_id").to_numpy()
    with atomic_file(parts / _part_name(ids), notify=None) as tmp:
        pq.write_table(table, str(tmp), compression="zstd")


@dataclass
class ExecutionStats:
    """Where the time went and how the designs were run.

    ``cluster_start_s``, ``evaluate_s``: wall-clock seconds of starting the cluster (and
    importing the model on every worker) and of the evaluation (batches dispatched, computed,
    part files written). ``driver_cpu_s``: CPU seconds of the calling process during the
    evaluation (with a local cluster it includes the scheduler); ``worker_cpu_s``: CPU seconds
    of all worker processes during the evaluation (0 in-process; ``None`` when a worker was
    replaced meanwhile, or the workers' CPU time cannot be read). CPU time is what the other
    load of a shared machine does not inflate.
    """

    mode: str = "serial"
    workers: int = 0
    batches: int = 0
    cluster_start_s: float = 0.0
    evaluate_s: float = 0.0
    driver_cpu_s: float = 0.0
    worker_cpu_s: float | None = 0.0
    extra: dict[str, Any] = field(default_factory=dict)


def _cpu_seconds() -> float:
    """CPU seconds (user + system, all threads) of the calling process."""
    t = os.times()
    return t.user + t.system


def _progress(total: int, done: int, enabled: bool | None) -> Any:
    from tqdm import tqdm

    return tqdm(total=total, initial=done, desc="sweep", unit="design", disable=None if enabled is None else not enabled,
                leave=False, smoothing=0.1)


def _serial(job: BatchJob, batches: list[Array], X: Array, parts: Path, bar: Any) -> None:
    for ids in batches:
        _write_part(parts, run_batch(job, ids, X[ids]))
        bar.update(len(ids))


def _client(workers: int, scheduler: str | None) -> tuple[Any, Any]:
    """A distributed client: to ``scheduler``, or to a new local cluster of ``workers``
    single-threaded worker processes. Returns ``(client, cluster or None)``."""
    from distributed import Client, LocalCluster

    if scheduler is not None:
        try:
            return Client(scheduler, timeout="30s"), None
        except (OSError, TimeoutError, ValueError, TypeError) as exc:
            reason = " ".join(str(exc).split()) or type(exc).__name__
            raise PkmdynError(f"--scheduler {scheduler}: cannot connect ({reason})") from None
    # Dask's own log lines stay quiet (a worker that dies and is replaced is expected; the
    # sweep reports what it cannot recover from itself, in one line)
    # the worker processes start with SIGINT ignored (inherited; Python then installs no
    # KeyboardInterrupt handler in them): a Ctrl-C at the terminal reaches the whole process
    # group, and this process alone stops the sweep, with one line, and closes the cluster

    main = threading.current_thread() is threading.main_thread()
    old = signal.signal(signal.SIGINT, signal.SIG_IGN) if main else None
    try:
        # no dashboard; the scheduler's HTTP server (health routes) on a free local port: its
        # default port 8787 may be held by another cluster, and Dask then warns on stderr
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None,
                               scheduler_kwargs={"dashboard": False, "dashboard_address": "127.0.0.1:0"},
                               # nothing of the cluster's own logging on stderr, its CRITICAL lines included:
                               # a Ctrl-C just after the job was scattered makes the scheduler log the
                               # closed connection with a traceback; a failure reaches the sweep as an
                               # exception and is said in one line
                               silence_logs=logging.CRITICAL + 10)
    finally:
        if main:
            signal.signal(signal.SIGINT, old)
    return Client(cluster), cluster


class Executor:
    """Evaluates batches of designs (:meth:`run`): in this process (``workers = 0`` and no
    ``scheduler``), or on Dask, a local cluster of ``workers`` processes or the cluster of
    ``scheduler``. A context manager: the cluster (or the connection) is started at the first
    :meth:`run` with work to do and kept for every later one (each generation of a search, each
    refinement round), then closed on exit; ``retries``: re-runs of a batch that raised (a
    worker that dies is handled by the scheduler, which moves its tasks to the other
    workers)."""

    def __init__(self, workers: int = 0, scheduler: str | None = None, retries: int = 2) -> None:
        self.workers, self.scheduler, self.retries = workers, scheduler, retries
        self.on_dask = workers > 0 or scheduler is not None
        self._client: Any = None
        self._cluster: Any = None
        self._job: BatchJob | None = None  # the job on the workers (scattered once) and its future
        self._shared: Any = None
        self._warm = False  # whether a first design ran on one worker of each host (:meth:`_on_dask`)

    def __enter__(self) -> Executor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Close the client and the local cluster, if started."""
        client, cluster, self._client, self._cluster = self._client, self._cluster, None, None
        self._job = self._shared = None
        self._warm = False
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()

    def _start(self, job: BatchJob, stats: ExecutionStats) -> None:
        import dask
        import distributed  # noqa: F401  (its configuration defaults, read below)

        t0 = time.perf_counter()
        # a task whose worker dies is moved to another worker up to this many times (then the
        # sweep stops with KilledWorker; the finished batches stay for a rerun). Local workers
        # keep glibc's own malloc trimming: Dask's default MALLOC_TRIM_THRESHOLD_ = 64 KiB
        # returns memory to the system after every freed temporary, which costs the many small
        # numpy arrays of an evaluation about a third more time (system time of brk calls)
        environ = {k: v for k, v in dask.config.get("distributed.nanny.pre-spawn-environ", {}).items()
                   if k != "MALLOC_TRIM_THRESHOLD_"}
        with dask.config.set({"distributed.scheduler.allowed-failures": max(self.retries, 0) + 3,
                              "distributed.nanny.pre-spawn-environ": environ}):
            self._client, self._cluster = _client(self.workers, self.scheduler)
        # start-up: every worker imports the machine's adapter (numpy, scipy, the model) once
        self._client.run(importlib.import_module, job.evaluate.__module__)
        stats.cluster_start_s = time.perf_counter() - t0

    def run(self, job: BatchJob, X: Array, todo: Array, parts: Path, batch_size: int | None = None,
            progress: bool | None = None) -> ExecutionStats:
        """Evaluate the designs ``todo`` (ids into ``X``) and write one part file per batch."""
        parts.mkdir(parents=True, exist_ok=True)
        total = X.shape[0]
        size = batch_size or default_batch_size(todo.shape[0], self.workers if self.on_dask else 1)
        batches = make_batches(todo, size)
        stats = ExecutionStats(mode="dask" if self.on_dask else "serial", workers=self.workers, batches=len(batches))
        bar = _progress(total, total - todo.shape[0], progress)
        try:
            if not batches:
                return stats
            if not self.on_dask:
                t0, c0 = time.perf_counter(), _cpu_seconds()
                _serial(job, batches, X, parts, bar)
                stats.evaluate_s = time.perf_counter() - t0
                stats.driver_cpu_s = _cpu_seconds() - c0
            else:
                if self._client is None:
                    self._start(job, stats)
                self._on_dask(job, batches, X, parts, bar, stats)
        finally:
            bar.close()
        return stats

    def _on_dask(self, job: BatchJob, batches: list[Array], X: Array, parts: Path, bar: Any,
                 stats: ExecutionStats) -> None:
        from distributed.scheduler import KilledWorker

        client = self._client
        stats.workers = len(client.scheduler_info().get("workers", {}))
        t1, c1 = time.perf_counter(), _cpu_seconds()
        cpu_before = client.run(_cpu_seconds)
        if job is not self._job:  # the job is sent to every worker once
            self._job, self._shared = job, client.scatter(job, broadcast=True, hash=False)
        shared = self._shared
        token = uuid.uuid4().hex[:12]

        batch_of: dict[str, Array] = {}  # each future's key -> its designs
        resubmitted: dict[str, int] = {}

        def submit(ids: Array, **where: Any) -> Any:
            fut = client.submit(run_batch, shared, ids, X[ids], key=f"pkmdyn-sweep-{token}-{int(ids[0])}",
                                retries=self.retries, pure=False, **where)
            batch_of[fut.key] = ids
            return fut

        def again(fut: Any) -> Any:
            """The batch of ``fut`` once more, under a new key: its result was forgotten by the
            scheduler before it was read (a worker lost just as the batch finished), or the job
            it reads was lost with the worker (the job is then sent to the workers again)."""
            n = resubmitted[fut.key] = resubmitted.get(fut.key, 0) + 1
            if n > self.retries + 1:
                return None
            ids = batch_of[fut.key]
            nonlocal shared
            if shared.status != "finished":  # the job itself lost with the worker: sent again
                self._shared = shared = client.scatter(job, broadcast=True, hash=False)
            new = client.submit(run_batch, shared, ids, X[ids], key=f"{fut.key}-again{n}", retries=self.retries,
                                pure=False)
            batch_of[new.key] = ids
            resubmitted[new.key] = n
            futures.append(new)
            return new

        futures: list[Any] = []
        try:
            if not self._warm:
                # the first design of the first batches alone, on one worker of each host, before
                # the rest: a kernel missing from a host's cache is compiled there once, and the
                # other workers of the host then load it, rather than compile it all at once
                # into the one cache (numba has no lock of its own)
                first = _one_worker_per_host(client.scheduler_info().get("workers", {}))
                head = [b[:1] for b in batches[:len(first)]]
                batches = [*[b[1:] for b in batches[:len(first)] if b.shape[0] > 1], *batches[len(first):]]
                futures = [submit(ids, workers=[w], allow_other_workers=True) for ids, w in zip(head, first)]
                self._collect(futures, parts, bar, again)
                self._warm = True
            futures = [submit(ids) for ids in batches]
            self._collect(futures, parts, bar, again)
        except KilledWorker as exc:
            raise PkmdynError(f"a batch killed its worker repeatedly ({exc}); the finished batches are kept in "
                              f"{parts}, rerun the same command to continue") from None
        except CancelledError:
            raise PkmdynError(f"the scheduler lost a batch more often than it is resubmitted; the finished batches are "
                              f"kept in {parts}, rerun the same command to continue") from None
        finally:
            client.cancel(futures)
        stats.evaluate_s = time.perf_counter() - t1
        stats.driver_cpu_s = _cpu_seconds() - c1
        cpu_after = client.run(_cpu_seconds)
        stats.worker_cpu_s = (sum(cpu_after[w] - cpu_before[w] for w in cpu_after)
                              if set(cpu_after) == set(cpu_before) else None)

    @staticmethod
    def _collect(futures: list[Any], parts: Path, bar: Any, again: Any = None) -> None:
        """Write each batch's part as its future completes. A future cancelled by the scheduler
        (its result forgotten when a worker was lost as the batch finished) is submitted again
        (``again(future)``: the new future, or None past the retries), so that a lost worker
        loses no batch."""
        from distributed import as_completed

        pending = as_completed(futures)
        for fut in pending:
            try:
                table = fut.result()
            except CancelledError:
                new = None if again is None else again(fut)
                if new is None:
                    raise
                pending.add(new)
                continue
            _write_part(parts, table)
            bar.update(table.num_rows)
            fut.release()


def _one_worker_per_host(workers: Mapping[str, Any]) -> list[str]:
    """One worker address of each host among the scheduler's ``workers`` (address -> info)."""
    chosen: dict[str, str] = {}
    for addr, info in sorted(workers.items()):
        host = (info or {}).get("host") or addr.rsplit(":", 1)[0]
        chosen.setdefault(str(host), addr)
    return list(chosen.values()) or list(workers)[:1]


def execute(job: BatchJob, X: Array, todo: Array, parts: Path, workers: int = 0, scheduler: str | None = None,
            batch_size: int | None = None, progress: bool | None = None, retries: int = 2) -> ExecutionStats:
    """Evaluate the designs ``todo`` (ids into ``X``) and write one part file per batch, on an
    :class:`Executor` of its own (``workers = 0`` and no ``scheduler``: in this process, batch
    after batch; otherwise on Dask, started and closed here)."""
    with Executor(workers, scheduler, retries) as ex:
        return ex.run(job, X, todo, parts, batch_size, progress)
