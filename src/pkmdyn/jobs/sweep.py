"""``pkmdyn sweep``, a whole sweep: space file -> designs -> evaluation (serial or Dask) -> results
folder (the sweep's parts: :mod:`pkmdyn.sweep`).

The output folder of a sweep (``docs/sweep.md``)::

    sweep.json          what is being swept (machine, space, base description): a rerun must match it
    parts/part-*.parquet  one file per finished batch, rows keyed by design_id
    designs.parquet     every design, one row each, sorted by design_id
    pareto.parquet      the Pareto set of the objectives among the feasible designs
    best_params.toml    the best design as a parameter file the machine's run accepts
    summary.json        counts, the best design, timings
    pareto_front.png, metric_vs_parameter.png, scatter_matrix.png

Unlike a single run, a sweep's folder is filled as it goes and a rerun resumes it; the
result files are each written atomically at the end.
"""

from __future__ import annotations

import json
import os
import stat as st_
import time
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ParameterError, PkmdynError
from ..io import (
    atomic_file,
    check_inputs_outside,
    check_table_format,
    dumps_toml,
    write_json,
)
from ..machines.registry import sweep_adapter
from ..params_util import parse_limit_options
from ..sweep import plots as _plots
from ..sweep.execute import (
    PARTS_DIR,
    BatchJob,
    ExecutionStats,
    Executor,
    finished_ids,
    part_schema,
)
from ..sweep.pareto import minimised, pareto_mask
from ..sweep.search import Nsga2Search, generation_values, hypervolumes, normalise
from ..sweep.space import (
    SweepSpace,
    design_description,
    from_unit,
    load_space,
    refine_designs,
    sample_designs,
)
from ..sweep_protocol import STATUSES, SweepAdapter
from ._files import JobResult

__all__ = ["run_sweep", "SweepReport", "prepare_sweep", "PreparedSweep", "RECORD", "PREFLIGHT_DESIGNS"]

RECORD = "sweep.json"
#: designs checked against the machine's parameter validation before any work (spread evenly
#: over the sample): when every one of them is invalid the sweep is refused
PREFLIGHT_DESIGNS = 1000


@dataclass(frozen=True)
class PreparedSweep:
    """A checked sweep, ready to run: the space, every design's values ``X (n, d)``, the job."""

    machine: str
    space: SweepSpace
    X: Any
    job: BatchJob
    record: dict[str, Any]


@dataclass(frozen=True)
class SweepReport:
    """What a sweep did: the folder, status counts, the Pareto set's size, the best design
    (``None`` when no design is feasible), the files written and the timings."""

    out: Path
    designs: int
    evaluated: int
    counts: dict[str, int]
    pareto: int
    best_design_id: int | None
    files: dict[str, Path]
    stats: ExecutionStats
    results_s: float


def _preflight(adapter: SweepAdapter, space: SweepSpace, base: Mapping[str, Any], X: Any) -> None:
    n = X.shape[0]
    probe = np.unique(np.linspace(0, n - 1, min(n, PREFLIGHT_DESIGNS)).round().astype(np.int64))
    first = ""
    for i in probe:
        try:
            adapter.check_description(design_description(base, space.parameters, X[i]), f"design {i}")
            return
        except PkmdynError as exc:
            first = first or str(exc)
    what = "every design" if probe.size == n else f"all {probe.size} designs checked (spread over the {n})"
    raise ParameterError(f"{space.source}: {what} invalid by the machine's parameter rules; the first: {first}")


def prepare_sweep(adapter: Any, space_path: str | Path, params: str | Path | None = None,
                  max_designs: int | None = None, search: str | None = None) -> PreparedSweep:
    """Read and check everything (space file, base parameters, motion, designs) before any work.

    ``adapter``: the machine's sweep module (``pkmdyn.machines.registry.sweep_adapter``);
    ``params``: a base parameter file overriding the space file's ``params``; ``search``: the
    sampling method overriding the space file's ``[sampling] method``.
    """
    def description_for(path: Path | None) -> dict[str, Any]:
        return adapter.base_description(Path(params) if params is not None else path)

    space, base = load_space(space_path, description_for, adapter.metrics, max_designs, search)
    context = adapter.prepare(base, space.motion, space.base_dir)
    X = sample_designs(space)
    _preflight(adapter, space, base, X)
    metrics = tuple(adapter.metrics(space.motion, base))
    job = BatchJob(evaluate=adapter.evaluate, context=context, base=base, parameters=space.parameters,
                   metrics=metrics, constraints=space.constraints, sample_designs=int(X.shape[0]),
                   round_designs=space.refine_designs)
    record = {"machine": adapter.NAME, "space": space.record(), "base_description": base,
              "metrics": [m.name for m in metrics], "designs": int(X.shape[0])}
    return PreparedSweep(adapter.NAME, space, X, job, json.loads(json.dumps(record)))


#: the result files a sweep writes beside its parts (replaced by a rerun)
OUTPUTS = ("designs.parquet", "pareto.parquet", "best_params.toml", "summary.json", "pareto_front.png",
           "metric_vs_parameter.png", "scatter_matrix.png", "convergence.png")
#: the folder of an NSGA-II run's Pareto designs as description files (replaced by a rerun)
PARETO_DESIGNS = "pareto_designs"


def _stamp(path: Path) -> list[int]:
    st = path.stat()
    return [int(st.st_size), int(st.st_mtime_ns)]


def _written(out: Path) -> dict[str, list[int]]:
    """The result files the last run wrote into ``out``, with their size and modification time
    (``summary.json`` ``written``); empty where none is recorded."""
    try:
        doc = json.loads((out / "summary.json").read_text(encoding="utf-8"))
        written = doc.get("written", {})
        return {str(k): list(v) for k, v in written.items()} if isinstance(written, dict) else {}
    except (OSError, ValueError, UnicodeDecodeError, AttributeError, TypeError):
        return {}


def _open_out(out: Path, record: dict[str, Any], inputs: Mapping[str, Any] = ()) -> None:
    """Create ``out`` or check that it holds a sweep of the same space (to resume), under the
    output rule (``docs/file_formats.md``): not a link or anything but a folder, no input of
    the run inside it, and no file where the sweep writes its results that an earlier run did
    not write or that was changed since (it would be replaced)."""

    if out.is_symlink():
        raise PkmdynError(f"--out {out}: is a symbolic link, not a folder pkmdyn wrote; refusing to write through it")
    if out.exists() and not out.is_dir():
        raise PkmdynError(f"--out {out}: exists and is a file, not a folder")
    check_inputs_outside(out, inputs)
    rec = out / RECORD
    if out.is_dir() and any(out.iterdir()):
        if not rec.is_file() or rec.is_symlink():
            raise PkmdynError(f"--out {out}: folder is not empty and holds no pkmdyn sweep; refusing to write into it")
        try:
            earlier = json.loads(rec.read_text(encoding="utf-8"))
        except (OSError, ValueError, UnicodeDecodeError):
            raise PkmdynError(f"--out {out}: {RECORD} is unreadable; use a new --out") from None
        if earlier != record:
            diff = next((k for k in record if earlier.get(k) != record[k]), "?")
            raise PkmdynError(f"--out {out}: holds a sweep of a different {diff.replace('_', ' ')}; use a new --out "
                              "(a rerun resumes only the same machine, space and parameters)")
        written = _written(out)
        for name in OUTPUTS:
            f = out / name
            if not os.path.lexists(f):
                continue
            lst = f.lstat()
            if not st_.S_ISREG(lst.st_mode):
                raise PkmdynError(f"--out {out}: {name} is not a file pkmdyn wrote; refusing to replace it")
            if name != "summary.json" and written.get(name) != _stamp(f):
                raise PkmdynError(f"--out {out}: {name} was not written by this sweep or was changed since; refusing "
                                  "to replace it (move it away, or use a new --out)")
        folder = out / PARETO_DESIGNS
        if os.path.lexists(folder):
            if folder.is_symlink() or not folder.is_dir():
                raise PkmdynError(f"--out {out}: {PARETO_DESIGNS} is not a folder pkmdyn wrote; refusing to replace it")
            for f in folder.iterdir():
                if f.is_symlink() or not f.is_file() or written.get(f"{PARETO_DESIGNS}/{f.name}") != _stamp(f):
                    raise PkmdynError(f"--out {out}: {PARETO_DESIGNS}/{f.name} was not written by this sweep or was "
                                      "changed since; refusing to replace it (move it away, or use a new --out)")
        return
    out.mkdir(parents=True, exist_ok=True)
    with atomic_file(rec, notify=None) as tmp:
        write_json(tmp, record)


def _remove_if_unused(out: Path) -> None:
    """Remove a sweep folder this run created when it failed before finishing any batch (a
    wrong scheduler address, Ctrl-C at once): nothing is left behind but what holds results."""
    parts = out / PARTS_DIR
    if parts.is_dir() and not any(p.name.startswith("part-") for p in parts.iterdir()):
        for p in parts.iterdir():
            p.unlink(missing_ok=True)
        parts.rmdir()
    if not parts.exists():
        (out / RECORD).unlink(missing_ok=True)
        try:
            out.rmdir()
        except OSError:
            pass


def _collect(parts: Path, schema: Any, n: int, later: bool = False, read: dict[str, Any] | None = None) -> Any:
    """Every part's rows as one table sorted by design_id; each design exactly once.

    ``later``: rows of designs ``>= n`` (refinement rounds of an interrupted earlier run that
    went further) are left out instead of refused. ``read``: the part files read by an earlier
    call of the same run, by name (a part file is written once and never changed), filled with
    the ones read now."""
    import pyarrow as pa
    import pyarrow.compute as pc
    import pyarrow.parquet as pq

    read = {} if read is None else read
    for p in sorted(parts.glob("part-*.parquet")):
        if p.name not in read:
            read[p.name] = pq.read_table(p, schema=schema)
    tables = [read[k] for k in sorted(read)]
    table = pa.concat_tables(tables) if tables else schema.empty_table()
    table = table.take(pc.sort_indices(table, sort_keys=[("design_id", "ascending")]))
    if later:
        table = table.filter(pc.less(table.column("design_id"), n))
    table = _unique_rows(table, parts)
    ids = table.column("design_id").to_numpy()
    if ids.shape[0] != n or not np.array_equal(ids, np.arange(n)):
        dup = ids[1:][ids[1:] == ids[:-1]]
        raise PkmdynError(f"{parts}: the part files hold {ids.shape[0]} rows for {n} designs"
                          + (f" (design {int(dup[0])} twice)" if dup.size else "") + "; use a new --out")
    return table


def _unique_rows(table: Any, parts: Path) -> Any:
    """``table`` (sorted by design id) with each design once: two runs into one folder at the
    same time (other batch sizes, so other part files) may both evaluate a design, and a
    design's row depends on the design alone, so the copies agree and one is kept; copies that
    differ are an error naming the design."""
    import pyarrow as pa

    ids = table.column("design_id").to_numpy()
    if ids.shape[0] < 2:
        return table
    dup = np.flatnonzero(ids[1:] == ids[:-1]) + 1
    if not dup.size:
        return table
    for k in dup:
        a, b = table.slice(int(k) - 1, 1).to_pylist()[0], table.slice(int(k), 1).to_pylist()[0]
        same = all(a[c] == b[c] or (isinstance(a[c], float) and isinstance(b[c], float) and a[c] != a[c] and
                                    b[c] != b[c]) for c in a)
        if not same:
            raise PkmdynError(f"{parts}: design {int(ids[k])} has two different rows; use a new --out")
    keep = np.ones(ids.shape[0], dtype=bool)
    keep[dup] = False
    return table.filter(pa.array(keep))


def _write_table(path: Path, table: Any) -> Path:
    import pyarrow.parquet as pq

    with atomic_file(path, notify=None) as tmp:
        pq.write_table(table, str(tmp), compression="zstd")
    return path


def run_sweep(adapter: Any, space_path: str | Path, out: str | Path, workers: int | None = None,
              scheduler: str | None = None, params: str | Path | None = None, batch_size: int | None = None,
              max_designs: int | None = None, plots: bool = True, progress: bool | None = None,
              retries: int = 2, search: str | None = None) -> SweepReport:
    """Run (or resume) a sweep and write its results into ``out``.

    ``search`` (``--search``): the sampling method (grid, random, lhs, sobol, nsga2) in place of
    the space file's ``[sampling] method``.

    ``workers``: local Dask worker processes (``None``: one per CPU core; ``0``: evaluate in
    this process without Dask); ``scheduler``: the address of a running Dask scheduler
    instead. Every check (space file, parameters, motion, the designs' validity, ``out``) comes
    before any design is evaluated; every user error is a :class:`~pkmdyn.errors.PkmdynError`.
    """
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 0):
        raise ParameterError(f"--workers: must be an integer >= 0, got {workers!r}")
    if workers is not None and scheduler is not None:
        raise ParameterError("--workers and --scheduler: give one of them (a scheduler has its own workers)")
    check_table_format("parquet")
    prep = prepare_sweep(adapter, space_path, params, max_designs, search)
    out = Path(out)
    fresh = not out.exists()
    _open_out(out, prep.record, {"--space": space_path, "--params": params})
    parts = out / PARTS_DIR
    done = finished_ids(parts)
    n = prep.X.shape[0]
    todo = np.setdiff1d(np.arange(n, dtype=np.int64), done)
    n_workers = (os.cpu_count() or 1) if workers is None and scheduler is None else (workers or 0)
    size = batch_size or prep.space.batch_size
    with Executor(n_workers, scheduler, retries) as ex:  # one cluster for every round
        try:
            stats = ex.run(prep.job, prep.X, todo, parts, size, progress)
        except BaseException:
            if fresh:
                _remove_if_unused(out)
            raise
        evaluated = int(todo.shape[0])
        X, rounds = prep.X, 0
        schema = part_schema(prep.job)
        search = None
        read: dict[str, Any] = {}
        for r in range(1, prep.space.refine_rounds + 1):
            table = _collect(parts, schema, X.shape[0], later=True, read=read)
            if prep.space.method == "nsga2":  # the next generation from the last one's rows (search.py)
                if search is None:
                    search = Nsga2Search(prep.space)
                    if not np.array_equal(from_unit(prep.space, search.ask()), prep.X):
                        raise PkmdynError("internal error: the NSGA-II search does not replay its first generation")
                N = prep.space.designs
                search.tell(*generation_values(table, (r - 1) * N, r * N, prep.space))
                Xg = from_unit(prep.space, search.ask())
                _check_replay(table, prep.space, r * N, Xg)
                X = np.vstack([X, Xg])
            else:
                _, front = _front(table, prep.space.objectives)
                if not front.size:
                    break  # nothing feasible to refine around
                X = np.vstack([X, refine_designs(prep.space, X, np.sort(front), r)])
            todo = np.setdiff1d(np.arange(X.shape[0] - prep.space.refine_designs, X.shape[0]), done)
            _add(stats, ex.run(prep.job, X, todo, parts, size, progress))
            evaluated += int(todo.shape[0])
            rounds = r
    t0 = time.perf_counter()
    files, counts, n_pareto, best = _results(prep, X, rounds, out, plots, stats)
    return SweepReport(out=out, designs=int(X.shape[0]), evaluated=evaluated, counts=counts, pareto=n_pareto,
                       best_design_id=best, files=files, stats=stats, results_s=time.perf_counter() - t0)


def _check_replay(table: Any, space: Any, first: int, Xg: Any) -> None:
    """The stored rows of a generation that an earlier run evaluated hold the designs the replay
    asks for now (the same seed and pymoo give the same designs; anything else would pair a
    design with another's metrics)."""
    ids = np.asarray(table.column("design_id").to_numpy(zero_copy_only=False))
    rows = np.flatnonzero((ids >= first) & (ids < first + Xg.shape[0]))
    for row in rows:
        stored = [table.column(p.key)[int(row)].as_py() for p in space.parameters]
        if not np.allclose(stored, Xg[int(ids[row]) - first], rtol=1e-12, atol=0.0):
            raise PkmdynError(f"design {int(ids[row])}: the stored design differs from the NSGA-II replay of its "
                              "generation (another pymoo version?); use a new --out")


def _add(total: ExecutionStats, more: ExecutionStats) -> None:
    """Accumulate the statistics of a refinement round."""
    total.batches += more.batches
    total.cluster_start_s += more.cluster_start_s
    total.evaluate_s += more.evaluate_s
    total.driver_cpu_s += more.driver_cpu_s
    total.worker_cpu_s = None if total.worker_cpu_s is None or more.worker_cpu_s is None \
        else total.worker_cpu_s + more.worker_cpu_s


def _front(table: Any, objectives: tuple[tuple[str, str], ...]) -> tuple[Any, Any]:
    """Row indices of the feasible designs and of the Pareto set among them, the latter sorted
    as the best design is chosen (first objective, then the next ones), plus ``F`` minimised."""
    feasible = np.flatnonzero(table.column("feasible").to_numpy(zero_copy_only=False))
    F = np.column_stack([table.column(m).to_numpy(zero_copy_only=False)[feasible].astype(float)
                         for m, _ in objectives]) if feasible.size else np.zeros((0, len(objectives)))
    Fm = minimised(F, [s for _, s in objectives])
    mask = pareto_mask(Fm)
    Fp = Fm[mask]
    return feasible, feasible[mask][np.lexsort(tuple(Fp[:, k] for k in range(Fp.shape[1] - 1, -1, -1)))]


def _results(prep: PreparedSweep, X: Any, rounds: int, out: Path, plots: bool, stats: ExecutionStats
             ) -> tuple[dict[str, Path], dict[str, int], int, int | None]:
    import pyarrow as pa

    table = _collect(out / PARTS_DIR, part_schema(prep.job), X.shape[0])
    files = {"designs": _write_table(out / "designs.parquet", table)}
    status = np.asarray(table.column("status").to_pylist(), dtype=object)
    counts = {s: int(np.count_nonzero(status == s)) for s in STATUSES}
    objectives = prep.space.objectives
    feasible, on_front = _front(table, objectives)
    front = table.take(pa.array(on_front, type=pa.int64()))
    files["pareto"] = _write_table(out / "pareto.parquet", front)
    best: int | None = None
    summary: dict[str, Any] = {
        "machine": prep.machine, "space": prep.space.source, "designs": int(X.shape[0]),
        "sample_designs": int(prep.X.shape[0]), "refine_rounds": rounds,
        "status_counts": counts, "feasible": int(feasible.size), "pareto_designs": int(on_front.size),
        "objectives": [{"metric": m, "sense": s} for m, s in objectives],
        "constraints": [{"metric": b.metric, "min": b.lo, "max": b.hi} for b in prep.space.constraints],
    }
    if feasible.size:
        best = int(on_front[0])  # best in the first objective, then the next ones: the front's first
        row = X[best]
        desc = design_description(prep.job.base, prep.space.parameters, row)
        values = {m: float(table.column(m)[best].as_py()) for m, _ in objectives}
        header = (f"Best design {best} of the sweep {prep.space.source} ({prep.machine}),\n"
                  "best in the first objective among the feasible designs; objectives:\n"
                  + "\n".join(f"  {m} = {v:.9g} ({s})" for (m, s), v in zip(objectives, values.values())))
        files["best_params"] = _write_best(out / "best_params.toml", desc, header)
        summary["best_design"] = {"design_id": best,
                                  "parameters": {p.key: (int(v) if p.integer else float(v))
                                                 for p, v in zip(prep.space.parameters, row)},
                                  "objectives": values}
    else:
        summary["best_design"] = None
        earlier = out / "best_params.toml"  # the best design of an earlier run of this sweep (checked by _open_out)
        if earlier.is_file() and not earlier.is_symlink() and _written(out).get(earlier.name) == _stamp(earlier):
            earlier.unlink()
    pareto_files: dict[str, Path] = {}
    if prep.space.method == "nsga2":
        summary["generations"] = _convergence(table, prep.space, X.shape[0])
        pareto_files = _pareto_designs(out, prep, X, table, on_front)
    summary["execution"] = {"mode": stats.mode, "workers": stats.workers, "batches": stats.batches,
                            "cluster_start_s": stats.cluster_start_s, "evaluate_s": stats.evaluate_s,
                            "driver_cpu_s": stats.driver_cpu_s, "worker_cpu_s": stats.worker_cpu_s}
    if plots:
        files.update(_plots.sweep_plots(out, table, prep.space, on_front))
        if "generations" in summary:
            files["convergence"] = _plots.convergence_plot(out / "convergence.png", summary["generations"])
    files["summary"] = out / "summary.json"
    summary["files"] = sorted(p.name for p in files.values())
    summary["written"] = {p.name: _stamp(p) for p in files.values() if p.name != "summary.json"}
    summary["written"].update({f"{PARETO_DESIGNS}/{p.name}": _stamp(p) for p in pareto_files.values()})
    files.update(pareto_files)
    with atomic_file(files["summary"], notify=None) as tmp:
        write_json(tmp, summary)
    return files, counts, int(on_front.size), best


def _convergence(table: Any, space: Any, n: int) -> list[dict[str, Any]]:
    """Per NSGA-II generation: the designs so far, the feasible ones, the size of their Pareto
    set and its hypervolume (objectives minimised and scaled to [0, 1] over every feasible design
    of the run, reference point 1.1 in each: the same scale for every generation)."""
    feasible, _ = _front(table, space.objectives)
    ids = np.asarray(table.column("design_id").to_numpy(zero_copy_only=False))[feasible]
    F = minimised(np.column_stack([table.column(m).to_numpy(zero_copy_only=False)[feasible].astype(float)
                                   for m, _ in space.objectives]), [s for _, s in space.objectives]) \
        if feasible.size else np.zeros((0, len(space.objectives)))
    N = space.designs
    gens = n // N
    Fn, ref, _ = normalise(F) if len(F) else (F, np.ones(F.shape[1]), None)
    per = []
    fronts = []
    front = Fn[:0]
    for g in range(gens):
        # the Pareto set of the designs so far is that of the last one and this generation's
        # designs (a design dominated by some of the designs stays dominated by all of them):
        # each generation costs (front + N)^2 comparisons, not (g N)^2
        new = Fn[(ids >= g * N) & (ids < (g + 1) * N)]
        both = np.concatenate([front, new]) if len(new) else front
        front = both[pareto_mask(both)] if len(both) else both
        fronts.append(front)
        per.append({"generation": g, "designs": int((g + 1) * N), "feasible": int((ids < (g + 1) * N).sum()),
                    "pareto_designs": int(len(front))})
    for row, hv in zip(per, hypervolumes(fronts, ref)):
        row["hypervolume"] = hv
    return per


def _pareto_designs(out: Path, prep: PreparedSweep, X: Any, table: Any, on_front: Any) -> dict[str, Path]:
    """Every Pareto design of an NSGA-II run as a description file ``pareto_designs/design_<id>.toml``
    (the earlier run's files replaced: :func:`_open_out` checked they are this sweep's)."""
    folder = out / PARETO_DESIGNS
    if folder.is_dir():
        for f in folder.iterdir():
            f.unlink()
    folder.mkdir(exist_ok=True)
    files = {}
    ids = np.asarray(table.column("design_id").to_numpy(zero_copy_only=False))
    for row in on_front:
        i = int(ids[row])
        desc = design_description(prep.job.base, prep.space.parameters, X[i])
        values = {m: float(table.column(m)[int(row)].as_py()) for m, _ in prep.space.objectives}
        header = (f"Pareto design {i} of the NSGA-II sweep {prep.space.source} ({prep.machine}); objectives:\n"
                  + "\n".join(f"  {m} = {v:.9g} ({s})" for (m, s), v in zip(prep.space.objectives, values.values())))
        files[f"pareto_design_{i}"] = _write_best(folder / f"design_{i}.toml", desc, header)
    return files


def _write_best(path: Path, description: dict[str, Any], header: str) -> Path:
    text = dumps_toml(description, header)
    if tomllib.loads(text) != description:  # the file must read back to the very same description
        raise PkmdynError("internal error: the best design's parameter file does not read back identically")
    with atomic_file(path, notify=None) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path


def job(machine: str, space_path: Path, out_dir: Path, *, params_path: Path | None = None, workers: int | None = None,
        scheduler: str | None = None, batch_size: int | None = None, limit_items: tuple[str, ...] = (),
        search: str | None = None, no_plots: bool = False) -> JobResult:
    """``pkmdyn sweep``: the designs of ``machine`` the space file ``space_path`` spans (over the
    base parameters ``params_path``), evaluated in this process (``workers`` 0), on a local Dask
    cluster or on ``scheduler``, into ``out_dir`` (:func:`run_sweep`); ``limit_items``:
    ``max_designs=N``; ``search`` in place of the space file's sampling method."""
    max_designs = parse_limit_options(limit_items, {"max_designs": int}).get("max_designs")
    report = run_sweep(sweep_adapter(machine), space_path, out_dir, workers=workers, scheduler=scheduler,
                       params=params_path, batch_size=batch_size, max_designs=max_designs, plots=not no_plots,
                       search=search)
    counts = ", ".join(f"{k} {v}" for k, v in report.counts.items() if v)
    lines = (f"designs: {report.designs} ({counts}); evaluated now: {report.evaluated}; "
             f"Pareto set: {report.pareto}; best: {report.best_design_id}",
             *(f"{name}: {path}" for name, path in report.files.items()))
    return JobResult(report.files, lines=lines)
