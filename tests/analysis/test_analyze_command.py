"""`netsim analyze`: analysis beside simulation on the shipped scenarios, a planted overrun is flagged, the CLI
writes analysis.csv."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

import netsim
from netsim.cli import main
from netsim.cli.analyze import analyze_run
from netsim.scenario import load_scenario

ROOT = Path(__file__).resolve().parents[2]


def _analyze(name: str, **overrides: object) -> tuple[pd.DataFrame, object, object]:
    scenario = load_scenario(ROOT / "scenarios" / name, overrides or None)
    result = netsim.run(scenario)
    return analyze_run(scenario, result).set_index(["kind", "name"]), scenario, result


def test_three_servos_dm_bounds_and_loop_costs() -> None:
    table, _, _ = _analyze("three_servos_dm.yaml")
    # DM with C = 2 ms each, T = 4, 5, 6 ms: R3 = 2 ms; R2 = 2 + 2 = 4 ms (one pid3 job); pid1's level load
    # 2/4 + 2/5 + 2/6 = 1.23 >= 1: unbounded (by hand, the Joseph & Pandya recurrence)
    assert table.loc[("task", "cpu.pid3"), "analysis"] == pytest.approx(2.0)
    assert table.loc[("task", "cpu.pid2"), "analysis"] == pytest.approx(4.0)
    assert table.loc[("task", "cpu.pid1"), "analysis"] == "unbounded"
    # the simulated worst responses reach the bounds exactly (synchronous release is the critical instant)
    assert table.loc[("task", "cpu.pid3"), "simulated"] == pytest.approx(2.0)
    assert table.loc[("task", "cpu.pid2"), "simulated"] == pytest.approx(4.0)
    assert not (table["verdict"] == "EXCEEDS").any()
    # the loops' expected ISE vs the run's: the run's ISE holds y on its 1 ms record grid, which adds about 1 %
    # (an exact 10 us time-stepping of the pid3 loop gives 0.4018, the analysis 0.4018, the metric 0.4063)
    for loop in ("cpu.pid2", "cpu.pid3"):
        analytic, simulated = table.loc[("loop", loop), ["analysis", "simulated"]]
        assert simulated == pytest.approx(analytic, rel=0.03)
    assert table.loc[("loop", "cpu.pid1"), "analysis"] == "n/a"  # its jobs overrun: outside the analysis


def test_dc_servo_can_message_bounds() -> None:
    table, _, _ = _analyze("dc_servo_can.yaml")
    # 80-bit frames at 80 kbit/s take 1 ms; each of the two streams can be blocked by the other one's frame
    # (non-preemptive), so the CAN bound is 1 + 1 = 2 ms; in the run they never collide: 1 ms
    for stream in ("can.sensor/p1", "can.controller/p2"):
        assert table.loc[("message", stream), "analysis"] == pytest.approx(2.0)
        assert table.loc[("message", stream), "simulated"] == pytest.approx(1.0)
    assert table.loc[("task", "sensor.sample"), "analysis"] == pytest.approx(0.9)  # 0.5 ms + 0.4 ms after_send
    analytic, simulated = table.loc[("loop", "controller.control"), ["analysis", "simulated"]]
    assert simulated == pytest.approx(analytic, rel=0.03)


def test_a_simulated_value_above_its_bound_is_flagged() -> None:
    scenario = load_scenario(ROOT / "scenarios" / "dc_servo_can.yaml")
    result = netsim.run(scenario)
    clean = analyze_run(scenario, result)
    assert not (clean["verdict"] == "EXCEEDS").any()
    # plant an overrun: one sensor job 1 ms slower than the bound allows, one message 1.5 ms late
    jobs = result.jobs
    first = jobs.index[(jobs["node"] == "sensor") & (jobs["task"] == "sample")][3]
    jobs.loc[first, "response_s"] = jobs.loc[first, "response_s"] + 1e-3
    msgs = result.messages
    late = msgs.index[msgs["sender"] == "sensor"][2]
    msgs.loc[late, "delay_s"] = msgs.loc[late, "delay_s"] + 1.5e-3
    flagged = analyze_run(scenario, result).set_index(["kind", "name"])
    assert flagged.loc[("task", "sensor.sample"), "verdict"] == "EXCEEDS"
    assert flagged.loc[("message", "can.sensor/p1"), "verdict"] == "EXCEEDS"
    assert flagged.loc[("task", "controller.control"), "verdict"] == "ok"


def test_cli_prints_the_table_and_writes_analysis_csv(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "run"
    code = main(["analyze", str(ROOT / "scenarios" / "dc_servo_can.yaml"), "--out", str(out)])
    text = capsys.readouterr().out
    assert code == 0
    assert "can.sensor/p1" in text and "verdict" in text
    table = pd.read_csv(out / "analysis.csv")
    assert list(table.columns) == ["kind", "name", "analysis", "simulated", "unit", "verdict", "note"]
    assert set(table["kind"]) == {"task", "message", "loop"}
