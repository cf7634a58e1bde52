"""Feedback scheduling (issue 20): the scheduler's period arithmetic by hand, the shipped scenario's utilisation
converging to its set-point (measured independently from the jobs table), and validation of its parameters."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import netsim
from netsim.scenario import check_scenario, load_scenario

ROOT = Path(__file__).resolve().parents[1]
MS = 1_000_000


def _servo_tasks(execution: object, setpoint: float, scheduler_period: str = "50 ms") -> list[dict]:
    pids = [{"name": f"pid{i}", "program": "adaptive_pid", "period": f"{p} ms", "priority": 4 - i,
             "execution": execution,
             "params": {"channel": f"y{i}", "output_channel": f"u{i}", "K": 0.96, "Ti": 0.12, "Td": 0.049, "N": 10,
                        "b": 0.5}} for i, p in ((1, 6), (2, 5), (3, 4))]
    return [{"name": "scheduler", "program": "feedback_scheduler", "period": scheduler_period, "priority": 0,
             "params": {"tasks": ["pid1", "pid2", "pid3"], "setpoint": setpoint}}, *pids]


def _raw(tasks: list[dict], duration: str = "400 ms") -> dict:
    io = {f"y{i}": {"type": "adc", "output": f"y{i}"} for i in (1, 2, 3)}
    io |= {f"u{i}": {"type": "dac", "input": f"u{i}"} for i in (1, 2, 3)}
    return {"name": "fs", "duration": duration, "seed": 1,
            "plant": {"model": "dc_servo", "params": {"gain": 1000, "a": 1, "count": 3}}, "io": io,
            "nodes": {"cpu": {"policy": "fp", "tasks": tasks}}}


def test_constant_execution_times_give_the_periods_by_hand():
    # C = 2 ms each: U_nom = 2/6 + 2/5 + 2/4 = 37/30; set-point 0.5 -> scale 37/15; the periods (whole us)
    # 6 ms * 37/15 = 14.8 ms, 5 ms * 37/15 = 12.333 ms, 4 ms * 37/15 = 9.867 ms. The first scheduler job (t = 0)
    # has no estimate yet; from its second job (t = 50 ms) on the periods are these.
    res = netsim.run(_raw(_servo_tasks("2 ms", 0.5)), out=None)
    jobs = res.jobs
    for name, period_ms in (("pid1", 14.8), ("pid2", 12.333), ("pid3", 9.867)):
        rel = jobs[jobs.task == name].release_s.to_numpy()
        late = np.diff(rel[rel >= 0.1])
        assert late == pytest.approx(period_ms * 1e-3, abs=1e-12)
    assert res.metrics["control.cpu.scheduler.scale"] == pytest.approx(37 / 15)
    # the three tasks' utilisation is then the set-point (2/14.8 + 2/12.333 + 2/9.867 = 0.50002, whole us)
    assert res.metrics["control.cpu.scheduler.utilization_late"] == pytest.approx(0.5, abs=0.01)


def test_the_shipped_scenario_converges_to_its_setpoint():
    scenario = load_scenario(ROOT / "scenarios" / "feedback_scheduling.yaml")
    res = netsim.run(scenario)
    jobs = res.jobs
    pids = jobs[jobs.task.isin(["pid1", "pid2", "pid3"])]
    # the tasks' CPU utilisation per 250 ms window, from the jobs table (each job's CPU time counted in the window
    # of its start: an independent measure of what the scheduler controls)
    edges = np.arange(0.0, 2.0 + 1e-9, 0.25)
    used, _ = np.histogram(pids.start_s, bins=edges, weights=pids.cpu_time_s)
    u = used / 0.25
    first = pids[pids.start_s < 0.05]  # the nominal periods overload the CPU (U = 1.23) until the scheduler acts
    assert first.cpu_time_s.sum() > 0.95 * 0.05
    assert np.abs(u[2:] - 0.8).max() < 0.05  # from 0.5 s on, every window within 0.05 of the set-point 0.8
    assert abs(u[4:].mean() - 0.8) < 0.02
    assert res.metrics["control.cpu.scheduler.utilization_late"] == pytest.approx(0.8, abs=0.02)
    # the periods settled at one common scale of the nominal ones, about 1.23 / 0.8
    gaps = {n: np.median(np.diff(jobs[(jobs.task == n) & (jobs.release_s > 1.0)].release_s)) for n in ("pid1", "pid3")}
    assert gaps["pid1"] / 6e-3 == pytest.approx(gaps["pid3"] / 4e-3, rel=0.02)
    assert 1.4 < gaps["pid1"] / 6e-3 < 1.8
    # every loop stays stable (in three_servos_dm, pid1 at its nominal period misses every deadline: ISE ~1e18)
    for y in ("y1", "y2", "y3"):
        assert res.metrics[f"{y}.ISE"] < 1.0


@pytest.mark.parametrize("tasks, index, words", [
    (["pid1", "pidx", "pid3"], 1, "has no task 'pidx'"),
    (["pid1", "bg"], 1, "is not periodic"),
])
def test_validate_names_the_controlled_tasks(tasks, index, words):
    raw = _raw(_servo_tasks("1 ms", 0.8))
    raw["nodes"]["cpu"]["tasks"][0]["params"]["tasks"] = tasks
    raw["nodes"]["cpu"]["tasks"].append({"name": "bg", "program": "idle", "release": "aperiodic", "priority": 9})
    errors = {p.path: p.message for p in check_scenario(raw) if p.severity == "error"}
    assert words in errors[f"nodes.cpu.tasks[0].params.tasks[{index}]"]


def test_analyze_says_its_bound_is_for_the_nominal_period():
    from netsim.cli.analyze import analyze_run

    scenario = load_scenario(_raw(_servo_tasks("1 ms", 0.5), duration="200 ms"))
    table = analyze_run(scenario, netsim.run(scenario)).set_index(["kind", "name"])
    # C = 1 ms at the nominal periods 6, 5, 4 ms: pid3 alone above pid2 and pid1, R = 1, 2, 3 ms (the scheduler's
    # zero execution adds nothing)
    assert [table.loc[("task", f"cpu.pid{i}"), "analysis"] for i in (3, 2, 1)] == [1.0, 2.0, 3.0]
    assert "at the nominal period (set at run time by scheduler)" in table.loc[("task", "cpu.pid1"), "note"]
    assert "nominal period" not in table.loc[("task", "cpu.scheduler"), "note"]
