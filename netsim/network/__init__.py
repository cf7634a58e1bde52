"""Networks: how messages travel between nodes (TrueTime's wired network block and simple links).

Build one with :func:`make_network` (``type_name`` registered under kind ``"network"``), attach each node's
receiver with :meth:`Network.attach`, and let kernels call :meth:`Network.send`. Every medium shares the
pipeline in :mod:`netsim.network.pipeline`; the modules :mod:`~netsim.network.link`,
:mod:`~netsim.network.can`, :mod:`~netsim.network.tdma`, :mod:`~netsim.network.csma_cd`,
:mod:`~netsim.network.ethernet`, :mod:`~netsim.network.round_robin` and :mod:`~netsim.network.fdma` model
the media.
"""

from netsim.network.can import CanBus, can_frame_bits
from netsim.network.factory import make_network, network_class
from netsim.network.link import Link
from netsim.network.message import BROADCAST, Message, Receiver
from netsim.network.params import NetworkParams, NodeDelays
from netsim.network.pipeline import Frame, Network
from netsim.network.records import DROP_REASONS, MessageRecord

__all__ = [
    "make_network",
    "network_class",
    "Network",
    "NetworkParams",
    "NodeDelays",
    "Frame",
    "Message",
    "Receiver",
    "BROADCAST",
    "MessageRecord",
    "DROP_REASONS",
    "Link",
    "CanBus",
    "can_frame_bits",
]
