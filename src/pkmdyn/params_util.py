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
        raise ParameterError(f"{path}: cannot read parameter file ({exc.strerror or exc})") from None
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError(f"{path}: not valid TOML ({exc})") from None


def describe_errors(exc: ValidationError, source: str) -> str:
    """One line naming every failing key as ``[table] key: rule``."""
    parts = []
    for err in exc.errors():
        loc = [str(p) for p in err["loc"]]
        if len(loc) >= 2:
            where = f"[{loc[0]}] {'.'.join(loc[1:])}"
        elif loc:
            where = f"[{loc[0]}]" if err["type"] != "extra_forbidden" else f"key {loc[0]!r}"
        else:
            where = "file"
        kind = err["type"]
        if kind == "extra_forbidden":
            msg = "unknown key"
        elif kind == "missing":
            msg = "missing required key"
        else:
            msg = err["msg"]
            if msg.startswith("Value error, "):
                msg = msg[len("Value error, ") :]
        parts.append(f"{where}: {msg}")
    return f"{source}: " + "; ".join(parts)


def validate(cls: type[M], data: dict[str, Any], source: str) -> M:
    """Validate ``data`` against ``cls``; failures become one :class:`ParameterError` line."""
    try:
        return cls.model_validate(data)
    except ValidationError as exc:
        raise ParameterError(describe_errors(exc, source)) from None
