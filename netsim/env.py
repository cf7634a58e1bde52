"""The simulation environment: one simpy environment, named random streams, and a signal recorder.

Time in the simpy environment is integer nanoseconds (see :mod:`netsim.timebase`).

Random streams
--------------
Every source of randomness asks for its own stream by name (``env.rng("network.can.loss")``). A stream is
a :class:`numpy.random.Generator` seeded from the scenario seed and a stable hash of the name, so adding a
new noise source does not shift the numbers drawn by the others, and a run is reproducible from its seed
alone, whatever the order in which streams are created.

Event loop
----------
simpy's heap holds ``(time, priority, event id, event)`` entries. netsim's own wake-ups (kernel segment ends,
releases, timers, network transmissions, the plant's recording grid) are *call entries* on the same heap:
``(time, priority, event id, fn, arg)``, scheduled with :func:`schedule_call` and run by :func:`run_events` as
``fn(entry)`` (the callback reads ``entry[4]``; the entry tuple itself identifies the wake-up, e.g. to tell a
superseded one). They cost no event object and no callback list; simpy events and processes still work
beside them, in the same order of (time, priority, id). simpy's own ``Environment.step``/``run`` cannot
process call entries: run the loop with :func:`run_events` (or :meth:`SimEnv.run`).

Same-instant order
------------------
Entries due at the same time run by priority (lower first), then in the order they were scheduled. Every
priority used at one instant is in this one table; kernel, networks and plants import it:

=====================  =  =================================================================================
:data:`URGENT`         0  set-up at the start of the run (kernel checks) and simpy's own process starts
                          and interrupts
:data:`NORMAL`         1  everything that *happens* at the instant: periodic releases, timers, sleeps ending,
                          ends of execute segments, ends of wired transmissions, interface delays,
                          deliveries; simpy's timeouts and triggered events
:data:`DISPATCH`       2  the kernel's deferred dispatch (and the end of a periodic-load window): the CPU is
                          given away once every release of the instant is known
:data:`AIR`            3  radio transmissions going on and off the air (after the instant's channel-access
                          decisions: CCAs, backoff expiries, frames finding the medium idle)
:data:`ARBITRATE`      4  media deciding who sends (CAN arbitration, CSMA/CD contention, TDMA slot starts,
                          token visits, priority queues of serial outputs)
:data:`DEADLINE`       5  deadline checks
:data:`RECORD`         6  the plant's ``record_grid`` samples
=====================  =  =================================================================================

Why this order:

- Releases before dispatch: a job released at *t* competes for the CPU at *t* (DESIGN.md, section 2).
- Dispatch before arbitration: a task released at *t* whose code sends a frame at *t* (zero-time code at
  the start of its segment) has its frame queued when the medium decides at *t* (TrueTime: a frame queued at
  the instant the bus goes idle takes part in the arbitration; issue 13 B). A transmission ending at *t* is
  NORMAL, so the frames it leaves waiting take part too.
- Radio decisions before the air changes: a CCA ending or a backoff expiring at *t* (NORMAL), or a frame
  sent at *t* by a dispatched task, sees the medium as it was just before *t*; carrier sense cannot detect
  a start at the very instant it senses, so nodes deciding together collide, and a CCA ending as a
  transmission ends has sensed it.
- Air changes before arbitration: a radio frame ending at *t* is delivered at *t*, and what a task does
  with it at *t* (forwarding it on a bus, say) is queued before that bus arbitrates at *t*.
- Arbitration before deadline checks: a job finishing at *t* meets a deadline at *t* (response-time
  analysis counts ``R <= D`` as met), whatever made it finish at *t*: a segment end, a release, or a
  message delivered by a transmission decided at *t*.
- Recording last: a grid sample at *t* records the outputs once every event of *t* is done, inputs set at
  *t* included (the held input is right-continuous; it matters only for a plant with direct feedthrough),
  and the first sample, at the start, sees the actuations of time 0 like every later one.
- Work created while an instant is processed needs no special care: a new entry at the current time goes
  into the same heap, so anything a dispatch or an arbitration starts at *t* at a lower priority (a release
  by a delivery, a further dispatch, a zero-length transmission) still runs before the remaining
  higher-priority entries of *t*. The medium decides only when nothing of lower priority is left at *t*.
  The invariant to keep: nothing that can change who competes at *t* may be scheduled at *t* with a
  priority above the decision that needs it.

URGENT and NORMAL equal simpy's :data:`simpy.events.URGENT` and :data:`simpy.events.NORMAL`, so simpy events
and call entries interleave by the same table.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from heapq import heappop, heappush
from typing import Any, Callable, Final

import numpy as np
import simpy
import simpy.events


__all__ = [
    "SimEnv", "Recorder", "stream_seed", "schedule_call", "run_events", "CallEntry",
    "URGENT", "NORMAL", "DISPATCH", "AIR", "ARBITRATE", "DEADLINE", "RECORD",
]

#: Set-up at the start of the run; simpy's process starts and interrupts (simpy's URGENT).
URGENT: Final[int] = simpy.events.URGENT
#: Releases, timers, sleeps, segment ends, transmission ends, deliveries, plant samples (simpy's NORMAL).
NORMAL: Final[int] = simpy.events.NORMAL
#: The kernel's deferred dispatch: after every release of the instant.
DISPATCH: Final[int] = NORMAL + 1
#: Radio transmissions going on and off the air: after the instant's channel-access decisions.
AIR: Final[int] = DISPATCH + 1
#: Medium decisions (arbitration, contention, slot starts): after every dispatch and delivery of the instant.
ARBITRATE: Final[int] = AIR + 1
#: Deadline checks: after everything that can finish a job at the instant.
DEADLINE: Final[int] = ARBITRATE + 1
#: The plant's grid samples: the outputs once everything of the instant (actuations included) is done.
RECORD: Final[int] = DEADLINE + 1

#: A call entry: ``(time_ns, priority, event_id, fn, arg)``; ``fn`` is called with the entry itself.
CallEntry = tuple[int, int, int, Callable[[Any], None], Any]


def schedule_call(sim: simpy.Environment, delay: int, priority: int, fn: Callable[[Any], None],
                  arg: Any = None) -> CallEntry:
    """Schedule ``fn(entry)`` ``delay`` ns from now with simpy ``priority``; returns the entry.

    Hot paths push the same tuple inline: ``heappush(sim._queue, (sim._now + d, prio, next(sim._eid), fn, arg))``.
    """
    entry = (sim._now + delay, priority, next(sim._eid), fn, arg)  # type: ignore[attr-defined]
    heappush(sim._queue, entry)  # type: ignore[attr-defined]
    return entry


def run_events(sim: simpy.Environment, t_end: int) -> None:
    """Process every event up to and including ``t_end`` ns: call entries and simpy events, in heap order.

    simpy re-raises a process's unhandled exception as a *copy* built from ``exc.args``; netsim errors with
    extra constructor arguments (``DivergenceError(message, time_ns)``) cannot be copied that way, and the
    copy would lose ``time_ns`` anyway. So the loop looks at a simpy event before popping it and raises the
    original exception of a failed, undefused event itself. An exception raised by a call entry's ``fn``
    propagates as it is.
    """
    queue = sim._queue  # type: ignore[attr-defined]
    until = int(t_end) + 1
    pop = heappop
    while queue:
        entry = queue[0]
        if entry[0] >= until:
            break
        if len(entry) == 5:  # a call entry
            pop(queue)
            sim._now = entry[0]  # type: ignore[attr-defined]
            entry[3](entry)
            continue
        # a simpy event: simpy's Environment.step, inlined
        event = entry[3]
        if event._ok is False and not hasattr(event, "_defused") and isinstance(event._value, BaseException):
            event._defused = True
            raise event._value
        pop(queue)
        sim._now = entry[0]  # type: ignore[attr-defined]
        callbacks, event.callbacks = event.callbacks, None
        for callback in callbacks:
            callback(event)
        if not event._ok and not hasattr(event, "_defused"):
            exc = type(event._value)(*event._value.args)
            exc.__cause__ = event._value
            raise exc


def stream_seed(seed: int, name: str) -> np.random.SeedSequence:
    """Seed sequence of the stream ``name`` under the scenario ``seed`` (stable across runs and platforms)."""
    digest = hashlib.sha256(name.encode("utf-8")).digest()
    key = tuple(int.from_bytes(digest[i : i + 4], "little") for i in range(0, 16, 4))
    return np.random.SeedSequence(entropy=int(seed), spawn_key=key)


@dataclass
class Recorder:
    """Time series recorded during a run, one list pair per signal name.

    ``record(name, t_ns, value)`` appends a sample; the results layer turns the samples into the wide
    ``signals.csv`` table (time first, one column per signal). Values are floats; a vector value is
    recorded as ``name[0]``, ``name[1]`` ....
    """

    enabled: set[str] | None = None  # None records everything
    times: dict[str, list[int]] = field(default_factory=dict)
    values: dict[str, list[float]] = field(default_factory=dict)

    def wants(self, name: str) -> bool:
        """True when ``name`` is to be recorded."""
        return self.enabled is None or name in self.enabled or name.split("[", 1)[0] in self.enabled

    def record(self, name: str, t_ns: int, value: Any) -> None:
        """Append one sample of ``name`` at ``t_ns`` (no-op for signals that were not asked for)."""
        if not self.wants(name):
            return
        if type(value) is float or type(value) is int:  # the common case, without a numpy round trip
            self._append(name, t_ns, float(value))
            return
        arr = np.asarray(value, dtype=float)
        if arr.ndim == 0:
            self._append(name, t_ns, float(arr))
        else:
            for i, v in enumerate(arr.ravel()):
                self._append(f"{name}[{i}]", t_ns, float(v))

    def _append(self, name: str, t_ns: int, value: float) -> None:
        ts = self.times.get(name)
        if ts is None:
            ts = self.times[name] = []
            self.values[name] = []
        ts.append(int(t_ns))
        self.values[name].append(value)

    def names(self) -> list[str]:
        """Recorded signal names, in first-recorded order."""
        return list(self.times)


class SimEnv:
    """A simpy environment in integer nanoseconds with named random streams and a recorder.

    Parameters
    ----------
    seed
        The scenario seed; every random draw in the run derives from it.
    record
        Names of the signals to record (``None``: all).

    Attributes
    ----------
    sim : simpy.Environment
        The underlying event loop; ``sim.now`` is the time in nanoseconds.
    recorder : Recorder
        Recorded signals.
    """

    def __init__(self, seed: int = 0, record: set[str] | None = None) -> None:
        self.seed = int(seed)
        self.sim = simpy.Environment(initial_time=0)
        self.recorder = Recorder(enabled=record)
        self._streams: dict[str, np.random.Generator] = {}
        self._finalizers: list[Callable[[int], None]] = []
        self.components: dict[str, Any] = {}
        self._counters: dict[str, int] = {}

    @property
    def now(self) -> int:
        """Current simulation time in nanoseconds."""
        return int(self.sim.now)

    def rng(self, name: str) -> np.random.Generator:
        """The random stream ``name`` (created on first use, then the same object every call)."""
        gen = self._streams.get(name)
        if gen is None:
            gen = np.random.Generator(np.random.PCG64(stream_seed(self.seed, name)))
            self._streams[name] = gen
        return gen

    def next_id(self, kind: str) -> int:
        """Next integer id of ``kind`` in this run (0, 1, 2, ...): reproducible ids for messages and jobs."""
        n = self._counters.get(kind, 0)
        self._counters[kind] = n + 1
        return n

    def timeout(self, delay_ns: int, value: Any = None) -> simpy.Timeout:
        """A simpy timeout of ``delay_ns`` nanoseconds."""
        return self.sim.timeout(int(delay_ns), value)

    def process(self, generator: Any) -> simpy.Process:
        """Start a simpy process."""
        return self.sim.process(generator)

    def record(self, name: str, value: Any, t_ns: int | None = None) -> None:
        """Record ``value`` of signal ``name`` at ``t_ns`` (default: now)."""
        self.recorder.record(name, self.now if t_ns is None else t_ns, value)

    def at_end(self, fn: Callable[[int], None]) -> None:
        """Register ``fn(t_end_ns)`` to run when the simulation finishes (flush plants, close intervals)."""
        self._finalizers.append(fn)

    def run(self, until_ns: int) -> None:
        """Run the event loop up to and including events at ``until_ns``, then call the finalizers."""
        run_events(self.sim, int(until_ns))
        if self.sim._now <= until_ns:  # as simpy's run(until=until_ns + 1) leaves the clock
            self.sim._now = int(until_ns) + 1
        for fn in self._finalizers:
            fn(int(until_ns))
