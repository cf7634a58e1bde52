"""``trigger: {periodic_load: ...}``: a fast ISR accounted in closed form equals the same ISR driven by a timer."""

from __future__ import annotations

import copy

import pandas.testing as pdt

from netsim.runner import run
from netsim.scenario import check_scenario

# two tasks under RM beside a 20 kHz ISR of 1 us latency + 4 us execution: the ISR steals 10 % of the CPU, so
# the tasks' responses and preemption counts depend on it (an independent check of that is the kernel's test
# against an explicit handler; here the YAML path must give the same tables as the timer-driven handler)
BASE = {
    "name": "isr_load",
    "duration": "50 ms",
    "seed": 3,
    "nodes": {
        "cpu": {
            "policy": "rm",
            "tasks": [
                {"name": "fast", "program": "idle", "period": "1 ms", "execution": "300 us"},
                {"name": "slow", "program": "idle", "period": "3 ms", "offset": "7 us", "execution": "1.1 ms"},
            ],
            "handlers": [
                {"name": "isr", "program": "idle", "latency": "1 us", "execution": "4 us",
                 "trigger": {"timer": {"period": "50 us", "start": "3 us"}}},
            ],
        }
    },
}


def _with_load() -> dict:
    raw = copy.deepcopy(BASE)
    raw["nodes"]["cpu"]["handlers"][0]["trigger"] = {"periodic_load": {"period": "50 us", "start": "3 us"}}
    return raw


def test_periodic_load_gives_the_same_jobs_and_cpu_as_the_timer_driven_isr():
    timer = run(BASE, write=False)
    load = run(_with_load(), write=False)
    tasks = timer.jobs[timer.jobs["task"] != "isr"].reset_index(drop=True)  # handler invocations have no jobs
    pdt.assert_frame_equal(load.jobs.reset_index(drop=True), tasks)
    # releases in [0, 50 ms] (a run covers its end instant): fast at 0, 1, ..., 50 ms = 51; slow at 7 us + 3k ms,
    # k = 0..16 = 17
    assert len(tasks) == 51 + 17
    # utilization: 30 % + 36.7 % for the tasks, 5 us every 50 us = 10 % for the ISR (up to the partial end)
    assert load.metrics["cpu.cpu.utilization"] == timer.metrics["cpu.cpu.utilization"]
    assert abs(load.metrics["cpu.cpu.utilization"] - (0.3 + 1.1 / 3 + 0.1)) < 0.01
    assert timer.jobs["preemptions"].sum() > 0


def test_periodic_load_needs_a_constant_execution_shorter_than_its_period():
    raw = _with_load()
    isr = raw["nodes"]["cpu"]["handlers"][0]
    isr["execution"] = {"dist": "uniform", "low": "1 us", "high": "3 us"}
    problems = {p.path: p.message for p in check_scenario(raw) if p.is_error}
    assert problems == {"nodes.cpu.handlers[0].execution": "a handler with a 'periodic_load' trigger needs a constant "
                        "execution time (e.g. 'execution: 2 us'), not a 'uniform' distribution"}
    isr["execution"] = "49 us"  # + 1 us latency = the whole period
    problems = {p.path: p.message for p in check_scenario(raw) if p.is_error}
    assert problems == {"nodes.cpu.handlers[0].execution": "latency + execution (50 us) must be shorter than the "
                        "periodic_load period (50 us)"}


def test_a_trigger_names_exactly_one_kind():
    raw = _with_load()
    raw["nodes"]["cpu"]["handlers"][0]["trigger"]["timer"] = {"period": "50 us"}
    messages = [p.message for p in check_scenario(raw) if p.is_error]
    assert any("give exactly one of 'timer', 'on_message', 'external' or 'periodic_load'" in m for m in messages)


def test_io_channels_named_in_record_are_recorded_at_each_read_and_write():
    # the README's example: y read and u written by a 10 ms PID task; both appear in signals.csv
    import re
    from pathlib import Path

    import yaml

    text = Path("README.md").read_text()
    raw = yaml.safe_load(next(b for b in re.findall(r"```yaml\n(.*?)```", text, re.S) if b.startswith("name: my_loop")))
    raw["duration"] = "100 ms"
    result = run(raw, write=False)
    assert list(result.signals.columns) == ["time_s", "y", "u", "r"]
    assert result.meta["warnings"] == []
    # periodic_controller reads y when its code starts and writes u when its execution ends: every finished
    # job's start and finish instants are sample instants of the table
    jobs = result.jobs[result.jobs["finish_s"].notna()]
    assert len(jobs) == 10  # releases at 0, 10, ..., 90 ms finish; the one at 100 ms is cut by the end
    instants = set(result.signals["time_s"].round(12))
    assert set(jobs["finish_s"].round(12)) <= instants
    # the first read follows the first dispatch (3 us, after the ISR window at 0) by the 10 us context switch
    # and the ISR window at 10 us (3 us): 3 + 10 + 3 = 16 us
    first_read = result.signals.loc[result.signals["y"].notna(), "time_s"].iloc[0]
    assert jobs["start_s"].iloc[0] == 3e-6
    assert round(first_read * 1e9) == 16_000
