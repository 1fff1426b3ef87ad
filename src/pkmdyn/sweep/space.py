"""The design space file: which keys vary and how, the motion, the constraints, the objectives.

Format (``docs/sweep.md``)::

    params = "base.toml"                 # optional base description (relative to this file)

    [sampling]
    method = "sobol"                     # grid | random | lhs | sobol
    designs = 1024                       # random, lhs, sobol: number of designs
    seed = 0
    max_designs = 100000                 # plausibility limit (raise it here or with --limit)
    batch_size = 100                     # optional: designs per task

    [motion]                             # machine-specific (docs/sweep.md)
    samples_per_cycle = 500

    [parameters]
    "geometry.base_radius_m" = { min = 0.22, max = 0.32 }           # grid: points = 5
    "geometry.platform_heights_m[1]" = { values = [0.45, 0.49] }
    "geometry.lever_length_m" = { min = 0.3, max = 0.4, scale = "log" }

    [constraints]
    peak_drive_force_N = { max = 3000.0 }

    [objectives]
    peak_drive_force_N = "min"
    gci = "max"

A parameter is any numeric key of the machine's description by its dotted path; list entries
by a zero-based index in brackets, or by their ``name`` (``bodies[platform].mass_kg``). Everything is checked before any design is evaluated; every
error is one :class:`~pkmdyn.errors.ParameterError` line that names the file and the key.
"""

from __future__ import annotations

import copy
import math
import re
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, model_validator

from ..errors import LimitError, ParameterError
from ..params_util import Section, read_toml, validate
from ..sweep_protocol import MetricInfo
from .search import Nsga2Search

__all__ = [
    "Parameter",
    "Bound",
    "SweepSpace",
    "load_space",
    "space_from_dict",
    "parse_path",
    "index_path",
    "get_value",
    "set_value",
    "sample_designs",
    "design_count",
    "design_description",
    "refine_designs",
    "read_space",
    "DEFAULT_MAX_DESIGNS",
    "METHODS",
]

Array = NDArray[np.float64]

#: NSGA-II's default distribution indices of simulated binary crossover and polynomial mutation
#: (pymoo's, after Deb et al. 2002)
CROSSOVER_ETA = 15.0
MUTATION_ETA = 20.0
#: designs of one sweep unless raised (``[sampling] max_designs`` or ``--limit max_designs=N``)
DEFAULT_MAX_DESIGNS = 100_000
METHODS = ("grid", "random", "lhs", "sobol", "nsga2")
_FINITE = Annotated[float, Field(allow_inf_nan=False)]


class _Param(Section):
    min: _FINITE | None = None
    max: _FINITE | None = None
    points: Annotated[int, Field(ge=1)] | None = None
    values: Annotated[list[_FINITE], Field(max_length=100_000)] | None = None
    scale: Literal["linear", "log"] = "linear"

    @model_validator(mode="after")
    def _shape(self) -> "_Param":
        if self.values is not None:
            if self.min is not None or self.max is not None or self.points is not None or self.scale != "linear":
                raise ValueError("give either values = [...] or min and max (with points for a grid), not both")
            if not self.values:
                raise ValueError("empty range: values = [] holds no value")
            return self
        if self.min is None or self.max is None:
            raise ValueError("give min and max, or values = [...]")
        if not self.min < self.max:
            raise ValueError(f"empty range: min = {self.min:g} must be < max = {self.max:g} "
                             "(for a fixed value give values = [x])")
        if self.scale == "log" and not self.min > 0:
            raise ValueError("scale = \"log\" needs min > 0")
        return self


class _Sampling(Section):
    method: Literal["grid", "random", "lhs", "sobol", "nsga2"] = "sobol"
    designs: Annotated[int, Field(ge=1)] | None = None
    #: nsga2: the generations after the first population (each of ``designs`` offspring)
    generations: Annotated[int, Field(ge=1, le=10_000)] | None = None
    seed: Annotated[int, Field(ge=0, le=2**63 - 1)] = 0
    max_designs: Annotated[int, Field(ge=1)] = DEFAULT_MAX_DESIGNS
    batch_size: Annotated[int, Field(ge=1, le=1_000_000)] | None = None
    #: nsga2: the distribution indices of simulated binary crossover and polynomial mutation
    crossover_eta: Annotated[float, Field(gt=0.0, le=1000.0)] | None = None
    mutation_eta: Annotated[float, Field(gt=0.0, le=1000.0)] | None = None


class _Refine(Section):
    rounds: Annotated[int, Field(ge=0, le=100)] = 0
    designs: Annotated[int, Field(ge=1)] = 256
    shrink: Annotated[float, Field(gt=0.0, le=1.0)] = 0.5


class _Bound(Section):
    min: _FINITE | None = None
    max: _FINITE | None = None

    @model_validator(mode="after")
    def _some(self) -> "_Bound":
        if self.min is None and self.max is None:
            raise ValueError("give min, max or both")
        if self.min is not None and self.max is not None and not self.min <= self.max:
            raise ValueError(f"min = {self.min:g} exceeds max = {self.max:g}: no value satisfies it")
        return self


class _SpaceFile(Section):
    params: str | None = None
    sampling: _Sampling = _Sampling()
    motion: dict[str, Any] = Field(default_factory=dict)
    parameters: dict[str, _Param]
    constraints: dict[str, _Bound] = Field(default_factory=dict)
    objectives: dict[str, Literal["min", "max"]]
    refine: _Refine = _Refine()
    #: a required task region (described mechanisms: ``grid``, ``pose``), handed to the machine
    #: with the ``[motion]`` options as ``requirements``
    requirements: dict[str, Any] | None = None


@dataclass(frozen=True)
class Parameter:
    """One swept key. ``path``: its place in the description (table names, key, list indices);
    ``integer``: the key holds an integer (samples are rounded); ``values``: a discrete set,
    or ``lo``/``hi`` with ``points`` (grid) and ``scale``."""

    key: str
    path: tuple[str | int, ...]
    integer: bool
    lo: float | None = None
    hi: float | None = None
    points: int | None = None
    values: tuple[float, ...] | None = None
    scale: str = "linear"


@dataclass(frozen=True)
class Bound:
    """A constraint ``lo <= metric <= hi`` (either side may be absent)."""

    metric: str
    lo: float | None
    hi: float | None

    def violation(self, value: float) -> str:
        """'' when satisfied, else a short statement of the violation."""
        if self.lo is not None and not value >= self.lo:
            return f"{self.metric} = {value:.6g} < min {self.lo:g}"
        if self.hi is not None and not value <= self.hi:
            return f"{self.metric} = {value:.6g} > max {self.hi:g}"
        return ""


@dataclass(frozen=True)
class SweepSpace:
    """A validated space file. ``objectives``: ``(metric, "min" | "max")`` in file order (the
    first is the primary one, which picks the best design)."""

    source: str
    base_dir: Path
    params_path: Path | None
    method: str
    designs: int
    seed: int
    max_designs: int
    batch_size: int | None
    motion: dict[str, Any]
    parameters: tuple[Parameter, ...]
    constraints: tuple[Bound, ...]
    objectives: tuple[tuple[str, str], ...]
    refine_rounds: int = 0
    refine_designs: int = 0
    refine_shrink: float = 0.5
    #: NSGA-II's distribution indices of crossover and mutation (pymoo's defaults)
    crossover_eta: float = CROSSOVER_ETA
    mutation_eta: float = MUTATION_ETA

    def record(self) -> dict[str, Any]:
        """A plain, JSON-able echo of the space (what a resumed run must match)."""
        return {
            "method": self.method, "designs": self.designs, "seed": self.seed,
            "motion": self.motion,
            "parameters": [{"key": p.key, "min": p.lo, "max": p.hi, "points": p.points,
                            "values": list(p.values) if p.values is not None else None, "scale": p.scale}
                           for p in self.parameters],
            "constraints": [{"metric": b.metric, "min": b.lo, "max": b.hi} for b in self.constraints],
            "objectives": [list(o) for o in self.objectives],
            "refine": {"rounds": self.refine_rounds, "designs": self.refine_designs, "shrink": self.refine_shrink},
            # only where not the defaults: the record of a run made before these keys existed
            **({"eta": [self.crossover_eta, self.mutation_eta]}
               if (self.crossover_eta, self.mutation_eta) != (CROSSOVER_ETA, MUTATION_ETA) else {}),
        }


_SEGMENT = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)((?:\[[^\[\]]+\])*)")


class ByName(str):
    """A path part that picks the entry of a list of tables whose ``name`` it is
    (``bodies[platform]``)."""


def parse_path(key: str) -> tuple[str | int, ...]:
    """``"geometry.platform_heights_m[1]"`` -> ``("geometry", "platform_heights_m", 1)``; a
    bracket that is not a number names a list entry by its ``name`` key: ``"bodies[platform].mass_kg"``
    -> ``("bodies", ByName("platform"), "mass_kg")``."""
    parts: list[str | int] = []
    pos = 0
    while True:
        m = _SEGMENT.match(key, pos)
        if m is None:
            raise ParameterError(f"{key!r}: not a dotted key path (table.key, list entries as key[i] or "
                                 "key[name])")
        parts.append(m.group(1))
        for sel in re.findall(r"\[([^\[\]]+)\]", m.group(2)):
            parts.append(int(sel) if sel.isdigit() else ByName(sel))
        pos = m.end()
        if pos == len(key):
            return tuple(parts)
        if key[pos] != "." or pos + 1 == len(key):
            raise ParameterError(f"{key!r}: not a dotted key path (table.key, list entries as key[i] or "
                                 "key[name])")
        pos += 1


def _named(node: Any, name: str, where: str) -> int:
    """The index of the entry of the list ``node`` whose ``name`` is ``name``."""
    if not isinstance(node, list):
        raise KeyError(f"{where} is not a list")
    found = [i for i, e in enumerate(node) if isinstance(e, Mapping) and e.get("name") == name]
    if len(found) != 1:
        names = [e.get("name") for e in node if isinstance(e, Mapping) and isinstance(e.get("name"), str)]
        raise KeyError(f"{len(found) or 'no'} entries named {name!r} in {where} (names: {', '.join(names) or 'none'})")
    return found[0]


def index_path(description: Mapping[str, Any], path: Sequence[str | int]) -> tuple[str | int, ...]:
    """``path`` with every :class:`ByName` part replaced by its entry's index in
    ``description`` (``KeyError`` naming the part that is missing)."""
    out: list[str | int] = []
    node: Any = description
    for k, part in enumerate(path):
        if isinstance(part, ByName):
            part = _named(node, str(part), _show(path[:k]))
        elif isinstance(part, int):
            if not isinstance(node, list) or part >= len(node):
                size = len(node) if isinstance(node, list) else 0
                raise KeyError(f"index [{part}] out of range (the list has {size} entries)"
                               if isinstance(node, list) else f"{_show(path[:k])} is not a list")
        elif not isinstance(node, Mapping) or part not in node:
            raise KeyError(f"no key {_show(path[:k + 1])}")
        out.append(part)
        node = node[part]
    return tuple(out)


def get_value(description: Mapping[str, Any], path: Sequence[str | int]) -> Any:
    """The value at ``path``; ``KeyError`` naming the first missing part."""
    node: Any = description
    for part in index_path(description, path):
        node = node[part]
    return node


def set_value(description: dict[str, Any], path: Sequence[str | int], value: Any) -> None:
    """Set the value at an existing ``path`` (list entries by index) in place."""
    node: Any = description
    for part in path[:-1]:
        node = node[part]
    node[path[-1]] = value


def _show(path: Sequence[str | int]) -> str:
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, (int, ByName)) else (f".{p}" if out else p)
    return out


def design_count(space: SweepSpace) -> int:
    """Designs of the space: the product of the grid sizes (an upper bound where integer keys
    merge grid points), or ``designs``; computed without building the grid."""
    if space.method != "grid":
        return space.designs
    n = 1
    for p in space.parameters:
        n *= len(p.values) if p.values is not None else int(p.points or 0)
    return n


def space_from_dict(raw: Mapping[str, Any], description: Mapping[str, Any], metrics: Sequence[MetricInfo],
                    source: str = "space", base_dir: Path | None = None,
                    max_designs: int | None = None) -> SweepSpace:
    """Validate a parsed space file against a machine's description and metrics.

    ``max_designs`` (from ``--limit max_designs=N``) overrides ``[sampling] max_designs``.
    """
    d = validate(_SpaceFile, dict(raw), source)
    s = d.sampling
    if not d.parameters:
        raise ParameterError(f"{source}: [parameters]: no parameter to vary")
    params = []
    seen: dict[tuple, str] = {}
    for key, spec in d.parameters.items():
        try:
            path = parse_path(key)
            top = description.get("parameters")
            if path[0] not in description and isinstance(top, dict) and path[0] in top:
                path = ("parameters", *path)  # a parameter by its bare name (an entry of a vector one too)
            path = index_path(description, path)
            value = get_value(description, path)
        except KeyError as exc:
            raise ParameterError(f"{source}: [parameters] {key}: unknown key of the machine's description "
                                 f"({exc.args[0]})") from None
        except ParameterError as exc:
            raise ParameterError(f"{source}: [parameters] {exc}") from None
        if (path and path[0] == "parameters" and isinstance(value, dict) and "value" in value
                and set(value) <= {"value", "min", "max"}):
            # a bounded parameter { value, min, max }: its value is swept, and a design outside
            # its bounds becomes a row with the description's reason
            path, value = tuple(path) + ("value",), value["value"]
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ParameterError(f"{source}: [parameters] {key}: not a numeric key "
                                 f"(it holds {type(value).__name__}); only numbers can be swept")
        if tuple(path) in seen:
            raise ParameterError(f"{source}: [parameters] {key}: the same key as {seen[tuple(path)]}; sweep it once")
        seen[tuple(path)] = key
        # a description's parameter is a real number whatever its spelling (1 or 1.0); another
        # key written as a whole number is swept on whole numbers
        integer = isinstance(value, int) and not (path and path[0] == "parameters")
        if s.method == "grid" and spec.values is None and spec.points is None:
            raise ParameterError(f"{source}: [parameters] {key}: method = \"grid\" needs points = N "
                                 "(or values = [...])")
        if s.method != "grid" and spec.points is not None:
            raise ParameterError(f"{source}: [parameters] {key}: points applies to method = \"grid\" only")
        if integer and spec.values is not None and any(v != round(v) for v in spec.values):
            raise ParameterError(f"{source}: [parameters] {key}: the key holds an integer; values must be integers")
        if integer and spec.values is None and math.ceil(spec.min) > math.floor(spec.max):  # type: ignore[arg-type]
            raise ParameterError(f"{source}: [parameters] {key}: empty range: no integer in "
                                 f"[{spec.min:g}, {spec.max:g}]")
        params.append(Parameter(key=key, path=path, integer=integer, lo=spec.min, hi=spec.max, points=spec.points,
                                values=tuple(spec.values) if spec.values is not None else None, scale=spec.scale))
    known = {m.name for m in metrics}
    names = ", ".join(m.name for m in metrics)
    for table, keys in (("constraints", d.constraints), ("objectives", d.objectives)):
        for k in keys:
            if k not in known:
                raise ParameterError(f"{source}: [{table}] {k}: unknown metric (known: {names})")
    if not d.objectives:
        raise ParameterError(f"{source}: [objectives]: give at least one, e.g. {next(iter(known))} = \"min\"")
    if s.method == "grid" and s.designs is not None:
        raise ParameterError(f"{source}: [sampling] designs: a grid's size is set by the parameters' points")
    if s.method != "grid" and s.designs is None:
        raise ParameterError(f"{source}: [sampling] designs: missing required key for method = \"{s.method}\"")
    if s.method == "nsga2":
        if s.generations is None:
            raise ParameterError(f"{source}: [sampling] generations: missing required key for method = \"nsga2\"")
        if d.refine.rounds:
            raise ParameterError(f"{source}: [refine]: method = \"nsga2\" evolves its own generations; "
                                 "leave [refine] out")
    elif s.generations is not None:
        raise ParameterError(f"{source}: [sampling] generations: applies to method = \"nsga2\" only")
    for key in ("crossover_eta", "mutation_eta"):
        if s.method != "nsga2" and getattr(s, key) is not None:
            raise ParameterError(f"{source}: [sampling] {key}: applies to method = \"nsga2\" only")
    if s.method == "nsga2" and s.designs < 4:  # type: ignore[operator]
        raise ParameterError(f"{source}: [sampling] designs: an NSGA-II population needs at least 4 designs")
    params_path = None
    base_dir = base_dir if base_dir is not None else Path(".")
    if d.params is not None:
        params_path = Path(d.params) if Path(d.params).is_absolute() else base_dir / d.params
    space = SweepSpace(
        source=source, base_dir=base_dir, params_path=params_path, method=s.method, designs=s.designs or 0,
        seed=s.seed, max_designs=max_designs if max_designs is not None else s.max_designs,
        batch_size=s.batch_size,
        motion={**dict(d.motion), **({"requirements": dict(d.requirements)} if d.requirements is not None else {})},
        parameters=tuple(params),
        constraints=tuple(Bound(k, b.min, b.max) for k, b in d.constraints.items()),
        objectives=tuple(d.objectives.items()),
        # an NSGA-II run's generations are its rounds, each of one population of designs
        refine_rounds=s.generations if s.method == "nsga2" else d.refine.rounds,
        refine_designs=(s.designs if s.method == "nsga2" else d.refine.designs if d.refine.rounds else 0),
        refine_shrink=d.refine.shrink,
        crossover_eta=CROSSOVER_ETA if s.crossover_eta is None else s.crossover_eta,
        mutation_eta=MUTATION_ETA if s.mutation_eta is None else s.mutation_eta,
    )
    n = design_count(space) + space.refine_rounds * space.refine_designs
    if n > space.max_designs:
        raise LimitError(f"{source}: {n:,} designs exceed the limit max_designs = {space.max_designs:,} (raise it "
                         "with [sampling] max_designs in the space file or --limit max_designs=N)")
    if s.method == "grid":
        n = math.prod(len(_grid_axis(p)) for p in space.parameters)
        space = SweepSpace(**{**space.__dict__, "designs": n})
    return space


def read_space(path: str | Path) -> dict[str, Any]:
    """The raw space file (UTF-8 TOML), one-line errors naming the file."""
    return read_toml(path)


def load_space(path: str | Path, description_for: Any, metrics_for: Any,
               max_designs: int | None = None, search: str | None = None) -> tuple[SweepSpace, dict[str, Any]]:
    """Read and validate a space file. ``description_for(params_path)`` returns the base
    description (``params`` of the space file, or ``None``), ``metrics_for(motion_options, description)``
    the metrics; ``search`` (``--search``) replaces ``[sampling] method``; returns the space and
    the base description."""
    p = Path(path)
    raw = read_space(p)
    if search is not None and isinstance(raw, dict):
        sampling = raw.get("sampling", {})
        raw["sampling"] = {**(sampling if isinstance(sampling, dict) else {}), "method": search}
    params = raw.get("params") if isinstance(raw, dict) else None
    base_dir = p.absolute().parent
    params_path = None
    if isinstance(params, str):
        params_path = Path(params) if Path(params).is_absolute() else base_dir / params
    description = description_for(params_path)
    motion = dict(raw.get("motion", {})) if isinstance(raw.get("motion", {}), dict) else {}
    if isinstance(raw.get("requirements"), dict):
        motion["requirements"] = dict(raw["requirements"])
    space = space_from_dict(raw, description, metrics_for(motion, description), str(p), base_dir,
                            max_designs)
    return space, description


def _unit_sample(space: SweepSpace) -> Array:
    """``(n, d)`` points in [0, 1) from the space's method and seed (random, lhs, sobol)."""
    n, d = space.designs, len(space.parameters)
    rng = np.random.default_rng(space.seed)
    if space.method == "random":
        return rng.random((n, d))
    from scipy.stats import qmc

    if space.method == "lhs":
        return qmc.LatinHypercube(d, rng=rng).random(n)
    engine = qmc.Sobol(d, scramble=True, rng=rng)
    with warnings.catch_warnings():
        # a count that is not a power of two loses Sobol's balance properties; the space file
        # may still ask for it (docs/sweep.md says so)
        warnings.simplefilter("ignore", UserWarning)
        return engine.random(n)


def from_unit(space: SweepSpace, U: Array) -> Array:
    """Designs ``(n, d)`` from points ``U (n, d)`` of the unit cube (each parameter's range, log
    range, integers or list of values)."""
    return np.stack([_from_unit(p, U[:, j]) for j, p in enumerate(space.parameters)], axis=-1)


def _from_unit(p: Parameter, u: Array) -> Array:
    if p.values is not None:
        vals = np.asarray(p.values, dtype=float)
        return vals[np.minimum((u * len(vals)).astype(np.int64), len(vals) - 1)]
    lo, hi = float(p.lo), float(p.hi)  # type: ignore[arg-type]
    if p.integer:
        a, b = math.ceil(lo), math.floor(hi)
        return np.minimum(np.floor(a + u * (b - a + 1)), b)
    if p.scale == "log":
        return np.exp(np.log(lo) + u * (np.log(hi) - np.log(lo)))
    return lo + u * (hi - lo)


def _grid_axis(p: Parameter) -> Array:
    if p.values is not None:
        return np.asarray(p.values, dtype=float)
    lo, hi, k = float(p.lo), float(p.hi), int(p.points)  # type: ignore[arg-type]
    if k == 1:
        axis = np.array([0.5 * (lo + hi)])
    elif p.scale == "log":
        axis = np.geomspace(lo, hi, k)
    else:
        axis = np.linspace(lo, hi, k)
    return np.unique(np.round(axis)) if p.integer else axis


def sample_designs(space: SweepSpace) -> Array:
    """Every design of the space, ``(n, d)``: row ``i`` is design ``i``, columns in parameter order.

    The same space file always gives the same designs (the seed fixes random, lhs and sobol);
    a grid varies the last parameter fastest.
    """
    if space.method == "grid":
        axes = [_grid_axis(p) for p in space.parameters]
        mesh = np.meshgrid(*axes, indexing="ij")
        return np.stack([m.reshape(-1) for m in mesh], axis=-1)
    if space.method == "nsga2":
        return from_unit(space, Nsga2Search(space).ask())
    u = _unit_sample(space)
    return np.stack([_from_unit(p, u[:, j]) for j, p in enumerate(space.parameters)], axis=-1)


def refine_designs(space: SweepSpace, X: Array, centres: Array, round_index: int) -> Array:
    """The ``refine_designs`` new designs of refinement round ``round_index`` (1, 2, ...).

    New design k is drawn around the design ``X[centres[k mod len(centres)]]`` (``centres``:
    the Pareto set so far, sorted by design id): each parameter moves by ``(2 u - 1) h`` with
    ``u`` from a scrambled Sobol sequence (seeded by the space's seed and the round) and the
    half-width ``h = shrink^r / 2`` of its range (of its log range for ``scale = "log"``; of
    the index range for a ``values`` list), clipped to the range; integer keys are rounded.
    """
    from scipy.stats import qmc

    m, d = space.refine_designs, len(space.parameters)
    rng = np.random.default_rng([space.seed, round_index])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # any count, as for the first sample
        s = 2.0 * qmc.Sobol(d, scramble=True, rng=rng).random(m) - 1.0
    half = 0.5 * space.refine_shrink ** round_index
    C = X[np.asarray(centres, dtype=np.int64)[np.arange(m) % len(centres)]]
    out = np.empty((m, d))
    for j, p in enumerate(space.parameters):
        c, step = C[:, j], s[:, j] * half
        if p.values is not None:
            vals = np.asarray(p.values, dtype=float)
            k = len(vals)
            ci = np.array([int(np.flatnonzero(vals == v)[0]) for v in c])
            out[:, j] = vals[np.clip(np.rint(ci + step * (k - 1)), 0, k - 1).astype(np.int64)]
            continue
        lo, hi = float(p.lo), float(p.hi)  # type: ignore[arg-type]
        if p.scale == "log":
            out[:, j] = np.exp(np.clip(np.log(c) + step * (math.log(hi) - math.log(lo)), math.log(lo), math.log(hi)))
        else:
            out[:, j] = np.clip(c + step * (hi - lo), lo, hi)
        if p.integer:
            out[:, j] = np.clip(np.rint(out[:, j]), math.ceil(lo), math.floor(hi))
    return out


def design_description(base: Mapping[str, Any], parameters: Sequence[Parameter], row: Array) -> dict[str, Any]:
    """The description of one design: the base with the swept keys set (integers as ``int``)."""
    d = copy.deepcopy(dict(base))
    for p, v in zip(parameters, row):
        set_value(d, p.path, int(v) if p.integer else float(v))
    return d
