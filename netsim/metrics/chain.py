"""Sample-to-actuation latency along a task chain: the walk back through the records, on whole tables or streamed.

The ``latency`` metric (:func:`netsim.metrics.runtime.latency`) follows each job of the chain's last task back
to the first task's job: through the message delivered to its node last at or before its release, sent by the
previous task during one of its jobs (:func:`chain_walk`). With the jobs and messages tables kept in full, the walk
runs once over the whole tables (:func:`netsim.metrics.runtime.chain_latencies_ns`).

With ``output.jobs`` or ``output.messages`` at ``summary`` (or ``off``) the tables are not kept; a
:class:`ChainLatencyStream` is fed the records as the run makes them (:func:`netsim.results.traces.attach_streams`)
and keeps, in memory that does not grow with the run's length, the count, sum, minimum and maximum of the
latencies. It runs the same :func:`chain_walk` on batches of the last task's jobs against bounded windows of the
records (the last :data:`KEEP` per task and per sender-receiver pair), so it gives the same numbers as the whole
tables; a latency whose walk would need a record older than the window is not counted, and is reported
(``<name>.beyond_window``, with a warning) instead of being guessed. A job is resolved only once nothing it
depends on can still change: a job of the previous task still running that started at or before the send (it may
have sent the message; the kernels say which job runs) or a delivery at the current instant defer it to the next
batch, or to the end of the run.
"""

from __future__ import annotations

import logging
import math
from typing import Any, Final, Sequence

import numpy as np

from netsim.timebase import S

__all__ = ["NO_TIME", "KEEP", "BATCH", "chain_walk", "ChainLatencyStream", "latency_values", "unkept_tables"]

_log = logging.getLogger(__name__)

#: Stands for "no time" (unfinished job, undelivered message, job that never started) in int64 ns arrays.
NO_TIME: Final[int] = int(np.iinfo(np.int64).max)
#: Records kept per chain task and per sender-receiver pair between batches (the streamed walk's window).
KEEP: Final[int] = 8192
#: Jobs of the last task resolved together (a batch).
BATCH: Final[int] = 2048

#: One link of the walk, from a task back to the previous one: the messages between their nodes (delivery and
#: send times, sorted by delivery) and the previous task's jobs (release, start, finish, sorted by start).
Link = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def chain_walk(end: np.ndarray, release: np.ndarray, start: np.ndarray, links: Sequence[Link]
               ) -> tuple[np.ndarray, np.ndarray, list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                                            np.ndarray]]]:
    """Walk the last task's jobs (``end`` = finish, ``release``, ``start``; int64 ns) back along ``links``.

    Returns ``(latency, ok, probes)``: the latency of each job (first task's job start to ``end``), whether its
    chain is complete, and per link what was looked up: ``(alive, release, k, sent_at, j)`` (the jobs whose chain
    was still complete before the link, the release the message was looked up for, the message's index, its send
    time, the previous job's index; an index of -1 found nothing). Vectorised: each link is two ``searchsorted``.
    """
    ok = np.ones(len(end), dtype=bool)
    probes = []
    cur_release, first_start = release, start
    for deliv, sent, p_rel, p_start, p_fin in links:
        alive = ok.copy()
        if len(deliv):
            # the message delivered last at or before the job's release ...
            k = np.searchsorted(deliv, cur_release, side="right") - 1
            sent_at = sent[np.clip(k, 0, None)]
        else:
            k = np.full(len(end), -1, dtype=np.int64)
            sent_at = np.zeros(len(end), dtype=np.int64)
        ok &= k >= 0
        if len(p_start):
            # ... sent by the previous task during one of its jobs (started at or before, not finished before)
            j = np.searchsorted(p_start, sent_at, side="right") - 1
            jj = np.clip(j, 0, None)
            ok &= (j >= 0) & (p_fin[jj] >= sent_at)
            probes.append((alive, cur_release, k, sent_at, j))
            cur_release, first_start = p_rel[jj], p_start[jj]
        else:
            j = np.full(len(end), -1, dtype=np.int64)
            ok[:] = False
            probes.append((alive, cur_release, k, sent_at, j))
    return end - first_start, ok, probes


def unkept_tables(fn: Any, index: int, kind: str, modes: Any) -> list[tuple[str, str]]:
    """``(table, message)`` for each table the metric function ``fn`` (``metrics[index]``, type ``kind``) reads
    row by row that the trace settings ``modes`` (``table -> mode``) do not keep in full; none for a metric that
    streams its rows (``fn.stream``, :func:`netsim.results.traces.attach_streams`). ``netsim validate`` and the
    runner both ask."""
    if getattr(fn, "stream", None) is not None:  # streamed while the run goes when a table is not kept
        return []
    out = []
    for table in getattr(fn, "tables", ()):
        mode = modes.get(table, "full")
        if mode != "full":
            out.append((table, f"metrics[{index}] ({kind}) reads the {table} table row by row, but output.{table} "
                               f"is '{mode}'; set output.{table}: full or remove the metric"))
    return out


def latency_values(name: str, count: int, total: int, low: int | None, high: int | None) -> dict[str, float]:
    """The ``latency`` metric's keys from the count, the exact integer sum, the minimum and maximum (ns)."""
    if count == 0 or low is None or high is None:
        return {f"{name}.mean_s": math.nan, f"{name}.max_s": math.nan, f"{name}.min_s": math.nan,
                f"{name}.count": 0.0}
    return {f"{name}.mean_s": total / (count * S), f"{name}.max_s": high / S, f"{name}.min_s": low / S,
            f"{name}.count": float(count)}


def _t(value: int | None) -> int:
    return NO_TIME if value is None else int(value)


class _Window:
    """The newest records of one chain task (jobs) or one sender-receiver pair (messages), in arrival order, and
    the earliest and latest time (start, delivery) among those dropped: a walk that looked up time ``q`` and found
    ``found`` might have picked a dropped one when ``earliest <= q`` and ``found < latest`` (:meth:`beyond`)."""

    __slots__ = ("items", "dropped_min", "dropped_max")

    def __init__(self) -> None:
        self.items: list[Any] = []
        self.dropped_min = NO_TIME
        self.dropped_max = -1

    def drop(self, times: list[int]) -> None:
        """Note the times of records dropped from the window."""
        if times:
            self.dropped_min = min(self.dropped_min, min(times))
            self.dropped_max = max(self.dropped_max, max(times))

    def beyond(self, query: np.ndarray, index: np.ndarray, times: np.ndarray) -> np.ndarray:
        """Where the lookup of ``query`` (which found ``times[index]``, -1: nothing) may have needed a dropped
        record (conservative: never misses one, may flag a lookup whose answer was in the window after all)."""
        if self.dropped_max < 0:
            return np.zeros(len(query), dtype=bool)
        found = times[np.clip(index, 0, None)] if len(times) else np.full(len(query), -1, dtype=np.int64)
        found = np.where(index >= 0, found, -1)
        return (self.dropped_min <= query) & (found < self.dropped_max)


class ChainLatencyStream:
    """The ``latency`` metric of one chain computed while the run goes, in bounded memory (module docstring).

    Parameters
    ----------
    chain
        The chain's tasks as ``(node, task)`` pairs, first to last.
    name
        The metric's name (prefix of its keys).
    """

    def __init__(self, chain: Sequence[tuple[str, str]], name: str) -> None:
        self.chain = [tuple(step) for step in chain]
        self.name = name
        n = len(self.chain)
        self._jobs = [_Window() for _ in range(n)]  # (release, start, finish) of tasks 0 .. n-2
        self._msgs = [_Window() for _ in range(n)]  # message records of link i (node i-1 -> node i), i >= 1
        self._unfinished: list[dict[int, tuple[int, int, int]]] = [{} for _ in range(n)]
        self._last_finish = [-1] * n  # latest finish among the task's recorded jobs that started
        self._pending: list[tuple[int, int, int]] = []  # last-task jobs (release, start, finish) to resolve
        self._now = -1
        self._final = False
        #: ``active(node, task)``: the start of the task's job now on the CPU (or blocked after starting), None
        #: when it has none; set by :func:`netsim.results.traces.attach_streams` from the kernels. Without it, a
        #: job is deferred whenever the previous task's last recorded job finished at or after the send.
        self.active: Any = None
        self.count = 0
        self.total = 0
        self.low: int | None = None
        self.high: int | None = None
        self.beyond = 0

    # feeding -------------------------------------------------------------------------------------------------
    def job(self, rec: Any) -> None:
        """A job record (at its finish, or unfinished when the run ends)."""
        key = (rec.node, rec.task)
        last = len(self.chain) - 1
        for i, step in enumerate(self.chain):
            if step != key:
                continue
            if rec.finish is not None:
                self._now = max(self._now, int(rec.finish))
            if i == last:
                if rec.finish is not None:
                    self._pending.append((int(rec.release), _t(rec.start), int(rec.finish)))
                    if len(self._pending) >= BATCH:
                        self._resolve()
                continue
            entry = (int(rec.release), _t(rec.start), _t(rec.finish))
            if rec.finish is None:  # held apart until the end (a later finalisation may replace it)
                self._unfinished[i][int(rec.job_id)] = entry
                continue
            self._unfinished[i].pop(int(rec.job_id), None)
            self._jobs[i].items.append(entry)
            if rec.start is not None:
                self._last_finish[i] = max(self._last_finish[i], int(rec.finish))

    def message(self, rec: Any) -> None:
        """A message record (when sent; its delivery or drop is read from it later)."""
        self._now = max(self._now, int(rec.sent_ns))
        for i in range(1, len(self.chain)):
            if rec.sender == self.chain[i - 1][0] and rec.receiver == self.chain[i][0]:
                self._msgs[i].items.append(rec)

    # resolving -----------------------------------------------------------------------------------------------
    def _links(self) -> list[tuple[Link, np.ndarray, np.ndarray]]:
        """Per link from the last task back: the walk's arrays, and the sort orders (into the windows)."""
        out = []
        for i in range(len(self.chain) - 1, 0, -1):
            final = [r for r in self._msgs[i].items if not r.dropped and r.delivered_ns is not None]
            deliv = np.array([r.delivered_ns for r in final], dtype=np.int64)
            sent = np.array([r.sent_ns for r in final], dtype=np.int64)
            m_order = np.argsort(deliv, kind="stable")
            jobs = self._jobs[i - 1].items
            if self._final:
                jobs = jobs + list(self._unfinished[i - 1].values())
            arr = np.array(jobs, dtype=np.int64).reshape(-1, 3)
            j_order = np.argsort(arr[:, 1], kind="stable")
            rel, start, fin = arr[j_order, 0], arr[j_order, 1], arr[j_order, 2]
            out.append(((deliv[m_order], sent[m_order], rel, start, fin), deliv[m_order], start))
        return out

    def _resolve(self) -> None:
        """Resolve the pending last-task jobs that nothing can change any more; keep the others pending."""
        if not self._pending:
            return
        arr = np.array(self._pending, dtype=np.int64)
        release, start, end = arr[:, 0], arr[:, 1], arr[:, 2]
        links = self._links()
        lat, ok, probes = chain_walk(end, release, start, [link for link, _, _ in links])
        unsafe = np.zeros(len(end), dtype=bool)
        beyond = np.zeros(len(end), dtype=bool)
        for step, ((alive, cur_release, k, sent_at, j), (_, deliv, p_start)) in enumerate(zip(probes, links)):
            i = len(self.chain) - 1 - step  # the link from task i back to task i - 1
            if not self._final:
                unsafe |= alive & (cur_release >= self._now)  # a delivery at this very instant may come next
            beyond |= alive & self._msgs[i].beyond(cur_release, k, deliv)
            found_msg = alive & (k >= 0)
            if not self._final:  # a job of the previous task that started and is still running may have sent it
                if self.active is not None:
                    running = self.active(*self.chain[i - 1])
                    if running is not None:
                        unsafe |= found_msg & (sent_at >= running)
                else:  # without the kernels: such a job started at or after the task's last recorded finish
                    unsafe |= found_msg & (sent_at >= self._last_finish[i - 1])
            beyond |= found_msg & self._jobs[i - 1].beyond(sent_at, j, p_start)
        done = ~unsafe
        counted = done & ok & ~beyond
        self.beyond += int(np.count_nonzero(done & beyond))
        values = lat[counted]
        if values.size:
            self.count += int(values.size)
            self.total += sum(int(v) for v in values)
            low, high = int(values.min()), int(values.max())
            self.low = low if self.low is None else min(self.low, low)
            self.high = high if self.high is None else max(self.high, high)
        self._pending = [p for p, keep in zip(self._pending, unsafe) if keep]
        self._trim()

    def _trim(self) -> None:
        """Drop all but the newest :data:`KEEP` records of each window (messages still in flight stay)."""
        for window in self._jobs:
            extra = len(window.items) - KEEP
            if extra > 0:
                window.drop([s for _, s, _ in window.items[:extra] if s != NO_TIME])
                del window.items[:extra]
        for window in self._msgs:
            extra = len(window.items) - KEEP
            if extra > 0:
                old, kept = window.items[:extra], window.items[extra:]
                in_flight = [r for r in old if not r.dropped and r.delivered_ns is None]
                window.drop([int(r.delivered_ns) for r in old if not r.dropped and r.delivered_ns is not None])
                window.items = in_flight + kept

    def metrics(self) -> dict[str, float]:
        """The metric's keys (``<name>.mean_s``, ``.max_s``, ``.min_s``, ``.count``) once the run has ended; every
        pending job is resolved with the records as they stand (unfinished jobs included)."""
        if not self._final:
            self._final = True
            self._resolve()
            if self.beyond:
                _log.warning("latency %s: %d chains reach back past the last %d records the summary keeps and are "
                             "not counted; set output.jobs and output.messages to full for them",
                             self.name, self.beyond, KEEP)
        out = latency_values(self.name, self.count, self.total, self.low, self.high)
        if self.beyond:
            out[f"{self.name}.beyond_window"] = float(self.beyond)
        return out
