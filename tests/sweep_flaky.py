"""A sweep adapter for the tests: the hip simulator's, except that the first batch evaluated
anywhere fails once (a flag file marks that it did), so that the retry path is exercised."""

from __future__ import annotations

from pathlib import Path

from pkmdyn.machines.registry import sweep_adapter

_hip = sweep_adapter("hip")
NAME = "hip"
base_description = _hip.base_description
check_description = _hip.check_description
metrics = _hip.metrics


def prepare(description, options, base_dir, flag: Path):
    return (_hip.prepare(description, options, base_dir), Path(flag))


def evaluate(descriptions, context):
    ctx, flag = context
    try:
        flag.touch(exist_ok=False)
    except FileExistsError:
        return _hip.evaluate(descriptions, ctx)
    raise RuntimeError("simulated failure of a batch (first attempt)")
