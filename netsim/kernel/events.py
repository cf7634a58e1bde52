"""A lean simpy event for the kernel's own wake-ups (segment ends, releases, timers, sleeps).

One object per wake-up, scheduled directly with a chosen simpy priority and one callback, without a
simpy process. The kernel uses three priorities at one instant: ``NORMAL`` (1) for segment ends,
releases, timers and sleeps; :data:`DISPATCH` (2) for the deferred dispatch, so that every release of
an instant is processed before the CPU is given away; :data:`DEADLINE` (3) for deadline checks, so that
a job finishing exactly at its deadline meets it.
"""

from __future__ import annotations

from heapq import heappush
from typing import Any, Callable

import simpy
from simpy.events import Event

__all__ = ["Wake", "NORMAL", "DISPATCH", "DEADLINE", "URGENT"]

URGENT = 0
NORMAL = 1
DISPATCH = 2
DEADLINE = 3


class Wake(Event):
    """An already-triggered event processed ``delay`` ns from now with ``priority``.

    ``value`` is available to the callback as ``event._value`` (the job or timer it concerns).
    """

    def __init__(self, env: simpy.Environment, delay: int, priority: int,
                 callback: Callable[[Any], None], value: Any = None) -> None:
        # Same initialisation as simpy.Timeout, with a chosen priority and a single callback.
        self.env = env
        self.callbacks = [callback]
        self._value = value
        self._ok = True
        # env.schedule(self, priority, delay), inlined (same heap entry, same event id)
        heappush(env._queue, (env._now + delay, priority, next(env._eid), self))  # type: ignore[attr-defined]
