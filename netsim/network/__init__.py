"""Networks: how messages travel between nodes (TrueTime's wired network block and simple links).

Build one with :func:`make_network` (``type_name`` registered under kind ``"network"``), attach each node's
receiver with :meth:`Network.attach`, and let kernels call :meth:`Network.send`. Every medium shares the
pipeline in :mod:`netsim.network.pipeline`; the modules :mod:`~netsim.network.link`,
:mod:`~netsim.network.can`, :mod:`~netsim.network.tdma`, :mod:`~netsim.network.csma_cd`,
:mod:`~netsim.network.ethernet`, :mod:`~netsim.network.round_robin`, :mod:`~netsim.network.fdma` and
:mod:`~netsim.network.wireless` (IEEE 802.15.4 and 802.11b radios) model the media.

A new medium is one module here with a ``@register("network", NAME)`` class (copy
:mod:`~netsim.network.fdma`, the smallest): :func:`netsim.registry.load_plugins` imports every module of this
package, so it registers without being imported below; export it here only if Python users need its class.
"""

from netsim.network.can import CanBus, can_frame_bits
from netsim.network.csma_cd import CsmaCdBus
from netsim.network.delay import DelaySpec
from netsim.network.ethernet import SwitchedEthernet
from netsim.network.fdma import FdmaMedium
from netsim.network.factory import make_network, network_class
from netsim.network.link import Link
from netsim.network.message import BROADCAST, Message, Receiver
from netsim.network.params import NetworkParams, NodeDelays
from netsim.network.pipeline import Frame, Network
from netsim.network.loss import LossSpec
from netsim.network.records import DROP_REASONS, MessageRecord
from netsim.network.round_robin import RoundRobinBus
from netsim.network.tdma import TdmaBus
from netsim.network.ieee802154 import Ieee802154
from netsim.network.ieee80211b import Ieee80211b
from netsim.network.wireless import WirelessMedium

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
    "DelaySpec",
    "LossSpec",
    "Link",
    "CanBus",
    "can_frame_bits",
    "TdmaBus",
    "CsmaCdBus",
    "SwitchedEthernet",
    "RoundRobinBus",
    "FdmaMedium",
    "WirelessMedium",
    "Ieee802154",
    "Ieee80211b",
]
