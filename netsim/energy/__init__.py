"""Energy of nodes: CPU and radio power by state, batteries that run out (issue 20).

- :mod:`netsim.energy.params`: the energy model a scenario writes under ``nodes.<n>.energy``;
- :mod:`netsim.energy.meter`: :class:`EnergyMeter`, the energy a node used and its battery;
- :func:`attach_energy`: one meter per node with an energy model, wired to its kernel and wireless media.
"""

from __future__ import annotations

from typing import Any

from netsim.energy.meter import EnergyMeter
from netsim.energy.params import Battery, CpuPower, EnergyModel, RadioPower
from netsim.errors import BuildError

__all__ = ["EnergyModel", "CpuPower", "RadioPower", "Battery", "EnergyMeter", "attach_energy"]


def attach_energy(scenario: Any, env: Any, kernels: dict[str, Any], networks: dict[str, Any]) -> dict[str, EnergyMeter]:
    """An :class:`EnergyMeter` per node of ``scenario`` with ``energy:`` (in ``env.components["energy.<node>"]``).

    Raises
    ------
    BuildError
        At ``nodes.<n>.energy.radio`` when a node with radio powers is on no wireless network.
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
        meter = meters[name] = EnergyMeter(env, name, kernels[name], model, media)
        env.components[f"energy.{name}"] = meter
    return meters
