"""Every medium declares its ``Params`` as the type parameter of :class:`~netsim.network.pipeline.Network`.

``class CanBus(Network["CanBus.Params"])`` is what lets the type check (.ci/mypy) see ``self.params.bitrate`` of
a CAN bus as a CAN parameter; a medium written ``class X(Network)`` has ``self.params`` typed only as the common
``NetworkParams``, and every medium field it reads is an error there.
"""

import typing

import pytest

from netsim.network.pipeline import Network
from netsim.registry import entries


def _declared_params(cls: type) -> object:
    """The type argument ``cls`` gives its Network base (resolving the string forward reference)."""
    for base in getattr(cls, "__orig_bases__", ()):
        origin = typing.get_origin(base)
        if isinstance(origin, type) and issubclass(origin, Network):
            (arg,) = typing.get_args(base)
            if isinstance(arg, typing.ForwardRef):
                return eval(arg.__forward_arg__, vars(__import__(cls.__module__, fromlist=["_"])))
            return arg
    return None


MEDIA = sorted({e.obj for e in entries("network") if e.obj.__module__.startswith("netsim.network.")},
               key=lambda cls: cls.__name__)


def test_every_medium_module_registers_its_class():
    # one medium class per module of netsim/network/ that defines one (aliases such as "ideal" and "link" name
    # the same class)
    modules = {cls.__module__.rsplit(".", 1)[1] for cls in MEDIA}
    assert modules == {"can", "csma_cd", "ethernet", "fdma", "flexray", "link", "round_robin", "tdma",
                       "ieee80211b", "ieee802154"}


@pytest.mark.parametrize("cls", MEDIA, ids=lambda cls: cls.__name__)
def test_a_medium_parameterizes_network_with_its_own_params(cls):
    assert _declared_params(cls) is cls.Params
