"""Round robin (token bus): the nodes take turns, in the order of ``nodes``, to send one frame each.

Passing the token to the next node takes ``token_pass`` (default TrueTime's ``min_frame_bits / bitrate``);
the medium is idle meanwhile. The token keeps circulating when nobody has anything to send; the model
computes where it is instead of simulating every pass, so an idle network costs no events. A node whose
turn comes with an empty queue passes the token on.
"""

from __future__ import annotations

from typing import Any

from netsim.env import ARBITRATE
from netsim.network.params import NetworkParams
from netsim.network.pipeline import Frame, Network
from netsim.network.stats import BusyMeter
from netsim.network.timing import Call, call_later, tx_time_ns
from netsim.registry import register
from netsim.units import Time

__all__ = ["RoundRobinBus"]


@register("network", "round_robin", "round robin (token bus): one frame per node per turn")
class RoundRobinBus(Network["RoundRobinBus.Params"]):
    """A token-passing medium (see the module docstring)."""

    class Params(NetworkParams):
        """Round-robin parameters: the common ones plus ``token_pass`` (None: ``min_frame_bits / bitrate``)."""

        token_pass: Time | None = None

    def _setup(self) -> None:
        p = self.params
        self._meter = self.meters["bus"] = BusyMeter(p.utilization_bin)
        self._pass = p.token_pass if p.token_pass is not None else tx_time_ns(p.min_frame_bits, p.bitrate)
        self._n = len(self.nodes)
        # the token is at node index _ref_pos at time _ref_t and moves on every _pass
        self._ref_t = 0
        self._ref_pos = 0
        self._busy = False
        self._next: tuple[tuple[int, int], Call] | None = None

    def visit_time(self, j: int, t: int) -> int:
        """First time at or after ``t`` the token reaches node index ``j`` (if nobody sends meanwhile)."""
        d = (j - self._ref_pos) % self._n
        first = self._ref_t + d * self._pass
        if first >= t:
            return first
        if self._pass == 0:
            return t
        cycle = self._n * self._pass
        return first + -(-(t - first) // cycle) * cycle

    def _offer(self, frame: Frame) -> None:
        if self._push(self.queues[frame.sender], frame):
            self._schedule()

    def _schedule(self) -> None:
        if self._busy:
            return
        now = self.sim.now
        best: tuple[int, int] | None = None
        best_j = -1
        for j, node in enumerate(self.nodes):
            if len(self.queues[node]):
                key = (self.visit_time(j, now), (j - self._ref_pos) % self._n)
                if best is None or key < best:
                    best, best_j = key, j
        if best is None:
            return
        if self._next is not None:
            if self._next[0] <= best:
                return
            self._next[1].cancel()
        self._next = (best, call_later(self.sim, best[0] - now, self._visit, best_j, priority=ARBITRATE))

    def _visit(self, j: int) -> None:
        self._next = None
        q = self.queues[self.nodes[j]]
        if self._busy:
            return
        if not len(q):
            self._schedule()
            return
        now = self.sim.now
        frame = q.pop(now)
        self._busy = True
        frame.tx_start_ns = now
        self._meter.start(now)
        call_later(self.sim, frame.tx_ns, self._done, (frame, j))

    def _done(self, arg: Any) -> None:
        frame, j = arg
        now = self.sim.now
        self._meter.stop(now)
        self._busy = False
        self._ref_t = now + self._pass
        self._ref_pos = (j + 1) % self._n
        self._transmitted(frame, frame.tx_start_ns, now)
        self._schedule()
