"""What a network remembers about each message copy, and the reasons a copy can be dropped.

One :class:`MessageRecord` is kept per receiver copy (a broadcast to three nodes gives three records that share
``msg_id``). The results layer turns ``net.records`` into ``messages.csv`` (times converted to seconds).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

__all__ = [
    "MessageRecord",
    "DROP_LOST",
    "DROP_QUEUE_FULL",
    "DROP_STALE",
    "DROP_SWITCH_FULL",
    "DROP_COLLISIONS",
    "DROP_NO_RECEIVER",
    "DROP_OUT_OF_RANGE",
    "DROP_INTERFERENCE",
    "DROP_NO_ACK",
    "DROP_CHANNEL_ACCESS",
    "DROP_SENDER_DEAD",
    "DROP_REASONS",
]

#: Lost on the medium (loss model draw after transmission; the frame still used the medium).
DROP_LOST: Final[str] = "lost"
#: The sender's queue was full when the frame arrived (after the pre-processing delay).
DROP_QUEUE_FULL: Final[str] = "queue_full"
#: Arrived after a newer message of the same sender (``drop_stale`` receivers only).
DROP_STALE: Final[str] = "stale"
#: The Ethernet switch had no memory left (overflow ``drop``).
DROP_SWITCH_FULL: Final[str] = "switch_full"
#: CSMA/CD gave up after ``max_attempts`` collisions.
DROP_COLLISIONS: Final[str] = "collisions"
#: Addressed to a node on the network that has no receiver attached.
DROP_NO_RECEIVER: Final[str] = "no_receiver"
#: Wireless: the power received was below the receiver threshold (a broadcast copy; unicast frames are retried).
DROP_OUT_OF_RANGE: Final[str] = "out_of_range"
#: Wireless: other transmissions overlapped the copy (signal-to-interference-and-noise ratio too low), or the
#: receiver was transmitting itself (a broadcast copy).
DROP_INTERFERENCE: Final[str] = "interference"
#: Wireless: no acknowledgement after the last retry.
DROP_NO_ACK: Final[str] = "no_ack"
#: Wireless (802.15.4): the channel was busy at every clear channel assessment allowed.
DROP_CHANNEL_ACCESS: Final[str] = "channel_access"
#: The sender stopped for good (its battery ran out, :meth:`Network.halt_node`) with the frame still queued, in its
#: pre-processing delay, or waiting for channel access: a halted node's frames do not go.
DROP_SENDER_DEAD: Final[str] = "sender_dead"
#: Every drop reason a network can report.
DROP_REASONS: Final[tuple[str, ...]] = (
    DROP_LOST,
    DROP_QUEUE_FULL,
    DROP_STALE,
    DROP_SWITCH_FULL,
    DROP_COLLISIONS,
    DROP_NO_RECEIVER,
    DROP_OUT_OF_RANGE,
    DROP_INTERFERENCE,
    DROP_NO_ACK,
    DROP_CHANNEL_ACCESS,
    DROP_SENDER_DEAD,
)


@dataclass(slots=True, eq=False)
class MessageRecord:
    """The life of one receiver copy of a message (all times integer nanoseconds).

    Attributes
    ----------
    msg_id, network, sender, receiver, tag, bits, priority
        Copied from the :class:`~netsim.network.message.Message` (``receiver`` is the copy's receiver).
    sent_ns
        When the sender issued ``send``.
    tx_start_ns, tx_end_ns
        First bit on the medium and end of the transmission that carried this copy (for switched Ethernet:
        start on the sender's uplink, end on the receiver's downlink). ``None`` if it never got there.
    delivered_ns
        When the receiver got it (``None`` if dropped or still in flight at the end of the run).
    dropped, drop_reason
        Whether and why it was dropped (one of :data:`DROP_REASONS`).
    delay_ns
        ``delivered_ns - sent_ns`` for delivered copies, else ``None``.
    """

    msg_id: int
    network: str
    sender: str
    receiver: str | None
    tag: str
    bits: int
    priority: int
    sent_ns: int
    tx_start_ns: int | None = None
    tx_end_ns: int | None = None
    delivered_ns: int | None = None
    dropped: bool = False
    drop_reason: str = ""
    delay_ns: int | None = None
