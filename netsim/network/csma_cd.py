"""CSMA/CD (e.g. classic Ethernet): carrier sense, collision detection, binary exponential backoff.

A node with a frame senses the medium: if it is busy the node waits until it is free (1-persistent). Nodes
that start within ``collision_window`` of each other (TrueTime: 1 us, the propagation time of a 200 m cable)
collide: the medium is occupied until ``collision_window`` after the first start, then each colliding node
waits ``R * min_frame_bits / bitrate`` with ``R`` uniform in ``0 .. 2**K - 1`` (``K`` = collisions of that
frame so far, at most ``max_backoff_exponent``; stream ``network.<name>.backoff``) and tries again. Nodes that
were waiting for the medium start together when it goes idle, so they collide first (TrueTime's model).
There is no limit on retries unless ``max_attempts`` is set (then the frame is dropped as ``collisions``).
"""

from __future__ import annotations

from typing import Any

from pydantic import Field

from netsim.env import ARBITRATE
from netsim.network.params import NetworkParams
from netsim.network.pipeline import Frame, Network
from netsim.network.records import (DROP_COLLISIONS, DROP_LOST, DROP_NO_RECEIVER, DROP_QUEUE_FULL, DROP_SENDER_DEAD,
                                     DROP_STALE)
from netsim.network.stats import BusyMeter
from netsim.network.timing import Call, call_later, tx_time_ns
from netsim.registry import register
from netsim.timebase import US
from netsim.units import Time

__all__ = ["CsmaCdBus"]


@register("network", "csma_cd", "CSMA/CD (shared Ethernet): collisions and binary exponential backoff")
class CsmaCdBus(Network["CsmaCdBus.Params"]):
    """A CSMA/CD medium (see the module docstring)."""

    class Params(NetworkParams):
        """CSMA/CD parameters; ``min_frame_bits`` (> 0) also sets the backoff slot."""

        min_frame_bits: int = Field(512, gt=0)
        collision_window: Time = 1 * US
        max_backoff_exponent: int = Field(10, ge=0, le=30)
        max_attempts: int | None = Field(None, ge=1)

    drop_reasons = (DROP_QUEUE_FULL, DROP_LOST, DROP_STALE, DROP_NO_RECEIVER, DROP_COLLISIONS)

    def _setup(self) -> None:
        p = self.params
        self._meter = self.meters["bus"] = BusyMeter(p.utilization_bin)
        self._rng = self.env.rng(f"network.{self.name}.backoff")
        self._slot_ns = tx_time_ns(p.min_frame_bits, p.bitrate)
        self._window = int(p.collision_window)
        self._current: dict[str, Frame | None] = {n: None for n in self.nodes}
        self._ready: list[str] = []
        self._state = "idle"  # idle | tx | collision
        self._tx: tuple[str, Frame, int, Call] | None = None
        self._coll_nodes: list[str] = []
        self._pending = False
        self.collisions = 0
        self.backoffs = 0

    def _offer(self, frame: Frame) -> None:
        node = frame.sender
        if self._push(self.queues[node], frame) and self._current[node] is None:
            self._load(node)

    def _load(self, node: str) -> None:
        """Take ``node``'s next frame to the MAC (if any) and make the node contend."""
        q = self.queues[node]
        if len(q):
            self._current[node] = q.pop(self.sim.now)
            self._ready.append(node)
            self._request()

    def _request(self) -> None:
        if not self._pending:
            self._pending = True
            call_later(self.sim, 0, self._contend, None, priority=ARBITRATE)

    def _contend(self, _: Any) -> None:
        self._pending = False
        if not self._ready:
            return
        now = self.sim.now
        if self._state == "tx":
            assert self._tx is not None
            node, _frame, start, call = self._tx
            if now - start < self._window:  # started within the window of the transmission: collision
                call.cancel()
                self._tx = None
                self._collide(start, [node])
            return  # otherwise wait for the medium to go idle
        if self._state == "collision":
            self._coll_nodes.extend(self._ready)
            self._ready.clear()
            return
        if len(self._ready) == 1:
            node = self._ready.pop()
            frame = self._current[node]
            assert frame is not None
            self._state = "tx"
            self._meter.start(now)
            frame.tx_start_ns = now
            self._tx = (node, frame, now, call_later(self.sim, frame.tx_ns, self._tx_end, node))
        else:
            self._meter.start(now)
            self._collide(now, [])

    def _collide(self, start: int, nodes: list[str]) -> None:
        self.collisions += 1
        self._state = "collision"
        self._coll_nodes = nodes + self._ready
        self._ready = []
        call_later(self.sim, start + self._window - self.sim.now, self._collision_end, None)

    def _collision_end(self, _: Any) -> None:
        now = self.sim.now
        self._meter.stop(now)
        self._state = "idle"
        nodes, self._coll_nodes = self._coll_nodes, []
        p = self.params
        for node in nodes:
            frame = self._current[node]
            assert frame is not None
            frame.attempts += 1
            if p.max_attempts is not None and frame.attempts >= p.max_attempts:
                self._drop_frame(frame, DROP_COLLISIONS)
                self._current[node] = None
                self._load(node)
                continue
            k = min(frame.attempts, p.max_backoff_exponent)
            r = int(self._rng.integers(0, 1 << k))
            self.backoffs += 1
            call_later(self.sim, r * self._slot_ns, self._backoff_done, node)
        if self._ready:
            self._request()

    def _backoff_done(self, node: str) -> None:
        if node in self._dead:  # the node halted while backing off: its frame does not go
            self._drop_current(node)
            return
        self._ready.append(node)
        self._request()

    def _halted(self, node: str, dropped: int) -> None:
        if node in self._ready:  # waiting for the next contention, not on the wire: dropped
            self._ready.remove(node)
            self._drop_current(node)
        # a frame on the wire finishes; one in a collision or backing off is dropped when its backoff ends

    def _drop_current(self, node: str) -> None:
        frame = self._current[node]
        if frame is not None:
            self._drop_frame(frame, DROP_SENDER_DEAD)
            self._current[node] = None

    def _tx_end(self, node: str) -> None:
        now = self.sim.now
        assert self._tx is not None
        _, frame, start, _call = self._tx
        self._tx = None
        self._meter.stop(now)
        self._state = "idle"
        self._current[node] = None
        self._transmitted(frame, start, now)
        self._load(node)
        if self._ready:
            self._request()

    def _extra_metrics(self, t_end_ns: int) -> dict[str, float]:
        return {"collisions": float(self.collisions), "backoffs": float(self.backoffs)}
