"""Static descriptions of tasks and interrupt handlers, and their run-time counterparts.

Following SimSo, the frozen :class:`TaskSpec`/:class:`HandlerSpec` (what the user asked for, validated at
build time) is kept apart from the mutable :class:`Task`/:class:`Handler` (job queue, counters). They are
the only definition of a task's and a handler's scheduling fields: a scenario's task entry *is* a
:class:`TaskSpec` (:class:`netsim.scenario.schema.TaskSpec` adds the program), validated once from YAML;
handler entries are read into :class:`HandlerSpec` (:meth:`netsim.scenario.schema.HandlerSpec.kernel_spec`).

This module imports nothing of the kernel's run time, so the scenario schema can use it cheaply.

Why this module is long: a task's fields, their checks and the run-time Task they fill are read together (about
500 lines; the server slot of issue 30 took it just past); the Task/Handler classes could move out next.
"""

from __future__ import annotations

import difflib
import functools
import inspect
import numbers
import re
from collections import deque
from collections.abc import Callable, Iterable
import dataclasses
from typing import TYPE_CHECKING, Annotated, Any, Literal, Union

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, PrivateAttr, model_validator

from netsim.distributions import Distribution, DistributionSpec, Empirical
from netsim.errors import BuildError, ConfigError
from netsim.timebase import format_time
from netsim.units import Duration, Time

if TYPE_CHECKING:  # the classes made below, as the type checker reads them
    from netsim.kernel.checked import CheckedHandler, CheckedTask

__all__ = ["RELEASE_KINDS", "SET_PERIOD_RULES", "CheckedHandler", "CheckedTask", "SetPeriodRule", "Handler", "HandlerSpec", "Task", "TaskSpec", "check_body", "check_time", "did_you_mean", "task_error"]


def did_you_mean(name: str, known: Iterable[str]) -> str:
    """``"; did you mean 'x'?"`` for the closest of ``known``, else the list of known names."""
    known = list(known)
    close = difflib.get_close_matches(name, known, n=1)
    if close:
        return f"; did you mean '{close[0]}'?"
    return f" (known: {', '.join(sorted(known)) or 'none'})"


def task_error(node: str, task: str, field: str, message: str) -> BuildError:
    """A :class:`BuildError` naming the node, the task (or handler) and the field to change.

    The error carries ``node``, ``task`` and ``field`` attributes so a scenario builder can map it to a
    YAML path, and ``reason``, the message without its node/task/field lead, which it shows at that path.
    """
    err = BuildError(f"node '{node}', task '{task}', field '{field}': {message}")
    err.node = node  # type: ignore[attr-defined]
    err.task = task  # type: ignore[attr-defined]
    err.field = field  # type: ignore[attr-defined]
    err.reason = message  # type: ignore[attr-defined]
    return err


def _is_generator_callable(body: Any) -> bool:
    target = body
    for _ in range(8):
        if isinstance(target, functools.partial):
            target = target.func
            continue
        unwrapped = inspect.unwrap(target) if callable(target) else target
        if inspect.isgeneratorfunction(unwrapped):
            return True
        if inspect.isfunction(unwrapped) or inspect.ismethod(unwrapped) or inspect.isbuiltin(unwrapped):
            return False
        call = getattr(type(target), "__call__", None)
        if call is None or call is target:
            return False
        target = call
    return False


def check_body(node: str, task: str, body: Any) -> None:
    """Raise a :class:`BuildError` unless ``body`` is a generator function (or an object whose
    ``__call__`` is one, or a ``functools.partial`` of one)."""
    if not callable(body):
        raise task_error(node, task, "body", f"must be a generator function body(job), got {body!r}")
    if not _is_generator_callable(body):
        name = getattr(body, "__qualname__", None) or type(body).__name__
        raise task_error(
            node, task, "body",
            f"'{name}' is not a generator function; a body must yield requests, "
            "e.g. def body(job): yield job.execute(500_000)",
        )


def check_time(node: str, task: str, field: str, value: Any, *, positive: bool = False,
               allow_none: bool = False) -> int | None:
    """Validate an integer-ns time field of a task; returns it as ``int`` (or ``None``)."""
    if value is None:
        if allow_none:
            return None
        raise task_error(node, task, field, "is required")
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise task_error(node, task, field, f"must be an integer number of ns, got {value!r}")
    value = int(value)
    if positive and value <= 0:
        raise task_error(node, task, field, f"must be positive, got {format_time(value)}")
    if value < 0:
        raise task_error(node, task, field, f"must not be negative, got {format_time(value)}")
    return value


#: The rules of :attr:`TaskSpec.set_period`: ``next_release`` (TrueTime 1.5) and ``keep_armed`` (TrueTime 2.0).
SET_PERIOD_RULES = ("next_release", "keep_armed")
SetPeriodRule = Literal["next_release", "keep_armed"]


#: The release kinds a task's ``release`` names (``on_message:<network>`` carries the network).
RELEASE_KINDS = ("periodic", "aperiodic", "sporadic", "on_message")

_ON_MESSAGE = re.compile(r"^on_message:([A-Za-z0-9_-]+)$")


def _release(value: Any) -> Any:
    """``release``: ``periodic``, ``aperiodic``, ``sporadic`` or ``on_message:<network>`` (spaces dropped)."""
    if value is None:
        return None
    if isinstance(value, str):
        text = value.strip().replace(" ", "")
        if text in ("periodic", "aperiodic", "sporadic") or _ON_MESSAGE.match(text):
            return text
    raise ValueError(f"release must be 'periodic', 'aperiodic', 'sporadic' or 'on_message:<network>', got {value!r}")


#: A handler reference of a task: a handler's name or, from Python, a callable ``fn(job)``.
HandlerRef = Union[str, Callable[[Any], Any], None]


class TaskSpec(BaseModel):
    """The static description of a task (times in ns): what the user asked for, apart from the run-time
    :class:`Task`. The one definition of a task's scheduling fields, their units and defaults: a scenario's
    task entry (:class:`netsim.scenario.schema.TaskSpec`) is this model with its program added, validated once
    from YAML (``period: 10 ms`` is read by the ``Duration`` type), and the kernel takes it as it is.

    From Python, build one with the name and keywords in integer ns (``TaskSpec("ctl", period=10_000_000)``):
    nothing is parsed, and :meth:`checked` (run by ``Kernel.add_task``) validates it and fills the defaults
    that depend on other fields.

    Attributes
    ----------
    name
        Task name, unique on its node.
    period
        Release period (``None``: not periodic).
    offset
        First release of a periodic or sporadic task.
    deadline
        Relative deadline (``None``: the period, or the ``min_interarrival`` of a sporadic task; no deadline
        for an aperiodic task without one).
    priority
        Explicit priority (lower = more urgent); needed by ``fp``.
    wcet
        Execution budget per job; exceeding it fires the task's ``wcet_handler``.
    release
        ``periodic`` (the default with a period), ``sporadic`` (the default with ``min_interarrival`` and no
        period), ``aperiodic`` (released by program code; the default otherwise) or ``on_message:<network>``
        (released by the node's messages on that network). A task that is not periodic has no period; one
        that is not sporadic has no ``min_interarrival`` (:meth:`checked` refuses them).
    preemptible
        ``False``: once started, only interrupt handlers can take the CPU from the job.
    wcet_handler, deadline_handler
        A handler name (invoked with the overrunning job as data) or a callable ``fn(job)`` run at the
        overrun instant (``None``: the overrun is only logged).
    release_jitter
        Release jitter of a periodic or sporadic task: each job arrives a draw of this distribution
        (:mod:`netsim.distributions`, or an integer of ns for a constant delay) after its nominal release,
        drawn from the task's stream ``kernel.<node>.release.<task>``. ``job.release``, the absolute deadline
        and the record's ``response`` are measured from the nominal release; the record's ``arrival`` is the
        actual arrival.
    min_interarrival
        A **sporadic** task (no ``period``): the kernel releases it by itself, successive arrivals at least
        this far apart (the first at ``offset``); the deadline defaults to it.
    extra_interarrival
        A sporadic task's random gap added to ``min_interarrival`` at each arrival (a distribution, e.g.
        ``ExecTime.exponential(mean)``; ``None``: arrivals exactly ``min_interarrival`` apart).
    abort_on_miss
        Kill a job that has not finished at its absolute deadline (after its ``deadline_handler``): its
        record is killed and missed, and the task's next job may start.
    set_period
        What a period change at run time (``Kernel.set_period``, TrueTime's ``ttSetPeriod``) does to the
        release already scheduled: ``"next_release"`` (TrueTime 1.5, the default) moves it to one new period
        after the last release; ``"keep_armed"`` (TrueTime 2.0) keeps it, and the new period counts from it
        (:mod:`netsim.kernel.arrivals`).
    """

    model_config = ConfigDict(extra="forbid", frozen=True, arbitrary_types_allowed=True)

    name: str
    period: Duration | None = None
    offset: Time = 0
    deadline: Duration | None = None
    priority: int | float | None = None
    wcet: Duration | None = None
    release: Annotated[str | None, BeforeValidator(_release)] = None
    preemptible: bool = True
    wcet_handler: HandlerRef = None
    deadline_handler: HandlerRef = None
    release_jitter: DistributionSpec | None = None
    min_interarrival: Duration | None = None
    extra_interarrival: DistributionSpec | None = None
    abort_on_miss: bool = False
    set_period: SetPeriodRule = Field("next_release", description=(
        "a period changed at run time: next_release (TrueTime 1.5) moves the armed release to one new period "
        "after the last; keep_armed (TrueTime 2.0) keeps it"))

    _checked: Any = PrivateAttr(default=None)

    def __init__(self, *args: Any, **fields: Any) -> None:
        if not args:  # keywords only: validated as YAML is (also how pydantic itself calls this)
            super().__init__(**fields)
            return
        _python_init(self, args, fields)  # Python: integer ns, checked by checked()

    @model_validator(mode="after")
    def _defaults(self) -> TaskSpec:
        """From YAML: ``release`` from the fields given, and the deadline from the period (or the gap)."""
        if self.release is None:
            object.__setattr__(self, "release", "periodic" if self.period is not None else
                               "sporadic" if self.min_interarrival is not None else "aperiodic")
        if self.deadline is None:
            object.__setattr__(self, "deadline", self.period if self.period is not None else self.min_interarrival)
        return self

    @property
    def release_kind(self) -> str:
        """``"periodic"``, ``"aperiodic"``, ``"sporadic"`` or ``"on_message"`` (from the fields when unset)."""
        if self.release is None:
            return ("periodic" if self.period is not None else
                    "sporadic" if self.min_interarrival is not None else "aperiodic")
        return str(self.release).split(":", 1)[0]

    @property
    def release_network(self) -> str | None:
        """The network whose messages release this task (``release: on_message:<net>``), else None."""
        kind, _, net = str(self.release).partition(":")
        return net if kind == "on_message" else None

    @property
    def self_released(self) -> bool:
        """True for a task the kernel releases by itself: periodic (``period``) or sporadic."""
        return self.period is not None or self.min_interarrival is not None

    def checked(self, node: str) -> CheckedTask:
        """This description validated for node ``node``, with ``deadline`` defaulting to the period: the
        :class:`CheckedTask` the kernel runs from.

        Every check depends on the description only, so ``netsim validate`` runs this same method on a
        scenario's tasks before anything is built (then the scheduling policy's ``check``). The result is kept:
        the dry run of ``netsim validate`` and the build of a run check a scenario's task once.

        Raises
        ------
        BuildError
            From :func:`task_error` (with ``node``, ``task`` and ``field`` attributes).
        """
        done = self._checked
        if done is not None and done[0] == node:
            return done[1]
        result = self._check(node)
        self._checked = (node, result)
        return result

    def _check(self, node: str) -> CheckedTask:
        name = self.name
        release = self.release_kind
        period_ns = check_time(node, name, "period", self.period, positive=True, allow_none=True)
        if release == "periodic" and self.release is not None and period_ns is None:
            raise task_error(node, name, "period", "a periodic task needs a period; add e.g. 'period: 10 ms', or "
                             "set 'release: aperiodic' or 'release: on_message:<network>'")
        if release != "periodic" and period_ns is not None:
            raise task_error(node, name, "period", f"only periodic tasks have a period (this one is released "
                             f"'{self.release}'); remove 'period' or set 'release: periodic'")
        offset_ns = check_time(node, name, "offset", self.offset)
        assert offset_ns is not None
        mia_ns = check_time(node, name, "min_interarrival", self.min_interarrival, positive=True, allow_none=True)
        if release == "sporadic" and mia_ns is None:
            raise task_error(node, name, "min_interarrival", "a sporadic task needs a minimum inter-arrival time; "
                             "add e.g. 'min_interarrival: 10 ms'")
        if self.release is not None and release != "sporadic" and mia_ns is not None:
            raise task_error(node, name, "min_interarrival", f"only sporadic tasks have a minimum inter-arrival "
                             f"time (this one is released '{self.release}'); remove it or set 'release: sporadic'")
        if mia_ns is not None and period_ns is not None:
            raise task_error(node, name, "min_interarrival", "is for sporadic tasks, which have no period; drop "
                             "'period' (a sporadic task) or 'min_interarrival' (a periodic task)")
        if period_ns is None and mia_ns is None and offset_ns:
            raise task_error(node, name, "offset", "applies to periodic and sporadic tasks only; give a period or "
                             "drop it")
        deadline_ns = check_time(node, name, "deadline", self.deadline, positive=True, allow_none=True)
        if deadline_ns is None:
            deadline_ns = period_ns if mia_ns is None else mia_ns
        jitter = _distribution(node, name, "release_jitter", self.release_jitter)
        if jitter is not None and period_ns is None and mia_ns is None:
            raise task_error(node, name, "release_jitter", "applies to periodic and sporadic tasks only (an "
                             "aperiodic task is released by program code or messages); give a period or drop it")
        extra = _distribution(node, name, "extra_interarrival", self.extra_interarrival)
        if extra is not None and mia_ns is None:
            raise task_error(node, name, "extra_interarrival", "needs 'min_interarrival' (the random gap is added "
                             "to it between two arrivals of a sporadic task)")
        if not isinstance(self.abort_on_miss, bool):
            raise task_error(node, name, "abort_on_miss", f"must be true or false, got {self.abort_on_miss!r}")
        if self.abort_on_miss and deadline_ns is None:
            raise task_error(node, name, "abort_on_miss", "needs a deadline (or a period) to abort the job at")
        if self.set_period not in SET_PERIOD_RULES:
            raise task_error(node, name, "set_period", f"must be one of {', '.join(SET_PERIOD_RULES)}, got "
                             f"{self.set_period!r}")
        priority = self.priority
        if priority is not None and (isinstance(priority, bool) or not isinstance(priority, (int, float))):
            raise task_error(node, name, "priority", f"must be a number (lower = more urgent), got {priority!r}")
        wcet_ns = check_time(node, name, "wcet", self.wcet, positive=True, allow_none=True)
        for field, ref in (("wcet_handler", self.wcet_handler), ("deadline_handler", self.deadline_handler)):
            if ref is not None and not isinstance(ref, str) and not callable(ref):
                raise task_error(node, name, field, f"must be a handler name or a callable fn(job), got {ref!r}")
        if self.wcet_handler is not None and wcet_ns is None:
            raise task_error(node, name, "wcet_handler", "needs a 'wcet' budget to detect overruns; add e.g. "
                             "'wcet: 2 ms' (the execution budget per job)")
        if self.deadline_handler is not None and deadline_ns is None:
            raise task_error(node, name, "deadline_handler", "needs a deadline (or a period) to detect misses")
        return CheckedTask(
            name=name, period=period_ns, offset=offset_ns, deadline=deadline_ns, priority=priority, wcet=wcet_ns,
            release=self.release, preemptible=bool(self.preemptible), wcet_handler=self.wcet_handler,
            deadline_handler=self.deadline_handler, release_jitter=jitter, min_interarrival=mia_ns,
            extra_interarrival=extra, abort_on_miss=self.abort_on_miss, set_period=self.set_period)


def _replaced(self: Any, **changes: Any) -> Any:
    """A copy with ``changes`` (run-time parameters in integer ns: ``Kernel.set_period`` ...)."""
    return dataclasses.replace(self, **changes)


#: The checked form of a :class:`TaskSpec` (:meth:`TaskSpec.checked`): the same fields, integer ns, defaults filled,
#: as a frozen slotted record, read at every release (a pydantic model's attribute reads cost about 4x a slot's:
#: kernel benchmark). Made by ``checked`` from TaskSpec's fields; the type checker reads :mod:`netsim.kernel.checked`.
if not TYPE_CHECKING:
    CheckedTask = dataclasses.make_dataclass(
        "CheckedTask", [(name, Any) for name in TaskSpec.model_fields], frozen=True, slots=True,
        namespace={"__module__": __name__, "__doc__": "A checked TaskSpec (see TaskSpec.checked).",
                   "release_kind": TaskSpec.release_kind, "release_network": TaskSpec.release_network,
                   "self_released": TaskSpec.self_released, "replaced": _replaced})


def _distribution(node: str, task: str, field: str, value: Any) -> Any:
    """A distribution field of a task as a :class:`~netsim.distributions.Distribution` (an int: constant ns)."""
    if value is None:
        return None
    if isinstance(value, Empirical):
        try:
            value.table()  # a CSV file is read now, so a missing one is refused at this field before the run
        except ConfigError as exc:
            raise task_error(node, task, field, exc.message) from None
    if isinstance(value, Distribution):
        return value
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise task_error(node, task, field, f"must be a distribution (netsim.distributions) or an integer number of "
                         f"ns, got {value!r}")
    if value < 0:
        raise task_error(node, task, field, f"must not be negative, got {format_time(int(value))}")
    return Distribution.constant(int(value))


class HandlerSpec(BaseModel):
    """The static description of an interrupt handler (the one definition; see :class:`TaskSpec`): a scenario's
    handler entry (:class:`netsim.scenario.schema.HandlerSpec`) is this model with its program and trigger added.

    From Python: ``HandlerSpec("isr", priority, latency)`` in integer ns, checked by :meth:`checked`.

    Attributes
    ----------
    name
        Handler name, unique on its node (shared name space with tasks).
    priority
        Among handlers (lower = more urgent); every handler beats every task.
    latency
        ISR entry latency in ns: CPU time consumed at each invocation before the body's code runs.
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    name: str
    priority: int | float = 0
    latency: Time = 0

    def __init__(self, *args: Any, **fields: Any) -> None:
        if not args:  # keywords only: validated as YAML is (also how pydantic itself calls this)
            super().__init__(**fields)
            return
        _python_init(self, args, fields)

    def checked(self, node: str) -> CheckedHandler:
        """This description validated for node ``node``: the :class:`CheckedHandler` the kernel runs from.

        Raises
        ------
        BuildError
            From :func:`task_error` (with ``node``, ``task`` and ``field`` attributes).
        """
        priority = self.priority
        if isinstance(priority, bool) or not isinstance(priority, (int, float)):
            raise task_error(node, self.name, "priority", f"must be a number (lower = more urgent), got {priority!r}")
        latency_ns = check_time(node, self.name, "latency", self.latency)
        assert latency_ns is not None
        return CheckedHandler(name=self.name, priority=priority, latency=latency_ns)


#: The checked form of a :class:`HandlerSpec` (read at every invocation; see :data:`CheckedTask`).
if not TYPE_CHECKING:
    CheckedHandler = dataclasses.make_dataclass(
        "CheckedHandler", [(name, Any) for name in HandlerSpec.model_fields], frozen=True, slots=True,
        namespace={"__module__": __name__, "__doc__": "A checked HandlerSpec (see HandlerSpec.checked)."})


def _python_init(self: BaseModel, args: tuple[Any, ...], fields: dict[str, Any]) -> None:
    """Fill a description from Python arguments (integer ns, in field order, then keywords), unvalidated."""
    names = list(type(self).model_fields)
    if len(args) > len(names):
        raise TypeError(f"{type(self).__name__}() takes at most {len(names)} positional arguments")
    given = dict(zip(names, args))
    twice = sorted(set(given) & set(fields))
    unknown = sorted(set(fields) - set(names))
    if twice or unknown:
        raise TypeError(f"{type(self).__name__}() got {'multiple values for' if twice else 'an unexpected keyword'} "
                        f"argument '{(twice or unknown)[0]}'")
    made = type(self).model_construct(**given, **fields)
    for attr in ("__dict__", "__pydantic_fields_set__", "__pydantic_extra__", "__pydantic_private__"):
        object.__setattr__(self, attr, getattr(made, attr))


class Task:
    """Run-time state of a task: its body, its FIFO of released jobs and its counters."""

    __slots__ = (
        "active",
        "body",
        "cpu",
        "data",
        "deadline_handler",
        "first_release",
        "key",
        "name",
        "queue",
        "released",
        "rng",
        "server",
        "spec",
        "trace_since",
        "trace_state",
        "watch_deadline",
        "wcet_handler",
    )

    def __init__(self, spec: CheckedTask, body: Callable[[Any], Any], data: Any) -> None:
        self.spec = spec
        self.name = spec.name
        self.body = body
        self.data = data
        self.wcet_handler = spec.wcet_handler  # copies of the spec's, read at every release and overrun
        self.deadline_handler = spec.deadline_handler
        self.queue: deque[Any] = deque()  # released jobs waiting for the active one to finish
        self.active: Any = None  # the job currently ready/running/blocked
        self.released = 0
        self.key: Any = None  # static policy key (None: computed per job)
        self.cpu = 0  # CPU time consumed by all its jobs, ns
        self.trace_state: str | None = None
        self.trace_since = 0
        self.watch_deadline = spec.deadline_handler is not None or spec.abort_on_miss  # push a deadline check
        self.rng: Any = None  # the task's own stream for release jitter and sporadic gaps (set by add_task)
        self.first_release: int | None = None  # nominal time of the first self-release
        self.server: Any = None  # the CBS or TBS serving the task (netsim.kernel.servers), None: none


class Handler:
    """Run-time state of an interrupt handler: its body and its queue of pending invocations."""

    __slots__ = (
        "active",
        "body",
        "cpu",
        "data",
        "invocations",
        "name",
        "queue",
        "spec",
        "trace_since",
        "trace_state",
    )

    def __init__(self, spec: CheckedHandler, body: Callable[[Any], Any], data: Any) -> None:
        self.spec = spec
        self.name = spec.name
        self.body = body
        self.data = data
        self.queue: deque[Any] = deque()  # invocations waiting for the active one
        self.active: Any = None
        self.invocations = 0
        self.cpu = 0
        self.trace_state: str | None = None
        self.trace_since = 0
