"""FlexRay: a communication cycle of a static segment (TDMA slots) and a dynamic segment (minislots).

One cycle of length ``cycle`` repeats from time 0::

    | static slot 1 | ... | static slot N | minislot 1 | ... | minislot M | network idle time |
    0               static_slot                       N static_slot + M minislot                cycle

Static segment
    ``static_schedule`` lists the owner of each static slot (slot ``i + 1`` is frame ID ``i + 1``; ``null``: a
    free slot). At the start of each slot it owns, a node sends the head of its sender queue, if any, frames
    queued at that very instant included; one frame per slot, which must fit in the slot: ``min_frame_bits`` and
    ``max_frame_bits`` longer than a slot are refused with the parameters, a longer message when it is sent. A frame queued just after its owner's slot started waits a whole cycle.
Dynamic segment
    The frame IDs continue after the static slots: ``dynamic_ids`` gives each node that sends there its ID
    (``N + 1`` to ``N + M``). The IDs take their turns in increasing order (lower ID first: the priority), each
    starting at the current minislot: an ID whose owner has no frame queued at that instant uses one minislot;
    an ID whose owner has one sends it and uses ``ceil(frame time / minislot)`` minislots, provided it ends by
    the end of the dynamic segment; otherwise the frame waits for the ID's turn in the next cycle and the ID
    uses one minislot (a shorter frame of a later ID may still fit). An ID no node owns uses one minislot. A
    frame that could not fit even in an empty dynamic segment is refused when it is sent.
A node may own static slots and a dynamic ID: its queue head goes at the first of its turns.

Simplifications (stated, as in TrueTime's own model): one channel, no action-point offsets, idle phases or
symbol window, no clock synchronisation; a frame's time on the bus is ``bits / bitrate`` (``bits`` padded to
``min_frame_bits``, give the FlexRay header and trailer there or in the message size).
"""

from __future__ import annotations

from typing import Any

from pydantic import Field, ValidationInfo, field_validator

from netsim.env import ARBITRATE
from netsim.errors import ConfigError
from netsim.network.params import NetworkParams
from netsim.network.pipeline import Frame, Network
from netsim.network.stats import BusyMeter
from netsim.network.timing import call_later, tx_time_ns
from netsim.registry import register
from netsim.timebase import format_time
from netsim.units import Duration

__all__ = ["FlexRayBus"]


def _dynamic_id_message(node: str, fid: int, n_static: int, m: int) -> str:
    """The message for a dynamic frame ID outside the dynamic segment, saying what to change.

    Frame IDs ``1 .. n_static`` are the static slots; the dynamic segment has one minislot per ID, so its IDs run
    from ``n_static + 1`` to ``n_static + m``. An ID past the last minislot needs more minislots (at least
    ``fid - n_static``, as long as the cycle still holds them); an ID at or below ``n_static`` belongs to a static
    slot and must be raised.
    """
    where = f"'{node}' has frame ID {fid}"
    if fid > n_static:  # past the dynamic segment: more minislots, or a lower ID
        have = "the dynamic segment has no minislot" if m == 0 else (
            f"dynamic frame IDs run from {n_static + 1} to {n_static + m} ({m} minislots after {n_static} static slots)")
        return (f"{where}, but {have}; set minislots to at least {fid - n_static} (one minislot per dynamic frame "
                f"ID, so ID {fid} needs {fid - n_static} after the {n_static} static slots) or give '{node}' a lower "
                "frame ID")
    if m == 0:
        return (f"{where}, but the dynamic segment has no minislot; set minislots to at least 1 and give '{node}' a "
                f"frame ID above the {n_static} static slots (from {n_static + 1})")
    return (f"{where}, inside the static segment; dynamic frame IDs run from {n_static + 1} to {n_static + m} "
            f"(IDs 1 to {n_static} are the {n_static} static slots, then one ID per minislot): give '{node}' a frame "
            "ID in that range")


@register("network", "flexray", "FlexRay: static segment of TDMA slots, dynamic segment of minislots by frame ID")
class FlexRayBus(Network["FlexRayBus.Params"]):
    """A FlexRay bus, one channel (see the module docstring)."""

    class Params(NetworkParams):
        """FlexRay parameters: the common ones plus the static slot table, the dynamic segment and the cycle."""

        static_slot: Duration | None = Field(None, description="length of one static slot ('50 us')")
        static_schedule: list[str | None] = Field(
            default_factory=list, description="owner node of each static slot, in order (slot i+1 is frame ID "
                                              "i+1); null: a free slot")
        minislot: Duration | None = Field(None, description="length of one minislot of the dynamic segment ('5 us')")
        minislots: int = Field(0, ge=0, description="number of minislots in the dynamic segment")
        dynamic_ids: dict[str, int] = Field(
            default_factory=dict, description="node -> its frame ID in the dynamic segment (number of static slots "
                                              "+ 1 to + minislots; a lower ID goes first)")
        cycle: Duration = Field(description="communication cycle: static segment + dynamic segment + network idle "
                                            "time ('5 ms')")

        @field_validator("static_slot")
        @classmethod
        def _check_slot(cls, value: int | None, info: ValidationInfo) -> int | None:
            d = info.data
            if value is None or "bitrate" not in d:
                return value
            for field in ("min_frame_bits", "max_frame_bits"):  # every frame is at least min, at most max bits
                bits = d.get(field)
                if bits and tx_time_ns(bits, d["bitrate"]) > value:
                    raise ValueError(
                        f"a frame of {field} = {bits} bits takes {format_time(tx_time_ns(bits, d['bitrate']))} at "
                        f"{d['bitrate']:g} bit/s, longer than a static slot ({format_time(value)}); lengthen "
                        f"static_slot or lower {field}")
            return value

        @field_validator("static_schedule")
        @classmethod
        def _check_static(cls, value: list[str | None], info: ValidationInfo) -> list[str | None]:
            nodes = info.data.get("nodes") or []
            for i, owner in enumerate(value):
                if owner not in (None, "") and owner not in nodes:
                    raise ValueError(f"static_schedule[{i}] names '{owner}', which is not one of the network's "
                                     f"nodes {nodes}; add it to nodes or fix the slot")
            if any(o not in (None, "") for o in value) and "static_slot" in info.data and info.data["static_slot"] is None:
                raise ValueError("give static_slot, the length of a static slot ('50 us')")
            return value

        @field_validator("dynamic_ids")
        @classmethod
        def _check_dynamic(cls, value: dict[str, int], info: ValidationInfo) -> dict[str, int]:
            nodes = info.data.get("nodes") or []
            n_static = len(info.data.get("static_schedule") or [])
            m = info.data.get("minislots", 0) or 0
            owner: dict[int, str] = {}
            for node, fid in value.items():
                if node not in nodes:
                    raise ValueError(f"'{node}' is not one of the network's nodes {nodes}")
                if "static_schedule" in info.data and "minislots" in info.data and not n_static < fid <= n_static + m:
                    raise ValueError(_dynamic_id_message(node, fid, n_static, m))
                if fid in owner:
                    raise ValueError(f"frame ID {fid} is given to both '{owner[fid]}' and '{node}'")
                owner[fid] = node
            if value and "minislot" in info.data and info.data["minislot"] is None:
                raise ValueError("give minislot, the length of a minislot ('5 us')")
            return value

        @field_validator("cycle")
        @classmethod
        def _check_cycle(cls, value: int, info: ValidationInfo) -> int:
            d = info.data
            if any(k not in d for k in ("static_slot", "static_schedule", "minislot", "minislots", "dynamic_ids")):
                return value  # a field the cycle depends on is invalid: reported there
            static = len(d.get("static_schedule") or []) * (d.get("static_slot") or 0)
            dynamic = (d.get("minislots") or 0) * (d.get("minislot") or 0)
            if static + dynamic > value:
                fits = (value - static) // d["minislot"] if d.get("minislot") and value >= static else 0
                raise ValueError(
                    f"the static segment ({format_time(static)}) and the dynamic segment ({format_time(dynamic)}) "
                    f"take {format_time(static + dynamic)}, longer than the cycle ({format_time(value)}); lengthen "
                    "the cycle or shorten the slot table"
                    + (f" (the cycle holds at most {fits} minislots after the static segment)" if dynamic else ""))
            if static + dynamic == 0:
                raise ValueError("the cycle has no slot: give static_schedule with static_slot, or minislots with "
                                 "minislot and dynamic_ids")
            return value

    utilization_mode = "single"

    def _setup(self) -> None:
        p = self.params
        self._meter = self.meters["bus"] = BusyMeter(p.utilization_bin)
        self._cycle = int(p.cycle)
        self._slot = int(p.static_slot or 0)
        self._n_static = len(p.static_schedule)
        self._ms = int(p.minislot or 0)
        self._m = int(p.minislots)
        self._dyn_start = self._n_static * self._slot
        # static slot offsets each node owns within a cycle
        self._slots: dict[str, list[int]] = {n: [] for n in self.nodes}
        for i, owner in enumerate(p.static_schedule):
            if owner not in (None, ""):
                self._slots[owner].append(i * self._slot)
        # dynamic turns in ID order: (frame ID, node)
        self._turns = sorted((fid, node) for node, fid in p.dynamic_ids.items())
        self._static_wake: dict[str, Any] = {}  # node -> its pending static-slot call
        self._dyn_call: Any = None  # the pending call of the dynamic segment's next turn
        self._done_base = -self._cycle  # start of the last cycle whose dynamic segment has had all its turns
        self.static_frames = 0
        self.dynamic_frames = 0
        self.deferred = 0  # dynamic frames that did not fit before the segment's end (waited a cycle)

    # ------------------------------------------------------------------------------------------ framing
    def _frame_time(self, wire_bits: int, sender: str) -> int:
        tx = super()._frame_time(wire_bits, sender)
        if sender not in self._slots:
            return tx
        if not self._slots[sender] and sender not in self.params.dynamic_ids:
            raise ConfigError(
                f"network '{self.name}': '{sender}' sends but owns no static slot and no dynamic frame ID; add it to "
                f"networks.{self.name}.static_schedule or networks.{self.name}.dynamic_ids",
                path=f"networks.{self.name}.static_schedule")
        if self._slots[sender] and tx > self._slot:
            raise ConfigError(
                f"network '{self.name}': '{sender}' sent a {wire_bits}-bit frame that takes {format_time(tx)}, longer "
                f"than a static slot ({format_time(self._slot)}); lengthen networks.{self.name}.static_slot or send "
                "smaller messages", path=f"networks.{self.name}.static_slot")
        if sender in self.params.dynamic_ids and -(-tx // self._ms) > self._m:
            raise ConfigError(
                f"network '{self.name}': '{sender}' sent a {wire_bits}-bit frame that takes {format_time(tx)}, longer "
                f"than the whole dynamic segment ({self._m} x {format_time(self._ms)}); add minislots or send "
                "smaller messages", path=f"networks.{self.name}.minislots")
        return tx

    # ------------------------------------------------------------------------------------------ access
    def _offer(self, frame: Frame) -> None:
        node = frame.sender
        if not self._push(self.queues[node], frame):
            return
        if self._slots[node] and node not in self._static_wake:
            self._arm_static(node)
        if node in self.params.dynamic_ids and self._dyn_call is None:
            self._arm_dynamic()

    def _next_static(self, node: str, t: int) -> int:
        """Start of the first static slot of ``node`` at or after ``t``."""
        base = (t // self._cycle) * self._cycle
        for off in self._slots[node]:
            if base + off >= t:
                return base + off
        return base + self._cycle + self._slots[node][0]

    def _arm_static(self, node: str, after: int | None = None) -> None:
        now = self.sim.now
        t = self._next_static(node, now if after is None else after)
        self._static_wake[node] = call_later(self.sim, t - now, self._static_turn, node, priority=ARBITRATE)

    def _static_turn(self, node: str) -> None:
        del self._static_wake[node]
        q = self.queues[node]
        if not q._len:
            return
        now = self.sim.now
        frame = q.pop(now)
        self.static_frames += 1
        self._start(frame, now)
        if q._len:
            self._arm_static(node, after=now + 1)

    def _arm_dynamic(self) -> None:
        """Schedule the next dynamic turn a queued frame could take, from an idle segment: in an idle segment
        every ID before it used one minislot, so the turn of ID ``k`` starts ``k - N - 1`` minislots in."""
        now = self.sim.now
        base = max((now // self._cycle) * self._cycle, self._done_base + self._cycle)
        for _ in range(2):
            for fid, node in self._turns:
                ms = fid - self._n_static - 1
                t = base + self._dyn_start + ms * self._ms
                if t >= now:
                    self._dyn_call = call_later(self.sim, t - now, self._dyn_turn, (base, ms, fid, node),
                                                priority=ARBITRATE)
                    return
            base += self._cycle

    def _dyn_turn(self, state: tuple[int, int, int, str]) -> None:
        base, ms, fid, node = state
        self._dyn_call = None
        now = self.sim.now
        q = self.queues[node]
        used = 1
        if q._len:
            frame = q.peek()
            need = max(1, -(-frame.tx_ns // self._ms))
            if ms + need <= self._m:
                q.pop(now)
                self.dynamic_frames += 1
                self._start(frame, now)
                used = need
            else:
                self.deferred += 1
        ms += used
        # the next ID that has an owner: the IDs between them use one minislot each
        for nfid, nnode in self._turns:
            if nfid > fid:
                ms += nfid - fid - 1
                if ms < self._m:
                    t = base + self._dyn_start + ms * self._ms
                    self._dyn_call = call_later(self.sim, t - now, self._dyn_turn, (base, ms, nfid, nnode),
                                                priority=ARBITRATE)
                    return
                break
        # the segment is over: the next cycle's, if a dynamic frame is waiting
        self._done_base = base
        if any(self.queues[n]._len for _, n in self._turns):
            b = base + self._cycle
            fid0, node0 = self._turns[0]
            ms0 = fid0 - self._n_static - 1
            t = b + self._dyn_start + ms0 * self._ms
            self._dyn_call = call_later(self.sim, t - now, self._dyn_turn, (b, ms0, fid0, node0), priority=ARBITRATE)

    def _start(self, frame: Frame, now: int) -> None:
        frame.tx_start_ns = now
        call_later(self.sim, frame.tx_ns, self._end, frame)

    def _end(self, frame: Frame) -> None:
        now = self.sim.now
        start = frame.tx_start_ns if frame.tx_start_ns is not None else now
        self._meter.add(start, now)
        self._transmitted(frame, start, now)

    def _halted(self, node: str, dropped: int) -> None:
        wake = self._static_wake.pop(node, None)
        if wake is not None:
            wake.cancel()

    def _extra_metrics(self, t_end_ns: int) -> dict[str, float]:
        return {"static_frames": float(self.static_frames), "dynamic_frames": float(self.dynamic_frames),
                "deferred": float(self.deferred)}

    def __repr__(self) -> str:
        return f"FlexRayBus(name={self.name!r}, nodes={self.nodes}, cycle={format_time(self._cycle)})"
