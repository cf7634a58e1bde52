"""Parameters every network shares (the base of each network type's ``Params``)."""

from __future__ import annotations

from pydantic import Field, model_validator

from netsim.network.loss import LossSpec
from netsim.network.queues import QueueDiscipline
from netsim.timebase import MS
from netsim.units import Bitrate, Duration, StrictModel, Time

__all__ = ["NodeDelays", "NetworkParams"]


class NodeDelays(StrictModel):
    """Per-node interface delays overriding the network-wide ``pre_delay`` / ``post_delay``."""

    pre_delay: Time | None = None
    post_delay: Time | None = None


class NetworkParams(StrictModel):
    """Common parameters of every network (TrueTime's wired network block plus bounded queues).

    Attributes
    ----------
    nodes
        Names of the nodes on the network (each attached with ``net.attach``).
    bitrate
        Data rate in bit/s (``"80 kbit/s"``).
    min_frame_bits
        Shorter frames are padded to this size, protocol overhead included (TrueTime's minimum frame size).
    max_frame_bits
        Largest message (``bits``) the medium carries; sending a larger one is an error (``None``: no limit).
    pre_delay, post_delay
        Sender and receiver interface (pre-/post-processing) delays, for every node.
    node_delays
        Per-node overrides ``{node: {pre_delay: .., post_delay: ..}}``.
    queue_limit
        Most frames waiting in one node's sender queue; more are dropped (``queue_full``). ``None``: unbounded.
    queue_discipline
        ``fifo`` or ``priority`` (lowest message priority first) in the sender queues.
    loss_probability
        Independent loss probability of each copy (TrueTime); or give ``loss`` for another model. Drawn after
        the transmission; on the radios per attempt, before the ACK, so a lost frame is retried (docs/loss.md).
    loss
        ``{model: bernoulli, p: ..}`` or ``{model: gilbert_elliott, p_good_to_bad: .., p_bad_to_good: ..,
        loss_good: 0, loss_bad: 1}``.
    drop_stale
        Receivers discard a message older (by per-pair sequence number) than one already delivered.
    record_messages
        Keep one :class:`~netsim.network.records.MessageRecord` per copy in ``net.records`` (turn off for
        very long runs; the metrics are kept either way).
    utilization_bin
        Bin width of the utilization-over-time series.
    """

    nodes: list[str] = Field(min_length=1, description="names of the nodes on the network")
    bitrate: Bitrate = Field(description="data rate ('80 kbit/s')")
    min_frame_bits: int = Field(0, ge=0, description="shorter frames are padded to this size, overhead included")
    max_frame_bits: int | None = Field(None, gt=0, description="largest message the medium carries (null: no limit)")
    pre_delay: Time = Field(0, description="sender interface (pre-processing) delay, every node")
    post_delay: Time = Field(0, description="receiver interface (post-processing) delay, every node")
    node_delays: dict[str, NodeDelays] = Field(
        default_factory=dict, description="per-node overrides {node: {pre_delay: .., post_delay: ..}}")
    queue_limit: int | None = Field(1000, ge=1, description="most frames waiting in one sender queue; more are "
                                                            "dropped as queue_full (null: unbounded)")
    queue_discipline: QueueDiscipline = Field("fifo", description="sender queue order: fifo, or priority (lowest "
                                                                  "message priority first)")
    loss_probability: float = Field(0.0, ge=0.0, le=1.0, description="independent loss probability of each copy")
    loss: LossSpec | None = Field(None, description="loss model instead of loss_probability: {model: bernoulli, "
                                                    "p: ..} or {model: gilbert_elliott, ..} (docs/loss.md)")
    drop_stale: bool = Field(False, description="receivers discard a message older than one already delivered")
    record_messages: bool = Field(True, description="keep one record per message copy (messages.csv)")
    utilization_bin: Duration = Field(10 * MS, description="bin width of the utilization-over-time series")

    @model_validator(mode="after")
    def _check_common(self) -> "NetworkParams":
        seen: set[str] = set()
        for n in self.nodes:
            if n in seen:
                raise ValueError(f"nodes: '{n}' is listed twice")
            seen.add(n)
        for n in self.node_delays:
            if n not in seen:
                raise ValueError(f"node_delays: '{n}' is not one of the network's nodes {self.nodes}")
        if self.loss is not None and self.loss_probability > 0:
            raise ValueError("give either loss_probability or loss, not both")
        raw_frames = getattr(self, "frame_format", "raw") == "raw"  # CAN data-field limits are not frame sizes
        if raw_frames and self.max_frame_bits is not None and self.max_frame_bits < self.min_frame_bits:
            raise ValueError(
                f"max_frame_bits ({self.max_frame_bits}) is smaller than min_frame_bits ({self.min_frame_bits})"
            )
        return self

    def pre_delay_of(self, node: str) -> int:
        """Sender interface delay of ``node`` (ns)."""
        d = self.node_delays.get(node)
        return self.pre_delay if d is None or d.pre_delay is None else d.pre_delay

    def post_delay_of(self, node: str) -> int:
        """Receiver interface delay of ``node`` (ns)."""
        d = self.node_delays.get(node)
        return self.post_delay if d is None or d.post_delay is None else d.post_delay
