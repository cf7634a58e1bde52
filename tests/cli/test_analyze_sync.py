"""`netsim analyze` with monitors and mailboxes: blocking terms, self-suspending tasks, protocol none."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pandas as pd
import pytest

import netsim
from netsim.cli.analyze import analyze_run
from netsim.scenario import load_scenario
from netsim.scenario.loader import read_yaml

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "sync_servo.yaml"


def _table(raw: Any, **overrides: Any) -> pd.DataFrame:
    scenario = load_scenario(raw, overrides or None)
    return analyze_run(scenario, netsim.run(scenario)).set_index(["kind", "name"])


def test_sync_servo() -> None:
    """The controller blocks on the mailbox (fetch) and the sensor may (post to a full one): no bound of their
    own; for the tasks below them their jitter is D - C (9 and 9.5 ms). Background (C 4, T 20, B 3 = the
    logger's section, inheritance): w = 4 + 3 + ceil((10 + 9)/10) 1 + ceil((10 + 9.5)/10) 0.5 = 10 ms.
    Logger (C 3, no blocking: nothing below it): w = 3 + 2 + 1 + ceil(10/20) 4 = 10 ms."""
    table = _table(SCENARIO, duration="0.4 s")
    assert table.loc[("task", "computer.controller"), "analysis"] == "n/a"
    assert "self-suspending" in table.loc[("task", "computer.controller"), "note"]
    assert table.loc[("task", "computer.sensor"), "analysis"] == "n/a"
    assert table.loc[("task", "computer.background"), "analysis"] == pytest.approx(10.0)
    assert "B = 3 ms (inherit)" in table.loc[("task", "computer.background"), "note"]
    assert table.loc[("task", "computer.logger"), "analysis"] == pytest.approx(10.0)
    assert not (table["verdict"] == "EXCEEDS").any()


def _inversion(protocol: str) -> pd.DataFrame:
    """tests/analysis/test_blocking.py's INVERSION set as a scenario of critical_section tasks."""
    raw, _ = read_yaml(SCENARIO)
    node = raw["nodes"]["computer"]
    node["sync"] = {"monitors": {"res": {"protocol": protocol}}}
    node["tasks"] = [
        {"name": "H", "program": "critical_section", "period": "20 ms", "offset": "1 ms", "priority": 1,
         "params": {"monitor": "res", "before": "1 ms", "inside": "1 ms", "after": "1 ms"}},
        {"name": "M", "program": "critical_section", "period": "30 ms", "offset": "1 ms", "priority": 2,
         "params": {"before": "5 ms"}},
        {"name": "L", "program": "critical_section", "period": "60 ms", "priority": 3,
         "params": {"monitor": "res", "before": "1 ms", "inside": "4 ms", "after": "1 ms"}}]
    raw["metrics"] = []
    raw["record"] = []
    return _table(raw, duration="0.3 s")


@pytest.mark.parametrize("protocol", ["inherit", "ceiling"])
def test_the_blocking_bound_is_reached(protocol: str) -> None:
    """R_H = 3 + 4 = 7, R_M = 5 + 4 + 3 = 12, R_L = 6 + 3 + 5 = 14 ms (test_blocking.py); the run reaches each."""
    table = _inversion(protocol)
    for task, bound in (("H", 7.0), ("M", 12.0), ("L", 14.0)):
        analysis, simulated = table.loc[("task", f"computer.{task}"), ["analysis", "simulated"]]
        assert analysis == pytest.approx(bound) and simulated == pytest.approx(bound)
    assert not (table["verdict"] == "EXCEEDS").any()


def test_without_inheritance_there_is_no_bound() -> None:
    table = _inversion("none")
    for task in ("H", "M"):
        assert table.loc[("task", f"computer.{task}"), "analysis"] == "n/a"
        assert "blocking unbounded" in table.loc[("task", f"computer.{task}"), "note"]
    assert table.loc[("task", "computer.H"), "simulated"] == pytest.approx(12.0)  # behind M: 1 + 5 + 4 + 2
    assert table.loc[("task", "computer.L"), "analysis"] == pytest.approx(14.0)
