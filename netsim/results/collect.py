"""The result of a finished (or aborted) simulation: its recorder, kernels and networks turned into tables."""

from __future__ import annotations

from typing import Any

import pandas as pd

from netsim.results import Lazy, RunResult
from netsim.results.tables import (
    JOB_SUMMARY_COLUMNS,
    MESSAGE_SUMMARY_COLUMNS,
    jobs_table,
    messages_table,
    schedule_table,
    signals_table,
    summary_table,
)
from netsim.results.traces import JobSummary, MessageSummary

__all__ = ["collect"]


def collect(sim: Any, t_end_ns: int) -> RunResult:
    """The tables of a (finished or aborted) simulation ``sim`` (a built :class:`~netsim.scenario.builder.Simulation`),
    without metrics: signals, jobs and messages (or their summaries, :mod:`netsim.results.traces`), and the
    schedule, built when first read."""
    rec = sim.env.recorder
    signals = signals_table(rec.times, rec.values, order=sim.scenario.record)
    output = sim.scenario.output
    job_rows = [row for k in sim.kernels.values() if isinstance(k.job_records, JobSummary)
                for row in k.job_records.rows()]
    msg_rows = [row for n in sim.networks.values() if isinstance(n.records, MessageSummary) for row in n.records.rows()]
    job_frames = [jobs_table(k.job_records, name) for name, k in sim.kernels.items()
                  if not isinstance(k.job_records, JobSummary)]
    jobs = pd.concat(job_frames, ignore_index=True) if job_frames else jobs_table([])
    if not jobs.empty:
        jobs = jobs.sort_values(["release_s", "node", "task", "job_id"], kind="stable").reset_index(drop=True)
    msg_frames = [messages_table(net.records) for net in sim.networks.values()
                  if not isinstance(net.records, MessageSummary)]
    messages = pd.concat(msg_frames, ignore_index=True) if msg_frames else messages_table([])
    if not messages.empty:
        messages = messages.sort_values(["msg_id", "network", "receiver"], kind="stable").reset_index(drop=True)
    traces_kept = [(name, getattr(k, "schedule", [])) for name, k in sim.kernels.items()]

    def schedule_frame() -> pd.DataFrame:  # built when first read (the Gantt chart): most runs never do
        frames = [schedule_table(name, intervals) for name, intervals in traces_kept]
        return pd.concat(frames, ignore_index=True) if frames else schedule_table("", [])

    schedule = Lazy(schedule_frame)
    traces = {"jobs": output.jobs, "messages": output.messages, "schedule": output.schedule}
    return RunResult(signals=signals, jobs=jobs, messages=messages, schedule=schedule, traces=traces,
                     job_summary=summary_table(job_rows, JOB_SUMMARY_COLUMNS) if output.jobs == "summary" else None,
                     message_summary=summary_table(msg_rows, MESSAGE_SUMMARY_COLUMNS)
                     if output.messages == "summary" else None)
