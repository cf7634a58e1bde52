"""The ``task.*`` and ``net.*`` metrics from the records' columns (issue 19: no DataFrame in a run).

:class:`netsim.results.rows.Rows` holds a run's jobs and messages tables as columns; these functions give the
numbers :func:`netsim.metrics.runtime.generic_metrics` computes from the DataFrames, bit for bit (the same sums in
the same row order): per task, jobs, deadline misses, killed, pending, mean and maximum response time; per
network, messages, lost, loss rate, mean and maximum delay.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["arrival_metrics", "network_metrics_rows", "table_rows", "task_metrics_rows"]


def table_rows(result: Any, name: str) -> Any:
    """The records' columns of ``result``'s table ``name`` while its DataFrame is unbuilt
    (:meth:`netsim.results.RunResult._table_rows`), else None (a result read back, or a table built)."""
    fn = getattr(result, "_table_rows", None)
    return fn(name) if callable(fn) else None


def _groups(*keys: list[Any]) -> dict[tuple[Any, ...], np.ndarray]:
    """Row indices per distinct key tuple, each in table order, keys sorted (``groupby(..., sort=True)``)."""
    index: dict[tuple[Any, ...], list[int]] = {}
    for i, key in enumerate(zip(*keys)):
        index.setdefault(key, []).append(i)
    return {key: np.asarray(index[key], dtype=np.intp) for key in sorted(index)}


def _mean_max(values: np.ndarray) -> tuple[float, float]:
    """Mean and maximum of the non-NaN ``values`` as pandas' ``Series.mean``/``max`` give them (NaN when none):
    the sum of every value with NaN counted as 0, divided by the count of the others."""
    missing = np.isnan(values)
    n = int(values.size - missing.sum())
    if n == 0:
        return math.nan, math.nan
    kept = np.where(missing, 0.0, values) if missing.any() else values
    return float(kept.sum() / n), float(np.max(values[~missing]))


def task_metrics_rows(rows: Any) -> dict[str, float]:
    """:func:`netsim.metrics.runtime._task_metrics` from the records' columns (:class:`netsim.results.rows.Rows`), no DataFrame."""
    out: dict[str, float] = {}
    if len(rows) == 0:
        return out
    outcome = rows.data["outcome"]
    response = rows.array("response_s")
    arrivals = "release_jitter_s" in rows.data  # release jitter (issue 20): only in runs that use it
    jitter_all = rows.array("release_jitter_s") if arrivals else None
    from_arrival_all = rows.array("response_from_arrival_s") if arrivals else None
    for (node, task), idx in _groups(rows.data["node"], rows.data["task"]).items():
        labels = [outcome[i] for i in idx.tolist()]
        killed = labels.count("killed")
        resp = response[idx]
        resp = resp[~np.isnan(resp)]  # killed and unfinished jobs have no response time
        key = f"task.{node}.{task}"
        out[f"{key}.jobs"] = float(len(idx))
        out[f"{key}.deadline_misses"] = float(labels.count("missed") + killed)
        out[f"{key}.killed"] = float(killed)
        out[f"{key}.pending"] = float(labels.count("pending"))
        out[f"{key}.max_response_s"] = float(resp.max()) if len(resp) else math.nan
        out[f"{key}.mean_response_s"] = float(resp.sum() / len(resp)) if len(resp) else math.nan
        if jitter_all is not None and from_arrival_all is not None:  # both read when arrivals
            out.update(arrival_metrics(key, jitter_all[idx], from_arrival_all[idx]))
    return out


def network_metrics_rows(rows: Any) -> dict[str, float]:
    """:func:`netsim.metrics.runtime._network_metrics` from the records' columns (:class:`netsim.results.rows.Rows`), no DataFrame."""
    out: dict[str, float] = {}
    if len(rows) == 0:
        return out
    dropped_all = rows.array("dropped")
    delivered_all = ~np.isnan(rows.array("delivered_s"))
    delay_all = rows.array("delay_s")
    for (net,), idx in _groups(rows.data["network"]).items():
        dropped = dropped_all[idx]
        lost = int(dropped.sum())
        key = f"net.{net}"
        out[f"{key}.messages"] = float(len(idx))
        out[f"{key}.lost"] = float(lost)
        out[f"{key}.loss_rate"] = float(lost / len(idx))
        delays = delay_all[idx][~dropped & delivered_all[idx]]
        out[f"{key}.mean_delay_s"], out[f"{key}.max_delay_s"] = _mean_max(delays)
    return out


def arrival_metrics(key: str, jitter: np.ndarray, response: np.ndarray) -> dict[str, float]:
    """``.max_release_jitter_s``, ``.max_response_from_arrival_s``, ``.mean_response_from_arrival_s`` of a task
    with release jitter (none for a task without: its jobs have no jitter values)."""
    jitter = jitter[~np.isnan(jitter)]
    if not len(jitter):
        return {}
    response = response[~np.isnan(response)]
    return {f"{key}.max_release_jitter_s": float(jitter.max()),
            f"{key}.max_response_from_arrival_s": float(response.max()) if len(response) else math.nan,
            f"{key}.mean_response_from_arrival_s": float(response.sum() / len(response)) if len(response) else math.nan}
