"""Switched Ethernet: full-duplex links to one store-and-forward switch with finite memory.

Each node has its own uplink to the switch and downlink from it (never any collision). A frame crosses the
sender's uplink (queued in the node's sender queue), is stored in the switch once fully received, waits
``switch_delay``, and is forwarded in FIFO order on the downlink of each receiver (one copy per receiver of
a broadcast). A copy holds ``wire_bits`` of switch memory from its arrival in the switch until it has left
on its downlink.

``switch_buffer``: ``common`` (all ports share ``switch_memory_bits``) or ``per_output`` (each output port
has ``switch_memory_bits / len(nodes)``). When a fully received copy does not fit, ``overflow`` decides:
``drop`` (reason ``switch_full``) or ``retransmit`` (the switch tells the sender, which sends it again:
it goes back to the head of the sender's queue).
"""

from __future__ import annotations

from heapq import heappush
from typing import Any, Literal

from pydantic import Field

from netsim.env import NORMAL
from netsim.network.params import NetworkParams
from netsim.network.pipeline import Copy, Frame, Network, Transmitter
from netsim.network.queues import SendQueue
from netsim.network.records import DROP_LOST, DROP_NO_RECEIVER, DROP_QUEUE_FULL, DROP_STALE, DROP_SWITCH_FULL
from netsim.network.stats import BusyMeter
from netsim.registry import register
from netsim.units import Time

__all__ = ["SwitchedEthernet"]


@register("network", "ethernet", "switched Ethernet: full duplex, store-and-forward switch with finite memory")
@register("network", "switched_ethernet", "switched Ethernet (same as 'ethernet')")
class SwitchedEthernet(Network["SwitchedEthernet.Params"]):
    """A switched Ethernet (see the module docstring)."""

    class Params(NetworkParams):
        """Switched Ethernet parameters: the common ones (Ethernet frame limits) plus the switch's."""

        min_frame_bits: int = Field(512, ge=0)
        max_frame_bits: int | None = Field(12144, gt=0)
        switch_memory_bits: int | None = Field(8_000_000, gt=0)
        switch_buffer: Literal["common", "per_output"] = "common"
        overflow: Literal["drop", "retransmit"] = "drop"
        switch_delay: Time = 0

    drop_reasons = (DROP_QUEUE_FULL, DROP_LOST, DROP_STALE, DROP_NO_RECEIVER, DROP_SWITCH_FULL)
    utilization_mode = "max"

    def _setup(self) -> None:
        p = self.params
        self._up: dict[str, Transmitter] = {}
        self._down: dict[str, Transmitter] = {}
        self.port_queues: dict[str, SendQueue] = {}
        for n in self.nodes:
            # a frame received by the switch is stored at once, or after the switch delay
            stored = self._at_switch if p.switch_delay else self._store
            self._up[n] = Transmitter(self, self.queues[n], p.bitrate, self._meter(f"up.{n}"), stored)
            q = self.port_queues[n] = SendQueue(None, "fifo")
            self._down[n] = Transmitter(self, q, p.bitrate, self._meter(f"down.{n}"), self._left_switch)
        mem = p.switch_memory_bits
        self._common = p.switch_buffer == "common"
        self._cap_total = mem
        self._cap_port = None if mem is None else mem // len(self.nodes)
        self._used = 0
        self._used_port = {n: 0 for n in self.nodes}
        self.memory_max = 0
        self.retransmissions = 0
        self._switch_delay = p.switch_delay

    def _meter(self, name: str) -> BusyMeter:
        m = self.meters[name] = BusyMeter(self.params.utilization_bin)
        return m

    def _offer(self, frame: Frame) -> None:
        self._up[frame.sender].offer(frame)

    def _at_switch(self, frame: Frame, start: int, end: int) -> None:
        """``frame`` is in the switch (with a switch delay): it is stored when the delay is over."""
        if frame.tx_start_ns is None:
            frame.tx_start_ns = start
        heappush(self._heap, (end + self._switch_delay, NORMAL, next(self._ids), (self._after_delay, frame)))

    def _after_delay(self, item: tuple[Any, Frame]) -> None:
        """The call item ``(fn, frame)`` of the end of a switch delay."""
        self._store(item[1])

    def _store(self, frame: Frame, start: int = -1, end: int = -1) -> None:
        """Store ``frame`` in the switch and forward it to its output ports (``start``: when its uplink
        transmission began, if the uplink hands it over directly)."""
        if start >= 0 and frame.tx_start_ns is None:
            frame.tx_start_ns = start
        bits = frame.wire_bits
        copies = frame.copies
        failed: list[Copy] = []
        unicast = len(copies) == 1
        cap = self._cap_total
        used_port = self._used_port
        for copy in copies:
            port = copy[0].receiver
            assert port is not None
            # does the frame fit the switch memory (common, or this output's share)?
            if cap is not None and (self._used + bits > cap if self._common
                                    else used_port[port] + bits > (self._cap_port or 0)):
                failed.append(copy)
                continue
            used = self._used = self._used + bits
            used_port[port] += bits
            if used > self.memory_max:
                self.memory_max = used
            # a unicast frame goes on as it is (it carries exactly this copy); a broadcast is split per port
            cf = frame if unicast else Frame(copy[0], [copy], frame.sender, frame.priority, bits, frame.tx_ns,
                                             frame.order, tx_start_ns=frame.tx_start_ns)
            self._down[port].offer(cf)
        if not failed:
            return
        if self.params.overflow == "drop":
            for copy in failed:
                self._drop_copy(copy, DROP_SWITCH_FULL)
            return
        self.retransmissions += 1
        again = Frame(frame.msg, failed, frame.sender, frame.priority, bits, frame.tx_ns, frame.order,
                      tx_start_ns=frame.tx_start_ns)
        self._up[frame.sender].offer(again, front=True)

    def _left_switch(self, frame: Frame, start: int, end: int) -> None:
        port = frame.copies[0][0].receiver
        self._used -= frame.wire_bits
        self._used_port[port] -= frame.wire_bits  # type: ignore[index]
        first = frame.tx_start_ns
        self._transmitted(frame, start if first is None else first, end)

    def _extra_metrics(self, t_end_ns: int) -> dict[str, Any]:
        out: dict[str, Any] = {
            "switch_memory_max_bits": float(self.memory_max),
            "retransmissions": float(self.retransmissions),
        }
        for n, q in self.port_queues.items():
            out[f"switch_queue_max.{n}"] = float(q.max_len)
        return out
