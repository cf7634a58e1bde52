"""The pipeline every medium shares, and the :class:`Network` base class.

A message goes through these stages (TrueTime's wired network block, plus bounded queues)::

    send -> sender pre-processing delay -> sender queue (FIFO or priority, bounded)
         -> medium access and transmission at the data rate (frame padded to min_frame_bits)
         -> loss draw (after transmission: a lost frame still used the medium; one draw per receiver copy;
            the wireless media draw it per attempt before the ACK, so a lost frame is retried: docs/loss.md)
         -> receiver post-processing delay -> stale filter (optional) -> receiver.deliver(network, msg)

Subclasses model the medium access (CAN arbitration, TDMA slots, CSMA/CD collisions ...) by implementing
:meth:`Network._offer`, which receives each frame when its pre-processing delay is over, and call
:meth:`Network._transmitted` when a frame has been sent. The "receiver queue" is the receiving kernel's
inbox for the network (``Kernel.deliver`` puts the message there and fires the receive handler).

Statistics are kept as the simulation runs: one :class:`~netsim.network.records.MessageRecord` per receiver
copy in :attr:`Network.records`, queue lengths per node, busy time per channel, drop counts per reason.

Why this module is long: the :class:`Network` base is one state machine (pre-delay, queue, medium,
post-delay, loss) whose stages share the per-node queues, records and statistics, and :class:`Transmitter` is
the half of it every medium drives; split, one message's life would be spread over several files.
"""

from __future__ import annotations

import abc
import logging
from heapq import heappush
from dataclasses import dataclass
from typing import Any, Callable, ClassVar, Generic, TypeVar

from netsim.env import ARBITRATE, NORMAL, SimEnv
from netsim.errors import ConfigError
from netsim.network.loss import make_loss
from netsim.network.message import Message, Receiver
from netsim.network.params import NetworkParams
from netsim.network.queues import SendQueue
from netsim.network.records import (
    DROP_LOST,
    DROP_NO_RECEIVER,
    DROP_QUEUE_FULL,
    DROP_SENDER_DEAD,
    DROP_STALE,
    MessageRecord,
)
from netsim.network.stats import BusyMeter
from netsim.network.timing import tx_time_ns
from netsim.timebase import S

__all__ = ["Frame", "Network", "Transmitter"]

log = logging.getLogger(__name__)

Copy = tuple[Message, MessageRecord]

#: The ``Params`` type of a medium: ``class CanBus(Network["CanBus.Params"])`` types ``self.params``.
P = TypeVar("P", bound=NetworkParams)


@dataclass(slots=True, eq=False)
class Frame:
    """One transmission unit: a sent message and the receiver copies it carries.

    Attributes
    ----------
    msg
        The message as sent (``receiver`` may be ``None`` for broadcast).
    copies
        ``(message, record)`` per receiver; the message object is the one the receiver gets.
    sender, priority
        From the message.
    wire_bits
        Bits on the medium (padded to the minimum frame, plus protocol overhead where modelled).
    tx_ns
        Transmission time at the network's data rate.
    order
        Network-wide arrival counter: FIFO tie-break among equal priorities.
    tx_start_ns
        When the first bit went out (set by the medium).
    attempts
        Collisions suffered so far (CSMA/CD).
    """

    msg: Message
    copies: list[Copy]
    sender: str
    priority: int
    wire_bits: int
    tx_ns: int
    order: int
    tx_start_ns: int | None = None
    attempts: int = 0


class Network(abc.ABC, Generic[P]):
    """Base of every network model (see the module docstring for the pipeline).

    Parameters
    ----------
    env
        The simulation environment.
    name
        Network name (scenario key); random streams are ``network.<name>.<purpose>``.
    params
        A validated ``Params`` of the concrete class (the class's type parameter ``P``).

    Attributes
    ----------
    records : list[MessageRecord]
        One record per receiver copy (empty when ``record_messages`` is off).
    queues : dict[str, SendQueue]
        The sender queue of each node.
    meters : dict[str, BusyMeter]
        Busy-time accounting per channel (``"bus"`` for shared media).
    """

    Params: ClassVar[type[NetworkParams]] = NetworkParams
    #: How :meth:`utilization` combines the channels: "single", "max" (busiest) or "weighted" (sum of shares).
    utilization_mode: ClassVar[str] = "single"
    #: Drop reasons this medium can produce (reported in the metrics even when zero).
    drop_reasons: ClassVar[tuple[str, ...]] = (DROP_QUEUE_FULL, DROP_LOST, DROP_STALE, DROP_NO_RECEIVER)

    def __init__(self, env: SimEnv, name: str, params: P) -> None:
        if not isinstance(params, self.Params):
            raise TypeError(f"{type(self).__name__} needs {self.Params.__qualname__}, got {type(params).__name__}")
        self.env = env
        self.sim = env.sim
        self.name = name
        self.params: P = params
        self.nodes: list[str] = list(params.nodes)
        self._node_set = set(self.nodes)
        self._receivers: dict[str, Receiver] = {}
        self._pre: dict[str, int] = {n: params.pre_delay_of(n) for n in self.nodes}
        self._post: dict[str, int] = {n: params.post_delay_of(n) for n in self.nodes}
        self.queues: dict[str, SendQueue] = {
            n: SendQueue(params.queue_limit, params.queue_discipline) for n in self.nodes
        }
        self.records: list[MessageRecord] = []
        self._keep = bool(params.record_messages)
        self._seq: dict[tuple[str, str | None], int] = {}
        self._last_seq: dict[tuple[str, str], int] = {}
        self._drop_stale = bool(params.drop_stale)
        self._loss = make_loss(params.loss, params.loss_probability, env.rng(f"network.{name}.loss"))
        self._order = 0
        self.meters: dict[str, BusyMeter] = {}
        self.n_frames = 0
        self.n_copies = 0
        self.n_delivered = 0
        self._delay_sum = 0
        self._delay_max = 0
        self.drops: dict[str, int] = {r: 0 for r in self.drop_reasons}
        self._warned: set[str] = set()
        self._dead: set[str] = set()  # nodes stopped for good (halt_node): their frames do not go
        # (wire bits, transmission time) by (payload bits, sender): what wire_bits and _frame_time give, which
        # depend on nothing else (a subclass whose framing also depends on the message must clear this cache)
        self._framing: dict[tuple[int, str], tuple[int, int]] = {}
        # deliveries and pre-processing ends are call items pushed inline on the loop's heap (netsim.env): no
        # Call object, no indirection through it
        _, self._heap, self._ids = self.sim.scheduler()
        self._deliver_item = self._deliver
        self._offer_item = self._offer_after_pre
        self._setup()

    # ------------------------------------------------------------------------------------------ public API
    def attach(self, node: str, receiver: Receiver, *, pre_delay: int | None = None, post_delay: int | None = None) -> None:
        """Connect ``receiver`` (a kernel) as node ``node``; optional interface delays override the params.

        Raises
        ------
        ConfigError
            If ``node`` is not in the network's ``nodes`` or already attached, or a delay is negative.
        """
        if node not in self._node_set:
            raise ConfigError(
                f"network '{self.name}': cannot attach '{node}', it is not in the network's nodes "
                f"{self.nodes}; add it to networks.{self.name}.nodes",
                path=f"networks.{self.name}.nodes",
            )
        if node in self._receivers:
            raise ConfigError(f"network '{self.name}': node '{node}' is attached twice")
        if not callable(getattr(receiver, "deliver", None)):
            raise ConfigError(f"network '{self.name}': the receiver of '{node}' has no deliver(network, msg) method")
        for label, value in (("pre_delay", pre_delay), ("post_delay", post_delay)):
            if value is not None and int(value) < 0:
                raise ConfigError(f"network '{self.name}': {label} of '{node}' must be >= 0, got {value}")
        self._receivers[node] = receiver
        if pre_delay is not None:
            self._pre[node] = int(pre_delay)
        if post_delay is not None:
            self._post[node] = int(post_delay)

    @property
    def receivers(self) -> dict[str, Receiver]:
        """Attached receivers by node name."""
        return dict(self._receivers)

    def send(self, msg: Message) -> None:
        """Hand ``msg`` to the network now (called by the sender's kernel; never blocks).

        Stamps ``msg.network``, ``msg.sent_ns``, ``msg.msg_id`` (if unset) and ``msg.seq``. A broadcast
        (``receiver=None``) reaches every attached node except the sender, each copy with its own loss draw.

        Raises
        ------
        ConfigError
            Sender or receiver not on this network, or a message larger than the medium carries.
        """
        sender = msg.sender
        if sender not in self._node_set:
            raise ConfigError(
                f"network '{self.name}': sender '{sender}' is not on this network (nodes: {self.nodes})"
            )
        receiver = msg.receiver
        if receiver is not None and receiver not in self._node_set:
            raise ConfigError(
                f"network '{self.name}': '{sender}' sent to unknown receiver '{receiver}'; "
                f"the network's nodes are {self.nodes} (or use None for broadcast)"
            )
        bits = msg.bits
        if type(bits) is not int or bits < 0:
            if not isinstance(bits, int) or isinstance(bits, bool) or bits < 0:
                raise ConfigError(f"network '{self.name}': '{sender}' sent a message of {bits!r} bits; use an int >= 0")
        framing = self._framing.get((bits, sender))
        if framing is None:  # wire bits and transmission time depend on (bits, sender) only: computed once
            wire = self.wire_bits(msg)
            framing = self._framing[(bits, sender)] = (wire, self._frame_time(wire, sender))
        now = self.sim.now
        msg.network = name = self.name
        msg.sent_ns = now
        if msg.msg_id < 0:
            counters = self.env._counters  # self.env.next_id("msg"), inlined
            msg.msg_id = counters.get("msg", 0)
            counters["msg"] = msg.msg_id + 1
        seqs = self._seq
        key = (sender, receiver)
        msg.seq = seq = seqs.get(key, -1) + 1
        seqs[key] = seq
        copies: list[Copy]
        if receiver is not None:
            # self._record(msg), inlined
            rec = MessageRecord(msg.msg_id, name, sender, receiver, msg.tag, bits, msg.priority, now)
            if self._keep:
                self.records.append(rec)
            copies = [(msg, rec)]
            if receiver not in self._receivers:
                self._drop_copy(copies[0], DROP_NO_RECEIVER)
                if receiver not in self._warned:
                    self._warned.add(receiver)
                    log.warning("network '%s': node '%s' has no receiver attached; its messages are dropped",
                                self.name, receiver)
                return
        else:
            copies = []
            for node in self._receivers:
                if node == sender:
                    continue
                c = msg.copy_for(node)
                k = (sender, node)
                c.seq = seqs.get(k, -1) + 1
                seqs[k] = c.seq
                copies.append((c, self._record(c)))
        self._order += 1
        frame = Frame(msg, copies, sender, msg.priority, framing[0], framing[1], self._order)
        self.n_frames += 1
        self.n_copies += len(copies)
        if self._dead and sender in self._dead:
            self._drop_frame(frame, DROP_SENDER_DEAD)
            return
        pre = self._pre[sender]
        if pre:
            heappush(self._heap, (now + pre, NORMAL, next(self._ids), (self._offer_item, frame)))
        else:
            self._offer(frame)

    def halt_node(self, node: str) -> None:
        """``node`` stopped for good (its battery ran out, :mod:`netsim.energy`): its frames do not go.

        The frames in its sender queue are dropped now (``sender_dead``), and so is every frame of it that is
        still in its pre-processing delay when that ends, or that it hands over later. A frame already on the
        medium finishes its transmission; a medium whose MAC holds a frame waiting for channel access drops it
        too (:meth:`_halted`). Calling it again does nothing.
        """
        if node not in self._node_set or node in self._dead:
            return
        self._dead.add(node)
        q = self.queues[node]
        now = self.sim.now
        n = 0
        while q._len:
            self._drop_frame(q.pop(now), DROP_SENDER_DEAD)
            n += 1
        self._halted(node, n)

    def utilization(self, t_end_ns: int) -> float:
        """Fraction of ``[0, t_end_ns]`` the medium carried frames (see ``utilization_mode``)."""
        if not self.meters or t_end_ns <= 0:
            return 0.0
        fr = [m.fraction(t_end_ns) for m in self.meters.values()]
        if self.utilization_mode == "weighted":
            return sum(m.weight * f for m, f in zip(self.meters.values(), fr))
        return max(fr)

    def utilization_series(self, t_end_ns: int) -> list[tuple[int, float]]:
        """Utilization per bin of ``utilization_bin``: ``[(bin_start_ns, fraction), ...]``."""
        if not self.meters or t_end_ns <= 0:
            return []
        bin_ns = self.params.utilization_bin
        meters = list(self.meters.values())
        if self.utilization_mode == "weighted":
            per = [m.series(t_end_ns) for m in meters]
            values = [sum(m.weight * s[k] for m, s in zip(meters, per)) for k in range(len(per[0]))]
        else:
            busiest = max(meters, key=lambda m: m.busy(t_end_ns))
            values = busiest.series(t_end_ns)
        return [(k * bin_ns, v) for k, v in enumerate(values)]

    def metrics(self, t_end_ns: int) -> dict[str, float]:
        """Summary statistics of the run up to ``t_end_ns`` (times in seconds, keys without the net name).

        Keys: ``utilization``, ``frames``, ``copies``, ``delivered``, ``in_flight``, ``dropped``,
        ``dropped.<reason>``, ``loss_rate`` (dropped / copies), ``mean_delay_s``, ``max_delay_s``,
        ``queue_max.<node>``, ``queue_mean.<node>`` (time-averaged), ``utilization.<channel>`` for media
        with several channels, and type-specific counters.
        """
        dropped = sum(self.drops.values())
        out: dict[str, float] = {
            "utilization": float(self.utilization(t_end_ns)),
            "frames": float(self.n_frames),
            "copies": float(self.n_copies),
            "delivered": float(self.n_delivered),
            "in_flight": float(self.n_copies - self.n_delivered - dropped),
            "dropped": float(dropped),
            "loss_rate": dropped / self.n_copies if self.n_copies else 0.0,
            "mean_delay_s": (self._delay_sum / self.n_delivered / S) if self.n_delivered else float("nan"),
            "max_delay_s": (self._delay_max / S) if self.n_delivered else float("nan"),
        }
        for reason, n in self.drops.items():
            out[f"dropped.{reason}"] = float(n)
        for node, q in self.queues.items():
            out[f"queue_max.{node}"] = float(q.max_len)
            out[f"queue_mean.{node}"] = float(q.mean_len(t_end_ns))
        if len(self.meters) > 1:
            for ch, m in self.meters.items():
                out[f"utilization.{ch}"] = float(m.fraction(t_end_ns))
        out.update(self._extra_metrics(t_end_ns))
        return out

    def __repr__(self) -> str:
        return f"{type(self).__name__}(name={self.name!r}, nodes={self.nodes})"

    # ------------------------------------------------------------------------------------------ subclass hooks
    def _setup(self) -> None:
        """Build the medium's runtime state (called at the end of ``__init__``)."""

    def wire_bits(self, msg: Message) -> int:
        """Bits ``msg`` occupies on the medium; raises ConfigError for messages larger than the medium allows.

        The result may depend on ``msg.bits`` only: :meth:`send` computes it once per (bits, sender).
        """
        mx = self.params.max_frame_bits
        if mx is not None and msg.bits > mx:
            self._too_large(msg, mx)
        return max(msg.bits, self.params.min_frame_bits)

    def _frame_time(self, wire_bits: int, sender: str) -> int:
        """Transmission time of a frame of ``wire_bits`` sent by ``sender`` (computed once per pair, as
        :meth:`wire_bits`)."""
        return tx_time_ns(wire_bits, self.params.bitrate)

    @abc.abstractmethod
    def _offer(self, frame: Frame) -> None:
        """The frame's pre-processing delay is over: queue it and let the medium act."""

    def _extra_metrics(self, t_end_ns: int) -> dict[str, float]:
        """Type-specific metrics added to :meth:`metrics`."""
        return {}

    def _halted(self, node: str, dropped: int) -> None:
        """:meth:`halt_node` emptied ``node``'s sender queue (``dropped`` frames): drop what the medium holds of
        it besides (a frame waiting for channel access) and fix its own counters."""

    # ------------------------------------------------------------------------------------------ helpers
    def _offer_after_pre(self, item: tuple[Any, Frame]) -> None:
        """The call item ``(fn, frame)`` of the end of a frame's pre-processing delay: offer the frame, unless the
        sender halted meanwhile."""
        frame = item[1]
        if self._dead and frame.sender in self._dead:
            self._drop_frame(frame, DROP_SENDER_DEAD)
            return
        self._offer(frame)

    def _too_large(self, msg: Message, limit: int, what: str = "max_frame_bits") -> None:
        raise ConfigError(
            f"network '{self.name}': '{msg.sender}' sent a {msg.bits}-bit message (tag '{msg.tag}') but the "
            f"medium carries at most {limit} bits per frame ({what}); split the message or raise "
            f"networks.{self.name}.{what}",
            path=f"networks.{self.name}.{what}",
        )

    def _record(self, msg: Message) -> MessageRecord:
        rec = MessageRecord(msg.msg_id, self.name, msg.sender, msg.receiver, msg.tag, msg.bits, msg.priority,
                            msg.sent_ns)
        if self._keep:
            self.records.append(rec)
        return rec

    def _push(self, queue: SendQueue, frame: Frame, *, front: bool = False) -> bool:
        """Put ``frame`` in ``queue``; if the queue is full, drop all its copies (``queue_full``)."""
        now = self.sim.now
        ok = queue.push_front(frame, now) if front else queue.push(frame, now)
        if not ok:
            self._drop_frame(frame, DROP_QUEUE_FULL)
        return ok

    def _drop_copy(self, copy: Copy, reason: str) -> None:
        msg, rec = copy
        msg.dropped = rec.dropped = True
        msg.drop_reason = rec.drop_reason = reason
        self.drops[reason] = self.drops.get(reason, 0) + 1

    def _drop_frame(self, frame: Frame, reason: str) -> None:
        for c in frame.copies:
            self._drop_copy(c, reason)

    def _transmitted(self, frame: Frame, start: int, end: int, *, sync: bool = True, draw_loss: bool = True) -> None:
        """``frame`` occupied the medium in ``[start, end]``: loss draw, post-delay, delivery of each copy.

        ``sync`` allows delivering in the current callback when no delay remains (only from event callbacks,
        never from inside ``send``). ``draw_loss`` False: the medium already drew the loss of these copies
        (the wireless media draw it per attempt, before the ACK; see docs/loss.md).
        """
        loss = self._loss if draw_loss else None
        post = self._post
        sender = frame.sender
        sim = self.sim
        deliver = self._deliver_item
        for copy in frame.copies:
            msg, rec = copy
            msg.tx_start_ns = rec.tx_start_ns = start
            msg.tx_end_ns = rec.tx_end_ns = end
            if loss is not None and loss.lost((sender, msg.receiver)):  # type: ignore[arg-type]
                self._drop_copy(copy, DROP_LOST)
                continue
            d = post[msg.receiver]  # type: ignore[index]
            item = (deliver, copy)
            if d == 0 and sync:
                deliver(item)
            else:
                heappush(self._heap, (sim.now + d, NORMAL, next(self._ids), item))

    def _deliver(self, item: tuple[Any, Copy]) -> None:
        """Hand a copy to its receiver now: ``item`` is the call item ``(self._deliver_item, copy)``, processed by
        the event loop at the copy's arrival or called directly when it arrives at once."""
        copy = item[1]
        msg, rec = copy
        node = msg.receiver
        if self._drop_stale:
            key = (msg.sender, node)
            if msg.seq <= self._last_seq.get(key, -1):  # type: ignore[arg-type]
                self._drop_copy(copy, DROP_STALE)
                return
            self._last_seq[key] = msg.seq  # type: ignore[index]
        now = self.sim.now
        msg.delivered_ns = rec.delivered_ns = now
        delay = now - msg.sent_ns
        rec.delay_ns = delay
        self.n_delivered += 1
        self._delay_sum += delay
        if delay > self._delay_max:
            self._delay_max = delay
        self._receivers[node].deliver(self.name, msg)  # type: ignore[index]


class Transmitter:
    """A serial output (one node's link, an FDMA sub-channel, a switch port): one frame at a time.

    Parameters
    ----------
    net
        The owning network (event loop, drops).
    queue
        Frames waiting for this output.
    rate_bps
        Data rate of the output.
    meter
        Busy-time accounting of the output.
    on_done
        ``on_done(frame, start_ns, end_ns)`` after each transmission.
    """

    __slots__ = ("net", "sim", "queue", "rate", "meter", "on_done", "busy", "_pending", "_tx_ns", "_heap", "_ids")

    def __init__(
        self,
        net: Network,
        queue: SendQueue,
        rate_bps: float,
        meter: BusyMeter,
        on_done: Callable[[Frame, int, int], None],
    ) -> None:
        self.net = net
        self.sim = net.sim
        self.queue = queue
        self.rate = float(rate_bps)
        self.meter = meter
        self.on_done = on_done
        self.busy = False
        self._pending = False
        self._tx_ns: dict[int, int] = {}  # tx_time_ns(wire_bits, rate) by wire_bits
        _, self._heap, self._ids = self.sim.scheduler()  # transmission ends are pushed inline (netsim.env)

    def offer(self, frame: Frame, *, front: bool = False) -> bool:
        """Queue ``frame`` (dropped as ``queue_full`` if the queue is full) and start sending if idle."""
        q = self.queue
        if not (self.busy or self._pending or q._len or q.priority) and (q.limit is None or q.limit > 0):
            # idle output, empty FIFO queue: what push + pop would do, without the queue round trip (the
            # frame counts as queued for an instant, as it did, so max_len becomes at least 1)
            now = self.sim.now
            q._last_t = now  # the length-time integral gains nothing: the queue was empty
            if q.max_len < 1:
                q.max_len = 1
            self._begin(frame, now)
            return True
        if not self.net._push(q, frame, front=front):
            return False
        self._kick()
        return True

    def _kick(self) -> None:
        if self.busy or self._pending:
            return
        if self.queue.priority:
            # let every frame queued in this instant compete on priority
            self._pending = True
            heappush(self._heap, (self.sim.now, ARBITRATE, next(self._ids), (self._start, None)))
        else:
            self._start(None)

    def _start(self, _: Any) -> None:
        self._pending = False
        if self.busy or not self.queue._len:
            return
        now = self.sim.now
        self._begin(self.queue.pop(now), now)

    def _begin(self, frame: Frame, now: int) -> None:
        """Put ``frame`` on the output now; its end is a call item ``(_done, frame, now)``."""
        self.busy = True
        self.meter.open_since = now  # meter.start(now)
        tx = self._tx_ns.get(frame.wire_bits)
        if tx is None:
            tx = self._tx_ns[frame.wire_bits] = tx_time_ns(frame.wire_bits, self.rate)
        heappush(self._heap, (now + tx, NORMAL, next(self._ids), (self._done, frame, now)))

    def _done(self, item: tuple) -> None:
        """The call item of a transmission's end: ``(_done, frame, start_ns)``."""
        _, frame, start = item
        now = self.sim.now
        meter = self.meter
        meter.open_since = None  # meter.stop(now), inlined
        if now > start:  # meter.add(start, now), inlined
            meter.total += now - start
            meter._intervals.append((start, now))
        self.busy = False
        self.on_done(frame, start, now)
        if self.queue._len:
            self._kick()
