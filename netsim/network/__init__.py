"""Networks: how messages travel between nodes (TrueTime's wired network block and simple links).

Build one with :func:`make_network` (``type_name`` registered under kind ``"network"``), attach each node's
receiver with :meth:`Network.attach`, and let kernels call :meth:`Network.send`. Every medium shares the
pipeline in :mod:`netsim.network.pipeline`; the modules :mod:`~netsim.network.link`,
:mod:`~netsim.network.can`, :mod:`~netsim.network.tdma`, :mod:`~netsim.network.csma_cd`,
:mod:`~netsim.network.ethernet`, :mod:`~netsim.network.round_robin`, :mod:`~netsim.network.fdma`,
:mod:`~netsim.network.flexray` (static TDMA slots and a dynamic minislot segment) and
:mod:`~netsim.network.wireless` (IEEE 802.15.4 and 802.11b radios) model the media.

A new medium is one module here with a ``@register("network", NAME)`` class (copy
:mod:`~netsim.network.fdma`, the smallest): :func:`netsim.registry.load_plugins` imports every module of this
package, so it registers without being imported below; export it here only if Python users need its class.
"""

from netsim.lazy_import import lazy_exports

#: Exported name -> the module that defines it, imported at first use (issue 19: importing one medium or one
#: control law must not import them all; the registry imports a plugin's own module).
_EXPORTS = {
    "CanBus": "netsim.network.can",
    "can_frame_bits": "netsim.network.can",
    "CsmaCdBus": "netsim.network.csma_cd",
    "DelaySpec": "netsim.network.delay",
    "SwitchedEthernet": "netsim.network.ethernet",
    "FdmaMedium": "netsim.network.fdma",
    "FlexRayBus": "netsim.network.flexray",
    "make_network": "netsim.network.factory",
    "network_class": "netsim.network.factory",
    "Link": "netsim.network.link",
    "BROADCAST": "netsim.network.message",
    "Message": "netsim.network.message",
    "Receiver": "netsim.network.message",
    "NetworkParams": "netsim.network.params",
    "NodeDelays": "netsim.network.params",
    "Frame": "netsim.network.pipeline",
    "Network": "netsim.network.pipeline",
    "LossSpec": "netsim.network.loss",
    "DROP_REASONS": "netsim.network.records",
    "MessageRecord": "netsim.network.records",
    "RoundRobinBus": "netsim.network.round_robin",
    "TdmaBus": "netsim.network.tdma",
    "Ieee802154": "netsim.network.ieee802154",
    "Ieee80211b": "netsim.network.ieee80211b",
    "WirelessMedium": "netsim.network.wireless",
}

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
    "FlexRayBus",
    "WirelessMedium",
    "Ieee802154",
    "Ieee80211b",
]


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
