"""The message that travels on every network, and the contract between networks and kernels.

Contract
--------
A network is attached to nodes (kernels) by name. A kernel's ``send`` request builds a :class:`Message`
and calls ``network.send(msg)`` at the instant the sending job's segment runs. The network delivers each
surviving copy by calling the receiving side's ``deliver(network_name, msg)`` (the kernel puts it in the
node's receive queue for that network and fires its receive handler or releases the task bound to it).
Broadcast messages (``receiver is None``) reach every attached node except the sender; each copy is a
separate loss draw.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Protocol

__all__ = ["Message", "Receiver", "BROADCAST"]

BROADCAST = None


@dataclass(slots=True)
class Message:
    """A frame in flight.

    Attributes
    ----------
    sender, receiver
        Node names; ``receiver`` is ``None`` for broadcast.
    payload
        Any Python object (a number, an array, a control packet).
    bits
        Payload size in bits before padding to the medium's minimum frame size.
    priority
        Lower number = more urgent (CAN identifiers, priority queues).
    msg_id
        Unique id per message within a run, assigned by the sender from ``env.next_id("msg")`` so it is
        reproducible (copies of a broadcast share it).
    network
        Name of the network carrying it (filled by the network).
    sent_ns
        Time the sender's job issued ``send``.
    seq
        Per (sender, receiver, network) sequence number, used to drop stale out-of-order packets.
    tag
        Free label used in tables (e.g. ``"y"``, ``"u"``); defaults to the sending task's name.
    delivered_ns, dropped, drop_reason
        Filled as the message goes through the pipeline.
    tx_start_ns, tx_end_ns
        When the frame's first bit went on the medium and when its transmission ended (filled by the network;
        ``None`` while queued, or when the frame never reached the medium).
    """

    sender: str
    receiver: str | None
    payload: Any
    bits: int
    priority: int = 0
    msg_id: int = -1
    network: str = ""
    sent_ns: int = 0
    seq: int = 0
    tag: str = ""
    delivered_ns: int | None = None
    dropped: bool = False
    drop_reason: str = ""
    tx_start_ns: int | None = None
    tx_end_ns: int | None = None

    def copy_for(self, receiver: str) -> "Message":
        """A copy addressed to ``receiver`` (broadcast fan-out)."""
        return replace(self, receiver=receiver)


class Receiver(Protocol):
    """What a network calls to hand a message to a node (implemented by the kernel)."""

    def deliver(self, network: str, msg: Message) -> None:
        """Accept ``msg`` arriving on ``network`` at the current simulation time."""
