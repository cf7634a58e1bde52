"""Busy-time accounting of a channel: total busy time and a binned utilization-over-time series."""

from __future__ import annotations

from array import array

__all__ = ["BusyMeter"]


class BusyMeter:
    """Accumulates the intervals during which one channel (a bus, a link, a switch port) carries bits.

    Closed intervals are collected in a short list and spread over the bins of the utilization series in batches
    of :attr:`FOLD` intervals; the bins are one 8-byte integer each (busy ns per bin). Memory grows with the run's
    length divided by ``bin_ns`` (80 kB per 100 s at 10 ms bins), not with the number of frames (issue 19).

    Parameters
    ----------
    bin_ns
        Width of the bins of the utilization series.
    weight
        Share of the network's capacity this channel represents (FDMA sub-channels); 1 otherwise.
    """

    __slots__ = ("bin_ns", "weight", "total", "open_since", "_intervals", "_bins")

    #: Closed intervals held before they are spread over the bins.
    FOLD = 1024

    def __init__(self, bin_ns: int, weight: float = 1.0) -> None:
        self.bin_ns = int(bin_ns)
        self.weight = float(weight)
        self.total = 0
        self.open_since: int | None = None
        self._intervals: list[tuple[int, int]] = []  # closed busy intervals not yet spread over the bins
        self._bins = array("q")  # busy ns of bin k at index k

    def start(self, t: int) -> None:
        """The channel becomes busy at ``t``."""
        self.open_since = t

    def stop(self, t: int) -> None:
        """The channel becomes idle at ``t`` (closes the interval opened by :meth:`start`)."""
        s = self.open_since
        if s is None:
            return
        self.open_since = None
        self.add(s, t)

    def add(self, s: int, t: int) -> None:
        """Count the closed busy interval ``[s, t)`` (spread over the bins when the series is asked for)."""
        if t > s:
            self.total += t - s
            held = self._intervals
            held.append((s, t))
            if len(held) >= self.FOLD:
                self._fold()

    def _fold(self) -> None:
        """Spread the held intervals over the bins."""
        b = self.bin_ns
        bins = self._bins
        for s, t in self._intervals:
            k = s // b
            last = (t - 1) // b
            if last >= len(bins):
                bins.frombytes(bytes(8 * (last + 1 - len(bins))))  # zeros up to bin ``last``
            while s < t:
                edge = min(t, (k + 1) * b)
                bins[k] += edge - s
                s = edge
                k += 1
        self._intervals.clear()

    @property
    def bins(self) -> dict[int, int]:
        """Busy ns per bin index ``k`` (bin ``[k*bin_ns, (k+1)*bin_ns)``) of the closed intervals (bins with
        busy time only)."""
        self._fold()
        return {k: v for k, v in enumerate(self._bins) if v}

    def busy(self, t_end: int) -> int:
        """Busy time in ``[0, t_end]`` (an interval still open counts up to ``t_end``)."""
        extra = 0
        if self.open_since is not None and t_end > self.open_since:
            extra = t_end - self.open_since
        return self.total + extra

    def fraction(self, t_end: int) -> float:
        """Busy time divided by ``t_end``."""
        return self.busy(t_end) / t_end if t_end > 0 else 0.0

    def series(self, t_end: int) -> list[float]:
        """Busy fraction of each bin ``[k*bin, (k+1)*bin)`` up to ``t_end`` (last bin may be partial)."""
        if t_end <= 0:
            return []
        b = self.bin_ns
        n = -(-t_end // b)
        out = []
        self._fold()
        bins = self._bins
        for k in range(n):
            width = min(b, t_end - k * b)
            busy = bins[k] if k < len(bins) else 0
            if self.open_since is not None:
                lo, hi = max(self.open_since, k * b), min(t_end, (k + 1) * b)
                busy += max(0, hi - lo)
            out.append(min(1.0, busy / width) if width > 0 else 0.0)
        return out
