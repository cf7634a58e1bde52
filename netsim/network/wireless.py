"""Wireless media: a shared radio channel with path loss, interference, CSMA/CA, acknowledgements and retries.

Two MACs on one radio model (TrueTime's wireless network block offers the same two), each in its own module
(:mod:`netsim.network.ieee802154`, :mod:`netsim.network.ieee80211b`); this module holds the radio channel they share:

``ieee802154`` (alias ``802.15.4``)
    Unslotted CSMA/CA of IEEE 802.15.4: wait a random number of unit backoff periods in
    ``0 .. 2**BE - 1``, then a clear channel assessment (CCA); a busy channel raises ``BE`` (up to
    ``max_be``) and counts one more backoff, and after ``max_csma_backoffs + 1`` busy CCAs the frame is
    dropped (``channel_access``). An idle CCA is followed by the receive-to-transmit turnaround, then
    the frame.
``ieee80211b`` (alias ``802.11b``)
    The DCF of IEEE 802.11 (basic access, no RTS/CTS): a node whose frame arrives when the medium has
    been idle for DIFS sends at once; otherwise, and for every frame after a transmission of its own, it
    draws a backoff of ``0 .. CW`` slots, counted down only while the medium stays idle after a DIFS
    (frozen while busy). ``CW`` starts at ``cw_min`` and doubles (``2 CW + 1``, at most ``cw_max``) at
    every retry.

The radio (both MACs)
    Nodes stand at ``positions`` (metres) at time 0; ``mobility`` moves them along a piecewise-linear
    ``path`` or at a constant ``velocity`` (:mod:`netsim.network.mobility`), and
    :meth:`WirelessMedium.set_position` moves one from Python during a run.
    A transmission of power ``P_tx`` (dBm) reaches a node at distance ``d`` with
    ``P_tx - 10 a log10(max(d, d0) / d0)`` dBm (log-distance path loss, exponent ``a``, TrueTime's
    ``1/d^a`` with ``d0`` = 1 m), or with what the model ``path_loss: {type: NAME, ...}`` gives
    (:mod:`netsim.network.path_loss`: ``log_distance``, ``free_space``, or a user's plugin). A node senses the medium busy while the powers it receives add up to at
    least ``carrier_sense_dbm`` (default: ``receiver_threshold_dbm``), or while it transmits: with a
    carrier-sense threshold below the decode threshold a node defers to transmissions it could not decode.
    A copy is received when its power is at least
    ``receiver_threshold_dbm``, the receiver did not transmit during it (half duplex), and the ratio of
    its power to the noise plus the largest sum of powers of the other transmissions that overlapped it
    stayed at least ``sinr_threshold_db``.
    Same instant: transmissions go on and off the air after every channel-access decision of their
    instant, so a decision at ``t`` (a CCA ending, a backoff expiring, a frame finding the medium idle for
    DIFS) sees the medium as it was just before ``t``: nodes deciding together transmit together and
    collide, and a CCA ending as a transmission ends has sensed it.

Acknowledgements
    A unicast frame received correctly is acknowledged by the receiver ``ack_delay`` after its end (SIFS or
    the turnaround), with an ACK frame lasting ``ack_ns`` that occupies the channel like any other
    transmission (it can collide, and be lost). Without an ACK within ``ack_timeout`` of the frame's end the
    sender retries, up to ``max_retries`` times, then drops the copy (``no_ack``). A copy is delivered at the
    end of the first transmission it was received from; the copies of later retransmissions (their ACK
    was lost) are discarded by the receiver as duplicates. Broadcasts are sent once, without ACK; each
    receiver that does not get one drops it as ``out_of_range`` or ``interference``.

Radio time (energy, :mod:`netsim.energy`)
    For the nodes whose energy model has a radio, the medium keeps the time each radio spends in each state:
    ``tx`` (it transmits a frame or an ACK), ``rx`` (not transmitting, it senses others' transmissions: their
    powers add up to ``carrier_sense_dbm``), ``idle`` (listening to a quiet channel) and ``sleep`` (a radio
    with ``listen: own_frames`` sleeps while its MAC holds no frame; a sleeping radio receives nothing, and a
    copy for it fails as ``out_of_range``). A node whose battery ran out (:meth:`WirelessMedium.halt_node`,
    also named ``radio_off``) neither sends nor receives from then on: its queued frames and the frame its MAC
    holds are dropped (``sender_dead``), copies for it fail, and its transmission under way reaches no one.

Why this module is long: the radio channel is one state machine over shared per-node state (positions and
motion, what each node senses, the receptions under way, ACK waits and retries, radio time); the MAC modules
only add their channel access on top of it.

Loss (``loss`` / ``loss_probability``, docs/loss.md)
    Drawn once per attempt for each copy the radio received (in range, SINR met), before the ACK: a lost copy
    is not received, so a unicast with ACKs gets no ACK and is retried like any other failed attempt (dropped
    as ``no_ack`` after ``max_retries``); a broadcast, or a unicast with ``acks: false``, drops it as ``lost``.
    ACK frames are not subject to it. ``lost_attempts`` (in the metrics when a loss model is set) counts the
    erased receptions.

Frames carry ``phy_overhead`` (time at the start of every frame: preamble and PHY header) and
``mac_overhead_bits`` (MAC header and checksum) besides the payload. Random backoffs come from the stream
``network.<name>.backoff``.
"""

from __future__ import annotations

import abc
import math
from typing import Any, ClassVar, TypeVar

from pydantic import BaseModel, Field, ValidationError, field_validator, model_validator

from netsim.env import AIR
from netsim.errors import ConfigError
from netsim.network.message import Message
from netsim.network.mobility import Motion, Track
from netsim.network.params import NetworkParams
from netsim.network.path_loss import exponent_dbm, make_path_loss, path_loss_class
from netsim.network.pipeline import Copy, Frame, Network
from netsim.network.records import (
    DROP_CHANNEL_ACCESS,
    DROP_INTERFERENCE,
    DROP_LOST,
    DROP_NO_ACK,
    DROP_NO_RECEIVER,
    DROP_OUT_OF_RANGE,
    DROP_QUEUE_FULL,
    DROP_SENDER_DEAD,
    DROP_STALE,
)
from netsim.network.stats import BusyMeter
from netsim.network.timing import Call, call_later, tx_time_ns
from netsim.timebase import US, format_time
from netsim.units import Duration, QuietDefaultsModel

__all__ = ["WirelessMedium", "WirelessParams", "RadioClock", "received_dbm", "RADIO_STATES"]

#: States of a radio, in the order the energy model lists their powers.
RADIO_STATES = ("tx", "rx", "idle", "sleep")


#: Power (dBm) received at a distance with the exponent path loss (:func:`netsim.network.path_loss.exponent_dbm`).
received_dbm = exponent_dbm


def _mw(dbm: float) -> float:
    return 10.0 ** (dbm / 10.0)


class WirelessParams(NetworkParams, QuietDefaultsModel):
    """What both wireless MACs share: the radio, the frame overheads and acknowledgements."""

    positions: dict[str, tuple[float, float]] = Field(description="node -> [x, y] in metres")
    transmit_power_dbm: float = 0.0
    receiver_threshold_dbm: float = -85.0
    carrier_sense_dbm: float | None = Field(
        None, description="carrier-sense (CCA) threshold in dBm: the medium is busy while the received powers add "
                          "up to this; null: receiver_threshold_dbm (a lower value defers to frames it cannot decode)")
    path_loss_exponent: float = Field(3.5, gt=0, description="exponent a of the default path loss, "
                                                               "P_tx - 10 a log10(d / d0)")
    reference_distance: float = Field(1.0, gt=0, description="d0 (m): no loss closer than this")
    path_loss: dict[str, Any] | None = Field(
        None, description="the path-loss model instead: {type: exponent | log_distance | free_space | a plugin's "
                          "name, ...its parameters} (netsim list path_loss); null: exponent with path_loss_exponent "
                          "and reference_distance")
    noise_dbm: float = -100.0
    sinr_threshold_db: float = 10.0
    phy_overhead: Duration = 0
    mac_overhead_bits: int = Field(0, ge=0)
    acks: bool = True
    ack_bits: int = Field(0, ge=0, description="MAC bits of an ACK frame (sent at bitrate, after phy_overhead)")
    ack_delay: Duration = 0
    ack_timeout: Duration | None = Field(None, description="default: ack_delay + ACK duration + 1 us")
    max_retries: int = Field(3, ge=0)
    mobility: dict[str, Motion] = Field(
        default_factory=dict, description="node -> {path: {time: [x, y], ...}} or {velocity: [vx, vy]} (m, m/s): "
                                          "how it moves from its position at 0 s")

    #: Fields added in issue 20, left out of the resolved scenario while at their defaults (its text, and the
    #: golden digests of the shipped radio scenarios, stay as they were).
    _QUIET_DEFAULTS: ClassVar[dict[str, Any]] = {"carrier_sense_dbm": None, "mobility": {}, "path_loss": None}

    @field_validator("path_loss")
    @classmethod
    def _check_path_loss(cls, value: dict[str, Any] | None) -> dict[str, Any] | None:
        if value is None:
            return None
        name = value.get("type")
        if not isinstance(name, str) or not name:
            raise ValueError("give the model's type: {type: exponent | log_distance | free_space | a plugin's name, "
                             "...}")
        try:
            model_cls = path_loss_class(name)
        except ConfigError as exc:
            raise ValueError(f"type: {exc.message}") from None
        params = getattr(model_cls, "Params", None)
        if isinstance(params, type) and issubclass(params, BaseModel):
            try:
                params.model_validate({k: v for k, v in value.items() if k != "type"})
            except ValidationError as exc:
                from netsim.network.factory import format_validation_error

                raise ValueError(f"{name}: {format_validation_error(exc)}") from None
        return value

    @model_validator(mode="after")
    def _check_radio(self) -> "WirelessParams":
        if self.path_loss is not None:
            both = sorted({"path_loss_exponent", "reference_distance"} & self.model_fields_set)
            if both:
                raise ValueError(f"give either path_loss or {' and '.join(both)}, not both (path_loss: {{type: "
                                 "exponent, exponent: .., reference_distance: ..}} is the default model)")
        missing = [n for n in self.nodes if n not in self.positions]
        if missing:
            raise ValueError(f"positions: no position for {missing}; give each node [x, y] in metres")
        extra = [n for n in self.positions if n not in self.nodes]
        if extra:
            raise ValueError(f"positions: {extra} not in the network's nodes {self.nodes}; remove their positions "
                             "or add them to nodes")
        stray = [n for n in self.mobility if n not in self.nodes]
        if stray:
            raise ValueError(f"mobility: {stray} not in the network's nodes {self.nodes}; remove them or add them "
                             "to nodes")
        return self


#: The ``Params`` type of a wireless MAC (a :class:`WirelessParams`).
W = TypeVar("W", bound=WirelessParams)


class RadioClock:
    """The time one node's radio spent in each of :data:`RADIO_STATES` (ns), kept by its medium.

    ``listen`` is ``"always"`` (the radio listens whenever it does not transmit) or ``"own_frames"`` (it sleeps
    while its MAC holds no frame). After :meth:`WirelessMedium.radio_off` the state is ``"off"`` and no time
    accrues any more.
    """

    __slots__ = ("listen", "state", "since", "totals")

    def __init__(self, listen: str, state: str, now: int) -> None:
        self.listen = listen
        self.state = state
        self.since = now
        self.totals = {k: 0 for k in RADIO_STATES}

    def set(self, state: str, now: int) -> None:
        """The radio is in ``state`` from ``now`` on."""
        if state != self.state:
            if self.state != "off":
                self.totals[self.state] += now - self.since
            self.state = state
            self.since = now

    def times(self, now: int) -> dict[str, int]:
        """Time (ns) in each state up to ``now``."""
        out = dict(self.totals)
        if self.state != "off":
            out[self.state] += now - self.since
        return out


class WirelessMedium(Network[W]):
    """The radio, acknowledgements and retries shared by the wireless MACs (see the module docstring).

    Subclasses implement the channel access: :meth:`_contend` (a frame is at the head of ``node``'s MAC),
    :meth:`_on_medium_change` (what a node senses may have changed) and :meth:`_after_attempt` (the attempt
    ended; ``success`` False means a retry is due).
    """

    Params: ClassVar[type[NetworkParams]] = WirelessParams
    drop_reasons = (DROP_QUEUE_FULL, DROP_LOST, DROP_STALE, DROP_NO_RECEIVER, DROP_OUT_OF_RANGE,
                    DROP_INTERFERENCE, DROP_NO_ACK, DROP_CHANNEL_ACCESS)

    def _setup(self) -> None:
        p = self.params
        self._meter = self.meters["channel"] = BusyMeter(p.utilization_bin)
        self._rng = self.env.rng(f"network.{self.name}.backoff")
        self._pos = {n: (float(x), float(y)) for n, (x, y) in p.positions.items()}
        self._gain: dict[tuple[str, str], float] = {}  # received power (mW) by (sender, receiver)
        self._thr = _mw(p.receiver_threshold_dbm)
        self._path_loss = make_path_loss(p.path_loss if p.path_loss is not None else {
            "type": "exponent", "exponent": p.path_loss_exponent, "reference_distance": p.reference_distance})
        cs = p.receiver_threshold_dbm if p.carrier_sense_dbm is None else p.carrier_sense_dbm
        self._cs = _mw(cs)
        self._tracks = {n: Track(self._pos[n], m) for n, m in p.mobility.items()}
        self._gain_t = -1  # the instant the positions of the moving nodes were last computed
        self._radios: dict[str, RadioClock] = {}  # nodes whose radio time is kept (netsim.energy)
        self._off: set[str] = set()  # nodes whose radio is off for good (battery ran out)
        self._noise = _mw(p.noise_dbm)
        self._sinr = 10.0 ** (p.sinr_threshold_db / 10.0)
        self._ack_ns = int(p.phy_overhead) + tx_time_ns(p.ack_bits, p.bitrate)
        self._ack_timeout = (int(p.ack_timeout) if p.ack_timeout is not None
                             else int(p.ack_delay) + self._ack_ns + 1 * US)
        if self._ack_timeout < int(p.ack_delay) + self._ack_ns:
            raise ConfigError(
                f"network '{self.name}': ack_timeout ({format_time(self._ack_timeout)}) is shorter than ack_delay + "
                f"the ACK frame ({format_time(int(p.ack_delay) + self._ack_ns)}): no ACK could ever arrive; raise "
                "ack_timeout",
                path=f"networks.{self.name}.ack_timeout")
        self._active: list[list[Any]] = []  # transmissions on the air: [sender, receptions]
        self._current: dict[str, Frame | None] = {n: None for n in self.nodes}
        self._pending: dict[str, list[Copy]] = {}  # copies still waiting for an ACK, per sender
        self._retries: dict[str, int] = {n: 0 for n in self.nodes}
        self._ack_wait: dict[str, Call | None] = {n: None for n in self.nodes}
        self._last_end: dict[str, int] = {}  # end of the last transmission of each node's current frame
        self._sending: set[str] = set()  # nodes whose current frame is on the air (from _send_frame to _frame_end)
        self._seen: set[tuple[int, str | None]] = set()  # (msg_id, receiver) delivered: later copies are duplicates
        self.attempts = 0
        self.retransmissions = 0
        self.acks_sent = 0
        self.duplicates = 0
        self.lost_attempts = 0  # received copies the loss model erased (each one an unacknowledged attempt)
        self._mac_setup()

    def _mac_setup(self) -> None:
        """MAC state (subclasses)."""

    # ------------------------------------------------------------------------------------------ public API
    def set_position(self, node: str, x: float, y: float) -> None:
        """Move ``node`` to ``(x, y)`` metres now; it stays there (a ``mobility`` entry of it ends)."""
        if node not in self._pos:
            raise ConfigError(f"network '{self.name}': no node '{node}' (nodes: {self.nodes})")
        self._tracks.pop(node, None)
        self._pos[node] = (float(x), float(y))
        self._gain.clear()

    def position(self, node: str) -> tuple[float, float]:
        """Where ``node`` is now (metres)."""
        if node not in self._pos:
            raise ConfigError(f"network '{self.name}': no node '{node}' (nodes: {self.nodes})")
        if self._tracks and self.sim.now != self._gain_t:
            self._move()
        return self._pos[node]

    def track_radio(self, node: str, listen: str = "always") -> RadioClock:
        """Keep the time ``node``'s radio spends in each state (:data:`RADIO_STATES`) from now on."""
        if node not in self._pos:
            raise ConfigError(f"network '{self.name}': no node '{node}' (nodes: {self.nodes})")
        clock = self._radios[node] = RadioClock(listen, self._radio_state(node, listen), self.sim.now)
        return clock

    def halt_node(self, node: str) -> None:
        """``node``'s radio stops for good (its battery ran out): it neither sends nor receives from now on.

        Its queued frames, and the frame its MAC holds when it is not on the air (backing off, sensing the
        channel, waiting for an ACK or a retry), are dropped (``sender_dead``); receptions under way at it fail
        (``out_of_range``); its own transmission under way reaches no one, and its frame is then dropped
        (``sender_dead``).
        """
        if node in self._off or node not in self._pos:
            return
        self._off.add(node)
        for tx in self._active:
            for rx in tx[1]:
                if rx[0] == node or tx[0] == node:
                    rx[2] = None
        clock = self._radios.get(node)
        if clock is not None:
            clock.set("off", self.sim.now)
        super().halt_node(node)

    radio_off = halt_node

    def _halted(self, node: str, dropped: int) -> None:
        if self._current[node] is not None and node not in self._sending:
            self._drop_held(node, self.sim.now)

    def _drop_held(self, node: str, now: int) -> None:
        """Drop the copies of ``node``'s current frame not delivered yet (``sender_dead``); the MAC holds none."""
        frame = self._current[node]
        wait = self._ack_wait[node]
        if wait is not None and wait.live:
            wait.cancel()
        self._ack_wait[node] = None
        for c in self._pending.get(node, []):
            if (c[0].msg_id, c[0].receiver) in self._seen:
                continue
            if frame is not None and frame.tx_start_ns is not None:
                self._drop_on_air(c, frame, self._last_end.get(node, now), DROP_SENDER_DEAD)
            else:
                self._drop_copy(c, DROP_SENDER_DEAD)
        self._current[node] = None
        self._pending.pop(node, None)

    def received_power_dbm(self, sender: str, receiver: str) -> float:
        """Power (dBm) ``receiver`` gets from a transmission of ``sender`` at their current positions."""
        return 10.0 * math.log10(self._power(sender, receiver))

    # ------------------------------------------------------------------------------------------ framing
    def wire_bits(self, msg: Message) -> int:
        return super().wire_bits(msg) + self.params.mac_overhead_bits

    def _frame_time(self, wire_bits: int, sender: str) -> int:
        return int(self.params.phy_overhead) + tx_time_ns(wire_bits, self.params.bitrate)

    # ------------------------------------------------------------------------------------------ radio
    def _move(self) -> None:
        """Positions of the moving nodes now (the gain cache is for one instant while nodes move)."""
        now = self.sim.now
        for n, track in self._tracks.items():
            self._pos[n] = track.at(now)
        self._gain.clear()
        self._gain_t = now

    def _power(self, sender: str, receiver: str) -> float:
        if self._tracks and self.sim.now != self._gain_t:
            self._move()
        g = self._gain.get((sender, receiver))
        if g is None:
            a, b = self._pos[sender], self._pos[receiver]
            dbm = self._path_loss.received_dbm(self.params.transmit_power_dbm,
                                               math.hypot(a[0] - b[0], a[1] - b[1]), sender, receiver, (a, b))
            if not isinstance(dbm, (int, float)) or not math.isfinite(dbm) or dbm > 1000:
                name = (self.params.path_loss or {}).get("type", "exponent")
                raise ConfigError(f"network '{self.name}': the path-loss model '{name}' gave {dbm!r} dBm from "
                                  f"'{sender}' to '{receiver}'; it must return a finite power in dBm: fix the model",
                                  path=f"networks.{self.name}.path_loss")
            g = self._gain[(sender, receiver)] = _mw(dbm)
        return g

    def _transmitting(self, node: str) -> bool:
        return any(tx[0] == node for tx in self._active)

    def _sensed_busy(self, node: str) -> bool:
        """Carrier sense at ``node``: it transmits, or the powers it receives reach the threshold."""
        total = 0.0
        for tx in self._active:
            if tx[0] == node:
                return True
            total += self._power(tx[0], node)
        return total >= self._cs

    def _radio_state(self, node: str, listen: str) -> str:
        if node in self._off:
            return "off"
        total = 0.0
        for tx in self._active:
            if tx[0] == node:
                return "tx"
            total += self._power(tx[0], node)
        if listen == "own_frames" and self._current[node] is None:
            return "sleep"
        return "rx" if total >= self._cs else "idle"

    def _radio_update(self) -> None:
        """The radio states of the tracked nodes now (a transmission started or ended, a MAC took a frame)."""
        now = self.sim.now
        for node, clock in self._radios.items():
            state = self._radio_state(node, clock.listen)
            if state != clock.state:
                clock.set(state, now)
                if state == "sleep":  # a radio that falls asleep loses the receptions under way
                    for tx in self._active:
                        for rx in tx[1]:
                            if rx[0] == node:
                                rx[2] = None

    def _deaf(self, node: str) -> bool:
        """``node`` receives nothing now (its radio is off, or asleep)."""
        if node in self._off:
            return True
        clock = self._radios.get(node)
        return clock is not None and clock.state == "sleep"

    def _interference(self, receiver: str, tx: list[Any]) -> float:
        return sum(self._power(o[0], receiver) for o in self._active if o is not tx)

    def _start_tx(self, sender: str, receivers: list[str], duration: int, on_end: Any, arg: Any) -> None:
        """Put a transmission of ``sender`` on the air for ``duration``; ``on_end(arg, ok)`` gets, at its end,
        the receivers that received it.

        The transmission goes on the air, and later leaves it, at ``AIR`` priority of its instant (see
        :mod:`netsim.env`): every channel-access decision taken at that instant (a CCA ending, a backoff
        expiring, a frame finding the medium idle for DIFS) sees the medium as it was just before it. Carrier
        sense cannot detect a transmission that starts at the very instant it senses, so two nodes deciding
        at the same instant both transmit and collide; and a CCA ending as a transmission ends has sensed it.
        """
        call_later(self.sim, 0, self._on_air, (sender, receivers, duration, on_end, arg), priority=AIR)

    def _on_air(self, item: tuple) -> None:
        sender, receivers, duration, on_end, arg = item
        now = self.sim.now
        for other in self._active:  # the new transmission interferes with every reception under way
            for rx in other[1]:
                if rx[0] == sender:
                    rx[2] = False  # half duplex: the receiver started to transmit
                else:
                    rx[1] = max(rx[1], self._interference(rx[0], other) + self._power(sender, rx[0]))
        tx: list[Any] = [sender, []]
        watch = self._radios or self._off
        for r in receivers:
            rx = [r, self._interference(r, tx), None if watch and self._deaf(r) else not self._transmitting(r)]
            tx[1].append(rx)
        if not self._active:
            self._meter.start(now)
        self._active.append(tx)
        call_later(self.sim, duration, self._end_tx, (tx, on_end, arg), priority=AIR)
        if self._radios:
            self._radio_update()
        self._on_medium_change()

    def _end_tx(self, item: tuple) -> None:
        tx, on_end, arg = item
        self._active.remove(tx)
        if not self._active:
            self._meter.stop(self.sim.now)
        sender = tx[0]
        outcome: dict[str, str | None] = {}
        if self._radios:
            self._radio_update()
        for r, interf, duplex_ok in tx[1]:
            signal = self._power(sender, r)
            if signal < self._thr or duplex_ok is None:  # None: the receiver's radio was asleep or off
                outcome[r] = DROP_OUT_OF_RANGE
            elif not duplex_ok or signal < self._sinr * (self._noise + interf):
                outcome[r] = DROP_INTERFERENCE
            else:
                outcome[r] = None
        on_end(arg, outcome)
        self._on_medium_change()

    # ------------------------------------------------------------------------------------------ frames
    def _offer(self, frame: Frame) -> None:
        node = frame.sender
        if self._push(self.queues[node], frame) and self._current[node] is None:
            self._load(node)

    def _load(self, node: str) -> None:
        """Take ``node``'s next frame to the MAC (if any) and start its channel access."""
        q = self.queues[node]
        if len(q):
            frame = self._current[node] = q.pop(self.sim.now)
            self._retries[node] = 0
            self._pending[node] = list(frame.copies)
            if self._radios:
                self._radio_update()
            self._start_access(node)
        elif self._radios:
            self._radio_update()

    def _start_access(self, node: str) -> None:
        """A new frame is at the head of ``node``'s MAC."""
        self._contend(node, first=True)

    def _send_frame(self, node: str) -> None:
        """The MAC grants the channel: ``node``'s current frame goes on the air now."""
        if node in self._off:
            return  # its battery ran out: the radio sends nothing more
        frame = self._current[node]
        assert frame is not None
        now = self.sim.now
        if frame.tx_start_ns is None:
            frame.tx_start_ns = now
        self.attempts += 1
        self._sending.add(node)
        receivers = [c[0].receiver for c in self._pending[node]]
        self._start_tx(node, receivers, frame.tx_ns, self._frame_end, (node, frame, now))  # type: ignore[arg-type]

    def _frame_end(self, item: tuple, outcome: dict[str, str | None]) -> None:
        node, frame, _start = item
        now = self.sim.now
        self._sending.discard(node)
        if node in self._off:  # the sender halted during the transmission: it reached no one, and ends here
            self._last_end[node] = now
            self._drop_held(node, now)
            return
        p = self.params
        pending = self._pending[node]
        loss = self._loss
        if loss is not None:  # the loss model erases a received copy of this attempt: not received, no ACK
            for c in pending:
                r = c[0].receiver
                if outcome.get(r) is None and loss.lost((node, r)):  # type: ignore[arg-type]
                    outcome[r] = DROP_LOST  # type: ignore[index]
                    self.lost_attempts += 1
        got = [c for c in pending if outcome.get(c[0].receiver) is None]  # type: ignore[arg-type]
        fresh = []
        for c in got:
            key = (c[0].msg_id, c[0].receiver)
            if key in self._seen:
                self.duplicates += 1
            else:
                self._seen.add(key)
                fresh.append(c)
        if fresh:
            self._deliver_copies(frame, fresh, now)
        unicast = frame.msg.receiver is not None
        self._last_end[node] = now
        if not (unicast and p.acks):
            for c in pending:
                reason = outcome.get(c[0].receiver)  # type: ignore[arg-type]
                if reason is not None:
                    self._drop_on_air(c, frame, now, reason)
            self._finish(node)
            return
        if got:  # the receiver acknowledges after ack_delay
            receiver = got[0][0].receiver
            call_later(self.sim, int(p.ack_delay), self._send_ack, (receiver, node))
        self._ack_wait[node] = call_later(self.sim, self._ack_timeout, self._ack_timed_out, node)

    def _drop_on_air(self, copy: Copy, frame: Frame, end: int, reason: str) -> None:
        """Drop a copy that was transmitted (its record keeps the first start and the last end on the air)."""
        msg, rec = copy
        msg.tx_start_ns = rec.tx_start_ns = frame.tx_start_ns
        msg.tx_end_ns = rec.tx_end_ns = end
        self._drop_copy(copy, reason)

    def _deliver_copies(self, frame: Frame, copies: list[Copy], now: int) -> None:
        start = frame.tx_start_ns if frame.tx_start_ns is not None else now
        self._transmitted(Frame(frame.msg, copies, frame.sender, frame.priority, frame.wire_bits, frame.tx_ns,
                                frame.order, tx_start_ns=start), start, now, draw_loss=False)

    def _send_ack(self, item: tuple) -> None:
        receiver, sender = item
        if receiver in self._off:
            return
        self.acks_sent += 1
        self._start_tx(receiver, [sender], self._ack_ns, self._ack_end, sender)

    def _ack_end(self, sender: str, outcome: dict[str, str | None]) -> None:
        wait = self._ack_wait[sender]
        if outcome.get(sender) is None and wait is not None and wait.live:
            wait.cancel()
            self._ack_wait[sender] = None
            self._finish(sender)

    def _ack_timed_out(self, node: str) -> None:
        self._ack_wait[node] = None
        p = self.params
        if self._retries[node] >= p.max_retries:
            frame = self._current[node]
            assert frame is not None
            for c in self._pending[node]:
                if (c[0].msg_id, c[0].receiver) not in self._seen:
                    self._drop_on_air(c, frame, self._last_end[node], DROP_NO_ACK)
            self._finish(node)
            return
        self._retries[node] += 1
        self.retransmissions += 1
        self._after_attempt(node, False)

    def _finish(self, node: str) -> None:
        """The current frame of ``node`` is done (acknowledged, broadcast, or given up)."""
        self._current[node] = None
        self._pending.pop(node, None)
        self._after_attempt(node, True)
        self._load(node)

    def _give_up_access(self, node: str) -> None:
        """Channel access failed: drop the current frame's copies (``channel_access``) and go on."""
        for c in self._pending.get(node, []):
            self._drop_copy(c, DROP_CHANNEL_ACCESS)
        self._current[node] = None
        self._pending.pop(node, None)
        self._load(node)

    # ------------------------------------------------------------------------------------------ MAC hooks
    @abc.abstractmethod
    def _contend(self, node: str, first: bool) -> None:
        """Start the channel access for ``node``'s current frame (``first``: its first attempt)."""

    def _on_medium_change(self) -> None:
        """What the nodes sense may have changed (a transmission started or ended)."""

    def _after_attempt(self, node: str, done: bool) -> None:
        """``done``: the frame is finished (the next one, if any, is loaded after this); else retry it."""
        if not done:
            self._contend(node, first=False)

    def _extra_metrics(self, t_end_ns: int) -> dict[str, float]:
        out = {"attempts": float(self.attempts), "retransmissions": float(self.retransmissions),
               "acks": float(self.acks_sent), "duplicates": float(self.duplicates)}
        if self._loss is not None:  # only with a loss model (the metrics of lossless runs keep their keys)
            out["lost_attempts"] = float(self.lost_attempts)
        return out
