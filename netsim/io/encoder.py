"""Incremental position encoders read by a fast ISR, with exact or polled edge detection.

The encoder quantizes a plant output with step ``delta``: ``count = floor(y / delta)``. An interrupt service
routine samples it on the grid ``offset_ns + k * tick_ns`` (10 us on the cart of Henningsson & Cervin) and
stores the count, the direction of the last change and the time stamp of the tick at which it saw the change.
``on_edge(count, direction, stamp_ns)`` is called at that tick.

Rule for fast motion: if the count changed since the previous tick (possibly by several steps, or back and
forth), the ISR reports once, with the count **at the tick** (the last count) and ``direction = sign(new -
old)``; an excursion that returns to the old count between two ticks is not seen. Both modes follow it:

``polling``
    read the plant at every tick (a simpy process; the reference behaviour).
``exact``
    predict from the plant's known trajectory (closed-form LTI solution evaluated on the tick grid, or
    solve_ivp band-crossing events for nonlinear plants) the first tick at which the count differs, sleep
    until then, confirm on the plant and report; recompute whenever the plant's inputs change. Same
    ``(count, direction, stamp)`` sequence as polling with a small fraction of the events.

The position output should have no direct feedthrough (``D = 0``): at an instant where the input changes
on a tick, the two modes may otherwise read the output before or after the change.

With process noise the noise enters at the plant's propagation instants, which differ between the two modes
(polling propagates at every tick), so the modes then agree in distribution, not sample by sample.
"""

from __future__ import annotations

import math
from heapq import heappush
from typing import TYPE_CHECKING, Any, Callable

from netsim.env import NORMAL
from netsim.errors import ConfigError

if TYPE_CHECKING:
    from netsim.env import SimEnv

__all__ = ["Encoder", "encoder_step"]

EdgeCallback = Callable[[int, int, int], object]  # what it returns is ignored


def encoder_step(base_step: float, q: int = 0) -> float:
    """Quantization step after dropping ``q`` low bits of an encoder with resolution ``base_step``
    (``base_step * 2**q``; the cart's 5e-5 m with q = 6 gives 3.2 mm)."""
    if q < 0:
        raise ConfigError(f"encoder q must be >= 0, got {q}")
    return float(base_step) * 2**int(q)


class Encoder:
    """A quantized position sensor whose edges are time-stamped on an ISR tick grid.

    Parameters
    ----------
    plant
        The plant (any :class:`~netsim.plant.Plant`; exact mode needs ``predict_exit``).
    output
        Output index or name holding the position.
    step
        Quantization step (before dropping ``q`` bits).
    tick_ns
        ISR sampling period in nanoseconds.
    mode
        ``"exact"`` or ``"polling"``.
    q
        Low bits dropped: the effective step is ``step * 2**q``.
    offset_ns
        Phase of the tick grid.
    name
        Used for the recorded signal ``<name>.count`` (with ``record=True``).
    horizon_ticks
        Exact mode: ticks predicted per look-ahead.

    Attributes
    ----------
    count, direction, stamp_ns
        What the ISR holds: last count, direction of the last change (+1/-1, 0 before any), its tick.
    edges
        Number of ``on_edge`` calls so far.
    """

    def __init__(
        self,
        plant: Any,
        output: int | str,
        *,
        step: float,
        tick_ns: int,
        mode: str = "exact",
        q: int = 0,
        offset_ns: int = 0,
        name: str = "encoder",
        horizon_ticks: int = 4096,
        record: bool = False,
    ) -> None:
        if not (step > 0 and math.isfinite(step)):
            raise ConfigError(f"encoder {name}: step must be positive, got {step}")
        if int(tick_ns) <= 0:
            raise ConfigError(f"encoder {name}: tick must be positive, got {tick_ns}")
        if mode not in ("exact", "polling"):
            raise ConfigError(f"encoder {name}: mode must be 'exact' or 'polling', got {mode!r}")
        if mode == "exact" and not hasattr(plant, "predict_exit"):
            raise ConfigError(f"encoder {name}: plant {plant.name} cannot predict edges; use mode: polling")
        if horizon_ticks < 1:
            raise ConfigError(f"encoder {name}: horizon_ticks must be >= 1")
        self.plant = plant
        self.output = plant.output_index(output)
        self.delta = encoder_step(step, q)
        self.tick_ns = int(tick_ns)
        self.offset_ns = int(offset_ns)
        self.mode = mode
        self.name = name
        self.horizon_ticks = int(horizon_ticks)
        self.record = record
        self.count = 0
        self.direction = 0
        self.stamp_ns = -1
        self.edges = 0
        self.wakeups = 0
        self.env: Any = None
        self._on_edge: EdgeCallback | None = None
        self._sim: Any = None
        self._heap: list = []  # the event loop's heap and id counter (netsim.env: EventLoop.scheduler)
        self._ids: Any = None
        self._pending: tuple | None = None  # the call item of the live wake-up (older ones are skipped)
        self._next_tick = 0
        self._cand: int | None = None
        self._examined = 0
        self._wake_at = -1  # the time of the live wake-up's heap entry
        self._wake_id = -1  # the id an entry pushed by the latest prediction would have (see _predict)
        self._entry_id = -1  # the id of the live wake-up's heap entry
        self._busy = False

    # ---------------------------------------------------------------- helpers
    def _first_tick_after(self, t: int) -> int:
        k = (t - self.offset_ns) // self.tick_ns + 1
        return self.offset_ns + k * self.tick_ns

    def _quantize(self, t: int) -> int:
        return math.floor(self.plant.output_value(self.output, t) / self.delta)

    def read(self, t_ns: int | None = None) -> float:
        """The position the ISR holds: ``count * delta`` (``t_ns`` unused; for analog_in compatibility)."""
        return self.count * self.delta

    def _report(self, count: int, t: int) -> None:
        self.direction = 1 if count > self.count else -1
        self.count = count
        self.stamp_ns = t
        self.edges += 1
        if self.record:
            self.env.record(f"{self.name}.count", count, t)
        if self._on_edge is not None:
            self._on_edge(count, self.direction, t)

    # ---------------------------------------------------------------- life cycle
    def start(self, env: SimEnv, on_edge: EdgeCallback | None = None) -> "Encoder":
        """Read the initial count now and start detecting edges; ``on_edge(count, direction, stamp_ns)``."""
        self.env = env
        self._sim = env.sim
        _, self._heap, self._ids = env.sim.scheduler()
        self._on_edge = on_edge
        now = int(env.now)
        self.count = self._quantize(now)
        if self.record:
            env.record(f"{self.name}.count", self.count, now)
        self._next_tick = self._first_tick_after(now)
        if self.mode == "polling":
            env.process(self._poll())
        else:
            self.plant.on_input_change(self._changed)
            self._predict()
        return self

    def _poll(self) -> Any:
        env = self.env
        t = self._next_tick
        while True:
            yield env.timeout(t - env.now)
            self.wakeups += 1
            c = self._quantize(t)
            if c != self.count:
                self._report(c, t)
            t += self.tick_ns

    def _predict(self) -> None:
        """Predict the next edge from the plant's state, which is at the current time (its callers see to it),
        and make sure a wake-up is due then."""
        now = self._sim.now
        cand, examined, wake = self.plant.predict_exit(
            self.output, self.delta, self.count, self._next_tick, self.tick_ns, self.horizon_ticks
        )
        self._cand, self._examined = cand, examined
        at = cand if cand is not None else wake
        if at < now:
            at = now
        # one call item per prediction (netsim.env), pushed with the (time, priority, id) a simpy timeout got, so
        # the same order; a superseded wake-up is told by identity and skipped
        self._wake_id = rid = next(self._ids)
        if at == self._wake_at and at > now and self._pending is not None:
            # the live entry is due at this very instant (most re-predictions after an input change find the
            # same tick): keep it; it stands for an entry (at, NORMAL, rid) and takes that place when it fires
            return
        self._wake_at = at
        self._entry_id = rid
        self._pending = item = (_wake, self)
        heappush(self._heap, (at, NORMAL, rid, item))

    def _wake(self) -> None:
        self.wakeups += 1
        now = self._sim.now
        self._busy = True
        try:
            if self._cand is not None and now == self._cand:
                c = self._quantize(now)
                self._next_tick = now + self.tick_ns
                if c != self.count:
                    self._report(c, now)
            else:
                self.plant.advance_to(now)
                self._next_tick = max(self._next_tick, self._examined + self.tick_ns)
        finally:
            self._busy = False
        self._predict()

    def _changed(self, t: int) -> None:
        if self._busy or self.env is None:
            return  # the running wake-up predicts again when it is done
        now = self._sim.now
        if self._wake_at <= now:
            return  # a wake-up at this instant is pending and will predict with the new inputs
        self._next_tick = self.offset_ns + ((now - self.offset_ns) // self.tick_ns + 1) * self.tick_ns
        if t != now:  # the plant notifies at its own time t: bring it to now (an input change at now is there)
            self._busy = True  # a noisy advance notifies listeners: do not re-enter
            try:
                self.plant.advance_to(now)
            finally:
                self._busy = False
        self._predict()


def _wake(item: tuple[Any, Encoder]) -> None:
    """The exact encoder's wake-up (a call item ``(_wake, encoder)``); a superseded one does nothing.

    A kept entry (see :meth:`Encoder._predict`) has an older id than the prediction it serves: when an entry
    due now at NORMAL priority lies between the two ids (the heap's head, since this entry came first), it
    is pushed again with the prediction's id and runs after that entry, as the entry of the prediction would;
    otherwise nothing can run in between and it runs now.
    """
    enc = item[1]
    if item is not enc._pending:
        return
    rid = enc._wake_id
    if enc._entry_id != rid:
        queue = enc._heap
        if queue:
            head = queue[0]
            if head[0] == enc._sim.now and head[1] == NORMAL and head[2] < rid:
                enc._entry_id = rid
                heappush(queue, (head[0], NORMAL, rid, item))
                return
    enc._wake()
