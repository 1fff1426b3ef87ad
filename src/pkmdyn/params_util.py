"""Shared helpers for turning TOML descriptions into validated models.

A description is validated with pydantic (strict types, unknown keys forbidden) and every
failure is reported as one line that names the file, the table and the key.
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any, TypeVar

from pydantic import BaseModel, ConfigDict, ValidationError

from .errors import ParameterError

__all__ = ["Section", "read_toml", "validate", "describe_errors"]

M = TypeVar("M", bound=BaseModel)


class Section(BaseModel):
    """Base for TOML tables: strict types, unknown keys are errors, immutable."""

    model_config = ConfigDict(extra="forbid", strict=True, frozen=True)


def read_toml(path: str | Path) -> dict[str, Any]:
    """Read a TOML file; a missing file or a syntax error is a :class:`ParameterError`."""
    path = Path(path)
    try:
        with path.open("rb") as fh:
            return tomllib.load(fh)
    except OSError as exc:
        raise ParameterError(f"{path}: cannot read file ({exc.strerror or exc})") from None
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError(f"{path}: not valid TOML ({exc})") from None


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
        return f"must be {bounds[kind]} {limit:g}"
    if kind == "too_short":
        return f"has {ctx.get('actual_length', '?')} entries, needs at least {ctx.get('min_length')}"
    if kind == "too_long":
        return f"has {ctx.get('actual_length', '?')} entries, allows at most {ctx.get('max_length')}"
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
    try:
        return cls.model_validate(data)
    except ValidationError as exc:
        raise ParameterError(describe_errors(exc, source)) from None
