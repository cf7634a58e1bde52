"""The build-time checks of a valid scenario, run by ``netsim validate`` without building programs or plants.

``build`` makes checks that need the runtime objects: the kernel refuses a task, a timer or a second periodic
load; a network refuses its parameters (an ACK timeout shorter than the ACK, a missing delay file) or a node;
the kernel's reference check (``Kernel.validate``, run when the simulation starts) refuses a binding. This
module runs **the same code** -- :func:`netsim.scenario.builder.wire_kernels`,
:func:`~netsim.scenario.builder.build_networks`, :func:`~netsim.scenario.builder.bind_receivers` and each
kernel's ``validate`` -- on a throw-away environment, with placeholder task bodies, and turns the first
error into a :class:`~netsim.scenario.problems.Problem` with its YAML path.

What it does not run (decided for speed and for issue 14, which forbids running a scenario's own code):
programs and signals are not constructed (their ``Params`` are checked by :mod:`netsim.scenario.validate`),
plants only as :mod:`~netsim.scenario.validate` builds them for their ports; a scenario with a node policy
or a network type given as a ``module:Class`` path is skipped, and networks whose registered type is not a
``Network`` (test doubles) are left out. Nothing is simulated;
it costs about a millisecond per node.
"""

from __future__ import annotations

import logging
from typing import Any

from netsim.errors import ConfigError
from netsim.scenario.problems import Problem

__all__ = ["build_problems"]

log = logging.getLogger(__name__)


def _placeholder(job: Any) -> Any:
    """A task body that does nothing (the kernel only checks that bodies are generator functions)."""
    return
    yield  # pragma: no cover - makes this a generator function


def _body(spec: Any, kernel: Any, node: str, path: str, period: int | None) -> Any:
    return _placeholder


def _own_code(scenario: Any) -> bool:
    """True when a node policy or a network type is a ``module:attr`` path (code from the scenario)."""
    from netsim.kernel.policies import BUILTIN_POLICIES

    if any(node.policy not in BUILTIN_POLICIES for node in scenario.nodes.values()):
        return True
    return any(":" in net.type for net in scenario.networks.values())


def _real_networks(scenario: Any) -> bool:
    """True when every network type is a :class:`~netsim.network.Network` (test doubles registered under kind
    ``network`` are not; ``run`` reports them, here they are left out with the receive bindings)."""
    from netsim import registry
    from netsim.network.pipeline import Network

    for net in scenario.networks.values():
        try:
            cls = registry.lookup("network", net.type)
        except ConfigError:
            return False
        if not (isinstance(cls, type) and issubclass(cls, Network)):
            return False
    return True


def _message(exc: ConfigError) -> str:
    """The message without the ``node 'n', task 't', field 'f': `` prefix the YAML path already says."""
    node, task, field = (getattr(exc, a, None) for a in ("node", "task", "field"))
    if node is not None and task is not None and field is not None:
        return exc.message.removeprefix(f"node '{node}', task '{task}', field '{field}': ")
    return exc.message


def build_problems(scenario: Any) -> list[Problem]:
    """The problem ``build`` would raise for ``scenario`` (a valid Scenario), as a list of at most one.

    Returns
    -------
    list[Problem]
        Empty when the kernels and networks build and every kernel's references resolve.
    """
    from netsim.env import SimEnv
    from netsim.scenario.builder import bind_receivers, build_networks, wire_kernels

    if _own_code(scenario):
        return []
    env = SimEnv(seed=scenario.seed)
    try:
        kernels, bindings = wire_kernels(scenario, env, _body)
        if _real_networks(scenario):
            networks = build_networks(scenario, env, kernels)
            bind_receivers(kernels, networks, bindings)
        for name, kernel in kernels.items():
            try:
                kernel.validate()
            except ConfigError as exc:
                raise type(exc)(exc.message, path=exc.path or f"nodes.{name}") from None
    except ConfigError as exc:
        return [Problem(exc.path or "", _message(exc))]
    return []
