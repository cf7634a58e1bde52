"""Priorities of the kernel's own wake-ups (segment ends, releases, timers, sleeps, dispatches, deadlines).

Each wake-up is a call item ``(callback, value)`` in an entry ``(time, priority, id, item)`` of the event
loop's heap (:func:`netsim.env.schedule_call`; hot paths push the entry inline with the heap and counter of
:meth:`netsim.env.EventLoop.scheduler`): no event object, no simpy process. The callback receives the item;
``item[1]`` is the job, timer or task it concerns, and the item itself tells a superseded wake-up from the
current one.

The priorities are the run's one same-instant table, defined (and explained) in :mod:`netsim.env` and
re-exported here for the kernel: :data:`NORMAL` for segment ends, releases, timers and sleeps;
:data:`DISPATCH` for the deferred dispatch, so that every release of an instant is processed before the CPU
is given away; :data:`DEADLINE` for deadline checks, so that a job finishing exactly at its deadline meets
it. Media arbitrate at :data:`~netsim.env.ARBITRATE`, between the two, so that a frame sent by a job
dispatched at an instant takes part in that instant's arbitration.
"""

from __future__ import annotations

from netsim.env import DEADLINE, DISPATCH, NORMAL, URGENT, schedule_call

__all__ = ["schedule_call", "NORMAL", "DISPATCH", "DEADLINE", "URGENT"]
