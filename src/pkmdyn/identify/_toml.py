"""A minimal TOML writer for parameter descriptions: tables of numbers, strings and lists.

Floats are written with ``repr`` (shortest text that reads back to the same double), so a
file written here and read by ``tomllib`` gives the same numbers bit for bit.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

__all__ = ["dumps_tables"]


def _value(v: Any, where: str) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise ValueError(f"refusing to write a non-finite value at {where}")
        return repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x, f"{where}[{i}]") for i, x in enumerate(v)) + "]"
    raise TypeError(f"cannot write {type(v).__name__} at {where} as TOML")


def dumps_tables(tables: Mapping[str, Mapping[str, Any]], header: str = "", notes: Mapping[str, str] | None = None) -> str:
    """TOML text of ``{table: {key: value}}``; ``notes[key]`` becomes a comment after that key."""
    notes = notes or {}
    lines = [f"# {h}" if h else "#" for h in header.splitlines()] if header else []
    for name, table in tables.items():
        if lines:
            lines.append("")
        lines.append(f"[{name}]")
        for key, v in table.items():
            text = f"{key} = {_value(v, f'{name}.{key}')}"
            if key in notes:
                text += f"  # {notes[key]}"
            lines.append(text)
    return "\n".join(lines) + "\n"
