"""What an encoder count means: the quantization convention shared by the estimators and the simulations.

The paper's measurement model (eq. 1) is ``y = D round(p / D)`` with ``D = Dp 2^q`` (``Dp = 5e-5 m``, ``q``
low bits dropped). A count ``c`` therefore says ``(c - 1/2) D <= p < (c + 1/2) D``; an edge into ``c`` in
the positive direction happened at ``p = (c - 1/2) D`` and one in the negative direction at
``p = (c + 1/2) D`` ("exactly half way between the two quantization levels"). ``rounding="floor"``
describes an encoder that truncates (``y = D floor(p / D)``): ``c D <= p < (c + 1) D``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from netsim.errors import ConfigError

__all__ = ["DELTA_P", "Quantizer", "check_q"]

#: Full encoder resolution of the cart in metres (paper eq. 1).
DELTA_P = 5e-5


def check_q(q: int) -> int:
    """Validate the number of dropped low bits (0..16) and return it as an int."""
    if isinstance(q, bool) or not isinstance(q, (int,)) and not (isinstance(q, float) and q.is_integer()):
        raise ConfigError(f"encoder bits dropped q must be an integer in 0..16, got {q!r}")
    qi = int(q)
    if not 0 <= qi <= 16:
        raise ConfigError(f"encoder bits dropped q must be in 0..16 (paper: 0..6), got {qi}")
    return qi


@dataclass(frozen=True)
class Quantizer:
    """Quantization step and rounding convention of an encoder count.

    Attributes
    ----------
    delta : float
        Quantization step in m.
    rounding : str
        ``"round"`` (paper eq. 1) or ``"floor"``.
    """

    delta: float
    rounding: str = "round"

    def __post_init__(self) -> None:
        if not (math.isfinite(self.delta) and self.delta > 0):
            raise ConfigError(f"quantization step must be positive, got {self.delta!r}")
        if self.rounding not in ("round", "floor"):
            raise ConfigError(f"rounding must be 'round' or 'floor', got {self.rounding!r}")

    @classmethod
    def from_bits(cls, q: int, delta_p: float = DELTA_P, rounding: str = "round") -> "Quantizer":
        """The quantizer of an encoder of resolution ``delta_p`` with ``q`` low bits dropped."""
        return cls(delta_p * 2 ** check_q(q), rounding)

    @property
    def _shift(self) -> float:
        return 0.5 if self.rounding == "round" else 0.0

    def count(self, p: float) -> int:
        """Count reported for position ``p``."""
        return int(math.floor(p / self.delta + self._shift))

    def level(self, count: int) -> float:
        """Measured position ``y`` of a count (eq. 1: the quantization level)."""
        return count * self.delta

    def interval(self, count: int) -> tuple[float, float]:
        """Positions ``(lo, hi)`` consistent with ``count``."""
        lo = (count - self._shift) * self.delta
        return lo, lo + self.delta

    def edge_position(self, count: int, direction: int) -> float:
        """Position of the edge that brought the count to ``count`` moving in ``direction`` (+1/-1)."""
        lo, hi = self.interval(count)
        return lo if direction >= 0 else hi
