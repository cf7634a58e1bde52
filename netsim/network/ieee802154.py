"""IEEE 802.15.4 on the shared radio channel of :mod:`netsim.network.wireless`: unslotted CSMA/CA (see there)."""

from __future__ import annotations

from pydantic import Field, model_validator

from netsim.network.timing import call_later
from netsim.network.wireless import WirelessMedium, WirelessParams
from netsim.registry import register
from netsim.timebase import US
from netsim.units import Bitrate, Duration

__all__ = ["Ieee802154"]


@register("network", "ieee802154", "IEEE 802.15.4 radio: unslotted CSMA/CA, path loss, interference, ACK and retries")
@register("network", "802.15.4", "IEEE 802.15.4 radio (same as 'ieee802154')")
class Ieee802154(WirelessMedium["Ieee802154.Params"]):
    """IEEE 802.15.4 (2.4 GHz O-QPSK PHY defaults), unslotted CSMA/CA (see the module docstring)."""

    class Params(WirelessParams):
        """802.15.4 defaults: 250 kbit/s, 16 us symbols, 127-byte PSDU (116 bytes of payload)."""

        bitrate: Bitrate = 250_000.0
        max_frame_bits: int | None = Field(928, gt=0)
        phy_overhead: Duration = 192 * US  # preamble, SFD and PHY header: 6 bytes at 250 kbit/s
        mac_overhead_bits: int = Field(88, ge=0)  # frame control, sequence, short addresses, PAN id, FCS
        ack_bits: int = Field(40, ge=0)  # 5-byte ACK frame
        ack_delay: Duration = 192 * US  # aTurnaroundTime, 12 symbols
        ack_timeout: Duration | None = 864 * US  # macAckWaitDuration, 54 symbols
        max_retries: int = Field(3, ge=0)  # macMaxFrameRetries
        unit_backoff: Duration = 320 * US  # aUnitBackoffPeriod, 20 symbols
        cca_time: Duration = 128 * US  # 8 symbols
        turnaround: Duration = 192 * US
        min_be: int = Field(3, ge=0, le=20)
        max_be: int = Field(5, ge=0, le=20)
        max_csma_backoffs: int = Field(4, ge=0)

        @model_validator(mode="after")
        def _check_be(self) -> "Ieee802154.Params":
            if self.min_be > self.max_be:
                raise ValueError(f"min_be ({self.min_be}) is larger than max_be ({self.max_be})")
            return self

    def _mac_setup(self) -> None:
        self._nb = {n: 0 for n in self.nodes}
        self._be = {n: 0 for n in self.nodes}
        self.busy_ccas = 0

    def _contend(self, node: str, first: bool) -> None:
        p = self.params
        self._nb[node] = 0
        self._be[node] = p.min_be
        self._backoff(node)

    def _backoff(self, node: str) -> None:
        p = self.params
        slots = int(self._rng.integers(0, 1 << self._be[node]))
        call_later(self.sim, slots * int(p.unit_backoff) + int(p.cca_time), self._cca, node)

    def _cca(self, node: str) -> None:
        p = self.params
        if not self._sensed_busy(node):
            call_later(self.sim, int(p.turnaround), self._transmit, node)
            return
        self.busy_ccas += 1
        self._nb[node] += 1
        self._be[node] = min(self._be[node] + 1, p.max_be)
        if self._nb[node] > p.max_csma_backoffs:
            self._give_up_access(node)
        else:
            self._backoff(node)

    def _transmit(self, node: str) -> None:
        self._send_frame(node)

    def _extra_metrics(self, t_end_ns: int) -> dict[str, float]:
        return {**super()._extra_metrics(t_end_ns), "busy_ccas": float(self.busy_ccas)}
