"""The result of a finished (or aborted) simulation: its recorder, kernels and networks turned into tables."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from netsim.lazy_import import lazy_module

if TYPE_CHECKING:
    import pandas as pd
else:  # imported at its first use: `netsim run` and `validate` build no DataFrame (issue 29)
    pd = lazy_module("pandas")

from netsim.results import Lazy, RunResult
from netsim.results.rows import Column, Rows, job_rows, message_rows
from netsim.results.signals import SignalSource
from netsim.results.tables import (
    JOB_SUMMARY_COLUMNS,
    MESSAGE_SUMMARY_COLUMNS,
    jobs_table,
    messages_table,
    schedule_table,
    summary_table,
)
from netsim.results.traces import JobSummary, MessageSummary

__all__ = ["collect"]

def collect(sim: Any, t_end_ns: int) -> RunResult:
    """The tables of a (finished or aborted) simulation ``sim`` (a built :class:`~netsim.build.builder.Simulation`),
    without metrics: signals, jobs and messages (or their summaries, :mod:`netsim.results.traces`), and the
    schedule, built when first read."""
    rec = sim.env.recorder
    source = SignalSource(rec.times, rec.values, order=sim.scenario.record)
    signals: Any = Lazy(source.table)  # RunResult resolves a Lazy when read; signals.csv and the metrics read the source window by window
    output = sim.scenario.output
    job_stats = [row for k in sim.kernels.values() if isinstance(k.job_records, JobSummary)
                 for row in k.job_records.rows()]
    msg_stats = [row for n in sim.networks.values() if isinstance(n.records, MessageSummary) for row in n.records.rows()]
    full_kernels = [(name, k.job_records) for name, k in sim.kernels.items()
                    if not isinstance(k.job_records, JobSummary)]
    full_networks = [net.records for net in sim.networks.values() if not isinstance(net.records, MessageSummary)]
    job_cols: Rows | None
    msg_cols: Rows | None
    try:  # columns straight from the records; a DataFrame only when result.jobs / .messages is read
        job_cols = job_rows(full_kernels, _arrival_columns(full_kernels))
        msg_cols = message_rows(full_networks)
        jobs: Any = Lazy(job_cols.frame)
        messages: Any = Lazy(msg_cols.frame)
    except TypeError:  # records whose sort keys do not compare (mixed types): the tables through pandas
        job_cols = msg_cols = None
        jobs, messages = _jobs_frame(full_kernels), _messages_frame(full_networks)
    traces_kept = [(name, getattr(k, "schedule", [])) for name, k in sim.kernels.items()]

    def schedule_frame() -> pd.DataFrame:  # built when first read (the Gantt chart): most runs never do
        frames = [schedule_table(name, intervals) for name, intervals in traces_kept]
        return pd.concat(frames, ignore_index=True) if frames else schedule_table("", [])

    schedule: Any = Lazy(schedule_frame)
    traces = {"jobs": output.jobs, "messages": output.messages, "schedule": output.schedule}
    return RunResult(signals=signals, jobs=jobs, messages=messages, schedule=schedule, traces=traces,
                     _job_rows=job_cols, _message_rows=msg_cols, _signal_source=source, _schedule_source=traces_kept,
                     _streams=getattr(sim, "metric_streams", None),
                     job_summary=summary_table(job_stats, JOB_SUMMARY_COLUMNS) if output.jobs == "summary" else None,
                     message_summary=summary_table(msg_stats, MESSAGE_SUMMARY_COLUMNS)
                     if output.messages == "summary" else None)


def _arrival_columns(kernels: list[tuple[str, Any]]) -> tuple[Column, ...]:
    """The jobs table's release-jitter columns (issue 20) when a job of the run has an arrival, else none (the
    table of a run without jitter keeps its columns)."""
    from netsim.kernel.records import (  # here: importing netsim.kernel loads simpy
        ARRIVAL_COLUMNS,
        has_arrivals,
    )

    if not any(has_arrivals(records) for _, records in kernels):
        return ()
    return tuple(Column(name, attr, "time") for name, attr in ARRIVAL_COLUMNS)


def _jobs_frame(kernels: list[tuple[str, Any]]) -> pd.DataFrame:
    """The jobs table built through pandas (records :func:`job_rows` cannot sort)."""
    frames = [jobs_table(records, name) for name, records in kernels]
    jobs = pd.concat(frames, ignore_index=True) if frames else jobs_table([])
    if not jobs.empty:
        jobs = jobs.sort_values(["release_s", "node", "task", "job_id"], kind="stable").reset_index(drop=True)
    return jobs


def _messages_frame(networks: list[Any]) -> pd.DataFrame:
    """The messages table built through pandas (records :func:`message_rows` cannot sort)."""
    frames = [messages_table(records) for records in networks]
    messages = pd.concat(frames, ignore_index=True) if frames else messages_table([])
    if not messages.empty:
        messages = messages.sort_values(["msg_id", "network", "receiver"], kind="stable").reset_index(drop=True)
    return messages
