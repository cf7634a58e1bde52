"""TDMA (e.g. TTP): a cyclic schedule of slots, each owned by one node (or idle).

A node sends only inside its own slots, with the whole bandwidth. A frame that does not fit in what is left
of the slot is continued in the node's next slot, with no extra cost (TrueTime); several frames may follow
each other in one slot. At each slot start the node picks the next frame from its queue at the end of the
instant, so frames queued exactly at the slot start take part.

``slot`` (a time) or ``slot_bits`` (slot time = ``slot_bits / bitrate``) sets the slot length; ``schedule``
lists the owner of each slot of the cycle by node name, ``null`` for an idle slot.
"""

from __future__ import annotations

from typing import Any, Generator

from pydantic import Field, model_validator

from netsim.errors import ConfigError
from netsim.network.message import Message
from netsim.network.params import NetworkParams
from netsim.network.pipeline import Frame, Network
from netsim.network.stats import BusyMeter
from netsim.network.timing import arbitration_event, tx_time_ns
from netsim.registry import register
from netsim.units import Duration

__all__ = ["TdmaBus"]


@register("network", "tdma", "TDMA: cyclic slot schedule, unfinished frames resume in the owner's next slot")
class TdmaBus(Network["TdmaBus.Params"]):
    """A TDMA medium (see the module docstring)."""

    class Params(NetworkParams):
        """TDMA parameters: the common ones plus ``slot`` or ``slot_bits`` and the ``schedule``."""

        slot: Duration | None = None
        slot_bits: int | None = Field(None, gt=0)
        schedule: list[str | None] = Field(min_length=1)

        @model_validator(mode="after")
        def _check_schedule(self) -> "TdmaBus.Params":
            if (self.slot is None) == (self.slot_bits is None):
                raise ValueError("give exactly one of slot (a time) or slot_bits")
            for i, owner in enumerate(self.schedule):
                if owner not in (None, "") and owner not in self.nodes:
                    raise ValueError(
                        f"schedule[{i}] names '{owner}', which is not one of the network's nodes {self.nodes}"
                    )
            return self

    utilization_mode = "weighted"

    def _setup(self) -> None:
        p = self.params
        # one meter per owner (their busy times never overlap; the bus utilization is their sum)
        for n in self.nodes:
            self.meters[n] = BusyMeter(p.utilization_bin)
        self._slot = p.slot if p.slot is not None else tx_time_ns(p.slot_bits or 0, p.bitrate)
        self._cycle = self._slot * len(p.schedule)
        # owned windows of each node within one cycle, adjacent slots merged: [(start_offset, end_offset)]
        self._windows: dict[str, list[tuple[int, int]]] = {n: [] for n in self.nodes}
        for i, owner in enumerate(p.schedule):
            if owner in (None, ""):
                continue
            w = self._windows[owner]
            s, e = i * self._slot, (i + 1) * self._slot
            if w and w[-1][1] == s:
                w[-1] = (w[-1][0], e)
            else:
                w.append((s, e))
        self._wake: dict[str, Any] = {}
        for n in self.nodes:
            if self._windows[n]:
                self.env.process(self._run(n))

    def send(self, msg: Message) -> None:
        if msg.sender in self._windows and not self._windows[msg.sender]:
            raise ConfigError(
                f"network '{self.name}': '{msg.sender}' sends but owns no slot in the TDMA schedule; "
                f"add it to networks.{self.name}.schedule",
                path=f"networks.{self.name}.schedule",
            )
        super().send(msg)

    def window(self, node: str, t: int) -> tuple[int, int]:
        """The owned window of ``node`` containing ``t`` (clipped to start at ``t``) or the next one."""
        base = (t // self._cycle) * self._cycle
        windows = self._windows[node]
        for s, e in windows:
            if t < base + e:
                return max(base + s, t), base + e
        s, e = windows[0]
        base += self._cycle
        return base + s, base + e

    def _offer(self, frame: Frame) -> None:
        if self._push(self.queues[frame.sender], frame):
            ev = self._wake.pop(frame.sender, None)
            if ev is not None and not ev.triggered:
                ev.succeed()

    def _run(self, node: str) -> Generator[Any, Any, None]:
        sim = self.sim
        q = self.queues[node]
        meter = self.meters[node]
        while True:
            if not len(q):
                ev = self._wake[node] = sim.event()
                yield ev
            s, _ = self.window(node, sim.now)
            if s > sim.now:
                yield sim.timeout(s - sim.now)
            yield arbitration_event(sim)  # frames queued at this very instant compete
            if not len(q):
                continue
            frame = q.pop(sim.now)
            remaining = frame.tx_ns
            start: int | None = None
            while True:
                s, e = self.window(node, sim.now)
                if s > sim.now:
                    yield sim.timeout(s - sim.now)
                if start is None:
                    start = sim.now
                chunk = min(remaining, e - sim.now)
                meter.start(sim.now)
                yield sim.timeout(chunk)
                meter.stop(sim.now)
                remaining -= chunk
                if remaining <= 0:
                    break
            frame.tx_start_ns = start
            self._transmitted(frame, start, sim.now)

    def _extra_metrics(self, t_end_ns: int) -> dict[str, float]:
        owned = sum(1 for o in self.params.schedule if o not in (None, ""))
        return {"schedule_share": owned / len(self.params.schedule)}
