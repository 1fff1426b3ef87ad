"""Imports on first use, so that importing a package costs little until a function needs what is
heavy (Numba's kernels, SciPy's solvers and filters, the plotting libraries).

:func:`attach` gives a package the module ``__getattr__`` and ``__dir__`` of PEP 562: each
public name is imported from the submodule that defines it when it is first looked up
(``from pkmdyn.multibody import solve_kinematics`` loads the kinematics then, ``import
pkmdyn.multibody`` loads nothing). :func:`lazy_module` binds a third-party module at module
level and imports it at the first attribute looked up on it. Both leave the real imports under
``if TYPE_CHECKING:`` beside them for type checkers and for the import contracts::

    if TYPE_CHECKING:
        from scipy import signal
    else:
        signal = lazy_module("scipy.signal")
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Mapping
from types import ModuleType
from typing import Any

__all__ = ["attach", "lazy_module"]


def attach(package: str, where: Mapping[str, str]) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """The ``__getattr__`` and ``__dir__`` of the package named ``package``; ``where`` maps each
    public name to the module that defines it, relative to the package as in an import statement
    (``{"solve_kinematics": ".kinematics"}``). A name is kept in the package once imported."""

    def __getattr__(name: str) -> Any:
        try:
            module = where[name]
        except KeyError:
            raise AttributeError(f"module {package!r} has no attribute {name!r}") from None
        value = getattr(importlib.import_module(module, package), name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted({*vars(sys.modules[package]), *where})

    return __getattr__, __dir__


class _LazyModule:
    """Stands for the module ``name`` and imports it at the first attribute looked up."""

    __slots__ = ("_name", "_module")

    def __init__(self, name: str) -> None:
        self._name = name
        self._module: ModuleType | None = None

    def __getattr__(self, attr: str) -> Any:
        if attr in _LazyModule.__slots__:  # not yet set (a copy being made): no recursion
            raise AttributeError(attr)
        if self._module is None:
            self._module = importlib.import_module(self._name)
        return getattr(self._module, attr)

    def __repr__(self) -> str:
        state = "imported" if self._module is not None else "imported on first use"
        return f"<module {self._name!r} ({state})>"


def lazy_module(name: str) -> Any:
    """The module ``name`` (absolute: ``"scipy.signal"``), imported when an attribute of it is
    first looked up; until then not even its parent package is imported."""
    return _LazyModule(name)
