"""Shared helpers for turning TOML descriptions into validated models.

A description is validated with pydantic (strict types, unknown keys forbidden, every number
finite) and every failure is reported as one line that names the file, the table and the key.
The file itself must be UTF-8 TOML (a UTF-8 byte-order mark is allowed) of at most
:data:`MAX_TOML_BYTES`; every other problem (UTF-16, NUL bytes, invalid bytes, nesting too
deep) is one :class:`~pkmdyn.errors.ParameterError` line naming the file.

Plausibility limits (a load above 20 kN, a slider faster than 2 m/s, ...) are not hard rules:
each machine's ``[limits]`` table holds them with documented defaults, and
:func:`check_limit` refuses a value beyond one with a message that says how to raise it.
"""

from __future__ import annotations

import os
import tomllib
from pathlib import Path
from typing import Any, TypeVar

from pydantic import BaseModel, ConfigDict, ValidationError

from .errors import LimitError, ParameterError
from .io import check_text_encoding

__all__ = ["Section", "read_toml", "validate", "describe_errors", "check_limit", "parse_limit_options", "MAX_TOML_BYTES"]

#: parameter files larger than this are refused before parsing (a description is a few kB)
MAX_TOML_BYTES = 1 << 20

M = TypeVar("M", bound=BaseModel)


class Section(BaseModel):
    """Base for TOML tables: strict types, unknown keys are errors, numbers finite, immutable."""

    model_config = ConfigDict(extra="forbid", strict=True, frozen=True, allow_inf_nan=False)


def read_toml(path: str | Path) -> dict[str, Any]:
    """Read a TOML file; a missing, over-large, non-UTF-8 or malformed file is a :class:`ParameterError`."""
    if not isinstance(path, (str, os.PathLike)):
        raise ParameterError(f"expected a parameter file path, got {type(path).__name__}")
    path = Path(path)
    try:
        with path.open("rb") as fh:
            raw = fh.read(MAX_TOML_BYTES + 1)
    except OSError as exc:
        raise ParameterError(f"{path}: cannot read file ({exc.strerror or type(exc).__name__})") from None
    if len(raw) > MAX_TOML_BYTES:
        raise ParameterError(f"{path}: larger than {MAX_TOML_BYTES // 1024} KiB; not a parameter file")
    check_text_encoding(path, raw[:4096], ParameterError)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        raise ParameterError(
            f"{path}: not UTF-8 text (byte 0x{raw[exc.start:exc.start + 1].hex()} on line {line}); save it as UTF-8"
        ) from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError(f"{path}: not valid TOML ({exc})") from None
    except RecursionError:
        raise ParameterError(f"{path}: not valid TOML (arrays or tables nested too deep)") from None


def _rule(err: Any) -> str:
    """A short statement of the broken rule, in the project's words."""
    kind, ctx = err["type"], err.get("ctx", {})
    if kind == "missing":
        return "missing required key"
    if kind == "extra_forbidden":
        return "unknown key"
    bounds = {"greater_than": ">", "greater_than_equal": ">=", "less_than": "<", "less_than_equal": "<="}
    if kind in bounds:
        limit = next(iter(ctx.values()))
        got = err.get("input")
        shown = f", got {got:g}" if isinstance(got, (int, float)) and not isinstance(got, bool) else ""
        return f"must be {bounds[kind]} {limit:g}{shown}"
    if kind == "too_short":
        return f"has {ctx.get('actual_length', '?')} entries, needs at least {ctx.get('min_length')}"
    if kind == "too_long":
        return f"has {ctx.get('actual_length', '?')} entries, allows at most {ctx.get('max_length')}"
    if kind == "finite_number":
        return "must be a finite number (not inf or nan)"
    if kind.endswith("_type") or kind.endswith("_parsing"):
        return "has the wrong type (" + str(err["msg"]).lower() + ")"
    return str(err["msg"]).removeprefix("Value error, ")


def describe_errors(exc: ValidationError, source: str) -> str:
    """One line naming every failing key as ``[table] key: rule`` (list items as ``key[i]``)."""
    parts = []
    for err in exc.errors():
        loc = [str(p) for p in err["loc"]]
        rule = _rule(err)
        if len(loc) >= 2:
            where = f"[{loc[0]}] {loc[1]}" + "".join(f"[{p}]" for p in loc[2:])
        elif loc and err["type"] == "extra_forbidden":
            where, rule = f"[{loc[0]}]", "unknown section"
        elif loc:
            where = f"[{loc[0]}]"
            rule = rule.replace("key", "section")
        else:
            where = "file"
        parts.append(f"{where}: {rule}")
    return f"{source}: " + "; ".join(parts)


def validate(cls: type[M], data: dict[str, Any], source: str) -> M:
    """Validate ``data`` against ``cls``; failures become one :class:`ParameterError` line."""
    if not isinstance(data, dict):
        raise ParameterError(f"{source}: expected a description (a dict of tables), got {type(data).__name__}")
    try:
        return cls.model_validate(data)
    except ValidationError as exc:
        raise ParameterError(describe_errors(exc, source)) from None


def check_limit(value: float, limit: float, what: str, key: str, unit: str = "", option: bool = True,
                file: str = "the parameter file") -> None:
    """Refuse ``value`` above ``limit`` (a plausibility limit named ``key`` in ``[limits]``).

    The message gives the value, the limit and how to raise it (``option``: the command also
    takes ``--limit KEY=VALUE``; ``file``: the file whose ``[limits]`` holds it).
    """
    if not value <= limit:
        u = f" {unit}" if unit else ""
        shown = f"{value}" if isinstance(value, int) else f"{value:.4g}"
        how = f"[limits] {key} in {file}" + (f" or --limit {key}=VALUE" if option else "")
        raise LimitError(f"{what}: {shown}{u} exceeds the limit {key} = {limit:g}{u} (raise it with {how})")


def parse_limit_options(items: tuple[str, ...] | list[str], known: dict[str, type]) -> dict[str, Any]:
    """``("key=value", ...)`` from ``--limit`` options -> ``{key: value}``; checks names, types and
    that every value is finite and > 0."""
    out: dict[str, Any] = {}
    for item in items:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or key not in known:
            raise ParameterError(
                f"--limit {item!r}: expected KEY=VALUE with KEY one of {', '.join(sorted(known))}"
            )
        kind = known[key]
        try:
            value = int(text) if kind is int else float(text)
        except ValueError:
            raise ParameterError(f"--limit {key}: {text.strip()!r} is not {'an integer' if kind is int else 'a number'}") from None
        if not (value > 0 and float(value) < float("inf")):
            raise ParameterError(f"--limit {key}: must be a finite number > 0, got {text.strip()!r}")
        out[key] = value
    return out
