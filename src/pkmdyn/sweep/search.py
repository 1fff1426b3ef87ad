"""The evolutionary multi-objective search of a sweep: NSGA-II (Deb et al. 2002) through pymoo's
ask-and-tell interface, its designs evaluated by the sweep's own executor (serial or Dask).

Generation 0 is the first population (``designs`` random points of the unit cube, seeded);
each further generation asks pymoo for ``designs`` offspring (binary tournament on rank and
crowding distance, simulated binary crossover, polynomial mutation: pymoo's NSGA-II defaults,
with the distribution indices of the space's ``crossover_eta`` and ``mutation_eta``, by default
pymoo's 15 and 20)
and tells it their objectives (every ``"max"`` objective negated) and constraint violation.
The violation of a design is 0 when it is feasible, the sum of its metrics' relative
distances beyond their ``[constraints]`` bounds when it is ``infeasible``, and 1e9 when its
evaluation failed (invalid, unreachable, singular, ...); an infeasible design's violation is
capped below that. A generation always holds ``designs`` rows: where pymoo returns fewer
offspring (duplicates removed), its offspring are repeated from the first and only pymoo's own
are told. The same space file and seed give the same designs,
generation after generation, so an interrupted run replays its finished generations from
their stored rows and resumes (``docs/sweep.md``)."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import PkmdynError
from .pareto import minimised

__all__ = ["Nsga2Search", "violation", "hypervolumes", "normalise", "generation_values", "FAILED_VIOLATION"]

Array = NDArray[np.float64]

#: the constraint violation of a design whose evaluation failed
FAILED_VIOLATION = 1e9


class Nsga2Search:
    """NSGA-II over the space's parameters (module docstring): ``ask()`` the next generation's
    points of the unit cube ``(designs, d)``, ``tell(F, cv)`` their minimised objectives and
    violations."""

    def __init__(self, space: Any) -> None:
        from pymoo.algorithms.moo.nsga2 import NSGA2
        from pymoo.core.problem import Problem
        from pymoo.termination import get_termination

        self.space = space
        d, k = len(space.parameters), len(space.objectives)
        self._problem = Problem(n_var=d, n_obj=k, n_ieq_constr=1, xl=np.zeros(d), xu=np.ones(d))
        from pymoo.operators.crossover.sbx import SBX
        from pymoo.operators.mutation.pm import PM

        self._algorithm = NSGA2(pop_size=int(space.designs), eliminate_duplicates=True,
                                crossover=SBX(eta=float(space.crossover_eta), prob=0.9),
                                mutation=PM(eta=float(space.mutation_eta)))
        self._algorithm.setup(self._problem, termination=get_termination("n_gen", 10**9), seed=int(space.seed) % 2**32,
                              verbose=False)
        self._pending: Any = None

    def ask(self) -> Array:
        """The next generation as ``designs`` points of the unit cube (``space.from_unit`` maps
        them to designs)."""
        pop = self._algorithm.ask()
        U = np.clip(np.asarray(pop.get("X"), dtype=float), 0.0, 1.0 - 1e-12)
        self._pending = pop
        n = int(self.space.designs)
        if U.shape[0] == 0:
            raise PkmdynError("NSGA-II: no new design in this generation (the population has collapsed onto "
                              "duplicates); fewer generations or a larger population")
        if U.shape[0] < n:
            U = np.vstack([U, U[np.arange(n - U.shape[0]) % U.shape[0]]])
        return U[:n]

    def tell(self, F: Array, cv: Array) -> None:
        """The minimised objectives ``F (designs, k)`` and violations ``cv (designs,)`` of the
        last generation asked (rows beyond pymoo's own offspring are ignored)."""
        from pymoo.core.evaluator import Evaluator
        from pymoo.problems.static import StaticProblem

        m = len(self._pending)
        F = np.where(np.isfinite(F[:m]), F[:m], 0.0)
        G = np.asarray(cv[:m], dtype=float)[:, None]
        Evaluator().eval(StaticProblem(self._problem, F=F, G=G), self._pending)
        self._algorithm.tell(infills=self._pending)


def violation(status: Array, values: dict[str, Array], constraints: Any) -> Array:
    """Each design's constraint violation (module docstring) from its status and metrics."""
    status = np.asarray(status, dtype=object)
    cv = np.where(status == "ok", 0.0, FAILED_VIOLATION)
    inf = status == "infeasible"
    if inf.any():
        total = np.zeros(len(status))
        for b in constraints:
            v = np.asarray([np.nan if x is None else float(x) for x in values[b.metric]], dtype=float)
            for bound, sign in ((b.lo, -1.0), (b.hi, 1.0)):
                if bound is None:
                    continue
                scale = max(abs(float(bound)), 1e-12)
                over = np.maximum(sign * (v - float(bound)), 0.0) / scale
                total += np.where(np.isfinite(over), over, 1.0)
        # below a failed design's violation whatever the bounds' scale: infeasible beats failed
        cv = np.where(inf, np.clip(total, 1e-12, 0.5 * FAILED_VIOLATION), cv)
    return cv


def hypervolumes(F_by_generation: list[Array], ref: Array) -> list[float]:
    """The hypervolume of each generation's feasible set (minimised objectives, normalised) up
    to ``ref`` (pymoo's indicator)."""
    from pymoo.indicators.hv import HV

    ind = HV(ref_point=ref)
    return [float(ind(F)) if len(F) else 0.0 for F in F_by_generation]


def normalise(F: Array) -> tuple[Array, Array, Array]:
    """``F`` scaled to [0, 1] per objective over all its rows; the reference point 1.1."""
    lo, hi = F.min(axis=0), F.max(axis=0)
    span = np.where(hi > lo, hi - lo, 1.0)
    return (F - lo) / span, np.full(F.shape[1], 1.1), span


def generation_values(table: Any, lo: int, hi: int, space: Any) -> tuple[Array, Array]:
    """The minimised objectives ``(hi - lo, k)`` and violations of designs ``lo .. hi - 1`` from
    the sweep's table (sorted by design id, each design once)."""
    ids = np.asarray(table.column("design_id").to_numpy(zero_copy_only=False))
    rows = np.flatnonzero((ids >= lo) & (ids < hi))
    if rows.size != hi - lo:
        raise RuntimeError(f"internal error: designs {lo} to {hi - 1} are not all evaluated")
    sub = table.take(rows)
    status = np.asarray(sub.column("status").to_pylist(), dtype=object)
    values = {m: sub.column(m).to_pylist() for m in {b.metric for b in space.constraints}
              | {m for m, _ in space.objectives}}
    F = np.column_stack([[np.nan if v is None else float(v) for v in values[m]] for m, _ in space.objectives])
    return minimised(F, [s_ for _, s_ in space.objectives]), violation(status, values, space.constraints)
