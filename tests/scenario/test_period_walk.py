"""Issue 28's walk: a task's ``period`` goes from YAML to the kernel's releases with one parse and one check.

Every time parser any netsim module holds (``parse_time``, ``parse_duration``) is wrapped to count the calls that
read this task's period text, and the kernel's check of a task description (``TaskSpec._check``) to count the
conversions of this period into the checked description the kernel releases from. Before issue 28 the text was
parsed 4 times (the schema's Duration, validate.py twice, limits.py) and the task converted 3 times (validate's
kernel check, the dry run, the build).
"""

from __future__ import annotations

import sys
from collections import Counter
from typing import Any

import pytest

import netsim.timebase
from netsim.kernel.task import TaskSpec
from netsim.scenario import load_scenario
from netsim.build.builder import build

PERIOD = "7.25 ms"  # a text no other field of the scenario uses
PERIOD_NS = 7_250_000


def _scenario() -> dict[str, Any]:
    return {"name": "period_walk", "duration": "20 ms", "nodes": {"cpu": {"policy": "fp", "tasks": [
        {"name": "t", "program": "idle", "period": PERIOD, "priority": 1, "execution": "1 ms"}]}}}


@pytest.fixture()
def counts(monkeypatch: pytest.MonkeyPatch) -> Counter[str]:
    seen: Counter[str] = Counter()
    for name in ("parse_time", "parse_duration"):
        original = getattr(netsim.timebase, name)

        def counting(value: Any, *args: Any, _original: Any = original, _name: str = name, **kwargs: Any) -> int:
            if value == PERIOD:
                seen[_name] += 1
            return _original(value, *args, **kwargs)

        for module in [m for m in list(sys.modules.values()) if getattr(m, "__name__", "").startswith("netsim")]:
            if getattr(module, name, None) is original:
                monkeypatch.setattr(module, name, counting)
    check = TaskSpec._check

    def counting_check(self: TaskSpec, node: str) -> TaskSpec:
        if self.period == PERIOD_NS:
            seen["check"] += 1
        return check(self, node)

    monkeypatch.setattr(TaskSpec, "_check", counting_check)
    return seen


def test_a_task_period_is_parsed_once_and_checked_once_from_yaml_to_its_releases(counts: Counter[str]) -> None:
    scenario = load_scenario(_scenario())  # schema, validate's checks, limits, the dry run
    sim = build(scenario)
    sim.run()
    # parse_duration reads the text through parse_time: one parse shows as one call of each
    assert counts == {"parse_duration": 1, "parse_time": 1, "check": 1}
    task = sim.kernels["cpu"].tasks["t"]
    assert task.spec.period == PERIOD_NS
    # where it acts: releases at 0, 7.25 and 14.5 ms in a 20 ms run (k * period)
    releases = [r.release for r in sim.kernels["cpu"].job_records]
    assert releases == [0, PERIOD_NS, 2 * PERIOD_NS]
