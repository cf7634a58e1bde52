"""Control packets with future actions and the actuator's playout buffer (section 2 of Cuenca et al.).

A :class:`ControlPacket` carries the current action ``u_k`` and ``h`` future ones
``u_{k+1} .. u_{k+h}``, stamped with the fast index ``k`` of its first value.

:class:`PlayoutBuffer` is what the actuator does at every fast period ``j``:

* a packet newer than the one in use replaces it (a packet older than or as old as the one in use is
  discarded as stale -- out-of-order arrival on a network);
* the value applied at ``j`` is ``values[j - k]`` of the packet in use: the current action when it
  arrives on time, then the future actions one per period while no new packet arrives; a late packet
  (network delay) starts at the entry for ``j`` instead of replaying stale entries;
* when the packet is exhausted (``j - k > h``) the last value is held (ZOH), as the paper's actuator
  does without future actions;
* before the first packet the initial value ``u0`` (default 0) is applied.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["ControlPacket", "PlayoutBuffer"]


@dataclass(frozen=True)
class ControlPacket:
    """Current and future control actions from fast instant ``k`` on: ``values[l] = u_{k+l}``."""

    k: int
    values: Sequence[float]  # a tuple, or the lazily computed CascadeActions of netsim.control.cascade

    def __post_init__(self) -> None:
        if len(self.values) == 0:
            raise ValueError("a control packet needs at least the current action")

    @property
    def horizon(self) -> int:
        """Number of future actions ``h``."""
        return len(self.values) - 1

    def value_at(self, j: int) -> float:
        """Value for fast instant ``j >= k`` (held last value past the horizon)."""
        idx = j - self.k
        if idx < 0:
            raise ValueError(f"packet starts at k={self.k}, asked for j={j}")
        return self.values[min(idx, len(self.values) - 1)]

    def bits(self, bits_per_value: int = 32, header_bits: int = 0) -> int:
        """Payload size for the network: one word per value plus a header."""
        return header_bits + bits_per_value * len(self.values)

    @classmethod
    def of(cls, k: int, values) -> "ControlPacket":
        return cls(int(k), tuple(float(v) for v in np.ravel(values)))


class PlayoutBuffer:
    """The actuator's buffer: apply current action, then future ones, then hold the last."""

    def __init__(self, u0: float = 0.0) -> None:
        self.u0 = float(u0)
        self.packet: ControlPacket | None = None
        self.fresh_count = 0  # packets accepted
        self.stale_count = 0  # packets discarded as older than the one in use

    def reset(self) -> None:
        self.packet = None
        self.fresh_count = 0
        self.stale_count = 0

    def receive(self, packet: ControlPacket) -> bool:
        """Take ``packet`` if newer than the one in use; return whether it was accepted."""
        if self.packet is not None and packet.k <= self.packet.k:
            self.stale_count += 1
            return False
        self.packet = packet
        self.fresh_count += 1
        return True

    def value(self, j: int) -> float:
        """Action to apply at fast instant ``j``."""
        p = self.packet
        if p is None or j < p.k:
            return self.u0 if p is None else p.values[0]
        idx = j - p.k
        vals = p.values
        return vals[idx] if idx < len(vals) else vals[-1]

    def exhausted(self, j: int) -> bool:
        """True when ``j`` is past the last value of the packet in use (the last value is being held)."""
        return self.packet is not None and j - self.packet.k > self.packet.horizon
