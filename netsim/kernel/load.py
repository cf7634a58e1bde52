"""A periodic interrupt load accounted in closed form (a fast ISR without one simpy event per tick).

A :class:`PeriodicLoad` stands for an interrupt handler of constant execution time ``e`` fired at
``t_k = start + k * period`` (``k = 0, 1, ...``). Its *windows* ``[t_k, t_k + e)`` are CPU time taken from
everything else on the node: a task segment that needs ``R`` ns of CPU from ``t`` ends at the smallest
``t'`` with ``(t' - t) - stolen(t, t') = R``, where ``stolen`` is the overlap of ``[t, t')`` with the windows.
The kernel asks this object for those instants (:meth:`finish`), for the progress a preempted segment made
(:meth:`free`) and for the window around an instant (:meth:`window_end`); the arithmetic is exact in
integer nanoseconds, so the results equal those of an explicit handler invoked by a periodic timer.

The kernel's side of the semantics (dispatch deferred to a window's end, preemption counts, the real
handler invoked at a tick, CPU accounting) is described in :meth:`netsim.kernel.Kernel.create_periodic_load`.
"""

from __future__ import annotations

__all__ = ["PeriodicLoad"]


class PeriodicLoad:
    """The windows ``[start + k period, start + k period + execution)``, ``k >= 0``, of a periodic ISR.

    Parameters
    ----------
    name
        Name under which the load's CPU time is reported (``Kernel.cpu_time[name]``).
    period, execution, start
        Tick period, constant execution per tick (``0 < execution < period``) and first tick, in ns.
    handler
        Optional name of a real handler of the node whose invocations *at a tick* are that tick's window
        (not extra CPU time).

    Attributes
    ----------
    claimed : int
        The last tick whose window a real invocation of ``handler`` took (``-1``: none yet).
    real_invocations : int
        Number of ticks at which the real handler was invoked as the window.
    """

    __slots__ = ("name", "period", "execution", "start", "handler", "claimed", "real_invocations", "_free")

    def __init__(self, name: str, period: int, execution: int, start: int = 0, handler: str | None = None) -> None:
        self.name = name
        self.period = period
        self.execution = execution
        self.start = start
        self.handler = handler
        self.claimed = -1
        self.real_invocations = 0
        self._free = period - execution  # free CPU per period

    # ------------------------------------------------------------------ windows
    def stolen_until(self, t: int) -> int:
        """CPU time taken by the windows in ``[start, t)`` (the last window counted partially)."""
        d = t - self.start
        if d <= 0:
            return 0
        n, r = divmod(d, self.period)
        e = self.execution
        return n * e + (r if r < e else e)

    def stolen(self, a: int, b: int) -> int:
        """Overlap of ``[a, b)`` with the windows."""
        return self.stolen_until(b) - self.stolen_until(a)

    def free(self, a: int, b: int) -> int:
        """CPU time left to the rest of the node in ``[a, b)``: ``(b - a) - stolen(a, b)``."""
        # stolen_until(b) and stolen_until(a) inlined (the kernel asks this for every charged segment)
        start, period, e = self.start, self.period, self.execution
        out = b - a
        d = b - start
        if d > 0:
            n, r = divmod(d, period)
            out -= n * e + (r if r < e else e)
        d = a - start
        if d > 0:
            n, r = divmod(d, period)
            out += n * e + (r if r < e else e)
        return out

    def finish(self, a: int, demand: int) -> int:
        """Smallest ``t >= a`` with ``free(a, t) == demand``: the end of a segment needing ``demand`` ns.

        A segment whose last nanosecond of work falls just before a window ends at that window's start
        (``t_k``), not after the window.
        """
        if demand <= 0:
            return a
        start = self.start
        g = a + demand - start  # target of F(t) = t - stolen_until(t), minus F(start)
        d = a - start
        if d > 0:  # minus stolen_until(a), inlined
            n, r = divmod(d, self.period)
            e = self.execution
            g -= n * e + (r if r < e else e)
        if g <= 0:
            return start + g
        n, rem = divmod(g, self._free)
        if rem == 0:
            return start + n * self.period
        return start + n * self.period + self.execution + rem

    def window_end(self, t: int) -> int:
        """End of the window containing ``t`` (``t_k <= t < t_k + execution``), else 0."""
        d = t - self.start
        if d < 0:
            return 0
        r = d % self.period
        return t - r + self.execution if r < self.execution else 0

    def is_tick(self, t: int) -> bool:
        """True if ``t`` is a tick ``t_k``."""
        d = t - self.start
        return d >= 0 and d % self.period == 0

    def ticks_before(self, t: int) -> int:
        """Number of ticks ``t_k < t``."""
        d = t - self.start
        return 0 if d <= 0 else (d + self.period - 1) // self.period

    def ticks_in(self, a: int, b: int) -> int:
        """Number of ticks in ``[a, b)``."""
        if b <= a:
            return 0
        start, period = self.start, self.period  # ticks_before(b) - ticks_before(a), inlined
        d = b - start
        if d <= 0:
            return 0
        n = (d + period - 1) // period
        d = a - start
        return n - (d + period - 1) // period if d > 0 else n

    def preempted_until(self, seg_start: int, t: int) -> bool:
        """True if the last tick before ``t`` fell at or after ``seg_start`` and its window ends at or after ``t``.

        A job whose segment started at ``seg_start`` and is preempted by the dispatcher at ``t`` is then
        still (or just) preempted by that window: the two preemptions are one.
        """
        n = self.ticks_before(t)
        if n == 0:
            return False
        tk = self.start + (n - 1) * self.period
        return tk >= seg_start and t <= tk + self.execution

    def windows(self, t0: int, t1: int) -> list[tuple[int, int]]:
        """The windows intersecting ``[t0, t1)``, clipped to it (for drawing a schedule)."""
        if t1 <= t0:
            return []
        k0 = max(0, (t0 - self.start - self.execution) // self.period + 1) if t0 > self.start else 0
        out = []
        tk = self.start + k0 * self.period
        while tk < t1:
            a, b = max(tk, t0), min(tk + self.execution, t1)
            if b > a:
                out.append((a, b))
            tk += self.period
        return out

    def __repr__(self) -> str:
        return (f"<PeriodicLoad {self.name} period={self.period} execution={self.execution} start={self.start} "
                f"handler={self.handler}>")
