"""Synchronisation objects for task bodies: bounded mailboxes, counting semaphores and events.

Bodies use them through requests (``item = yield job.fetch(mb)``, ``yield job.take(sem)``,
``yield job.wait(ev)``); a request that cannot complete blocks the job, which gives up the CPU until
another job (or a callback) posts, gives or notifies. Waiters are served first come, first served.
The objects are plain Python: they may be created before the simulation and shared between the
tasks and handlers of a node (``kernel.shared``).

Semantics (TrueTime-like)
-------------------------
- :class:`Mailbox`: FIFO of items with an optional ``capacity``. ``post`` blocks while full,
  ``fetch`` blocks while empty; ``try_post`` returns ``False`` when full, ``try_fetch`` returns ``None``
  when empty. A post to an empty mailbox with a blocked fetcher hands the item directly to it.
- :class:`Semaphore`: counting; ``take`` blocks at zero; ``give`` wakes the first waiter or increments
  the count (saturating at ``maximum`` if given).
- :class:`Event`: a condition without memory; ``wait`` always blocks until the next ``notify``
  (one waiter) or ``notify(all=True)`` (every waiter). A notify with nobody waiting is lost.
"""

from __future__ import annotations

from collections import deque
from typing import TYPE_CHECKING, Any

from netsim.errors import ConfigError
from netsim.kernel.states import BLOCKED

if TYPE_CHECKING:
    from netsim.kernel.job import Job

__all__ = ["Mailbox", "Semaphore", "Event"]


def _live(job: Job, obj: Any) -> bool:
    """True when ``job`` is still blocked on ``obj`` (killed jobs are skipped lazily)."""
    return job._state == BLOCKED and job._blocked_on is obj


class Mailbox:
    """A bounded FIFO mailbox.

    Parameters
    ----------
    name
        Label used in error messages and traces.
    capacity
        Maximum number of stored items (``None``: unbounded).
    """

    def __init__(self, name: str = "", capacity: int | None = None) -> None:
        if capacity is not None and (isinstance(capacity, bool) or not isinstance(capacity, int) or capacity < 1):
            raise ConfigError(f"mailbox '{name}': capacity must be a positive integer or None, got {capacity!r}")
        self.name = name
        self.capacity = capacity
        self.items: deque[Any] = deque()
        self._getters: deque[Any] = deque()
        self._putters: deque[tuple[Any, Any]] = deque()

    def __len__(self) -> int:
        return len(self.items)

    @property
    def full(self) -> bool:
        """True when a post would block."""
        return self.capacity is not None and len(self.items) >= self.capacity

    def try_put(self, item: Any) -> bool:
        """Post ``item`` without blocking (usable from outside a job); ``False`` when full."""
        getters = self._getters
        while getters:
            job = getters.popleft()
            if _live(job, self):
                job._ctx.unblock(job, item)
                return True
        if self.capacity is not None and len(self.items) >= self.capacity:
            return False
        self.items.append(item)
        return True

    def try_get(self) -> tuple[bool, Any]:
        """Take the oldest item without blocking: ``(True, item)`` or ``(False, None)`` when empty."""
        if not self.items:
            return False, None
        item = self.items.popleft()
        putters = self._putters
        while putters:
            job, pending = putters.popleft()
            if _live(job, self):
                self.items.append(pending)
                job._ctx.unblock(job, None)
                break
        return True, item

    def __repr__(self) -> str:
        return f"Mailbox({self.name!r}, capacity={self.capacity}, items={len(self.items)})"


class Semaphore:
    """A counting semaphore.

    Parameters
    ----------
    name
        Label used in error messages.
    count
        Initial count (>= 0).
    maximum
        Optional saturation value of the count.
    """

    def __init__(self, name: str = "", count: int = 0, maximum: int | None = None) -> None:
        if isinstance(count, bool) or not isinstance(count, int) or count < 0:
            raise ConfigError(f"semaphore '{name}': count must be a non-negative integer, got {count!r}")
        if maximum is not None and (not isinstance(maximum, int) or maximum < max(count, 1)):
            raise ConfigError(f"semaphore '{name}': maximum must be an integer >= count and >= 1, got {maximum!r}")
        self.name = name
        self.count = count
        self.maximum = maximum
        self._waiters: deque[Any] = deque()

    def try_take(self) -> bool:
        """Decrement the count if positive (usable from outside a job); ``False`` at zero."""
        if self.count > 0:
            self.count -= 1
            return True
        return False

    def give(self) -> None:
        """Wake the first waiter, or increment the count (usable from outside a job)."""
        waiters = self._waiters
        while waiters:
            job = waiters.popleft()
            if _live(job, self):
                job._ctx.unblock(job, None)
                return
        if self.maximum is None or self.count < self.maximum:
            self.count += 1

    def __repr__(self) -> str:
        return f"Semaphore({self.name!r}, count={self.count})"


class Event:
    """A notification point without memory (TrueTime's free events).

    Parameters
    ----------
    name
        Label used in error messages.
    """

    def __init__(self, name: str = "") -> None:
        self.name = name
        self._waiters: deque[Any] = deque()

    @property
    def waiting(self) -> int:
        """Number of jobs currently waiting."""
        return sum(1 for job in self._waiters if _live(job, self))

    def notify(self, all: bool = False) -> int:  # noqa: A002 - TrueTime's name for notify-all
        """Wake the first waiter (or every waiter with ``all=True``); returns how many were woken."""
        woken = 0
        waiters = self._waiters
        while waiters:
            job = waiters.popleft()
            if _live(job, self):
                job._ctx.unblock(job, None)
                woken += 1
                if not all:
                    break
        return woken

    def __repr__(self) -> str:
        return f"Event({self.name!r})"
