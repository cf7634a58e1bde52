"""IEEE 802.11b on the shared radio channel of :mod:`netsim.network.wireless`: the DCF's basic access (see there)."""

from __future__ import annotations

from pydantic import Field, model_validator

from netsim.network.timing import Call, call_later
from netsim.network.wireless import WirelessMedium, WirelessParams
from netsim.registry import register
from netsim.timebase import US
from netsim.units import Bitrate, Duration

__all__ = ["Ieee80211b"]


@register("network", "ieee80211b", "IEEE 802.11b radio: DCF (CSMA/CA with frozen backoff), path loss, ACK and retries")
@register("network", "802.11b", "IEEE 802.11b radio (same as 'ieee80211b')")
class Ieee80211b(WirelessMedium["Ieee80211b.Params"]):
    """IEEE 802.11b (DSSS, long preamble defaults) with the DCF's basic access (see the module docstring)."""

    class Params(WirelessParams):
        """802.11b defaults: 11 Mbit/s data, 192 us PLCP preamble and header, 2304-byte payload at most."""

        bitrate: Bitrate = 11_000_000.0
        max_frame_bits: int | None = Field(18432, gt=0)
        transmit_power_dbm: float = 20.0
        receiver_threshold_dbm: float = -82.0
        phy_overhead: Duration = 192 * US
        mac_overhead_bits: int = Field(272, ge=0)  # 34-byte MAC header and FCS
        ack_bits: int = Field(112, ge=0)  # 14-byte ACK frame
        ack_delay: Duration = 10 * US  # SIFS
        ack_timeout: Duration | None = None
        max_retries: int = Field(7, ge=0)  # dot11ShortRetryLimit
        slot: Duration = 20 * US
        sifs: Duration = 10 * US
        cw_min: int = Field(31, ge=0)
        cw_max: int = Field(1023, ge=0)

        @model_validator(mode="after")
        def _check_cw(self) -> "Ieee80211b.Params":
            if self.cw_min > self.cw_max:
                raise ValueError(f"cw_min ({self.cw_min}) is larger than cw_max ({self.cw_max})")
            return self

    def _mac_setup(self) -> None:
        p = self.params
        self._difs = int(p.sifs) + 2 * int(p.slot)
        self._slot = int(p.slot)
        self._cw = {n: p.cw_min for n in self.nodes}
        self._bo: dict[str, int | None] = {n: None for n in self.nodes}  # backoff slots left (None: none drawn)
        self._timer: dict[str, Call | None] = {n: None for n in self.nodes}
        self._count_from: dict[str, int] = {n: 0 for n in self.nodes}
        # when each node's medium went idle (None while sensed busy); before the run it was idle for a DIFS
        self._idle_since: dict[str, int | None] = {n: -self._difs for n in self.nodes}
        self._post_backoff: dict[str, bool] = {n: False for n in self.nodes}
        self._contending: set[str] = set()

    def _contend(self, node: str, first: bool) -> None:
        p = self.params
        now = self.sim.now
        idle = self._idle_since[node]
        if first and not self._post_backoff[node] and idle is not None and now - idle >= self._difs:
            self._bo[node] = None
            self._send_frame(node)  # the medium has been idle for DIFS: immediate access
            return
        if not first:
            self._cw[node] = min(2 * self._cw[node] + 1, p.cw_max)
        if self._bo[node] is None:
            self._bo[node] = int(self._rng.integers(0, self._cw[node] + 1))
        self._contending.add(node)
        self._arm(node)

    def _arm(self, node: str) -> None:
        """Count the backoff down from now if the medium is idle (after a DIFS), else stay frozen."""
        if self._timer[node] is not None or self._sensed_busy(node):
            return
        self._count_from[node] = self.sim.now
        slots = self._bo[node] or 0
        self._timer[node] = call_later(self.sim, self._difs + slots * self._slot, self._backoff_done, node)

    def _freeze(self, node: str) -> None:
        timer = self._timer[node]
        if timer is None:
            return
        timer.cancel()
        self._timer[node] = None
        counted = (self.sim.now - self._count_from[node] - self._difs) // self._slot
        if counted > 0:
            self._bo[node] = max(0, self._bo[node] - counted)  # type: ignore[operator]

    def _backoff_done(self, node: str) -> None:
        self._timer[node] = None
        self._contending.discard(node)
        self._bo[node] = None
        self._post_backoff[node] = False
        if self._current[node] is not None:  # else nothing to send: the next frame may access at once
            self._send_frame(node)

    def _on_medium_change(self) -> None:
        now = self.sim.now
        for n in self.nodes:
            busy = self._sensed_busy(n)
            if busy:
                self._idle_since[n] = None
            elif self._idle_since[n] is None:
                self._idle_since[n] = now
        for n in sorted(self._contending):
            if self._sensed_busy(n):
                self._freeze(n)
            else:
                self._arm(n)

    def _after_attempt(self, node: str, done: bool) -> None:
        p = self.params
        if done:  # success or given up: CW resets and a post-transmission backoff starts
            self._cw[node] = p.cw_min
            self._post_backoff[node] = True
            self._bo[node] = int(self._rng.integers(0, self._cw[node] + 1))
            self._contending.add(node)
            self._arm(node)
        else:
            self._contend(node, first=False)

    def _start_access(self, node: str) -> None:
        if not self._post_backoff[node]:  # else the post-transmission backoff under way sends it when it ends
            self._contend(node, first=True)
