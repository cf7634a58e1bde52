"""Kernels and networks of a scenario, wired as :func:`netsim.build.builder.build` makes them (steps 5 and 6).

:func:`wire_kernels` creates one kernel per node (its policy by name, resolved by
:func:`netsim.kernel.policies.find_policy`), adds each task and handler from its kernel description
(a task or handler entry is the kernel's ``TaskSpec`` or ``HandlerSpec`` itself) and creates the timers, external triggers and
periodic loads; :func:`build_networks` creates the networks and attaches them; :func:`bind_receivers` binds
message receptions. ``netsim validate`` runs them within the same build, on a dry-run environment
(:mod:`netsim.build.dry_run`), so it refuses what the kernel would refuse, at the same YAML path:
:func:`checked_call` places a kernel error at the field it names (the error's ``field`` and ``reason``
attributes, :func:`netsim.kernel.task.task_error`), never by reading its message.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable

from netsim.env import SimEnv
from netsim.errors import BuildError, ConfigError, NetsimError
from netsim.kernel.task import HandlerSpec, TaskSpec
from netsim.scenario.paths import parse_path

if TYPE_CHECKING:
    from netsim.scenario.schema import Scenario

__all__ = ["BodyFn", "wire_kernels", "bind_receivers", "build_networks", "checked_call", "located", "SPEC_FIELDS"]

#: ``body(spec, kernel, node, path, period)``: the program body of a task or handler entry.
BodyFn = Callable[[Any, Any, str, str, "int | None"], Any]


def wire_kernels(scenario: Scenario, env: SimEnv, body: BodyFn,
                 attach: Callable[[Any], None] | None = None) -> tuple[dict[str, Any], list[tuple[str, str, str]]]:
    """One kernel per node with its handlers, tasks and triggers, exactly as
    :func:`~netsim.build.builder.build` creates them.

    Parameters
    ----------
    body
        ``body(spec, kernel, node, path, period)`` returns the program body of a task or handler spec
        (a dry run passes a placeholder for a program it does not build).
    attach
        Called with each new kernel before its tasks are created (the builder attaches the io channels).

    Returns
    -------
    kernels, bindings
        The kernels by node name and the ``(node, network, target)`` receive bindings.

    Raises
    ------
    BuildError
        With the YAML path (``nodes.<n>.tasks[i].<field>``) of what the kernel refused.
    """
    from netsim.kernel import Kernel
    from netsim.kernel.cores import cpu_options

    kernels: dict[str, Any] = {}
    bindings: list[tuple[str, str, str]] = []
    for node_name, node in scenario.nodes.items():
        npath = f"nodes.{node_name}"
        options = cpu_options(node, npath)  # cores, multicore, speed (issue 30), checked at their YAML paths
        try:
            kernel = Kernel(env, node_name, policy=node.policy, context_switch=node.context_switch, **options)
        except NetsimError as exc:
            raise BuildError(str(exc), path=npath) from None
        kernels[node_name] = kernel
        env.components[f"kernel.{node_name}"] = kernel
        if attach is not None:
            attach(kernel)
        if node.sync is not None:  # before the programs, which look their objects up by name
            from netsim.scenario.schema_sync import create_sync

            checked_call(create_sync, f"{npath}.sync", kernel, node, f"{npath}.sync")
        for i, h in enumerate(node.handlers):
            hpath = f"{npath}.handlers[{i}]"
            checked_call(kernel.add_handler, hpath, h, body(h, kernel, node_name, hpath, None))
        for i, t in enumerate(node.tasks):
            tpath = f"{npath}.tasks[{i}]"
            checked_call(kernel.add_task, tpath, t, body(t, kernel, node_name, tpath, t.period))
            if t.release_network is not None:
                bindings.append((node_name, t.release_network, t.name))
        if node.servers or node.timetable is not None or node.policy == "tt" or any(t.server for t in node.tasks):
            from netsim.scenario.schema_servers import wire_servers  # CBS/TBS and time-triggered tables (issue 30)

            wire_servers(kernel, node, npath)
        # triggers after every handler exists
        for i, h in enumerate(node.handlers):
            hpath = f"{npath}.handlers[{i}]"
            trig = h.trigger
            if trig is None:
                continue
            if trig.timer is not None:  # exactly one of the four is given (HandlerTrigger)
                checked_call(kernel.create_timer, f"{hpath}.trigger", f"{h.name}_timer", h.name,
                      period=trig.timer.period, start=trig.timer.start)
            elif trig.external is not None:
                checked_call(kernel.create_trigger, f"{hpath}.trigger", h.name, h.name,
                      min_interarrival=trig.external.min_interarrival)
            elif trig.periodic_load is not None:
                # the validator made sure the execution time is constant (an int of ns, or {dist: constant})
                execution = h.execution if isinstance(h.execution, int) else getattr(h.execution, "value", 0)
                checked_call(kernel.create_periodic_load, f"{hpath}.trigger", h.name,
                      period=trig.periodic_load.period, execution=h.latency + int(execution or 0),
                      start=trig.periodic_load.start, handler=h.name)
            elif trig.on_message is not None:
                bindings.append((node_name, trig.on_message, h.name))
    return kernels, bindings


def bind_receivers(kernels: dict[str, Any], networks: dict[str, Any], bindings: list[tuple[str, str, str]]) -> None:
    """Bind each ``(node, network, target)`` reception (the kernels check the targets when the run starts)."""
    for node, net, target in bindings:
        if net not in networks:
            raise BuildError(f"node '{node}' receives on network '{net}', which is not defined",
                             path=f"nodes.{node}")
        checked_call(kernels[node].bind_receive, f"nodes.{node}", net, target)


#: Task/handler fields a kernel error may name: the fields of the kernel's descriptions, keys of the scenario's
#: task or handler.
SPEC_FIELDS = frozenset([*TaskSpec.model_fields, *HandlerSpec.model_fields])


def checked_call(fn: Callable[..., Any], path: str, *args: Any, **kwargs: Any) -> Any:
    """Call a kernel/network/plant constructor, turning its user errors into BuildErrors with ``path``.

    A kernel's task error (:func:`netsim.kernel.task.task_error`) names its field: when that is a key of the task
    or handler at ``path``, the error is placed at ``<path>.<field>``; at the entry's path, its message is the
    kernel's reason alone (the path names the node, the entry and the field).
    """
    try:
        return fn(*args, **kwargs)
    except ConfigError as exc:
        if exc.path is None:
            raise located(exc, path) from None
        raise
    except NetsimError as exc:
        raise BuildError(str(exc), path=path) from None
    except (ValueError, TypeError) as exc:
        raise BuildError(str(exc), path=path) from exc


def located(exc: ConfigError, path: str) -> BuildError:
    """``exc`` (raised without a path) as a BuildError at ``path``, or at ``<path>.<field>`` for a kernel error
    naming a field of the entry at ``path`` (see :func:`checked_call`).

    A kernel error's message is its ``reason`` when ``path`` lies at or inside a task or handler entry (the path
    names the node and the entry); at a node's path, the whole message, which names the task.
    """
    field = getattr(exc, "field", None)  # the structured attributes of netsim.kernel.task.task_error
    reason = getattr(exc, "reason", None)
    parts = parse_path(path)
    entry = len(parts) >= 4 and parts[0] == "nodes" and parts[2] in ("tasks", "handlers") and isinstance(parts[3], int)
    where = f"{path}.{field}" if entry and len(parts) == 4 and field in SPEC_FIELDS else path
    err = BuildError(reason if entry and isinstance(reason, str) else exc.message, path=where)
    for attr in ("node", "task", "field", "reason"):
        if hasattr(exc, attr):
            setattr(err, attr, getattr(exc, attr))
    return err


def build_networks(scenario: Scenario, env: SimEnv, kernels: dict[str, Any]) -> dict[str, Any]:
    """The scenario's networks (``make_network``), each attached to its nodes' kernels."""
    if not scenario.networks:
        return {}
    from netsim.network import make_network

    nets: dict[str, Any] = {}
    for name, spec in scenario.networks.items():
        path = f"networks.{name}"
        net = checked_call(make_network, path, env, name, spec.type, spec.validated_params())
        nets[name] = net
        env.components[f"network.{name}"] = net
        for node in spec.nodes:
            kernel = kernels.get(node)
            if kernel is None:
                raise BuildError(f"network '{name}' lists node '{node}', which is not defined under 'nodes'",
                                 path=f"{path}.nodes")
            checked_call(net.attach, f"{path}.nodes", node, kernel)
            kernel.attach_network(net)
    return nets
