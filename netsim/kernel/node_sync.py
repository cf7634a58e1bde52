"""The named synchronisation objects of a node: ``kernel.sync``, and the parameter types that name them.

A scenario declares a node's mailboxes, semaphores, events and monitors under ``nodes.<n>.sync``; the builder
creates them on the node's kernel (:class:`NodeSync`, ``kernel.sync``) before the programs, and a program
finds them by name when it is built::

    class Params(StrictModel):
        inbox: MailboxName          # a parameter naming a mailbox of the program's node
        guard: MonitorName | None = None

    def __init__(self, ctx, params):
        self.inbox = ctx.kernel.sync.mailbox(params.inbox)

Parameters typed :data:`MailboxName`, :data:`SemaphoreName`, :data:`EventName` or :data:`MonitorName` (plain
strings carrying a :class:`SyncRef` marker) are what ``netsim validate`` checks against the node's
declarations, for netsim's programs and plugin programs alike (:func:`sync_refs`).
"""

from __future__ import annotations

import difflib
from typing import Annotated, Any, Iterable, Iterator

from netsim.errors import ConfigError
from netsim.kernel.monitor import Monitor
from netsim.kernel.sync import Event, Mailbox, Semaphore

__all__ = ["NodeSync", "SyncRef", "unknown_sync_name", "MailboxName", "SemaphoreName", "EventName", "MonitorName", "SYNC_KINDS",
           "sync_refs"]

#: The sections of ``nodes.<n>.sync`` and the class each creates.
SYNC_KINDS: dict[str, type] = {"mailboxes": Mailbox, "semaphores": Semaphore, "events": Event, "monitors": Monitor}

_SINGULAR = {"mailboxes": "mailbox", "semaphores": "semaphore", "events": "event", "monitors": "monitor"}


def unknown_sync_name(node: str, kind: str, name: str, known: Iterable[str]) -> str:
    """The message for a sync object ``name`` of ``kind`` that node ``node`` does not declare: the names it has,
    the closest one, and where to declare it."""
    known = sorted(known)
    singular = _SINGULAR[kind]
    declared = f"its {kind}: {', '.join(known)}" if known else f"it declares no {kind}"
    close = difflib.get_close_matches(str(name), known, n=1)
    hint = f"; did you mean '{close[0]}'?" if close else ""
    return (f"node '{node}' has no {singular} '{name}' ({declared}){hint}; declare it under "
            f"nodes.{node}.sync.{kind}")


class SyncRef:
    """Marker (in ``Annotated`` metadata) of a program parameter that names a sync object of its node.

    Attributes
    ----------
    kind : str
        ``"mailboxes"``, ``"semaphores"``, ``"events"`` or ``"monitors"``.
    """

    __slots__ = ("kind",)

    def __init__(self, kind: str) -> None:
        if kind not in SYNC_KINDS:
            raise ValueError(f"SyncRef kind must be one of {', '.join(SYNC_KINDS)}, got {kind!r}")
        self.kind = kind

    def __repr__(self) -> str:
        return f"SyncRef({self.kind!r})"


#: A program parameter naming a mailbox declared under ``nodes.<n>.sync.mailboxes``.
MailboxName = Annotated[str, SyncRef("mailboxes")]
#: A program parameter naming a semaphore declared under ``nodes.<n>.sync.semaphores``.
SemaphoreName = Annotated[str, SyncRef("semaphores")]
#: A program parameter naming an event declared under ``nodes.<n>.sync.events``.
EventName = Annotated[str, SyncRef("events")]
#: A program parameter naming a monitor declared under ``nodes.<n>.sync.monitors``.
MonitorName = Annotated[str, SyncRef("monitors")]


class NodeSync:
    """The named mailboxes, semaphores, events and monitors of one node (``kernel.sync``).

    Parameters
    ----------
    node
        The node name (for error messages).
    """

    def __init__(self, node: str) -> None:
        self.node = node
        self.mailboxes: dict[str, Mailbox] = {}
        self.semaphores: dict[str, Semaphore] = {}
        self.events: dict[str, Event] = {}
        self.monitors: dict[str, Monitor] = {}

    def add(self, obj: "Mailbox | Semaphore | Event | Monitor") -> Any:
        """Register ``obj`` under its name; returns it.

        Raises
        ------
        ConfigError
            When the object is not a sync object, or its kind already has that name.
        """
        for kind, cls in SYNC_KINDS.items():
            if isinstance(obj, cls):
                table = getattr(self, kind)
                if obj.name in table:
                    raise ConfigError(f"node '{self.node}': {_SINGULAR[kind]} '{obj.name}' is declared twice")
                table[obj.name] = obj
                return obj
        raise ConfigError(f"node '{self.node}': {obj!r} is not a Mailbox, Semaphore, Event or Monitor")

    def get(self, kind: str, name: str) -> Any:
        """The object of ``kind`` (``"mailboxes"`` ...) called ``name``.

        Raises
        ------
        ConfigError
            Naming the node, the YAML section to declare it in and the names it has.
        """
        table: dict[str, Any] = getattr(self, kind)
        obj = table.get(name)
        if obj is None:
            raise ConfigError(unknown_sync_name(self.node, kind, name, table))
        return obj

    def mailbox(self, name: str) -> Mailbox:
        """The mailbox ``name`` (see :meth:`get`)."""
        return self.get("mailboxes", name)

    def semaphore(self, name: str) -> Semaphore:
        """The semaphore ``name`` (see :meth:`get`)."""
        return self.get("semaphores", name)

    def event(self, name: str) -> Event:
        """The event ``name`` (see :meth:`get`)."""
        return self.get("events", name)

    def monitor(self, name: str) -> Monitor:
        """The monitor ``name`` (see :meth:`get`)."""
        return self.get("monitors", name)

    def __repr__(self) -> str:
        counts = ", ".join(f"{kind}={len(getattr(self, kind))}" for kind in SYNC_KINDS)
        return f"NodeSync({self.node!r}, {counts})"


def _ref_of(annotation: Any, metadata: list[Any]) -> SyncRef | None:
    for m in metadata:
        if isinstance(m, SyncRef):
            return m
    for arg in getattr(annotation, "__args__", ()) or ():  # MailboxName | None, list[MailboxName]
        for m in getattr(arg, "__metadata__", ()) or ():
            if isinstance(m, SyncRef):
                return m
        inner = _ref_of(arg, [])
        if inner is not None:
            return inner
    return None


def sync_refs(params: Any) -> Iterator[tuple[str, str, list[str | int]]]:
    """Every sync object a program's validated ``Params`` names: ``(kind, name, path inside params)``.

    Walks the fields typed :data:`MailboxName` ... (also inside ``X | None``, lists and nested models).
    """
    fields = getattr(type(params), "model_fields", None)
    if not fields:
        return
    for fname, info in fields.items():
        value = getattr(params, fname, None)
        if value is None:
            continue
        ref = _ref_of(info.annotation, list(info.metadata))
        if ref is not None:
            if isinstance(value, str):
                yield ref.kind, value, [fname]
            elif isinstance(value, (list, tuple)):
                for i, item in enumerate(value):
                    if isinstance(item, str):
                        yield ref.kind, item, [fname, i]
        elif hasattr(type(value), "model_fields"):
            for kind, name, sub in sync_refs(value):
                yield kind, name, [fname, *sub]
