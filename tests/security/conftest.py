"""Shared pieces of the security tests (issue 14): a small valid scenario and a tree snapshot."""

from __future__ import annotations

import copy
import os
from pathlib import Path
from typing import Any

import pytest

#: scenarios/dc_servo_ideal.yaml, shortened: a plant, a signal, a task program, a policy and a metric.
SCENARIO: dict[str, Any] = {
    "name": "sec_servo",
    "duration": "60 ms",
    "plant": {"model": "dc_servo", "params": {"gain": 1000, "a": 1}},
    "io": {"y": {"type": "adc", "output": 0}, "u": {"type": "dac", "input": 0}},
    "signals": {"r": {"type": "square", "amplitude": 1.0, "period": "1 s"}},
    "nodes": {
        "computer": {
            "policy": "fp",
            "tasks": [{"name": "pid", "program": "periodic_controller",
                       "params": {"channel": "y", "output_channel": "u", "reference": "r", "K": 0.96, "Ti": 0.12,
                                  "Td": 0.049, "N": 10, "b": 0.5, "record_as": "u"},
                       "period": "6 ms", "priority": 1, "execution": "2 ms"}],
        },
    },
    "record": ["r", "y", "u"],
    "metrics": [{"type": "control_error", "params": {"reference": "r", "output": "y"}}],
}


@pytest.fixture
def scenario() -> Any:
    """A function returning a fresh copy of :data:`SCENARIO`."""
    return lambda: copy.deepcopy(SCENARIO)


def _write_yaml(path: Path, data: Any) -> Path:
    import json

    path.write_text(json.dumps(data, indent=1))  # JSON is YAML
    return path


def _snapshot(root: Path) -> dict[str, int]:
    out = {}
    for dirpath, _, files in os.walk(root):
        for f in files:
            p = Path(dirpath) / f
            out[str(p)] = p.lstat().st_mtime_ns
    return out


@pytest.fixture
def write_yaml() -> Any:
    """``write_yaml(path, data)``: ``data`` as a YAML file at ``path``; returns ``path``."""
    return _write_yaml


@pytest.fixture
def snapshot() -> Any:
    """``snapshot(root)``: every file below ``root`` (symlinks not followed) with its modification time."""
    return _snapshot
