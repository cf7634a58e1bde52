"""Energy of nodes: CPU and radio power by state, batteries that run out (issue 20).

- :mod:`netsim.energy.params`: the energy model a scenario writes under ``nodes.<n>.energy``;
- :mod:`netsim.energy.meter`: :class:`EnergyMeter`, the energy a node used and its battery;
- :func:`attach_energy`: one meter per node with an energy model, wired to its kernel and wireless media.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from netsim.energy.meter import EnergyMeter
from netsim.energy.params import Battery, CpuPower, EnergyModel, RadioPower
from netsim.errors import BuildError

if TYPE_CHECKING:
    from netsim.env import SimEnv
    from netsim.scenario.schema import Scenario

__all__ = ["EnergyModel", "CpuPower", "RadioPower", "Battery", "EnergyMeter", "attach_energy"]


def attach_energy(scenario: Scenario, env: SimEnv, kernels: dict[str, Any], networks: dict[str, Any]) -> dict[str, EnergyMeter]:
    """An :class:`EnergyMeter` per node of ``scenario`` with ``energy:`` (in ``env.components["energy.<node>"]``).

    Raises
    ------
    BuildError
        At ``nodes.<n>.energy.radio`` when a node with radio powers is on no wireless network, and at
        ``nodes.<n>.energy.radio.listen`` when a radio that sleeps between its own frames would have to receive.
    """
    meters: dict[str, EnergyMeter] = {}
    if not any(getattr(node, "energy", None) is not None for node in scenario.nodes.values()):
        return meters  # most scenarios: nothing to build, nothing imported
    from netsim.network.wireless import WirelessMedium

    for name, node in scenario.nodes.items():
        model = getattr(node, "energy", None)
        if model is None or name not in kernels:
            continue
        media = [networks[n] for n in scenario.node_networks(name)
                 if isinstance(networks.get(n), WirelessMedium)]
        if model.radio is not None and not media:
            raise BuildError(f"node '{name}' has radio powers but is on no wireless network (ieee802154, "
                             "ieee80211b); remove 'radio' or attach the node to a radio network",
                             path=f"nodes.{name}.energy.radio")
        if model.radio is not None and model.radio.listen == "own_frames":
            radio_nets = {m.name for m in media}
            for what, net in _receptions(node):
                if net in radio_nets:
                    raise BuildError(
                        f"node '{name}': {what} is released by messages on radio network '{net}', but the radio "
                        "sleeps except while it sends (listen: own_frames), so it would never receive; use "
                        "listen: always", path=f"nodes.{name}.energy.radio.listen")
        meter = meters[name] = EnergyMeter(env, name, kernels[name], model, media)
        env.components[f"energy.{name}"] = meter
    return meters


def _receptions(node: Any) -> list[tuple[str, str]]:
    """``(what, network)`` for each task or handler of ``node`` run by message receptions."""
    out = [(f"task '{t.name}'", t.release_network) for t in node.tasks if t.release_network is not None]
    out += [(f"handler '{h.name}'", h.trigger.on_message) for h in node.handlers
            if h.trigger is not None and h.trigger.on_message is not None]
    return out
