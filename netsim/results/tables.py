"""The tables of a run: column lists and the builders that make each table from the engine's records.

``signals_table`` (recorded samples -> the wide, held signals table), ``jobs_table``, ``messages_table``,
``schedule_table`` (kernel and network records -> tables in seconds), ``summary_table`` (the ``summary`` traces
of :mod:`netsim.results.traces`), and :func:`check_out_dir`. :class:`netsim.results.RunResult` holds the tables.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from netsim.lazy_import import lazy_module

if TYPE_CHECKING:
    import pandas as pd
else:  # imported at its first use: `netsim run` and `validate` build no DataFrame (issue 29)
    pd = lazy_module("pandas")

from netsim.errors import ConfigError
from netsim.timebase import S

__all__ = [
    "JOB_COLUMNS",
    "JOB_SUMMARY_COLUMNS",
    "MESSAGE_COLUMNS",
    "MESSAGE_SUMMARY_COLUMNS",
    "SCHEDULE_COLUMNS",
    "check_out_dir",
    "jobs_table",
    "messages_table",
    "schedule_table",
    "signals_table",
    "summary_table",
]


JOB_COLUMNS = [
    "node",
    "task",
    "job_id",
    "release_s",
    "start_s",
    "finish_s",
    "response_s",
    "deadline_s",
    "deadline_met",
    "preemptions",
    "cpu_time_s",
    "killed",
    "outcome",
]
MESSAGE_COLUMNS = [
    "msg_id",
    "network",
    "sender",
    "receiver",
    "tag",
    "bits",
    "priority",
    "sent_s",
    "tx_start_s",
    "delivered_s",
    "dropped",
    "drop_reason",
    "delay_s",
    "tx_end_s",
]
SCHEDULE_COLUMNS = ["node", "task", "state", "start_s", "end_s"]
#: Columns of ``jobs_summary.csv`` (``output.jobs: summary``, :class:`netsim.results.traces.JobSummary`).
JOB_SUMMARY_COLUMNS = ["node", "task", "jobs", "met", "missed", "killed", "pending", "done", "deadline_misses",
                       "mean_response_s", "max_response_s", "p50_response_s", "p95_response_s", "p99_response_s"]
#: Columns of ``messages_summary.csv`` (``output.messages: summary``, :class:`netsim.results.traces.MessageSummary`).
MESSAGE_SUMMARY_COLUMNS = ["network", "messages", "delivered", "lost", "in_flight", "loss_rate", "mean_delay_s",
                           "max_delay_s", "p50_delay_s", "p95_delay_s", "p99_delay_s"]


def check_out_dir(path: str | Path) -> Path:
    """Check that a run folder can be written at ``path`` (before anything runs); returns it as a Path.

    Raises
    ------
    ConfigError
        When ``path`` is an existing file, lies under a file, or its nearest existing folder is not writable.
    """
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise ConfigError(f"output '{out}' is a file, not a folder; give a folder path with --out "
                          "(a new or an existing folder), or remove the file")
    anchor = out
    while not anchor.exists() and anchor != anchor.parent:
        anchor = anchor.parent
    if anchor.exists() and not anchor.is_dir():
        raise ConfigError(f"cannot create run folder '{out}': '{anchor}' is a file; give another --out")
    if anchor.exists() and not os.access(anchor, os.W_OK | os.X_OK):
        raise ConfigError(f"cannot create run folder '{out}': no permission to write in '{anchor}'; "
                          "give another --out")
    return out


def _sec(ns: Any) -> float:
    """ns -> s, with None -> NaN."""
    if ns is None:
        return math.nan
    return int(ns) / S


def _field(rec: Any, name: str, default: Any = None) -> Any:
    if isinstance(rec, dict):
        return rec.get(name, default)
    return getattr(rec, name, default)


def signals_table(
    times: Mapping[str, Sequence[int]], values: Mapping[str, Sequence[float]], order: Iterable[str] | None = None
) -> pd.DataFrame:
    """The wide signals table from per-signal sample lists.

    Parameters
    ----------
    times, values
        Sample instants (int ns) and values per signal name (as in :class:`netsim.env.Recorder`).
    order
        Preferred column order (names, or base names whose ``name[i]`` columns follow); the remaining
        columns come after, sorted by name.

    When a signal has several samples at one instant, the last one counts.
    """
    names = list(times)
    ordered: list[str] = []
    if order is not None:
        for want in order:
            group = [n for n in names if n not in ordered and (n == want or n.split("[", 1)[0] == want)]
            ordered += sorted(group, key=lambda n: (len(n), n))
    ordered += sorted(n for n in names if n not in ordered)
    if not ordered:
        return pd.DataFrame({"time_s": pd.Series([], dtype=float)})
    series: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    for n in ordered:
        t = np.asarray(times[n], dtype=np.int64)
        v = np.asarray(values[n], dtype=float)
        if len(t) != len(v):  # a run interrupted (Ctrl-C, SIGTERM) between a sample's time and its value
            t, v = t[: len(v)], v[: len(t)]
        if len(t) > 1 and not bool(np.all(t[1:] > t[:-1])):  # out of order or repeated instants (rare)
            order = np.argsort(t, kind="stable")
            t, v = t[order], v[order]
            last = np.append(t[1:] != t[:-1], True)  # the last sample of each instant counts
            t, v = t[last], v[last]
        series[n] = (t, v)
    union = np.unique(np.concatenate([t for t, _ in series.values()]))
    data: dict[str, np.ndarray] = {"time_s": union / S}
    for n, (t, v) in series.items():
        data[n] = _held(t, v, union)
    return pd.DataFrame(data, copy=False)


def _held(t: np.ndarray, v: np.ndarray, at: np.ndarray) -> np.ndarray:
    """Each signal's value held from its samples ``(t, v)`` (sorted, unique instants) at the instants ``at``: the
    last sample at or before each instant, NaN before the first; a NaN sample holds the last value before it (what
    ``reindex(at).ffill()`` gives, without building a pandas Series per signal)."""
    k = np.searchsorted(t, at, side="right") - 1
    out = np.where(k >= 0, v[np.clip(k, 0, None)], np.nan)
    missing = np.isnan(out)
    if missing.any():  # forward fill: each NaN takes the last non-NaN value before it
        idx = np.where(missing, 0, np.arange(len(out)))
        np.maximum.accumulate(idx, out=idx)
        out = out[idx]  # a NaN with no value before it (idx 0 pointing at a NaN) stays NaN
    return out


def _ns_column(values: list[Any]) -> np.ndarray:
    """ns values (None allowed) -> float seconds array (None -> NaN); equal to :func:`_sec` per value (ns below
    2**53 convert to float exactly, and both divisions are correctly rounded)."""
    return np.array([np.nan if v is None else v for v in values], dtype=float) / S


def jobs_table(records: Iterable[Any], node: str | None = None) -> pd.DataFrame:
    """Jobs table from kernel :class:`JobRecord` objects (times in ns, converted to seconds)."""
    recs = list(records)
    if not recs:
        return pd.DataFrame(columns=JOB_COLUMNS)

    plain = not any(isinstance(r, dict) for r in recs)

    def col(name: str, default: Any = None) -> list[Any]:
        if plain:
            return [getattr(r, name, default) for r in recs]
        return [_field(r, name, default) for r in recs]

    frame = pd.DataFrame(
        {
            "node": [n if n is not None else node for n in col("node", node)],
            "task": col("task"),
            "job_id": col("job_id"),
            "release_s": _ns_column(col("release")),
            "start_s": _ns_column(col("start")),
            "finish_s": _ns_column(col("finish")),
            "response_s": _ns_column(col("response")),
            "deadline_s": _ns_column(col("deadline")),
            "deadline_met": pd.array(col("deadline_met"), dtype="boolean"),
            "preemptions": col("preemptions", 0),
            "cpu_time_s": _ns_column(col("cpu_time", 0)),
            "killed": [bool(v) for v in col("killed", False)],
        },
        columns=JOB_COLUMNS[:-1],
    )
    # imported here: importing netsim.kernel loads simpy
    from netsim.kernel.records import ARRIVAL_COLUMNS, has_arrivals, job_outcome

    if has_arrivals(recs):  # release jitter (issue 20): its columns only in runs that use it
        for name, attr in ARRIVAL_COLUMNS:
            frame[name] = _ns_column(col(attr))
    frame["outcome"] = [job_outcome(d, k, m) for d, k, m in zip(col("deadline"), frame["killed"], col("deadline_met"))]
    return frame


def messages_table(records: Iterable[Any]) -> pd.DataFrame:
    """Messages table from network :class:`MessageRecord` objects (times in ns, converted to seconds)."""
    recs = list(records)
    if not recs:
        return pd.DataFrame([], columns=MESSAGE_COLUMNS)

    def col(name: str, default: Any = None) -> list[Any]:
        if not any(isinstance(r, dict) for r in recs):
            return [getattr(r, name, default) for r in recs]
        return [_field(r, name, default) for r in recs]

    delivered = col("delivered_ns")
    delays = col("delay_ns")
    sent = col("sent_ns")
    delays = [int(d) - int(s) if (y is None and d is not None) else y for y, d, s in zip(delays, delivered, sent)]
    # built column by column (the same values and dtypes as one dict per row, a fraction of the time)
    data = {
        "msg_id": col("msg_id"),
        "network": col("network"),
        "sender": col("sender"),
        "receiver": col("receiver"),
        "tag": col("tag", ""),
        "bits": col("bits"),
        "priority": col("priority"),
        "sent_s": _ns_column(sent),
        "tx_start_s": _ns_column(col("tx_start_ns")),
        "delivered_s": _ns_column(delivered),
        "dropped": [bool(v) for v in col("dropped", False)],
        "drop_reason": [v or "" for v in col("drop_reason", "")],
        "delay_s": _ns_column(delays),
        "tx_end_s": _ns_column(col("tx_end_ns")),
    }
    return pd.DataFrame(data, columns=MESSAGE_COLUMNS)


def schedule_table(node: str, intervals: Iterable[Any]) -> pd.DataFrame:
    """Schedule trace ``(task, state, t0, t1)`` of one kernel as a table in seconds."""
    tasks, states, t0s, t1s, cores = [], [], [], [], []
    with_core = False  # a multicore kernel's intervals carry their core (netsim.kernel.multicore)
    for iv in intervals:
        if isinstance(iv, (tuple, list)):
            task, state, t0, t1 = iv[:4]
            with_core = with_core or len(iv) > 4
            cores.append(iv[4] if len(iv) > 4 else None)
        else:
            task, state, t0, t1 = (_field(iv, k) for k in ("task", "state", "t0", "t1"))
            cores.append(None)
        tasks.append(task)
        states.append(state)
        t0s.append(t0)
        t1s.append(t1)
    if not tasks:
        return pd.DataFrame([], columns=SCHEDULE_COLUMNS)
    frame = pd.DataFrame({"node": [node] * len(tasks), "task": tasks, "state": states, "start_s": _ns_column(t0s),
                          "end_s": _ns_column(t1s)}, columns=SCHEDULE_COLUMNS)
    if with_core:
        frame["core"] = pd.array(cores, dtype="Int64")
    return frame


def summary_table(rows: list[dict[str, Any]], columns: list[str]) -> pd.DataFrame:
    """A jobs or messages summary table (``output: {jobs|messages: summary}``) from its rows."""
    return pd.DataFrame(rows, columns=columns)
