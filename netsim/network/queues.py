"""The sender queue of a network interface: FIFO or priority order, a bound, and length statistics."""

from __future__ import annotations

import heapq
from collections import deque
from typing import Any, Literal

__all__ = ["SendQueue", "QueueDiscipline"]

QueueDiscipline = Literal["fifo", "priority"]


class SendQueue:
    """Frames waiting for the medium at one node (the frame being transmitted is not counted).

    Parameters
    ----------
    limit
        Most frames that may wait (``None``: unbounded). :meth:`push` refuses a frame beyond it.
    discipline
        ``"fifo"`` (arrival order) or ``"priority"`` (lowest ``frame.priority`` first, FIFO among equals).

    Attributes
    ----------
    max_len : int
        Longest the queue has been.
    """

    __slots__ = ("limit", "priority", "_fifo", "_heap", "_len", "max_len", "_area", "_last_t")

    def __init__(self, limit: int | None, discipline: QueueDiscipline = "fifo") -> None:
        self.limit = limit
        self.priority = discipline == "priority"
        self._fifo: deque[Any] = deque()
        self._heap: list[tuple[int, int, Any]] = []
        self._len = 0
        self.max_len = 0
        self._area = 0  # integral of the length over time (frames * ns)
        self._last_t = 0

    def __len__(self) -> int:
        return self._len

    def _account(self, now: int) -> None:
        self._area += self._len * (now - self._last_t)
        self._last_t = now

    def push(self, frame: Any, now: int) -> bool:
        """Queue ``frame`` (needs ``.priority`` and ``.order``); False if the queue is full."""
        return self._insert(frame, now, front=False)

    def push_front(self, frame: Any, now: int) -> bool:
        """Put a frame back to be sent next among its equals (retransmission); False if full."""
        return self._insert(frame, now, front=True)

    def _insert(self, frame: Any, now: int, *, front: bool) -> bool:
        if self.limit is not None and self._len >= self.limit:
            return False
        self._account(now)
        if self.priority:
            # a retransmitted frame keeps its original order key, so it goes back ahead of later equals
            heapq.heappush(self._heap, (frame.priority, frame.order, frame))
        elif front:
            self._fifo.appendleft(frame)
        else:
            self._fifo.append(frame)
        self._len += 1
        if self._len > self.max_len:
            self.max_len = self._len
        return True

    def peek(self) -> Any:
        """The frame that :meth:`pop` would return (IndexError if empty)."""
        return self._heap[0][2] if self.priority else self._fifo[0]

    def pop(self, now: int) -> Any:
        """Remove and return the next frame (IndexError if empty)."""
        self._account(now)
        frame = heapq.heappop(self._heap)[2] if self.priority else self._fifo.popleft()
        self._len -= 1
        return frame

    def mean_len(self, t_end: int) -> float:
        """Time-averaged length over ``[0, t_end]``."""
        if t_end <= 0:
            return 0.0
        area = self._area + self._len * max(0, t_end - self._last_t)
        return area / t_end
