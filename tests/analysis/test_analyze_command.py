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
    table, _, result = _analyze("three_servos_dm.yaml")
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
    # pid3 runs first in every period (one constant 2 ms delay): the analysis is then exact, and equals the run's
    # ISE by the trapezoidal rule on signals.csv (r held over each grid step; the run stopped at 1.48 s)
    s = result.signals
    t, r, y = s["time_s"].to_numpy(), s["r"].to_numpy(), s["y3"].to_numpy()
    e0, e1 = r[:-1] - y[:-1], r[:-1] - y[1:]
    trapezoid = float(((e0 * e0 + e1 * e1) / 2 * (t[1:] - t[:-1])).sum())
    assert table.loc[("loop", "cpu.pid3"), "analysis"] == pytest.approx(trapezoid, rel=1e-4)
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


def test_a_state_feedback_loop_cost_equals_the_runs_integral() -> None:
    # A DC servo under LQR state feedback (estimator none: both states measured), u written 3 ms after each
    # 10 ms sample, square reference. The analysis' expected ISE equals the run's ISE computed here by the
    # trapezoidal rule from signals.csv (r held on each grid step) to 1e-5; the run's metric holds the error on
    # its 1 ms grid, which adds about dt/2 * sum of e^2 at the steps (0.5 ms * 13 = 0.0065, 3 %).
    sc = {"name": "sf", "seed": 1, "duration": "2 s",
          "plant": {"type": "ss", "A": [[0, 1], [0, -1]], "B": [[0], [1000]], "C": [[1, 0], [0, 1]],
                    "outputs": ["theta", "omega"], "inputs": ["u"], "record_grid": "1 ms"},
          "io": {"th": {"type": "adc", "output": "theta"}, "om": {"type": "adc", "output": "omega"},
                 "u": {"type": "dac", "input": "u"}},
          "signals": {"r": {"type": "square", "amplitude": 1.0, "period": "1 s"}},
          "nodes": {"cpu": {"policy": "fp", "tasks": [
              {"name": "ctl", "program": "state_feedback", "period": "10 ms", "priority": 1, "execution": "3 ms",
               "params": {"measurements": [{"channel": "th", "outputs": ["theta"]},
                                           {"channel": "om", "outputs": ["omega"]}],
                          "estimator": {"type": "none"}, "law": {"type": "lqr", "Q": [1, 0], "R": 1e-2},
                          "reference": "r", "output_channel": "u"}}]}},
          "record": ["r", "theta", "u"],
          "metrics": [{"type": "control_error", "params": {"reference": "r", "output": "theta"}}]}
    scenario = load_scenario(sc)
    result = netsim.run(scenario)
    table = analyze_run(scenario, result).set_index(["kind", "name"])
    analytic, metric = table.loc[("loop", "cpu.ctl"), ["analysis", "simulated"]]
    s = result.signals
    t, r, y = s["time_s"].to_numpy(), s["r"].to_numpy(), s["theta"].to_numpy()
    e0, e1 = r[:-1] - y[:-1], r[:-1] - y[1:]
    trapezoid = float(((e0 * e0 + e1 * e1) / 2 * (t[1:] - t[:-1])).sum())
    assert analytic == pytest.approx(trapezoid, rel=1e-5)
    assert metric == pytest.approx(analytic + 0.0005 * 13, rel=0.01)
