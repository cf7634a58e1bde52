"""Simple links for studies that need no MAC model: delay distributions, loss, optional reordering.

A link gives every node its own output. With a ``bitrate`` the output serializes frames (queue, then
``max(bits, min_frame_bits) / bitrate`` each: a single-server queue per sender); without one, sending takes
no time. Each copy then travels for a delay drawn from ``delay`` (stream ``network.<name>.delay``) and is lost
per the loss model. Unless ``reorder`` is true, copies between the same two nodes keep their order (a copy
never overtakes an earlier one: it arrives at ``max(own arrival, previous arrival)``). Receivers can discard
stale copies (``drop_stale``) when reordering is on.

The type ``ideal`` is the same class with its defaults: no delay, no loss, no bit rate.
"""

from __future__ import annotations

from heapq import heappush

from pydantic import Field

from netsim.env import NORMAL
from netsim.network.delay import ConstantDelay, DelaySpec, make_delay_sampler
from netsim.network.params import NetworkParams
from netsim.network.pipeline import Frame, Network, Transmitter
from netsim.network.records import DROP_LOST
from netsim.network.stats import BusyMeter
from netsim.network.timing import tx_time_ns
from netsim.registry import register
from netsim.units import Bitrate

__all__ = ["Link"]


@register("network", "link", "link with constant or random delay, Bernoulli/Gilbert-Elliott loss, reordering")
@register("network", "ideal", "ideal link: zero delay, no loss (a link with its defaults)")
class Link(Network["Link.Params"]):
    """A delay/loss link (see the module docstring)."""

    class Params(NetworkParams):
        """Link parameters: the common ones (``bitrate`` optional here) plus ``delay`` and ``reorder``."""

        bitrate: Bitrate | None = None  # type: ignore[assignment]
        delay: DelaySpec = Field(default_factory=ConstantDelay)
        reorder: bool = False

    utilization_mode = "max"

    def _setup(self) -> None:
        p = self.params
        self._rate = p.bitrate
        self._draw = make_delay_sampler(p.delay, self.env.rng(f"network.{self.name}.delay"))
        delay: object = p.delay  # (DelaySpec is an alias the checker cannot narrow; a plain object it can)
        self._constant = delay.value if isinstance(delay, ConstantDelay) else None
        self._reorder = bool(p.reorder)
        self._last_arrival: dict[tuple[str, str | None], int] = {}
        self._tx: dict[str, Transmitter] = {}
        if self._rate is not None:
            for n in self.nodes:
                m = self.meters[n] = BusyMeter(p.utilization_bin)
                self._tx[n] = Transmitter(self, self.queues[n], self._rate, m, self._sent)
        else:  # sending takes no time: a frame handed over is sent at once (one call fewer per frame)
            self._offer = self._sent  # type: ignore[method-assign]

    def _frame_time(self, wire_bits: int, sender: str) -> int:
        return 0 if self._rate is None else tx_time_ns(wire_bits, self._rate)

    def _offer(self, frame: Frame) -> None:
        # with a bit rate; without one, _setup makes _sent the offer itself
        self._tx[frame.sender].offer(frame)

    def _sent(self, frame: Frame, start: int = -1, end: int = -1) -> None:
        """``frame`` occupied the sender's output in ``[start, end]`` (no times: offered without a bit rate, sent
        now): loss draw, delay, and the delivery of each surviving copy pushed as a call item."""
        if start < 0:
            start = end = self.sim.now
        loss = self._loss
        post = self._post
        sender = frame.sender
        heap, ids, deliver = self._heap, self._ids, self._deliver_item  # deliveries pushed inline (netsim.env)
        constant = self._constant
        for copy in frame.copies:
            msg, rec = copy
            msg.tx_start_ns = rec.tx_start_ns = start
            msg.tx_end_ns = rec.tx_end_ns = end
            receiver = msg.receiver
            if loss is not None and loss.lost((sender, receiver)):  # type: ignore[arg-type]
                self._drop_copy(copy, DROP_LOST)
                continue
            arrival = end + (constant if constant is not None else self._draw())
            if not self._reorder and constant is None:
                key = (sender, receiver)
                last = self._last_arrival.get(key, 0)
                if arrival < last:
                    arrival = last
                self._last_arrival[key] = arrival
            heappush(heap, (arrival + post[receiver], NORMAL, next(ids), (deliver, copy)))  # type: ignore[index]
