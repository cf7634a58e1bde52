"""A custom network medium: a shared bus on which every frame takes one fixed time slot.

Slots start on a grid (``0, slot, 2 slot, ...``); a frame offered mid-slot waits for the next slot boundary,
and frames from all senders take the slots in the order they were offered (one FIFO for the whole bus). Loss,
interface delays, queue limits and the message records come from netsim's shared pipeline
(:class:`netsim.network.pipeline.Network`): a medium only decides *when* each frame occupies the wire.

Load it from a scenario with ``plugins: [slotted_bus.py]`` and ``networks: {bus: {type: slotted_bus, ...}}``
(run with ``--allow-plugins``).
"""

from __future__ import annotations

from collections import deque

from netsim.network.params import NetworkParams
from netsim.network.pipeline import Frame, Network
from netsim.network.stats import BusyMeter
from netsim.registry import register
from netsim.units import Bitrate, Duration

MS = 1_000_000  # ns


@register("network", "slotted_bus", "shared bus: one frame per fixed time slot, slots on a grid (example plugin)")
class SlottedBus(Network):
    """One frame per slot, FIFO over all senders (see the module docstring)."""

    class Params(NetworkParams):
        """The common network parameters, a ``slot`` length, and no bit rate (the slot sets the timing)."""

        bitrate: Bitrate | None = None  # type: ignore[assignment]
        slot: Duration = 1 * MS

    def _setup(self) -> None:
        self._meter = self.meters["bus"] = BusyMeter(self.params.utilization_bin)
        self._turns: deque[str] = deque()  # one entry per queued frame: its sender, in the order offered
        self._busy_until = 0

    def _frame_time(self, wire_bits: int, sender: str) -> int:
        return self.params.slot

    def _offer(self, frame: Frame) -> None:
        if self._push(self.queues[frame.sender], frame):  # the sender's bounded queue (queue_limit)
            self._turns.append(frame.sender)
            if len(self._turns) == 1:
                self._next_slot()

    def _next_slot(self) -> None:
        slot, now = self.params.slot, self.sim.now
        start = max(now, self._busy_until)
        start = -(-start // slot) * slot  # the next slot boundary at or after start
        self.sim.call_later(start - now, self._start, self._turns[0])

    def _start(self, sender: str) -> None:
        frame = self.queues[sender].pop(self.sim.now)  # that sender's next frame (fifo or priority)
        start, end = self.sim.now, self.sim.now + self.params.slot
        self._busy_until = end
        self._meter.add(start, end)
        self.sim.call_later(end - start, self._end, frame, start)

    def _end(self, frame: Frame, start: int) -> None:
        self._turns.popleft()
        self._transmitted(frame, start, self.sim.now)  # loss, receiver delay, delivery and records
        if self._turns:
            self._next_slot()
