"""FDMA: every node has its own share of the bandwidth; transmissions never interfere.

``shares`` gives each sender's fraction of ``bitrate`` (a mapping node -> share, or a list in the order of
``nodes``); they must sum to at most 1. Without ``shares`` the bandwidth is split equally. A node sends at
``share * bitrate``, one frame at a time from its queue. The network's utilization is the fraction of the
total bandwidth in use (shares weighted).
"""

from __future__ import annotations

from pydantic import model_validator

from netsim.errors import ConfigError
from netsim.network.message import Message
from netsim.network.params import NetworkParams
from netsim.network.pipeline import Frame, Network, Transmitter
from netsim.network.stats import BusyMeter
from netsim.network.timing import tx_time_ns
from netsim.registry import register

__all__ = ["FdmaMedium"]


@register("network", "fdma", "FDMA: fixed bandwidth shares per sender, no interference")
class FdmaMedium(Network["FdmaMedium.Params"]):
    """An FDMA medium (see the module docstring)."""

    class Params(NetworkParams):
        """FDMA parameters: the common ones plus the bandwidth ``shares``."""

        shares: dict[str, float] | list[float] | None = None

        @model_validator(mode="after")
        def _check_shares(self) -> "FdmaMedium.Params":
            sh = self.shares
            if sh is None:
                return self
            if isinstance(sh, list):
                if len(sh) != len(self.nodes):
                    raise ValueError(f"shares: {len(sh)} values for {len(self.nodes)} nodes")
                items = list(zip(self.nodes, sh))
            else:
                for n in sh:
                    if n not in self.nodes:
                        raise ValueError(f"shares: '{n}' is not one of the network's nodes {self.nodes}")
                items = list(sh.items())
            for n, v in items:
                if not 0.0 <= v <= 1.0:
                    raise ValueError(f"shares: the share of '{n}' must be in [0, 1], got {v}")
            total = sum(v for _, v in items)
            if total > 1.0 + 1e-9:
                raise ValueError(f"shares sum to {total:g}; bandwidth shares must sum to at most 1")
            return self

        def share_of(self, node: str) -> float:
            """Bandwidth share of ``node``."""
            if self.shares is None:
                return 1.0 / len(self.nodes)
            if isinstance(self.shares, list):
                return float(self.shares[self.nodes.index(node)])
            return float(self.shares.get(node, 0.0))

    utilization_mode = "weighted"

    def _setup(self) -> None:
        p = self.params
        self._share = {n: p.share_of(n) for n in self.nodes}
        self._tx: dict[str, Transmitter] = {}
        for n, share in self._share.items():
            if share > 0:
                m = self.meters[n] = BusyMeter(p.utilization_bin, weight=share)
                self._tx[n] = Transmitter(self, self.queues[n], share * p.bitrate, m, self._sent)

    def send(self, msg: Message) -> None:
        if msg.sender in self._share and self._share[msg.sender] <= 0:
            raise ConfigError(
                f"network '{self.name}': '{msg.sender}' sends but has no bandwidth share; "
                f"give it one in networks.{self.name}.shares",
                path=f"networks.{self.name}.shares",
            )
        super().send(msg)

    def _frame_time(self, wire_bits: int, sender: str) -> int:
        share = self._share.get(sender, 0.0)
        return tx_time_ns(wire_bits, share * self.params.bitrate) if share > 0 else 0

    def _offer(self, frame: Frame) -> None:
        self._tx[frame.sender].offer(frame)

    def _sent(self, frame: Frame, start: int, end: int) -> None:
        frame.tx_start_ns = start
        self._transmitted(frame, start, end)
