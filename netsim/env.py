"""The simulation environment: one simpy environment, named random streams, and a signal recorder.

Time in the simpy environment is integer nanoseconds (see :mod:`netsim.timebase`).

Why this module is long: it is the one place that knows simpy's internals, and its docstring is the run's
one same-instant table with the reasons for its order; the loop, its scheduling calls and that table are
read together, and split they would spread simpy's internals over several modules.

Random streams
--------------
Every source of randomness asks for its own stream by name (``env.rng("network.can.loss")``). A stream is
a :class:`numpy.random.Generator` seeded from the scenario seed and a stable hash of the name, so adding a
new noise source does not shift the numbers drawn by the others, and a run is reproducible from its seed
alone, whatever the order in which streams are created.

Event loop
----------
:class:`EventLoop` is a :class:`simpy.Environment` subclass and the one module of netsim that knows how
simpy stores its schedule. Its heap holds one entry shape, simpy's own ``(time, priority, id, item)``, run
in the order of ``(time, priority, id)``. The item is either

- a simpy event (timeouts, processes, stores, resources: everything simpy schedules through
  :meth:`EventLoop.schedule`), processed as :meth:`simpy.Environment.step` processes it; or
- a *call item*, a plain tuple whose first element is a function: the loop calls ``fn(item)``. As a rule
  the item is ``(fn, arg)`` and ``fn`` reads ``item[1]``; a hot path may carry more fields (a transmission's
  end is ``(done, frame, start_ns)``). netsim's own wake-ups (kernel segment ends, releases, timers,
  network transmissions, the plant's recording grid) are call items: no event object, no callback list, one
  heap push. The item itself identifies the wake-up, so a component tells a superseded one by identity
  (``if item is not job.wake: return``).

Ways to schedule, cheapest first:

- hot paths take ``push, heap, ids = sim.scheduler()`` once and push ``(t, priority, next(ids), (fn, arg))``
  inline (``t`` absolute, never before ``sim.now``);
- :func:`schedule_call` ``(sim, delay, priority, fn, arg)`` does the same and returns the item;
- :meth:`EventLoop.call_at` ``(t, fn, *args, priority=...)`` and :meth:`EventLoop.call_later` return a
  :class:`Call` handle whose :meth:`Call.cancel` is O(1) (the entry stays in the heap and is skipped);
- :meth:`EventLoop.event_at` is a simpy event (for a process to yield) processed at a chosen priority.

Cheaper still is not to schedule: a call item whose last act would be to schedule its own continuation
(a kernel's next CPU segment) asks :meth:`EventLoop.advance_if_next` whether that entry would be the next one
processed anyway; if so the clock moves there and the item goes on at once, one push and one pop fewer,
with the same order of everything (issue 19: nothing can happen before the continuation).

``sim.now`` is a plain attribute (simpy's is a property over ``_now``): read on every hot path, it costs a
dictionary look-up, not a function call.

Two loops run the same heap in the same order. :func:`run_events` (and :meth:`SimEnv.run`, and
:meth:`netsim.build.builder.Simulation.run`) is netsim's fast loop: every entry up to and *including*
``t_end``. simpy's own :meth:`simpy.Environment.run` works too, through the overridden :meth:`EventLoop.step`:
``sim.run(until=t_end + 1)`` processes the same entries (simpy stops *before* ``until``) and leaves the clock
at ``t_end + 1``, as :meth:`SimEnv.run` does; ``sim.run()`` runs until the heap is empty (never, with a
periodic task), ``sim.run(until=event)`` until that event.

A failed simpy event (a process that raised) is handed to the processes waiting for it, as in simpy (which
throws a copy built from ``exc.args`` into each of them); when none of them defuses it, both loops raise the
*original* exception (simpy's own ``step`` raises such a copy, which netsim errors with extra constructor
arguments, e.g. ``DivergenceError(message, time_ns)``, cannot survive). An exception raised by a call item's
``fn`` propagates as it is.

A plain simpy process in a netsim run
-------------------------------------
Anything written for simpy runs beside kernels, networks and plants, in the one clock and the one
same-instant table (a custom traffic source, a test harness, a simpy model of a machine). The README's
section of this name has a complete example on a shipped scenario; in short::

    env = SimEnv(seed=1)
    sim = env.sim                              # an EventLoop: a simpy.Environment
    parts = simpy.Store(sim)                   # kernels, networks and plants are built on env as usual

    def machine():                             # a plain simpy process
        while True:
            yield sim.timeout(2_000_000)       # 2 ms, in integer nanoseconds
            yield parts.put(sim.now)

    sim.process(machine())
    env.run(10_000_000)                        # or simpy's own: sim.run(until=10_000_001); env.finish(10_000_000)

simpy's timeouts and triggered events are NORMAL and its process starts and interrupts URGENT (the first two
rows of the table below), so a process resumed at *t* acts before the kernels dispatch at *t* and the media
arbitrate at *t*: a frame it sends at *t* takes part in that instant's arbitration, like one sent by a task.

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
from array import array
from dataclasses import dataclass, field
from heapq import heappop, heappush
from typing import TYPE_CHECKING, Any, Callable, Final, Iterator, NamedTuple

import numpy as np
import simpy
import simpy.events
from simpy.core import EmptySchedule, StopSimulation


__all__ = [
    "SimEnv", "EventLoop", "Call", "CallItem", "Scheduler", "Recorder", "stream_seed", "schedule_call",
    "run_events", "URGENT", "NORMAL", "DISPATCH", "AIR", "ARBITRATE", "DEADLINE", "RECORD",
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

#: A call item ``(fn, arg)``: the event loop calls ``fn(item)``; ``fn`` reads ``arg`` as ``item[1]``.
CallItem = tuple[Callable[[Any], None], Any]


class Scheduler(NamedTuple):
    """What a hot path needs to push call entries inline (:meth:`EventLoop.scheduler`).

    ``push(heap, (t, priority, next(ids), (fn, arg)))`` schedules ``fn((fn, arg))`` at absolute time ``t``
    (never before ``sim.now``); ``heap[0][0]`` and ``heap[0][1]`` are the time and priority of the next entry
    (when ``heap`` is not empty). See :meth:`EventLoop.advance_if_next` for processing an entry without
    pushing it.
    """

    push: Callable[[list, tuple], None]
    heap: list
    ids: Iterator[int]


class Call:
    """A cancellable scheduled call ``fn(*args)`` (:meth:`EventLoop.call_at`, :meth:`EventLoop.call_later`).

    :meth:`cancel` is O(1): the entry stays in the heap and is skipped when it comes due.
    """

    __slots__ = ("fn", "args", "live")

    def __init__(self, fn: Callable[..., None], args: tuple) -> None:
        self.fn = fn
        self.args = args
        self.live = True

    def cancel(self) -> None:
        """Do not call ``fn`` after all."""
        self.live = False


def _fire(item: tuple[Any, Call]) -> None:
    call = item[1]
    if call.live:
        call.fn(*call.args)


class EventLoop(simpy.Environment):
    """A simpy environment in integer nanoseconds whose heap also runs netsim's call items.

    Everything simpy offers works on it (processes, timeouts, stores, resources, :meth:`run`); netsim's
    components add call items (see the module docstring). ``now`` is a plain attribute, the current time
    in ns: read it, never assign it.

    Parameters
    ----------
    initial_time
        Start time in ns.
    """

    now: int = 0  # shadows simpy's property: a plain instance attribute, set by the loop
    #: simpy's heap, whose entries are ``(time, priority, id, item)`` with the item a simpy event or a call item
    #: (simpy's annotation knows only events)
    _queue: list[Any]
    #: The last instant (ns) the running :meth:`run_until` processes; -1 when it is not running (simpy's own
    #: ``run``/``step``): :meth:`advance_if_next` moves the clock only inside netsim's loop.
    horizon: int = -1

    def __init__(self, initial_time: int = 0) -> None:
        super().__init__(int(initial_time))
        self.now = int(initial_time)
        self.horizon = -1

    # simpy's base class and simpy.rt name the clock _now; here it is an alias of the attribute ``now``
    @property
    def _now(self) -> int:
        return self.now

    @_now.setter
    def _now(self, t: int) -> None:
        self.now = t

    def schedule(self, event: simpy.Event, priority: int = NORMAL, delay: float = 0) -> None:
        """Schedule a simpy ``event`` ``delay`` ns from now with ``priority`` (simpy's extension point).

        netsim's delays are integers; a plain simpy process's ``timeout(delay)`` passes its own number.
        """
        heappush(self._queue, (self.now + delay, priority, next(self._eid), event))

    def scheduler(self) -> Scheduler:
        """The push function, the heap and the id counter, for hot paths that push call entries inline."""
        return Scheduler(heappush, self._queue, self._eid)

    def call_at(self, t: int, fn: Callable[..., None], *args: Any, priority: int = NORMAL) -> Call:
        """Call ``fn(*args)`` at absolute time ``t`` ns with ``priority``; returns the cancellable :class:`Call`."""
        if t < self.now:
            raise ValueError(f"call_at: time {t} ns is before now ({self.now} ns)")
        call = Call(fn, args)
        heappush(self._queue, (t, priority, next(self._eid), (_fire, call)))
        return call

    def call_later(self, delay: int, fn: Callable[..., None], *args: Any, priority: int = NORMAL) -> Call:
        """Call ``fn(*args)`` ``delay`` ns from now (0: later in this instant); returns the :class:`Call`."""
        if delay < 0:
            raise ValueError(f"negative delay {delay} ns")
        call = Call(fn, args)
        heappush(self._queue, (self.now + delay, priority, next(self._eid), (_fire, call)))
        return call

    def event_at(self, delay: int, priority: int, value: Any = None) -> simpy.Event:
        """A simpy event, already triggered with ``value``, processed ``delay`` ns from now at ``priority``.

        Like ``timeout(delay, value)`` (which is always NORMAL), at another row of the same-instant table.
        """
        ev = simpy.Event(self)
        ev._ok = True
        ev._value = value
        self.schedule(ev, priority, delay)
        return ev

    def advance_if_next(self, t: int, priority: int = NORMAL) -> bool:
        """Move the clock to ``t`` if an entry ``(t, priority)`` scheduled now would be the next one processed.

        For a call item that would schedule its own continuation as the very last thing it does: when nothing
        else is due before that continuation (no entry before ``t``, none at ``t`` with a priority up to
        ``priority``, and ``t`` within the running :meth:`run_until`), the caller sets the clock here and goes
        on at once, which is what the loop would do after a push and a pop. Outside :meth:`run_until` it
        returns False (simpy's ``step`` processes one entry per call). Returns whether the clock moved.
        """
        if t > self.horizon or t < self.now:
            return False
        queue = self._queue
        if queue:
            head = queue[0]
            if head[0] < t or (head[0] == t and head[1] <= priority):
                return False
        self.now = t
        return True

    def events_scheduled(self) -> int:
        """How many entries (events and call items) have been scheduled so far."""
        return int(repr(self._eid)[6:-1])  # itertools.count's repr is "count(n)"

    def step(self) -> None:
        """Process the next entry, a call item or a simpy event (simpy's extension point; :meth:`run` uses it).

        Raises
        ------
        simpy.core.EmptySchedule
            When nothing is scheduled.
        """
        try:
            self.now, _, _, item = heappop(self._queue)
        except IndexError:
            raise EmptySchedule from None
        if item.__class__ is tuple:
            item[0](item)
            return
        callbacks, item.callbacks = item.callbacks, None
        for i, callback in enumerate(callbacks):
            try:
                callback(item)
            except StopSimulation:
                # as simpy: the remaining callbacks run when the simulation resumes
                item.callbacks = callbacks[i + 1:]
                self.schedule(item, URGENT - 1)
                raise
        if not item._ok and not hasattr(item, "_defused"):
            raise item._value

    def run_until(self, t_end: int) -> None:
        """Process every entry up to and including ``t_end`` ns (netsim's fast loop; the clock stays at the
        last entry processed)."""
        queue = self._queue
        until = int(t_end) + 1
        pop = heappop
        self.horizon = until - 1
        try:
            while queue:
                entry = queue[0]
                if entry[0] >= until:
                    break
                pop(queue)
                self.now = entry[0]
                item = entry[3]
                if item.__class__ is tuple:  # a call item
                    item[0](item)
                    continue
                # a simpy event: step(), inlined
                callbacks, item.callbacks = item.callbacks, None
                for callback in callbacks:
                    callback(item)
                if not item._ok and not hasattr(item, "_defused"):
                    raise item._value
        finally:
            self.horizon = -1


def schedule_call(sim: EventLoop, delay: int, priority: int, fn: Callable[[Any], None],
                  arg: Any = None) -> CallItem:
    """Schedule ``fn(item)`` ``delay`` ns from now with ``priority``; returns the call item ``(fn, arg)``.

    Hot paths push the same entry inline with :meth:`EventLoop.scheduler`.
    """
    item = (fn, arg)
    heappush(sim._queue, (sim.now + delay, priority, next(sim._eid), item))
    return item


def run_events(sim: EventLoop, t_end: int) -> None:
    """Process every entry of ``sim`` up to and including ``t_end`` ns (:meth:`EventLoop.run_until`)."""
    sim.run_until(t_end)


def stream_seed(seed: int, name: str) -> np.random.SeedSequence:
    """Seed sequence of the stream ``name`` under the scenario ``seed`` (stable across runs and platforms)."""
    digest = hashlib.sha256(name.encode("utf-8")).digest()
    key = tuple(int.from_bytes(digest[i : i + 4], "little") for i in range(0, 16, 4))
    return np.random.SeedSequence(entropy=int(seed), spawn_key=key)


if TYPE_CHECKING:
    _SampleArray = array[Any]  # typeshed's array is generic; the runtime class is not subscriptable before 3.12
else:
    _SampleArray = array


class Samples(_SampleArray):
    """A typed array of samples (``array('q')`` times, ``array('d')`` values) that compares equal to a list of
    the same numbers, as the lists it replaces did."""

    __slots__ = ()

    def __eq__(self, other: object) -> bool:
        if isinstance(other, list):
            return len(self) == len(other) and all(a == b for a, b in zip(self, other))
        return bool(array.__eq__(self, other))

    __hash__ = None


@dataclass
class Recorder:
    """Time series recorded during a run, one list pair per signal name.

    ``record(name, t_ns, value)`` appends a sample; the results layer turns the samples into the wide
    ``signals.csv`` table (time first, one column per signal). Values are floats; a vector value is
    recorded as ``name[0]``, ``name[1]`` .... Samples are kept in typed arrays (``array('q')`` times,
    ``array('d')`` values: 16 bytes per sample against about 60 in lists of Python objects, issue 19's flat
    memory); they take ``append``, indexing and ``numpy.asarray`` as lists do.
    """

    enabled: set[str] | None = None  # None records everything
    times: dict[str, Samples] = field(default_factory=dict)
    values: dict[str, Samples] = field(default_factory=dict)

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
            ts = self.times[name] = Samples("q")
            self.values[name] = Samples("d")
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
    sim : EventLoop
        The event loop (a :class:`simpy.Environment`); ``sim.now`` is the time in nanoseconds.
    recorder : Recorder
        Recorded signals.
    """

    def __init__(self, seed: int = 0, record: set[str] | None = None) -> None:
        self.seed = int(seed)
        self.sim = EventLoop(0)
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
        """Run the event loop up to and including events at ``until_ns``, then call the finalizers.

        The clock ends at ``until_ns + 1``, where simpy's ``sim.run(until=until_ns + 1)`` leaves it.
        """
        sim = self.sim
        sim.run_until(int(until_ns))
        if sim.now <= until_ns:
            sim.now = int(until_ns) + 1
        self.finish(int(until_ns))

    def finish(self, until_ns: int) -> None:
        """Call the finalizers registered with :meth:`at_end` (after :meth:`run`, or after ``sim.run``)."""
        for fn in self._finalizers:
            fn(int(until_ns))
