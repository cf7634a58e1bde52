"""Traces as a choice (issue 19): job and message statistics accumulated while a run goes, in flat memory.

A scenario's ``output: {jobs: full|summary|off, messages: full|summary|off, schedule: on|off}`` says what a run
keeps. ``full`` keeps one record per job (per message copy) and writes ``jobs.csv`` (``messages.csv``), as before.
``summary`` keeps, per task (per network), the count, the outcomes, the mean and the maximum of the response
time (delay), and its percentiles from a :class:`QuantileSketch`; the records themselves are dropped as soon as
they are final, so memory does not grow with the run's length. ``off`` keeps neither.

The hook into the engine is the container the records are appended to: the runner replaces a kernel's
``job_records`` list by a :class:`JobSummary` and a network's ``records`` list by a :class:`MessageSummary`
(:func:`attach_traces`). Both take ``append`` like the list did and hold only the records that can still
change (a job unfinished at the end of the run, a message copy still in flight), so the kernel and the networks
are unchanged.

A metric that reads the rows (``latency``) and can stream them is fed the records as they are appended, by
listeners on those containers (:func:`attach_streams`; a table still kept in full gets an :class:`ObservedList`).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from netsim.scenario.schema import Scenario

__all__ = ["QUANTILES", "TRACE_MODES", "JobSummary", "MessageSummary", "ObservedList", "QuantileSketch",
           "attach_streams", "attach_traces", "trace_problems"]

#: The percentiles a summary reports (``p50``, ``p95``, ``p99``).
QUANTILES = (0.50, 0.95, 0.99)

#: The values of ``output.jobs`` and ``output.messages``.
TRACE_MODES = ("full", "summary", "off")


class QuantileSketch:
    """Streaming quantiles of non-negative numbers with a bounded relative error (log-spaced buckets).

    A value ``v > 0`` falls in bucket ``k = ceil(log(v) / log(gamma))`` with ``gamma = (1 + a) / (1 - a)``; the
    bucket's representative ``2 gamma^k / (gamma + 1)`` is within a relative error ``a`` of every value in it.
    Zeros are counted apart. Memory grows with the logarithm of the values' range, not with their number
    (about 700 buckets span 1 ns to 1000 s at ``a = 1 %``). The smallest and largest values are kept exactly,
    and estimates are clipped to them.

    Parameters
    ----------
    accuracy
        Relative accuracy ``a`` of a quantile estimate, in (0, 1).
    """

    __slots__ = ("_buckets", "_gamma", "_log_gamma", "_zeros", "accuracy", "count", "high", "low")

    def __init__(self, accuracy: float = 0.01) -> None:
        if not 0.0 < accuracy < 1.0:
            raise ValueError(f"QuantileSketch accuracy must be in (0, 1), got {accuracy!r}")
        self.accuracy = float(accuracy)
        self._gamma = (1.0 + accuracy) / (1.0 - accuracy)
        self._log_gamma = math.log(self._gamma)
        self._buckets: dict[int, int] = {}
        self._zeros = 0
        self.count = 0
        self.low = math.inf
        self.high = -math.inf

    def add(self, value: float) -> None:
        """Count one value (``>= 0``; a negative value raises ``ValueError``)."""
        if value < 0:
            raise ValueError(f"QuantileSketch takes values >= 0, got {value!r}")
        self.count += 1
        self.low = min(self.low, value)
        self.high = max(self.high, value)
        if value == 0:
            self._zeros += 1
            return
        k = math.ceil(math.log(value) / self._log_gamma)
        buckets = self._buckets
        buckets[k] = buckets.get(k, 0) + 1

    def quantile(self, q: float) -> float:
        """The ``q``-quantile (``0 <= q <= 1``; the value of rank ``q (n - 1)``); NaN when nothing was added."""
        if not 0.0 <= q <= 1.0:
            raise ValueError(f"quantile q must be in [0, 1], got {q!r}")
        if self.count == 0:
            return math.nan
        rank = q * (self.count - 1)
        seen = self._zeros
        if rank < seen:
            return 0.0
        estimate = self.high
        for k in sorted(self._buckets):
            seen += self._buckets[k]
            if rank < seen:
                estimate = 2.0 * self._gamma ** k / (self._gamma + 1.0)
                break
        return min(max(estimate, self.low), self.high)

    def __len__(self) -> int:
        return self.count


class _Stats:
    """Count, outcomes, sum, maximum and sketch of one task's response times or one network's delays (ns)."""

    __slots__ = ("counts", "high", "n", "n_values", "sketch", "total")

    def __init__(self) -> None:
        self.n = 0
        self.n_values = 0
        self.total = 0
        self.high = -1
        self.sketch = QuantileSketch()
        self.counts: dict[str, int] = {}

    def value(self, v: int) -> None:
        self.n_values += 1
        self.total += v
        self.high = max(self.high, v)
        self.sketch.add(v)

    def row(self, prefix: str) -> dict[str, float]:
        """``mean``, ``max`` and the :data:`QUANTILES` in seconds, keys ``<prefix>_s``..."""
        from netsim.timebase import S

        if not self.n_values:
            out = {f"mean_{prefix}_s": math.nan, f"max_{prefix}_s": math.nan}
            out.update({f"p{round(q * 100)}_{prefix}_s": math.nan for q in QUANTILES})
            return out
        out = {f"mean_{prefix}_s": self.total / self.n_values / S, f"max_{prefix}_s": self.high / S}
        out.update({f"p{round(q * 100)}_{prefix}_s": self.sketch.quantile(q) / S for q in QUANTILES})
        return out


class JobSummary:
    """Per-task job statistics of one kernel, in place of its list of :class:`~netsim.kernel.records.JobRecord`.

    Takes ``append`` / ``extend`` as the kernel's list did. A finished or killed job is counted at once and its
    record dropped; a record without a finish time (a job still unfinished when the run ends, added by the
    kernel's end-of-run finalisation, which may replace them) is held until :meth:`rows`.

    Parameters
    ----------
    node
        The kernel's name.
    keep
        False (``output.jobs: off``): count nothing, hold only what the kernel's finalisation needs.
    """

    def __init__(self, node: str, keep: bool = True) -> None:
        self.node = node
        self.keep = bool(keep)
        self._held: list[Any] = []
        self._tasks: dict[str, _Stats] = {}
        #: Called with every record appended (streamed metrics, :func:`attach_streams`).
        self.listeners: list[Any] = []

    # the list interface the kernel uses -------------------------------------------------------------------
    def append(self, rec: Any) -> None:
        """Count a final record (finished or killed); hold an unfinished one."""
        for listen in self.listeners:
            listen(rec)
        if rec.finish is None:
            self._held.append(rec)
        elif self.keep:
            self._count(rec)

    def extend(self, recs: Iterable[Any]) -> None:
        for rec in recs:
            self.append(rec)

    def __iter__(self) -> Iterator[Any]:
        return iter(self._held)

    def __len__(self) -> int:
        return len(self._held)

    def __getitem__(self, key: Any) -> Any:
        return self._held[key]

    def __setitem__(self, key: Any, value: Any) -> None:
        self._held[key] = value

    # statistics -------------------------------------------------------------------------------------------
    def _count(self, rec: Any) -> None:
        from netsim.kernel.records import job_outcome

        stats = self._tasks.get(rec.task)
        if stats is None:
            stats = self._tasks[rec.task] = _Stats()
        stats.n += 1
        outcome = job_outcome(rec.deadline, rec.killed, rec.deadline_met)
        stats.counts[outcome] = stats.counts.get(outcome, 0) + 1
        if rec.response is not None:
            stats.value(int(rec.response))

    def rows(self) -> list[dict[str, Any]]:
        """One row per task (sorted by name): ``node, task, jobs, met, missed, killed, pending, done,
        deadline_misses, mean_response_s, max_response_s, p50_response_s, p95_response_s, p99_response_s``.

        The held (unfinished) records are counted here; the summary is read once, at the end of the run.
        """
        if not self.keep:
            return []
        for rec in self._held:
            self._count(rec)
        self._held = []
        out = []
        for task in sorted(self._tasks):
            s = self._tasks[task]
            c = s.counts
            row: dict[str, Any] = {"node": self.node, "task": task, "jobs": s.n}
            for name in ("met", "missed", "killed", "pending", "done"):
                row[name] = c.get(name, 0)
            row["deadline_misses"] = c.get("missed", 0) + c.get("killed", 0)
            row.update(s.row("response"))
            out.append(row)
        return out


class MessageSummary:
    """Per-network message statistics, in place of a network's list of
    :class:`~netsim.network.records.MessageRecord`.

    A record changes after it is appended (delivered or dropped later), so records are held while in flight and
    folded into the statistics in batches once final: memory stays bounded by the messages in flight.

    Parameters
    ----------
    network
        The network's name.
    keep
        False (``output.messages: off``): count nothing and hold nothing.
    """

    _BATCH = 4096

    def __init__(self, network: str, keep: bool = True) -> None:
        self.network = network
        self.keep = bool(keep)
        self._live: list[Any] = []
        self._next = self._BATCH
        self._stats = _Stats()
        #: Called with every record appended (streamed metrics, :func:`attach_streams`).
        self.listeners: list[Any] = []

    def append(self, rec: Any) -> None:
        """Hold ``rec`` until it is final (delivered or dropped)."""
        for listen in self.listeners:
            listen(rec)
        if not self.keep:
            return
        live = self._live
        live.append(rec)
        if len(live) >= self._next:
            self._fold()
            self._next = max(self._BATCH, 2 * len(self._live))

    def __iter__(self) -> Iterator[Any]:
        return iter(self._live)

    def __len__(self) -> int:
        return len(self._live)

    def _fold(self) -> None:
        keep: list[Any] = []
        stats = self._stats
        for rec in self._live:
            if rec.dropped:
                stats.n += 1
                stats.counts["lost"] = stats.counts.get("lost", 0) + 1
            elif rec.delivered_ns is not None:
                stats.n += 1
                stats.value(int(rec.delivered_ns) - int(rec.sent_ns))
            else:
                keep.append(rec)
        self._live = keep

    def rows(self) -> list[dict[str, Any]]:
        """One row: ``network, messages, delivered, lost, in_flight, loss_rate, mean_delay_s, max_delay_s,
        p50_delay_s, p95_delay_s, p99_delay_s`` (empty when nothing was kept)."""
        if not self.keep:
            return []
        self._fold()
        s = self._stats
        n = s.n + len(self._live)
        lost = s.counts.get("lost", 0)
        row: dict[str, Any] = {"network": self.network, "messages": n, "delivered": s.n_values, "lost": lost,
                               "in_flight": len(self._live), "loss_rate": lost / n if n else math.nan}
        row.update(s.row("delay"))
        return [row]


def attach_traces(sim: Any, output: Any) -> None:
    """Apply a scenario's ``output`` trace settings to a built simulation, before it runs.

    ``schedule: off`` turns the kernels' schedule trace off; ``jobs`` and ``messages`` other than ``full`` put a
    :class:`JobSummary` / :class:`MessageSummary` where the kernels and networks append their records.
    """
    jobs = getattr(output, "jobs", "full")
    messages = getattr(output, "messages", "full")
    if getattr(output, "schedule", "on") == "off":
        for kernel in sim.kernels.values():
            kernel.trace = False
    if jobs != "full":
        for name, kernel in sim.kernels.items():
            kernel.job_records = JobSummary(name, keep=jobs == "summary")
    if messages != "full":
        for name, net in sim.networks.items():
            net.records = MessageSummary(name, keep=messages == "summary")
    attach_streams(sim)


class ObservedList(list):
    """A list of records (a table kept in full) that also hands each appended record to its ``listeners``."""

    def __init__(self, items: Iterable[Any] = ()) -> None:
        super().__init__(items)
        self.listeners: list[Any] = []

    def append(self, rec: Any) -> None:
        for listen in self.listeners:
            listen(rec)
        super().append(rec)

    def extend(self, recs: Iterable[Any]) -> None:
        for rec in recs:
            self.append(rec)


def _streamed(spec: Any) -> tuple[Any, Any] | None:
    """The (key, stream) of a metric spec whose function streams the rows it reads (``fn.stream``), else None."""
    from netsim.errors import ConfigError
    from netsim.registry import lookup

    try:
        fn = lookup("metric", spec.type)
    except ConfigError:  # an unknown metric: validation reports it, and nothing streams for it
        return None
    make = getattr(fn, "stream", None)
    if make is None:
        return None
    return fn.stream_key(spec.params or {}), make(spec.params or {})


def attach_streams(sim: Any) -> None:
    """Feed the metrics that stream (``latency``) the job and message records as the run makes them, when
    ``output.jobs`` or ``output.messages`` keeps no table (:mod:`netsim.metrics.chain`); the streams are in
    ``sim.metric_streams`` (key: the metric function's ``stream_key(params)``), read by the metric at the end."""
    scenario = getattr(sim, "scenario", None)
    output = getattr(scenario, "output", None)
    if scenario is None or output is None or (
            getattr(output, "jobs", "full") == "full" and getattr(output, "messages", "full") == "full"):
        return
    streams = dict(s for s in (_streamed(spec) for spec in scenario.metrics) if s is not None)
    if not streams:
        return
    kernels = sim.kernels

    def active(node: str, task: str) -> int | None:
        """The start of the job of ``node.task`` that has started and not finished, if any."""
        state = getattr(kernels.get(node), "tasks", {}).get(task)
        job = getattr(state, "active", None)
        start = getattr(job, "start", None)
        return None if start is None else int(start)

    for stream in streams.values():
        stream.active = active
    for kernel in sim.kernels.values():
        if not hasattr(kernel.job_records, "listeners"):
            kernel.job_records = ObservedList(kernel.job_records)
        kernel.job_records.listeners.extend(stream.job for stream in streams.values())
    for net in sim.networks.values():
        if not hasattr(net.records, "listeners"):
            net.records = ObservedList(net.records)
        net.records.listeners.extend(stream.message for stream in streams.values())
    sim.metric_streams = streams


def trace_problems(scenario: Scenario) -> list[str]:
    """What a scenario's metrics need that its ``output`` trace settings do not keep, one sentence each.

    A metric function that reads the rows of the jobs or messages table says so in a ``tables`` attribute
    (``et_control.tables = ("messages",)``); it needs ``output.<table>: full``, unless it streams them (a
    ``stream`` attribute, as ``latency`` has: :func:`attach_streams`).
    """
    from netsim.errors import ConfigError
    from netsim.metrics.chain import unkept_tables
    from netsim.registry import lookup

    output = scenario.output
    modes = {table: getattr(output, table, "full") for table in ("jobs", "messages")}
    problems: list[str] = []
    for i, spec in enumerate(scenario.metrics):
        try:
            fn = lookup("metric", spec.type)
        except ConfigError:  # an unknown metric: validation reports it
            continue
        problems.extend(message for _, message in unkept_tables(fn, i, spec.type, modes))
    return problems
