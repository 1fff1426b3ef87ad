"""pkmdyn's build backend: setuptools', with the project's own dependencies added to what a
wheel's build needs.

Building a wheel compiles pkmdyn's numerical kernels into numba's cache inside the package
(``setup.py``, ``pkmdyn compile``), which imports pkmdyn and runs its commands: the isolated
build environment needs what pkmdyn needs at run time, read here from ``pyproject.toml``'s
``[project] dependencies`` so that the list is written once. An editable install and a source
distribution compile nothing and need nothing more than setuptools.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

from setuptools import build_meta as _setuptools
from setuptools.build_meta import *  # noqa: F401,F403  (the PEP 517 hooks not redefined here)


def _runtime_dependencies() -> list[str]:
    with open(Path(__file__).resolve().parent.parent / "pyproject.toml", "rb") as f:
        return list(tomllib.load(f)["project"]["dependencies"])


def get_requires_for_build_wheel(config_settings=None):
    """setuptools' requirements and pkmdyn's run-time dependencies (module docstring)."""
    return [*_setuptools.get_requires_for_build_wheel(config_settings), *_runtime_dependencies()]
