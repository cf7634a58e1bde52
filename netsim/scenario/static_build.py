"""The build-time checks of a valid scenario, run by ``netsim validate`` without simulating anything.

``build`` makes checks that need its runtime objects: the plant refuses an ``x0`` or a ``process_noise`` of
the wrong size; the kernel refuses a task, a timer or a second periodic load on a node; a network refuses
its parameters (e.g. an ACK timeout shorter than the ACK) or a node; each kernel's reference check
(``Kernel.validate``, run when the simulation starts) refuses a binding. :func:`build_problems` runs **the
same code** -- the builder's signals, plant and io channels, :func:`netsim.scenario.builder.wire_kernels`,
:func:`~netsim.scenario.builder.build_networks`, :func:`~netsim.scenario.builder.bind_receivers` and
``Kernel.validate`` -- on a throw-away environment with placeholder task bodies, and turns the first error
into a :class:`~netsim.scenario.problems.Problem` with its YAML path.

It also runs the control design of the tasks whose program declares ``check_design`` (the ``state_feedback``
program: discretised model, estimator and law built as ``build`` builds them, so a weight that is not positive
definite, an unstabilisable pair or an MPC whose initial state is infeasible is refused at its YAML path).

What it does not run (for speed, and for issue 14: validating must not run code a scenario brings along):
programs are never constructed (their ``Params`` are checked by :mod:`netsim.scenario.validate`); plants,
signals and networks are built only when they come from netsim's own plugin modules
(:func:`netsim.registry.is_builtin`), and kernels only when every node uses a built-in policy. Cost: about
a millisecond per node, plus the plant's own construction (the HDD plant's first design in a process imports
python-control, about 1.3 s, then ``netsim.models.hdd`` caches it; a second check of hdd_case4 takes about 10 ms).
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any

from netsim.errors import ConfigError
from netsim.scenario.problems import WARNING, Problem

if TYPE_CHECKING:
    from netsim.kernel.kernel import Kernel
    from netsim.kernel.job import Job
    from netsim.scenario.schema import Scenario

__all__ = ["build_problems"]

log = logging.getLogger(__name__)


def _placeholder(job: Job) -> Any:
    """A task body that does nothing (the kernel only checks that bodies are generator functions)."""
    return
    yield  # pragma: no cover - makes this a generator function


def _body(spec: Any, kernel: Kernel, node: str, path: str, period: int | None) -> Any:
    return _placeholder


def _lookup(kind: str, name: str) -> Any:
    from netsim import registry

    try:
        return registry.lookup(kind, name)
    except ConfigError:
        return None


def _netsim_kernels(scenario: Scenario) -> bool:
    """True when every node policy is built into the kernel (a custom policy is not instantiated here)."""
    from netsim.kernel.policies import is_builtin_policy

    return all(is_builtin_policy(node.policy) for node in scenario.nodes.values())


def _netsim_plant(scenario: Scenario) -> bool:
    """True when the plant and every signal come from netsim's own plugin modules (then they are built)."""
    from netsim.registry import is_builtin

    objs = [_lookup("signal", s.type) for s in scenario.signals.values()]
    if scenario.plant is not None:
        objs.append(_lookup("plant", scenario.plant.model))
    return all(o is not None and is_builtin(o) for o in objs)


def _netsim_networks(scenario: Scenario) -> bool:
    """True when every network type is one of netsim's own :class:`~netsim.network.Network` classes."""
    from netsim.network.pipeline import Network
    from netsim.registry import is_builtin

    for net in scenario.networks.values():
        cls = _lookup("network", net.type)
        if not (isinstance(cls, type) and issubclass(cls, Network) and is_builtin(cls)):
            return False
    return True


def _message(exc: ConfigError) -> str:
    """The message without the ``node 'n', task 't', field 'f': `` prefix the YAML path already says."""
    node, task, field = (getattr(exc, a, None) for a in ("node", "task", "field"))
    if node is not None and task is not None and field is not None:
        return exc.message.removeprefix(f"node '{node}', task '{task}', field '{field}': ")
    return exc.message


def _design_checks(scenario: Scenario, plant: Any) -> None:
    """The control design of each task whose program (one of netsim's own) declares ``check_design``: e.g. the
    ``state_feedback`` program's model, estimator and law (shapes, weights, stabilisability, detectability,
    observer poles, MPC feasibility of ``plant.x0``), exactly as building the program checks them."""
    from netsim.registry import is_builtin

    for node_name, node in scenario.nodes.items():
        for i, task in enumerate(node.tasks):
            cls = _lookup("program", task.program)
            check = getattr(cls, "check_design", None)
            if cls is None or not callable(check) or not is_builtin(cls):
                continue
            check(scenario, node_name, i, task, plant)


def build_problems(scenario: Scenario) -> list[Problem]:
    """The problem ``build`` would raise for ``scenario`` (a valid Scenario), as a list of at most one.

    Returns
    -------
    list[Problem]
        Empty when the kernels and networks build and every kernel's references resolve.
    """
    from netsim.env import SimEnv
    from netsim.scenario.builder import (_build_io, _build_plant, _make_signals, bind_receivers, build_networks,
                                         wire_kernels)
    from netsim.energy import attach_energy

    if not _netsim_kernels(scenario):
        return []
    env = SimEnv(seed=scenario.seed, record=None if scenario.record is None else set(scenario.record))
    warnings: list[Problem] = []
    try:
        if _netsim_plant(scenario):
            signals = _make_signals(scenario)
            plant = _build_plant(scenario, env, signals)
            _build_io(scenario, env, plant)
            _design_checks(scenario, plant)
            from netsim.programs.design_summary import nominal_warnings_at  # issue 26 s4: unstable nominal loops

            warnings = [Problem(at, text, severity=WARNING) for at, text in nominal_warnings_at(scenario, plant)]
        kernels, bindings = wire_kernels(scenario, env, _body)
        if _netsim_networks(scenario):
            networks = build_networks(scenario, env, kernels)
            bind_receivers(kernels, networks, bindings)
            attach_energy(scenario, env, kernels, networks)
        for name, kernel in kernels.items():
            try:
                kernel.validate()
            except ConfigError as exc:
                raise type(exc)(exc.message, path=exc.path or f"nodes.{name}") from None
    except ConfigError as exc:
        return [Problem(exc.path or "", _message(exc))]
    return warnings
