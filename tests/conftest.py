"""Test set-up: the test helpers' folder on the path, and no quiet skips of optional engines in CI.

Tests that need an optional third-party engine (Pinocchio, MuJoCo) call
``pytest.importorskip``. On a developer's machine without the engine they are skipped; under
CI (the environment variable ``CI`` set, or ``PKMDYN_REQUIRE_OPTIONAL=1``), where
``.[test]`` installs every engine, such a skip is turned into a failure, so a broken or
missing engine cannot hide the tests that use it.
"""

import os
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))


def _engines_required() -> bool:
    return bool(os.environ.get("CI") or os.environ.get("PKMDYN_REQUIRE_OPTIONAL"))


def _fail_import_skip(report) -> None:
    """Turn a skip for a failed import into a failure where the engines are required."""
    if not (report.skipped and _engines_required()):
        return
    reason = report.longrepr[2] if isinstance(report.longrepr, tuple) else str(report.longrepr)
    if "could not import" in reason:
        report.outcome = "failed"
        report.longrepr = f"required under CI, skipped instead: {reason}"


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    _fail_import_skip(outcome.get_result())


@pytest.hookimpl(hookwrapper=True)
def pytest_make_collect_report(collector):
    outcome = yield
    _fail_import_skip(outcome.get_result())


def pytest_collection_modifyitems(config, items):
    """The long tests (marked slow: browser pages, memory, worker kills) first, each file's in
    its order, so that with two workers none of them starts near the end of the run while the
    other worker has nothing left to do."""
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)
