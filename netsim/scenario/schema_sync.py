"""A node's mailboxes, semaphores, events and monitors in a scenario (``nodes.<n>.sync``).

Kept apart from :mod:`netsim.scenario.schema` (whose ``NodeSpec`` has the ``sync`` field) so the whole feature
reads in one place: the YAML models, the objects they create on the node's kernel (:func:`create_sync`, run by
the builder and by ``netsim validate``'s build checks) and the check that every name a program uses is declared
(:func:`sync_ref_problems`)::

    nodes:
      ctrl:
        sync:
          mailboxes:  {samples: {capacity: 4}}     # capacity: omitted = unbounded
          semaphores: {slots: {count: 1, maximum: 1}}
          events:     {tick: {}}
          monitors:   {state: {protocol: inherit}} # inherit | ceiling | none
        tasks:
          - {name: sensor, program: mailbox_sampler, params: {channel: y, mailbox: samples}, ...}

Every name is a key of its section; a program finds the object with ``ctx.kernel.sync.mailbox(name)`` and its
``Params`` type the parameter as :data:`~netsim.kernel.node_sync.MailboxName` (or ``SemaphoreName``,
``EventName``, ``MonitorName``), which is what ``netsim validate`` checks. A ``ceiling`` monitor's ceiling is the
most urgent priority of its users: the tasks whose parameters name it, plus any listed in ``users``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, Any, Literal

from pydantic import BeforeValidator, ConfigDict, Field, StringConstraints, model_validator

from netsim.errors import BuildError
from netsim.scenario.problems import Problem
from netsim.units import StrictModel

if TYPE_CHECKING:
    from netsim.kernel.kernel import Kernel

__all__ = ["MailboxDecl", "SemaphoreDecl", "EventDecl", "MonitorDecl", "SyncSpec", "create_sync",
           "sync_ref_problems"]

_Name = Annotated[str, StringConstraints(pattern=r"^[A-Za-z0-9_-]+$")]


def _empty_is_default(value: Any) -> Any:
    """``tick:`` (nothing after the colon) declares the object with its defaults."""
    return {} if value is None else value


class _Decl(StrictModel):
    model_config = ConfigDict(extra="forbid", frozen=True, validate_assignment=False)


class MailboxDecl(_Decl):
    """A mailbox: a FIFO of items; ``capacity`` bounds it (a post blocks while full); omitted: unbounded."""

    capacity: int | None = Field(None, ge=1)


class SemaphoreDecl(_Decl):
    """A counting semaphore with an initial ``count`` and an optional ``maximum`` (a give saturates there)."""

    count: int = Field(0, ge=0)
    maximum: int | None = Field(None, ge=1)

    @model_validator(mode="after")
    def _max(self) -> "SemaphoreDecl":
        if self.maximum is not None and self.maximum < self.count:
            raise ValueError(f"maximum {self.maximum} is below the initial count {self.count}; raise 'maximum' "
                             "or lower 'count'")
        return self


class EventDecl(_Decl):
    """An event without memory: ``wait`` blocks until the next ``notify``."""


class MonitorDecl(_Decl):
    """A monitor (mutual exclusion): ``inherit`` (priority inheritance, TrueTime's monitors), ``ceiling``
    (immediate priority ceiling; needs policy fp, rm, dm or np_fp) or ``none`` (a plain mutex).

    ``users``: tasks that enter it besides those whose parameters name it (their priorities count for the
    ceiling)."""

    protocol: Literal["inherit", "ceiling", "none"] = "inherit"
    users: list[_Name] = Field(default_factory=list)


# `name:` with nothing after it is accepted (the defaults), and the JSON Schema for editors says so
_M = Annotated[MailboxDecl, BeforeValidator(_empty_is_default, json_schema_input_type=MailboxDecl | None)]
_S = Annotated[SemaphoreDecl, BeforeValidator(_empty_is_default, json_schema_input_type=SemaphoreDecl | None)]
_E = Annotated[EventDecl, BeforeValidator(_empty_is_default, json_schema_input_type=EventDecl | None)]
_Mo = Annotated[MonitorDecl, BeforeValidator(_empty_is_default, json_schema_input_type=MonitorDecl | None)]


class SyncSpec(_Decl):
    """The named synchronisation objects of a node, created on its kernel before its programs are built."""

    mailboxes: dict[_Name, _M] = Field(default_factory=dict, description=(
        "name: {capacity: N} (a FIFO; a post blocks while N items wait; capacity omitted: unbounded)"))
    semaphores: dict[_Name, _S] = Field(default_factory=dict, description=(
        "name: {count: N, maximum: M} (counting; take blocks at 0; a give saturates at maximum)"))
    events: dict[_Name, _E] = Field(default_factory=dict, description=(
        "name: {} (wait blocks until the next notify; a notify with nobody waiting is lost)"))
    monitors: dict[_Name, _Mo] = Field(default_factory=dict, description=(
        "name: {protocol: inherit | ceiling | none, users: [tasks]} (priority inheritance, immediate priority "
        "ceiling, or a plain mutex; the ceiling counts the tasks naming the monitor plus users)"))


def _task_refs(node: Any) -> list[tuple[str, str, str, list[Any]]]:
    """``(task, kind, name, path inside params)`` of every sync name the node's tasks and handlers use."""
    from netsim.kernel.node_sync import sync_refs

    out = []
    for item in (*node.tasks, *node.handlers):
        try:
            params = item.validated_params()
        except Exception:  # noqa: BLE001 - a parameter problem is reported by the params check at its path
            continue
        out += [(item.name, kind, name, sub) for kind, name, sub in sync_refs(params)]
    return out


def create_sync(kernel: Kernel, node: Any, path: str) -> None:
    """Create the node's declared sync objects on ``kernel.sync`` (``node``: a validated ``NodeSpec``).

    Raises
    ------
    BuildError
        At ``<path>.monitors.<m>.protocol`` for a ceiling monitor under a dynamic-priority policy, or at
        ``<path>.monitors.<m>.users`` for a user that is not a task of the node.
    """
    from netsim.kernel import Event, Mailbox, Monitor, Semaphore

    spec: SyncSpec = node.sync
    sync = kernel.sync
    for name, mb in spec.mailboxes.items():
        sync.add(Mailbox(name, capacity=mb.capacity))
    for name, sem in spec.semaphores.items():
        sync.add(Semaphore(name, count=sem.count, maximum=sem.maximum))
    for name in spec.events:
        sync.add(Event(name))
    if not spec.monitors:
        return
    tasks = [t.name for t in node.tasks]
    users: dict[str, list[str]] = {name: list(mon.users) for name, mon in spec.monitors.items()}
    for task, kind, name, _ in _task_refs(node):
        if kind == "monitors" and name in users and task in tasks and task not in users[name]:
            users[name].append(task)
    for name, mon in spec.monitors.items():
        mpath = f"{path}.monitors.{name}"
        for user in mon.users:
            if user not in tasks:
                from netsim.kernel.task import did_you_mean

                raise BuildError(f"monitor '{name}': user '{user}' is not a task of this node"
                                 f"{did_you_mean(user, tasks)}", path=f"{mpath}.users")
        if mon.protocol == "ceiling":
            if not kernel.policy.static:
                raise BuildError(f"protocol 'ceiling' needs a static-priority policy (fp, rm, dm, np_fp), and this "
                                 f"node uses '{kernel.policy.name}'; use 'inherit' (the owner then inherits the "
                                 "waiter's deadline)", path=f"{mpath}.protocol")
            if not users[name]:
                raise BuildError(f"monitor '{name}' has protocol 'ceiling' but no task uses it; add it to the "
                                 "parameters of the tasks that enter it, or list them in 'users'",
                                 path=f"{mpath}.users")
        sync.add(Monitor(name, protocol=mon.protocol, users=tuple(users[name])))


def sync_ref_problems(node_name: str, node: dict[str, Any], params: Any, at: list[Any]) -> list[Problem]:
    """A problem for every sync name in a program's validated ``params`` that the node does not declare.

    Parameters
    ----------
    node_name, node
        The node and its raw YAML entry (``sync`` read from it).
    params
        The program's validated ``Params`` instance (``None``: nothing to check).
    at
        The YAML path of the entry's ``params``.
    """
    from netsim.kernel.node_sync import sync_refs, unknown_sync_name
    from netsim.scenario.paths import format_path

    if params is None:
        return []
    sync = node.get("sync") if isinstance(node, dict) else None
    sync = sync if isinstance(sync, dict) else {}
    problems = []
    for kind, name, sub in sync_refs(params):
        declared = sync.get(kind)
        known = [k for k in declared if isinstance(k, str)] if isinstance(declared, dict) else []
        if name not in known:
            problems.append(Problem(format_path([*at, *sub]), unknown_sync_name(node_name, kind, name, known)))
        elif kind == "monitors" and "handlers" in at:
            problems.append(Problem(format_path([*at, *sub]), f"monitor '{name}': an interrupt handler cannot wait "
                                    "for a monitor (the kernel refuses its enter); use it from a task"))
    return problems
