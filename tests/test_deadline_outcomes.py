"""One deadline rule in every table: jobs.csv, metrics.csv and the report's tasks.csv agree.

The rule (netsim.kernel.records.deadline_verdict): a job is met when it finishes at or before its deadline; missed
when it finishes late, is killed, or is unfinished with its deadline at or before the end of the run (every event
at the end instant has run); pending (neither) when it is unfinished and not yet due at the end.
"""

from __future__ import annotations

import math
from pathlib import Path

import pandas as pd
import pytest

from netsim.env import SimEnv
from netsim.kernel import Kernel
from netsim.kernel.records import deadline_verdict
from netsim.report import report
from netsim.results import jobs_table
from netsim.runner import run
from netsim.metrics.runtime import generic_metrics
from netsim.timebase import MS


def _scenario() -> dict:
    # One CPU, fixed priorities, no context-switch cost, run for exactly 10 ms.
    #   A: period 5 ms, 1 ms, deadline 5 ms, priority 1: jobs at 0 and 5 ms finish at 1 and 6 ms (met); the job
    #      released at 10 ms (= the end) is due at 15 ms: pending.
    #   B: period 10 ms, 9.5 ms of CPU, deadline 10 ms, priority 2: preempted by A for 1 ms at 5 ms, it needs
    #      until 0.5 + 9.5 + 1 = 11 ms > 10 ms, so the job due exactly at the end (10 ms) is unfinished: missed;
    #      B's job released at 10 ms is pending.
    return {
        "name": "deadline_edges", "seed": 1, "duration": "10 ms",
        "nodes": {"cpu": {"policy": "fp", "tasks": [
            {"name": "A", "program": "idle", "period": "5 ms", "priority": 1, "execution": "1 ms"},
            {"name": "B", "program": "idle", "period": "10 ms", "priority": 2, "execution": "9.5 ms"},
        ]}},
    }


def test_jobs_metrics_and_report_tables_agree_on_a_job_due_at_the_end_and_one_released_at_the_end(tmp_path):
    result = run(_scenario(), out=tmp_path / "run")
    assert result.ok, result.meta.get("error")
    jobs = pd.read_csv(tmp_path / "run" / "jobs.csv")
    # expected from the schedule worked out in _scenario
    want = {("A", 0): "met", ("A", 1): "met", ("A", 2): "pending", ("B", 0): "missed", ("B", 1): "pending"}
    got = {(t, int(j)): o for t, j, o in zip(jobs["task"], jobs["job_id"], jobs["outcome"])}
    assert got == want
    assert jobs.loc[jobs["outcome"] == "pending", "deadline_met"].isna().all()  # pending: neither met nor missed
    m = result.metrics
    assert (m["task.cpu.A.deadline_misses"], m["task.cpu.A.pending"]) == (0, 1)
    assert (m["task.cpu.B.deadline_misses"], m["task.cpu.B.pending"]) == (1, 1)
    tasks = report(tmp_path / "run", plots=False)["tasks"].set_index("task")
    for task in ("A", "B"):
        assert tasks.loc[task, "deadline_misses_count"] == m[f"task.cpu.{task}.deadline_misses"]
        assert tasks.loc[task, "pending_count"] == m[f"task.cpu.{task}.pending"]
        assert tasks.loc[task, "deadline_misses_count"] == int((jobs[jobs.task == task]["outcome"] == "missed").sum())


def test_a_killed_job_has_no_response_time_and_counts_as_killed_and_missed(tmp_path):
    # T: 3 ms of CPU per 10 ms period, WCET budget 2 ms, the overrun handler kills the job when the budget is
    # spent (at 2 ms after its release). Over 25 ms: jobs at 0, 10, 20 ms are all killed; none completes.
    env = SimEnv()
    k = Kernel(env, "n")

    def kill_it(job):
        yield job.kill(job.data)

    def body(job):
        yield job.execute(3 * MS)

    k.create_handler("overrun", kill_it)
    k.create_task("T", body, period=10 * MS, priority=1, wcet=2 * MS, wcet_handler="overrun")
    env.run(25 * MS)
    k._finalize(25 * MS)
    recs = [r for r in k.job_records if r.task == "T"]
    assert [r.finish for r in recs] == [2 * MS, 12 * MS, 22 * MS]
    assert all(r.killed and r.response is None and r.deadline_met is False for r in recs)
    jobs = jobs_table(k.job_records, "n")
    assert list(jobs["outcome"]) == ["killed"] * 3 and jobs["response_s"].isna().all()
    metrics = generic_metrics(type("R", (), {"jobs": jobs, "messages": pd.DataFrame(),
                                             "signals": pd.DataFrame({"time_s": [0.025]})})(), None, 25 * MS)
    assert metrics["task.n.T.killed"] == 3 and metrics["task.n.T.deadline_misses"] == 3
    assert math.isnan(metrics["task.n.T.max_response_s"])  # no job completed: no response time at all
    folder = tmp_path / "run"
    folder.mkdir()
    jobs.to_csv(folder / "jobs.csv", index=False)
    pd.DataFrame({"metric": [], "value": []}).to_csv(folder / "metrics.csv", index=False)
    (folder / "meta.json").write_text('{"status": "ok", "duration_s": 0.025}')
    row = report(folder, plots=False)["tasks"].iloc[0]
    assert (row["killed_count"], row["deadline_misses_count"]) == (3, 3) and math.isnan(row["response_max_s"])


@pytest.mark.parametrize(
    "deadline, finish, killed, t_end, want",
    [
        (10, 10, False, None, True),   # finished exactly at the deadline: met
        (10, 11, False, None, False),  # late
        (10, 5, True, None, False),    # killed before its deadline: never completed, a miss
        (10, None, False, 10, False),  # unfinished, due exactly at the end: every event at the end ran: missed
        (15, None, False, 10, None),   # unfinished, not yet due: pending
        (None, None, False, 10, None),  # unfinished, no deadline: pending
        (None, 7, False, None, True),  # finished, no deadline
    ],
)
def test_deadline_verdict_is_the_documented_rule(deadline, finish, killed, t_end, want):
    assert deadline_verdict(deadline, finish, killed, t_end) is want


def test_report_reads_older_jobs_tables_with_the_same_rule(tmp_path: Path):
    # written before the outcome column: an empty deadline_met is pending (it used to be read as a miss), and a
    # killed job recorded as "met" with a response time is a miss without one
    folder = tmp_path / "old"
    folder.mkdir()
    pd.DataFrame({
        "node": ["c"] * 3, "task": ["t"] * 3, "job_id": [0, 1, 2], "release_s": [0.0, 0.01, 0.02],
        "start_s": [0.0, 0.01, None], "finish_s": [0.002, 0.012, None], "response_s": [0.002, 0.002, None],
        "deadline_s": [0.01, 0.02, 0.03], "deadline_met": [True, True, None], "preemptions": [0, 0, 0],
        "cpu_time_s": [0.002, 0.002, 0.0], "killed": [False, True, False],
    }).to_csv(folder / "jobs.csv", index=False)
    pd.DataFrame({"metric": [], "value": []}).to_csv(folder / "metrics.csv", index=False)
    (folder / "meta.json").write_text('{"status": "ok", "duration_s": 0.03}')
    row = report(folder, plots=False)["tasks"].iloc[0]
    assert (row["deadline_misses_count"], row["killed_count"], row["pending_count"]) == (1, 1, 1)
    assert row["response_max_s"] == pytest.approx(0.002)
