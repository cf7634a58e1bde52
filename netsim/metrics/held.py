"""Integrals of a held signal read window by window, with the same numbers as over the whole table (issue 19).

``control_error`` integrates ``|r - y|`` and ``(r - y)²`` over the rows of the signals table. A long run's table
is read in windows (:meth:`netsim.results.RunResult._signal_chunks`) so that it is never whole in memory; the sums
must still be the ones ``np.sum`` gives over the whole column, bit for bit (the run folder's ``metrics.csv`` is
compared byte for byte). :func:`pairwise_sum` gets them: numpy sums a contiguous float64 array pairwise (halves
cut at a multiple of 8 elements, blocks of up to 128 summed with 8 accumulators), so the sum of the whole is the
same tree of partial sums whichever window the values arrive in; every subtree that fits :data:`LEAF` values is
summed by ``np.add.reduce`` itself. A test checks the result against ``np.sum`` on arrays of many lengths.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from typing import Any

import numpy as np

from netsim.timebase import S

__all__ = ["LEAF", "control_error_chunked", "held_integrals_chunked", "pairwise_sum"]

#: Values summed by one ``np.add.reduce`` call (a subtree of numpy's pairwise sum): up to 512 kB held at once.
LEAF = 1 << 16


class _Stream:
    """Values arriving in blocks, read left to right in ranges ``[lo, hi)`` and forgotten once read."""

    def __init__(self, blocks: Iterable[np.ndarray]) -> None:
        self._blocks = iter(blocks)
        self._buf = np.zeros(0)
        self._off = 0

    def take(self, lo: int, hi: int) -> np.ndarray:
        while self._off + len(self._buf) < hi:
            self._buf = np.concatenate([self._buf[lo - self._off:], np.asarray(next(self._blocks), dtype=float)])
            self._off = lo
        got = np.ascontiguousarray(self._buf[lo - self._off:hi - self._off])
        self._buf = self._buf[hi - self._off:]
        self._off = hi
        return got


def pairwise_sum(blocks: Iterable[np.ndarray], n: int, leaf: int = LEAF) -> float:
    """``np.sum`` of the ``n`` values that ``blocks`` give one after the other, without holding them all.

    Parameters
    ----------
    blocks
        Float arrays whose concatenation has ``n`` values.
    n
        The number of values (the shape of numpy's summation tree depends on it).
    leaf
        The largest subtree summed by one ``np.add.reduce`` call (a multiple of 8 keeps the tree's cuts).
    """
    stream = _Stream(blocks)

    def tree(lo: int, hi: int) -> float:
        size = hi - lo
        if size <= leaf:
            return np.add.reduce(stream.take(lo, hi))
        half = size // 2
        half -= half % 8  # numpy's cut (pairwise_sum in loops_utils.h)
        return tree(lo, lo + half) + tree(lo + half, hi)

    return float(np.float64(0.0) + tree(0, n)) if n else 0.0


def _edges(chunks: Iterable[tuple[np.ndarray, np.ndarray]], t0: float, t1: float
           ) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """``(e, dt)`` per window: each row's value and the width of its step clipped to ``[t0, t1]`` (the next row's
    time, the last row's up to ``max(t1, t_last)``), as :func:`netsim.metrics.runtime.held_integrals` cuts them."""
    held: tuple[np.ndarray, np.ndarray] | None = None  # the last row of the chunks so far: (t, e)
    for t, e in chunks:
        if len(t) == 0:
            continue
        if held is not None:
            t, e = np.concatenate([held[0], t]), np.concatenate([held[1], e])
        edges = np.clip(t, t0, t1)
        yield e[:-1], np.diff(edges)
        held = t[-1:], e[-1:]
    if held is not None:
        held_t, held_e = held
        last = np.clip(np.append(held_t, max(t1, float(held_t[0]))), t0, t1)
        yield held_e, np.diff(last)


def held_integrals_chunked(chunks: Callable[[], Iterable[tuple[np.ndarray, np.ndarray]]], t0: float, t1: float
                           ) -> tuple[float, float, float]:
    """IAE, ISE and max |e| of a held signal given as windows ``(t_s, e)`` (``chunks()`` gives them afresh; it
    is read twice): the numbers :func:`netsim.metrics.runtime.held_integrals` gives for the whole arrays."""
    if t1 <= t0:
        return 0.0, 0.0, 0.0
    n, mx, seen = 0, 0.0, False
    for e, dt in _edges(chunks(), t0, t1):
        seen = True
        valid = ~np.isnan(e) & (dt > 0)
        n += int(valid.sum())
        if valid.any():
            mx = max(mx, float(np.max(np.abs(e[valid]))))
    if not seen:
        return 0.0, 0.0, 0.0

    def parts(which: int) -> Iterator[np.ndarray]:
        for e, dt in _edges(chunks(), t0, t1):
            valid = ~np.isnan(e) & (dt > 0)
            ev = e[valid]
            yield np.abs(ev) * dt[valid] if which == 0 else ev * ev * dt[valid]

    return pairwise_sum(parts(0), n), pairwise_sum(parts(1), n), mx


def control_error_chunked(result: Any, p: Any) -> dict[str, float] | None:
    """:func:`netsim.metrics.runtime.control_error` (``p``: its checked parameters) from the signals table read window by window (``result._signal_chunks``, issue 19:
    a long run's table is never whole in memory), with the same numbers; None when the result has no windows
    (a table already built, or read back from a folder)."""
    fn = getattr(result, "_signal_chunks", None)
    names = [p.output] + ([p.reference] if p.reference else [])
    if not callable(fn) or "time_s" in names:
        return None
    try:
        if fn(names) is None:
            return None
    except KeyError:  # not recorded: the table path says so
        return None
    def windows() -> Any:
        for t_ns, cols in fn(names):
            y = cols[0]
            r = cols[1] if p.reference else np.zeros_like(y)
            yield t_ns / S, r - y

    t_end = None
    if "t_end_s" in getattr(result, "meta", {}):
        t_end = float(result.meta["t_end_s"])
    else:
        for t_ns, _ in fn(names):
            t_end = float(t_ns[-1] / S) if len(t_ns) else t_end
        t_end = 0.0 if t_end is None else t_end
    t1 = t_end if p.t1 is None else p.t1 / S
    iae, ise, mx = held_integrals_chunked(windows, p.t0 / S, t1)
    name = p.name or p.output
    return {f"{name}.IAE": iae, f"{name}.ISE": ise, f"{name}.max_abs_error": mx}
