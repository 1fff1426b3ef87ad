"""Writing a description (nested dict of numbers, strings, booleans, lists) back as TOML.

Only what parameter files hold is supported: tables, sub-tables, scalars and (nested) arrays
of scalars. Floats are written in Python's shortest round-trip form, so reading the file back
gives the identical doubles.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping
from typing import Any

__all__ = ["to_toml"]

_BARE = re.compile(r"^[A-Za-z0-9_-]+$")


def _key(k: str) -> str:
    return k if _BARE.match(k) else json.dumps(k, ensure_ascii=False)


def _value(v: Any, where: str) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise ValueError(f"{where}: non-finite value {v}")
        text = repr(v + 0.0)
        return text if any(c in text for c in ".en") else text + ".0"
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x, f"{where}[{i}]") for i, x in enumerate(v)) + "]"
    if isinstance(v, Mapping):
        return "{" + ", ".join(f"{_key(k)} = {_value(x, f'{where}.{k}')}" for k, x in v.items()) + "}"
    raise ValueError(f"{where}: cannot write {type(v).__name__} as TOML")


def _table(lines: list[str], name: str, table: Mapping[str, Any]) -> None:
    scalars = {k: v for k, v in table.items() if not isinstance(v, Mapping)}
    subs = {k: v for k, v in table.items() if isinstance(v, Mapping)}
    if name and (scalars or not subs):
        lines.append(f"\n[{name}]")
    for k, v in scalars.items():
        lines.append(f"{_key(k)} = {_value(v, f'{name}.{k}' if name else k)}")
    for k, v in subs.items():
        _table(lines, f"{name}.{_key(k)}" if name else _key(k), v)


def to_toml(description: Mapping[str, Any], header: str = "") -> str:
    """TOML text of ``description``; ``header`` lines are written as comments first."""
    lines = [f"# {h}" if h else "#" for h in header.splitlines()]
    _table(lines, "", description)
    return "\n".join(lines).lstrip("\n") + "\n"
