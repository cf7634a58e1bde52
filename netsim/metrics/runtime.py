"""Metrics every run gets, and the registered metrics ``control_error`` and ``latency``.

Generic metrics (:func:`generic_metrics`, always added by the runner), named with dots:

``cpu.<node>.utilization``
    busy fraction of the node's CPU over the run (tasks, handlers and context switches, from the kernel).
``task.<node>.<task>.jobs`` / ``.deadline_misses`` / ``.max_response_s`` / ``.mean_response_s``
    from the jobs table (finished jobs; a job unfinished at the end whose deadline passed counts as a miss).
    A task with release jitter also gets ``.max_release_jitter_s`` (arrival - nominal release) and
    ``.max_response_from_arrival_s`` / ``.mean_response_from_arrival_s`` (``response_s`` counts from the
    nominal release).
``net.<network>.messages`` / ``.utilization`` / ``.lost`` / ``.loss_rate`` / ``.mean_delay_s`` / ``.max_delay_s``
    from the messages table, plus everything the network's own ``metrics(t_end)`` reports (prefixed).
``energy.<node>.J`` / ``.cpu_J`` / ``.radio_J`` / ``.depleted_s`` ...
    what a node's energy model reports (issue 20, :mod:`netsim.energy`; only nodes that have one).
``control.<node>.<task>.<name>``
    what a task's program reports from its ``metrics()`` method (e.g. ``state_feedback``: ``fused``,
    ``prediction_only``, ``stale``, ``mpc_fallbacks``; see :mod:`netsim.programs.state_feedback`).

Registered metrics (scenario ``metrics:`` list, ``fn(result, params, baseline) -> dict``):

``control_error``
    ``IAE`` = ∫|r - y| dt and ``ISE`` = ∫(r - y)² dt over ``[t0, t1]`` from the signals table. The table holds
    each signal constant between its samples, so the integrals are exact sums over the table's rows
    (left-rectangle rule on the held values). Keys ``<name>.IAE``, ``<name>.ISE``, ``<name>.max_abs_error``.
``latency``
    sample-to-actuation latency along a chain of tasks, e.g. ``[sensor.sample, controller.control,
    actuator.actuate]``: for every job of the last task, the chain is followed backwards through the messages
    table (the message delivered to the job's node last at or before its release, sent by the previous task
    during one of its jobs) to the first task's job; latency = actuation job finish - sampling job start.
    Keys ``<name>.mean_s``, ``.max_s``, ``.min_s``, ``.count``. With ``output.jobs`` or ``output.messages`` not
    ``full`` the same walk is streamed while the run goes, in bounded memory (:mod:`netsim.metrics.chain`).
"""

from __future__ import annotations

import logging
import math
from typing import TYPE_CHECKING, Any

import numpy as np
from pydantic import Field, ValidationError, field_validator

from netsim.errors import ConfigError
from netsim.registry import lookup, register
from netsim.timebase import S
from netsim.units import StrictModel, Time

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

_log = logging.getLogger(__name__)

__all__ = [
    "generic_metrics",
    "control_error",
    "latency",
    "chain_latencies",
    "chain_latencies_ns",
    "latency_stream",
    "latency_stream_key",
    "compute_metrics",
    "job_outcome_counts",
    "held_integrals",
    "validate_params",
    "ControlErrorParams",
    "LatencyParams",
]


def job_outcome_counts(jobs: pd.DataFrame) -> dict[str, int]:
    """Jobs per outcome (``met, missed, killed, pending, done``) of a jobs table (this run's or one read back).

    Uses the ``outcome`` column when there is one; for tables written before it existed, derives it from
    ``deadline_met`` and ``killed`` with the same rule (an empty ``deadline_met`` is pending, not a miss).
    """
    import pandas as pd  # here, not at import: `netsim validate` loads this module and needs no pandas

    from netsim.kernel.records import OUTCOMES, job_outcome

    if "outcome" in jobs:
        labels = jobs["outcome"].astype(str)
    else:
        def _flag(v: Any) -> bool | None:
            if v is None or (isinstance(v, float) and v != v) or v is pd.NA or str(v).strip() == "":
                return None
            return str(v).strip().lower() in {"true", "1", "1.0"}

        killed = jobs["killed"] if "killed" in jobs else pd.Series(False, index=jobs.index)
        deadline = jobs["deadline_s"] if "deadline_s" in jobs else pd.Series(None, index=jobs.index)
        met = jobs["deadline_met"] if "deadline_met" in jobs else pd.Series(True, index=jobs.index)
        labels = pd.Series([job_outcome(None if pd.isna(d) else d, _flag(k) is True, _flag(m))
                            for d, k, m in zip(deadline, killed, met)], index=jobs.index, dtype=object)
    counts = labels.value_counts()
    return {name: int(counts.get(name, 0)) for name in OUTCOMES}


def _task_metrics(jobs: pd.DataFrame, t_end_s: float) -> dict[str, float]:
    out: dict[str, float] = {}
    if jobs is None or jobs.empty:
        return out
    for (node, task), grp in jobs.groupby(["node", "task"], sort=True):
        # the kernel applied the one deadline rule (netsim.kernel.records.deadline_verdict) to every record
        counts = job_outcome_counts(grp)
        resp = grp["response_s"].dropna().astype(float)  # killed and unfinished jobs have no response time
        key = f"task.{node}.{task}"
        out[f"{key}.jobs"] = float(len(grp))
        out[f"{key}.deadline_misses"] = float(counts["missed"] + counts["killed"])
        out[f"{key}.killed"] = float(counts["killed"])
        out[f"{key}.pending"] = float(counts["pending"])
        out[f"{key}.max_response_s"] = float(resp.max()) if len(resp) else math.nan
        out[f"{key}.mean_response_s"] = float(resp.mean()) if len(resp) else math.nan
        if "release_jitter_s" in grp:
            from netsim.metrics.rows import arrival_metrics

            out.update(arrival_metrics(key, grp["release_jitter_s"].to_numpy(dtype=float),
                                        grp["response_from_arrival_s"].to_numpy(dtype=float)))
    return out


def _network_metrics(messages: pd.DataFrame) -> dict[str, float]:
    out: dict[str, float] = {}
    if messages is None or messages.empty:
        return out
    for net, grp in messages.groupby("network", sort=True):
        dropped = grp["dropped"].astype(str).str.lower() == "true"
        delivered = grp[~dropped & grp["delivered_s"].notna()]
        key = f"net.{net}"
        out[f"{key}.messages"] = float(len(grp))
        out[f"{key}.lost"] = float(dropped.sum())
        out[f"{key}.loss_rate"] = float(dropped.mean()) if len(grp) else math.nan
        delays = delivered["delay_s"].astype(float)
        out[f"{key}.mean_delay_s"] = float(delays.mean()) if len(delays) else math.nan
        out[f"{key}.max_delay_s"] = float(delays.max()) if len(delays) else math.nan
    return out


#: Summary columns (``output.jobs: summary``) -> metric names: the same names as from the rows, plus percentiles.
_JOB_SUMMARY_KEYS = {"jobs": "jobs", "deadline_misses": "deadline_misses", "killed": "killed", "pending": "pending",
                     "max_response_s": "max_response_s", "mean_response_s": "mean_response_s",
                     "p50_response_s": "p50_response_s", "p95_response_s": "p95_response_s",
                     "p99_response_s": "p99_response_s"}
_MESSAGE_SUMMARY_KEYS = {"messages": "messages", "lost": "lost", "loss_rate": "loss_rate",
                         "mean_delay_s": "mean_delay_s", "max_delay_s": "max_delay_s", "p50_delay_s": "p50_delay_s",
                         "p95_delay_s": "p95_delay_s", "p99_delay_s": "p99_delay_s"}


def _summary_metrics(table: Any, scope: str, keys: tuple[str, ...], names: dict[str, str]) -> dict[str, float]:
    """``<scope>.<key...>.<name>`` metrics from a summary table (:mod:`netsim.results.traces`); none if absent."""
    out: dict[str, float] = {}
    if table is None or len(table) == 0:
        return out
    for row in table.to_dict("records"):
        base = ".".join([scope] + [str(row[k]) for k in keys])
        for column, name in names.items():
            out[f"{base}.{name}"] = float(row[column])
    return out


def generic_metrics(result: Any, sim: Any | None = None, t_end_ns: int | None = None) -> dict[str, float]:
    """The metrics the runner always adds (see the module docstring).

    Parameters
    ----------
    result
        The :class:`~netsim.results.RunResult` (its ``jobs`` and ``messages`` tables are used).
    sim
        The built simulation (kernels and networks), for CPU utilization and network statistics; optional.
    t_end_ns
        End of the measured window (the time the run reached).
    """
    t_end_s = (t_end_ns / S) if t_end_ns is not None else float(result.signals["time_s"].max() or 0.0)
    out: dict[str, float] = {}
    if sim is not None:
        for name in sorted(getattr(sim, "kernels", {})):
            out[f"cpu.{name}.utilization"] = float(sim.kernels[name].utilization(0, t_end_ns))
    elif not result.jobs.empty and t_end_s > 0:
        for node, grp in result.jobs.groupby("node", sort=True):
            out[f"cpu.{node}.utilization"] = float(grp["cpu_time_s"].astype(float).sum() / t_end_s)
    from netsim.metrics.rows import network_metrics_rows, table_rows, task_metrics_rows

    traces = getattr(result, "traces", None) or {}
    rows = table_rows(result, "jobs")
    if traces.get("jobs", "full") == "full":
        out.update(task_metrics_rows(rows) if rows is not None else _task_metrics(result.jobs, t_end_s))
    else:
        out.update(_summary_metrics(getattr(result, "job_summary", None), "task", ("node", "task"), _JOB_SUMMARY_KEYS))
    if traces.get("messages", "full") == "full":
        rows = table_rows(result, "messages")
        out.update(network_metrics_rows(rows) if rows is not None else _network_metrics(result.messages))
    else:
        out.update(_summary_metrics(getattr(result, "message_summary", None), "net", ("network",),
                                    _MESSAGE_SUMMARY_KEYS))
    if sim is not None:
        for name in sorted(getattr(sim, "networks", {})):
            net = sim.networks[name]
            try:
                extra = net.metrics(t_end_ns)
            except Exception as exc:  # noqa: BLE001 - reported: the run's other metrics are still written
                _log.warning("network '%s': its own metrics could not be computed (%s: %s); the net.%s.* metrics "
                             "from the messages table are kept", name, type(exc).__name__, exc, name)
                continue
            for k in sorted(extra):
                v = extra[k]
                if isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool):
                    out[f"net.{name}.{k}"] = float(v)
        energy = getattr(sim, "energy", None) or {}
        for node in sorted(energy):  # nodes with an energy model (issue 20): energy.<node>.J, ...
            extra = energy[node].metrics(t_end_ns)
            for k in sorted(extra):
                out[f"energy.{node}.{k}"] = float(extra[k])
        programs = getattr(sim, "programs", None) or {}
        for key in sorted(programs):  # "node.task": a program's own counters (state_feedback: fallbacks ...)
            fn = getattr(programs[key], "metrics", None)
            if not callable(fn):
                continue
            extra = fn()
            for k in sorted(extra):
                out[f"control.{key}.{k}"] = float(extra[k])
    return out


# ----------------------------------------------------------------------------------------------- control_error
class ControlErrorParams(StrictModel):
    """Parameters of the ``control_error`` metric.

    ``diverged_above``: the run's status becomes ``diverged at t = ...`` when ``|reference - output|`` passes this
    many times the loop's scale (:mod:`netsim.divergence`; ``null``: never).
    """

    reference: str | None = None
    output: str
    name: str | None = None
    t0: Time = 0
    t1: Time | None = None
    diverged_above: float | None = Field(1000.0, gt=0, allow_inf_nan=False)


def _column(result: Any, name: str) -> np.ndarray:
    if name not in result.signals.columns:
        raise ConfigError(
            f"metric needs signal '{name}', which was not recorded "
            f"(recorded: {', '.join(result.signals.columns[1:]) or 'none'}); add it to 'record:'"
        )
    return result.signals[name].to_numpy(dtype=float)


def validate_params(model: type[StrictModel], params: Any, what: str) -> Any:
    """``params`` (a mapping, or already a ``model``) checked by a metric's ``Params`` model; a :class:`ConfigError`
    naming the metric ``what`` and each bad field otherwise (``netsim validate`` checks a scenario's metric
    parameters before a run; this is the check for metrics called from Python)."""
    if isinstance(params, model):
        return params
    try:
        return model.model_validate(dict(params or {}))
    except ValidationError as exc:
        problems = "; ".join(_param_problem(e, model) for e in exc.errors())
        raise ConfigError(f"metric '{what}': {problems}") from None


def _param_problem(error: Any, model: type[StrictModel]) -> str:
    """One pydantic error as a short sentence saying what to change."""
    loc = ".".join(str(p) for p in error["loc"])
    if error["type"] == "extra_forbidden":
        known = ", ".join(sorted(model.model_fields))
        return f"unknown key '{loc}' (known: {known}); remove or rename it"
    if error["type"] == "missing":
        return f"missing required key '{loc}'; add it"
    return f"{loc}: {error['msg']}"


def held_integrals(t: np.ndarray, e: np.ndarray, t0: float, t1: float) -> tuple[float, float, float]:
    """IAE, ISE and max |e| of a held (piecewise-constant) signal ``e`` sampled at ``t`` over ``[t0, t1]``."""
    if len(t) == 0 or t1 <= t0:
        return 0.0, 0.0, 0.0
    edges = np.clip(np.append(t, max(t1, t[-1])), t0, t1)
    dt = np.diff(edges)
    valid = ~np.isnan(e) & (dt > 0)
    ev = e[valid]
    iae = float(np.sum(np.abs(ev) * dt[valid]))
    ise = float(np.sum(ev * ev * dt[valid]))
    mx = float(np.max(np.abs(ev))) if ev.size else 0.0
    return iae, ise, mx


@register("metric", "control_error", "IAE and ISE of reference minus output over [t0, t1]")
def control_error(result: Any, params: Any, baseline: Any = None) -> dict[str, float]:
    """IAE/ISE of ``reference - output`` (reference 0 when not given) from the signals table."""
    p = validate_params(ControlErrorParams, params, "control_error")
    from netsim.metrics.held import control_error_chunked

    chunked = control_error_chunked(result, p)
    if chunked is not None:
        return chunked
    t = result.signals["time_s"].to_numpy(dtype=float)
    y = _column(result, p.output)
    r = _column(result, p.reference) if p.reference else np.zeros_like(y)
    e = r - y
    t_end = float(t[-1]) if len(t) else 0.0
    if "t_end_s" in getattr(result, "meta", {}):
        t_end = float(result.meta["t_end_s"])
    t1 = t_end if p.t1 is None else p.t1 / S
    iae, ise, mx = held_integrals(t, e, p.t0 / S, t1)
    name = p.name or p.output
    return {f"{name}.IAE": iae, f"{name}.ISE": ise, f"{name}.max_abs_error": mx}


# ----------------------------------------------------------------------------------------------------- latency
#: The message for an empty ``chain``: what to list in it.
EMPTY_CHAIN = "'chain' is empty; list the tasks of the chain as 'node.task', e.g. [sensor.sample, controller.control]"


class LatencyParams(StrictModel):
    """Parameters of the ``latency`` metric: the task chain as ``node.task`` names."""

    chain: list[str] = Field(min_length=1)
    name: str = "latency"

    @field_validator("chain", mode="before")
    @classmethod
    def _not_empty(cls, value: Any) -> Any:
        # before min_length's generic "at least 1 item": say what goes in the list (the words validate uses)
        if isinstance(value, (list, tuple)) and not value:
            raise ValueError(EMPTY_CHAIN)
        return value


def _split_task(ref: str) -> tuple[str, str]:
    node, sep, task = ref.partition(".")
    if not sep or not node or not task:
        raise ConfigError(f"latency chain entries are 'node.task', got '{ref}'")
    return node, task


_NO_TIME = np.iinfo(np.int64).max  #: stands for "no time" (unfinished job, undelivered message) in ns arrays


def _ns(column: pd.Series) -> np.ndarray:
    """A ``*_s`` column of a result table as exact int64 nanoseconds (NaN -> ``_NO_TIME``).

    The tables hold ``ns / 1e9`` rounded to the nearest float (or the ``%.12g`` text of it, for a run folder
    read back); rounding ``s * 1e9`` recovers the integer for every time below ~52 days.
    """
    values = column.to_numpy(dtype=float)
    missing = np.isnan(values)
    out = np.rint(np.where(missing, 0.0, values) * S).astype(np.int64)
    out[missing] = _NO_TIME
    return out


def chain_latencies_ns(jobs: pd.DataFrame, messages: pd.DataFrame, chain: list[str]) -> np.ndarray:
    """Sample-to-actuation latencies in integer ns along ``chain`` (see the module docstring).

    One value per complete chain (int64 array). Every comparison and the final subtraction work on exact
    integer nanoseconds, so a 3.5 ms latency is exactly 3 500 000 ns. The walk itself is
    :func:`netsim.metrics.chain.chain_walk` (the one a summary-mode run streams through).
    """
    from netsim.metrics.chain import chain_walk

    empty = np.zeros(0, dtype=np.int64)
    if len(chain) < 1 or jobs is None or jobs.empty:
        return empty
    steps = [_split_task(c) for c in chain]

    def task_arrays(node: str, task: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        sel = jobs[(jobs["node"] == node) & (jobs["task"] == task)]
        start = _ns(sel["start_s"])
        order = np.argsort(start, kind="stable")
        return _ns(sel["release_s"])[order], start[order], _ns(sel["finish_s"])[order]

    rel, first_start, fin = task_arrays(*steps[-1])
    keep = fin != _NO_TIME
    links = []
    if len(steps) > 1:
        if messages is None or messages.empty:
            return empty
        delivered = messages[
            (messages["dropped"].astype(str).str.lower() != "true") & messages["delivered_s"].notna()
        ]
    for i in range(len(steps) - 1, 0, -1):
        node, prev_node = steps[i][0], steps[i - 1][0]
        pair = delivered[(delivered["receiver"] == node) & (delivered["sender"] == prev_node)]
        deliv = _ns(pair["delivered_s"])
        order = np.argsort(deliv, kind="stable")
        links.append((deliv[order], _ns(pair["sent_s"])[order], *task_arrays(*steps[i - 1])))
    latency, ok, _ = chain_walk(fin[keep], rel[keep], first_start[keep], links)
    return latency[ok]


def chain_latencies(jobs: pd.DataFrame, messages: pd.DataFrame, chain: list[str]) -> list[float]:
    """Sample-to-actuation latencies in seconds along ``chain``: :func:`chain_latencies_ns` converted once."""
    return [int(v) / S for v in chain_latencies_ns(jobs, messages, chain)]


@register("metric", "latency", "sample-to-actuation latency along a task chain, from the jobs/messages tables")
def latency(result: Any, params: Any, baseline: Any = None) -> dict[str, float]:
    """Mean/max/min latency and the number of complete chains."""
    from netsim.metrics.chain import latency_values

    p = validate_params(LatencyParams, params, "latency")
    stream = (getattr(result, "_streams", None) or {}).get(latency_stream_key(params))
    if stream is not None:  # output.jobs / messages not full: streamed while the run went (netsim.metrics.chain)
        return stream.metrics()
    values = chain_latencies_ns(result.jobs, result.messages, p.chain)
    if values.size == 0:
        return latency_values(p.name, 0, 0, None, None)
    total = sum(int(v) for v in values)  # exact integer sum; one division for the mean
    return latency_values(p.name, int(values.size), total, int(values.min()), int(values.max()))


def latency_stream_key(params: Any) -> tuple[str, str, tuple[str, ...]]:
    """The key of a ``latency`` metric's stream in a run result (its name and chain)."""
    p = validate_params(LatencyParams, params, "latency")
    return ("latency", p.name, tuple(p.chain))


def latency_stream(params: Any) -> Any:
    """A :class:`~netsim.metrics.chain.ChainLatencyStream` for a ``latency`` metric's ``params``, fed by a run
    whose jobs or messages table is not kept in full (:func:`netsim.results.traces.attach_streams`)."""
    from netsim.metrics.chain import ChainLatencyStream

    p = validate_params(LatencyParams, params, "latency")
    return ChainLatencyStream([_split_task(c) for c in p.chain], p.name)


latency.tables = ("jobs", "messages")  # type: ignore[attr-defined]  # rows it reads (output.jobs/messages: full)
latency.stream = latency_stream  # type: ignore[attr-defined]  # ... or streams them when they are not kept
latency.stream_key = latency_stream_key  # type: ignore[attr-defined]


def compute_metrics(result: Any, specs: list[Any], baseline: Any = None) -> dict[str, float]:
    """Run the scenario's listed metrics; each spec has ``type`` and ``params``."""
    out: dict[str, float] = {}
    for spec in specs or []:
        if hasattr(spec, "model_dump"):
            spec = spec.model_dump()
        fn = lookup("metric", spec["type"])
        try:
            values = fn(result, spec.get("params") or {}, baseline)
        except KeyError as exc:  # a signal or column the run's tables do not hold: a message, not a traceback
            missing = exc.args[0] if exc.args else exc
            raise ConfigError(f"metric '{spec['type']}' reads a column this run did not record ({missing}); add "
                              "the signals it reads to 'record:', or leave 'record:' out to record everything") from None
        out.update({str(k): float(v) for k, v in values.items()})
    return out


control_error.Params = ControlErrorParams  # type: ignore[attr-defined]
latency.Params = LatencyParams  # type: ignore[attr-defined]
