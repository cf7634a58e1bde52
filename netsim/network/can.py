"""CAN (TrueTime's CSMA/AMP): a shared bus with non-destructive arbitration on message priority.

When the bus is idle, every node offers the head of its sender queue at the end of the instant and the frame
with the lowest priority number wins (equal priorities: the one queued first, then node order). A frame,
once started, is never preempted. The next arbitration happens when the bus goes idle again, among the
frames queued by then (including those queued in that very instant).

The winner is the least ``(priority, order)`` among the heads of the sender queues (``order`` is unique, so
there are no ties). The bus keeps the heads in one heap of candidates instead of visiting every node at each
arbitration: a frame enters it when it becomes the head of its queue (queued into an empty queue, or ahead of
the head of a priority queue, or left at the head when the winner is taken); an entry whose frame is no
longer a head is dropped when it comes to the top. So an arbitration costs O(log n) whatever the number of
nodes, not O(nodes) (CAN at 50 nodes ran at half the messages per second of 10 nodes).

Frame sizes:

``frame_format: raw`` (default, TrueTime)
    ``bits`` is the whole frame; it is padded to ``min_frame_bits``. ``bit_stuffing`` adds the worst case
    ``floor((n - 1) / 4)`` stuff bits for an n-bit frame.
``standard`` / ``extended``
    ``bits`` is the data field (at most 64 bits, rounded up to whole bytes); the 47 / 67 bits of CAN 2.0A /
    2.0B overhead are added, and with ``bit_stuffing`` the worst case ``floor((34 + 8s - 1) / 4)`` /
    ``floor((54 + 8s - 1) / 4)`` stuff bits for ``s`` data bytes (Davis et al., 2007).
"""

from __future__ import annotations

from heapq import heappop, heappush
from typing import Literal

from pydantic import model_validator

from netsim.env import ARBITRATE
from netsim.network.message import Message
from netsim.network.params import NetworkParams
from netsim.network.pipeline import Frame, Network
from netsim.network.queues import QueueDiscipline
from netsim.network.stats import BusyMeter
from netsim.network.timing import call_later
from netsim.registry import register

__all__ = ["CanBus", "can_frame_bits"]

_OVERHEAD = {"standard": (47, 34), "extended": (67, 54)}


def can_frame_bits(data_bits: int, frame_format: str = "standard", bit_stuffing: bool = True) -> int:
    """Bits on the wire of a CAN frame carrying ``data_bits`` of data (worst-case stuffing if asked).

    >>> can_frame_bits(64)   # 8 data bytes, standard identifier: 135 bits worst case
    135
    """
    s = -(-data_bits // 8)
    overhead, stuffable = _OVERHEAD[frame_format]
    n = overhead + 8 * s
    if bit_stuffing:
        n += (stuffable + 8 * s - 1) // 4
    return n


@register("network", "can", "CAN bus (CSMA/AMP): priority arbitration, non-preemptive frames")
class CanBus(Network["CanBus.Params"]):
    """A CAN bus (see the module docstring)."""

    class Params(NetworkParams):
        """CAN parameters: the common ones plus the frame format and bit stuffing.

        The sender queues default to priority order (a CAN controller offers its most urgent frame).
        """

        queue_discipline: QueueDiscipline = "priority"
        frame_format: Literal["raw", "standard", "extended"] = "raw"
        bit_stuffing: bool = False

        @model_validator(mode="after")
        def _check_format(self) -> "CanBus.Params":
            if self.frame_format != "raw" and self.max_frame_bits is not None and self.max_frame_bits > 64:
                raise ValueError("max_frame_bits: a CAN data field holds at most 64 bits")
            return self

    def _setup(self) -> None:
        self._meter = self.meters["bus"] = BusyMeter(self.params.utilization_bin)
        self._busy = False
        self._arb_pending = False
        self._cands: list[tuple[int, int, str]] = []  # (priority, order, sender): heads of queues, maybe stale
        self._queued = 0  # frames waiting in all sender queues

    def wire_bits(self, msg: Message) -> int:
        p = self.params
        if p.frame_format == "raw":
            n = super().wire_bits(msg)
            if p.bit_stuffing and n > 0:
                n += (n - 1) // 4
            return n
        limit = min(64, p.max_frame_bits or 64)
        if msg.bits > limit:
            self._too_large(msg, limit, "max_frame_bits" if p.max_frame_bits else "frame_format")
        return max(can_frame_bits(msg.bits, p.frame_format, p.bit_stuffing), p.min_frame_bits)

    def _offer(self, frame: Frame) -> None:
        q = self.queues[frame.sender]
        if self._push(q, frame):
            self._queued += 1
            if q.peek() is frame:  # the new head of its queue: a candidate
                heappush(self._cands, (frame.priority, frame.order, frame.sender))
            self._request_arbitration()

    def _halted(self, node: str, dropped: int) -> None:
        self._queued -= dropped  # their candidate entries are stale now: dropped when they come to the top

    def _request_arbitration(self) -> None:
        if not self._busy and not self._arb_pending:
            self._arb_pending = True
            call_later(self.sim, 0, self._arbitrate, None, priority=ARBITRATE)

    def _arbitrate(self, _: object) -> None:
        self._arb_pending = False
        if self._busy:
            return
        cands = self._cands
        queues = self.queues
        while cands:
            _, order, sender = cands[0]
            q = queues[sender]
            if q._len:
                best = q.peek()
                if best.order == order:  # orders are unique: this entry is the head of its queue
                    break
            heappop(cands)  # no longer the head of its queue (sent, or overtaken in a priority queue)
        else:
            return
        heappop(cands)
        now = self.sim.now
        q.pop(now)
        self._queued -= 1
        if q._len:
            head = q.peek()
            heappush(cands, (head.priority, head.order, head.sender))
        self._busy = True
        best.tx_start_ns = now
        self._meter.start(now)
        call_later(self.sim, best.tx_ns, self._done, best)

    def _done(self, frame: Frame) -> None:
        now = self.sim.now
        self._meter.stop(now)
        self._busy = False
        start = frame.tx_start_ns
        self._transmitted(frame, now if start is None else start, now)
        if self._queued:
            self._request_arbitration()
