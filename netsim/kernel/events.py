"""Priorities of the kernel's own wake-ups (segment ends, releases, timers, sleeps, dispatches).

Each wake-up is a call entry ``(time, priority, id, callback, value)`` on simpy's heap
(:func:`netsim.env.schedule_call`; hot paths push the tuple inline): no event object, no simpy process.
The callback receives the entry; ``entry[4]`` is the job, timer or task it concerns, and the entry itself
tells a superseded wake-up from the current one. The kernel uses three priorities at one instant:
:data:`NORMAL` (1) for segment ends, releases, timers and sleeps; :data:`DISPATCH` (2) for the deferred
dispatch, so that every release of an instant is processed before the CPU is given away; :data:`DEADLINE` (3)
for deadline checks, so that a job finishing exactly at its deadline meets it.
"""

from __future__ import annotations

from netsim.env import schedule_call

__all__ = ["schedule_call", "NORMAL", "DISPATCH", "DEADLINE", "URGENT"]

URGENT = 0
NORMAL = 1
DISPATCH = 2
DEADLINE = 3
