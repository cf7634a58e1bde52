"""A job: one execution of a task body (or one invocation of an interrupt handler).

The kernel calls the task's body once per job with the :class:`Job` as its only argument. The body is a
generator; every interaction with the simulated computer is a request built by a method of the job and
**yielded**::

    def controller(job):
        y = yield job.analog_in("y")
        yield job.execute(ExecTime.uniform(400_000, 600_000))   # preemptible CPU time
        yield job.send("can", "actuator", -2.0 * y, bits=64)
        yield job.sleep(1 * MS)

Code between two yields takes no simulated time and is never interrupted: it runs when the job holds
the CPU, at the start of the job's next segment (TrueTime's segment functions).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable

import numpy as np

from netsim.errors import SimulationError
from netsim.kernel import requests as rq
from netsim.kernel.monitor import Monitor
from netsim.kernel.requests import Request
from netsim.kernel.states import NEW, STATE_NAMES
from netsim.kernel.sync import Event, Mailbox, Semaphore

if TYPE_CHECKING:  # pragma: no cover
    from netsim.kernel.exectime import ExecTime
    from netsim.kernel.kernel import Kernel

__all__ = ["Job", "JobContext", "JobState"]

_EXECUTE = rq.EXECUTE


class JobContext:
    """What the jobs of one kernel need of it: the one object a :class:`Job` holds instead of the kernel.

    A job reads the clock, the node's shared state and random stream through it, and the synchronisation
    objects (:mod:`netsim.kernel.sync`) hand a blocked job its result through :attr:`unblock`; nothing else of
    the kernel is reached from a job.

    Attributes
    ----------
    kernel : Kernel
        The kernel (``job.kernel``: its public API, e.g. ``create_job`` or ``trigger``).
    name : str
        The node name.
    sim : EventLoop
        The event loop (``sim.now`` is the time in ns).
    shared : dict[str, Any]
        The node's state shared by its bodies (``kernel.shared``).
    rng : numpy.random.Generator
        The node's random stream for body code.
    unblock : Callable[[Job, Any], None]
        Wake a blocked job with a value as the result of its request (called by the sync objects).
    """

    __slots__ = ("kernel", "name", "sim", "shared", "rng", "unblock")

    def __init__(self, kernel: "Kernel", name: str, sim: Any, shared: dict[str, Any], rng: np.random.Generator,
                 unblock: Callable[["Job", Any], None]) -> None:
        self.kernel = kernel
        self.name = name
        self.sim = sim
        self.shared = shared
        self.rng = rng
        self.unblock = unblock


class JobState:
    """The scheduling state the kernel keeps on each job (read and written by the kernel only).

    Every field is a class-level default, so creating a job (one per handler invocation, possibly 100 000
    per simulated second) sets only what differs.

    Attributes
    ----------
    _state : int
        Life-cycle state (:mod:`netsim.kernel.states`).
    _rank, _base_rank : tuple
        Urgency in the ready queue (smaller is more urgent): ``(0, priority)`` for handlers, ``(1, key)``
        for task jobs (the policy's key); ``_rank`` is raised while a non-preemptible job runs.
    _seq : int
        Order of becoming ready (FIFO among equal ranks).
    _np : bool
        Non-preemptible between tasks once started.
    _gen, _value
        The body's generator and the value its pending request returns.
    _remaining : int
        CPU time left of the current ``execute``.
    _pre_left : int
        Kernel time to run before the body continues: a context switch or a handler's ISR latency.
    _budget : int | None
        WCET budget left (``None``: no budget).
    _seg_start, _seg_end : int
        Start and planned end of the current CPU segment.
    _ev, _ev_time
        The pending segment wake-up of the job and its time.
    _win_end : int
        For a periodic load's real invocation at a tick: the end of its window.
    _blocked_on, _wake
        What a blocked job waits on; its pending sleep wake-up.
    _held, _own_rank
        The monitors the job owns (``None`` until it first enters or waits for one) and its own rank while
        ``_rank``/``_base_rank`` carry an inherited or ceiling rank (:mod:`netsim.kernel.monitor`).
    _server
        The constant bandwidth server whose budget the job uses (:mod:`netsim.kernel.servers`), else None.
    _core, _last_core, _in_seg, _seg_work
        Multicore and speed-scaling kernels only (:mod:`netsim.kernel.multicore`): the core the job holds
        (-1: none), the core it last ran on (-1: never ran), whether one of its segments is under way, and
        the work (execution ns at speed 1) its current execution segment was planned for (0: a kernel-time
        segment: context switch, migration or ISR latency).
    """

    _gen: Any = None
    _state = NEW
    _rank: tuple[Any, Any] = (1, 0)
    _base_rank: tuple[Any, Any] = (1, 0)
    _seq = 0
    _remaining = 0
    _pre_left = 0
    _budget: int | None = None
    _value: Any = None
    _seg_start = 0
    _seg_end = 0
    _ev: Any = None
    _ev_time = 0
    _win_end = 0
    _blocked_on: Any = None
    _wake: Any = None
    _np = False
    _held: "list[Monitor] | None" = None
    _own_rank: Any = None
    _server: Any = None
    _core = -1
    _last_core = -1
    _in_seg = False
    _seg_work = 0


class Job(JobState):
    """One job of a task, or one invocation of an interrupt handler.

    Attributes
    ----------
    task_name : str
        Name of the task (or handler) the job belongs to.
    job_id : int
        Index of the job within its task (0, 1, 2, ...).
    data : Any
        Data given at release (``create_job(task, data)``, the message of a receive, the trigger's data,
        the overrunning job for an overrun handler), else the task's ``data``.
    release : int
        Release (or invocation) time in ns.
    deadline : int | None
        Absolute deadline in ns (``None``: no deadline).
    start, finish : int | None
        First time the job got the CPU; time it finished or was killed.
    cpu_time : int
        CPU time consumed so far (execution plus context switches charged to it), ns.
    preemptions : int
        How many times it lost the CPU to a more urgent job or handler while not finished.
    killed : bool
        True when it was ended by ``kill``.
    invoker : str | None
        For handler invocations: who raised it (timer, trigger, network, task name).
    arrival : int | None
        For a task with release jitter: the time the job actually arrived (``release`` is the nominal one);
        ``None`` otherwise.
    """

    start: int | None = None
    finish: int | None = None
    cpu_time = 0
    preemptions = 0
    killed = False
    invoker: str | None = None
    arrival: int | None = None
    wcet_overrun = False
    deadline_overrun = False

    def __init__(self, ctx: JobContext, task: Any, job_id: int, data: Any, release: int,
                 deadline: int | None, is_handler: bool = False, invoker: str | None = None) -> None:
        self._ctx = ctx
        self._task = task
        self.is_handler = is_handler
        self.task_name: str = task.name
        self.job_id = job_id
        self.data = data
        self.release = release
        self.deadline = deadline
        if invoker is not None:
            self.invoker = invoker

    # ----------------------------------------------------------------- context
    @property
    def now(self) -> int:
        """Current simulation time in ns."""
        return self._ctx.sim.now

    @property
    def spec(self) -> Any:
        """The static description of the task (:class:`TaskSpec`) or handler (:class:`HandlerSpec`)."""
        return self._task.spec

    @property
    def kernel(self) -> "Kernel":
        """The kernel (node) the job runs on."""
        return self._ctx.kernel

    @property
    def shared(self) -> dict[str, Any]:
        """The node's shared state (``kernel.shared``)."""
        return self._ctx.shared

    @property
    def rng(self) -> np.random.Generator:
        """The node's random stream for body code, ``env.rng(f"kernel.{node}.rng")``."""
        return self._ctx.rng

    @property
    def state(self) -> str:
        """``"queued"``, ``"ready"``, ``"running"``, ``"blocked"`` or ``"done"``."""
        return STATE_NAMES[self._state]

    @property
    def done(self) -> bool:
        """True once the job finished or was killed."""
        return self.finish is not None

    # ----------------------------------------------------------------- time
    def execute(self, duration: "int | ExecTime") -> Request:
        """Consume ``duration`` ns (or one draw of an :class:`ExecTime`) of preemptible CPU time."""
        return Request(_EXECUTE, duration)

    def sleep(self, duration: int) -> Request:
        """Give up the CPU for ``duration`` ns."""
        return Request(rq.SLEEP, duration)

    def sleep_until(self, t_ns: int) -> Request:
        """Give up the CPU until absolute time ``t_ns`` (returns at once if it has passed)."""
        return Request(rq.SLEEP_UNTIL, t_ns)

    def set_speed(self, speed: float) -> Request:
        """Set the node's CPU speed now (TrueTime's ``ttSetCPUScaling``): from now on ``execute(w)`` takes
        ``w / speed`` ns (the node needs ``nodes.<n>.speed``: :mod:`netsim.kernel.speed`)."""
        return Request(rq.SET_SPEED, speed)

    # ----------------------------------------------------------------- I/O and network
    def analog_in(self, channel: str) -> Request:
        """Read the analog input ``channel`` now; the yield returns the value."""
        return Request(rq.ANALOG_IN, channel)

    def analog_out(self, channel: str, value: Any) -> Request:
        """Write ``value`` to the analog output ``channel`` now."""
        return Request(rq.ANALOG_OUT, channel, value)

    def send(self, network: str, to: str | None, payload: Any, bits: int, priority: int = 0,
             tag: str = "") -> Request:
        """Send ``payload`` (``bits`` long) to node ``to`` (``None``: broadcast) on ``network``.

        The kernel fills ``sender``, ``receiver``, ``bits``, ``priority`` and ``tag`` (default: the task
        name) of a :class:`~netsim.network.message.Message` and calls ``network.send(msg)``.
        """
        return Request(rq.SEND, network, (to, payload, bits), (priority, tag))

    def receive(self, network: str) -> Request:
        """The next message of the node's inbox for ``network``; the yield returns it, or ``None``."""
        return Request(rq.RECEIVE, network)

    def receive_newest(self, network: str) -> Request:
        """Empty the node's inbox for ``network`` in one request; the yield returns the newest message, or
        ``None`` when it was empty (the older ones are dropped unread, as by a loop of :meth:`receive`)."""
        return Request(rq.RECEIVE_NEWEST, network)

    # ----------------------------------------------------------------- synchronisation
    def fetch(self, mailbox: Mailbox) -> Request:
        """Take the oldest item of ``mailbox``, blocking while it is empty; the yield returns the item."""
        self._check(mailbox, Mailbox, "fetch")
        return Request(rq.FETCH, mailbox)

    def post(self, mailbox: Mailbox, item: Any) -> Request:
        """Put ``item`` into ``mailbox``, blocking while it is full."""
        self._check(mailbox, Mailbox, "post")
        return Request(rq.POST, mailbox, item)

    def try_fetch(self, mailbox: Mailbox) -> Request:
        """Take the oldest item of ``mailbox`` without blocking; the yield returns ``None`` if empty."""
        self._check(mailbox, Mailbox, "try_fetch")
        return Request(rq.TRY_FETCH, mailbox)

    def try_post(self, mailbox: Mailbox, item: Any) -> Request:
        """Put ``item`` into ``mailbox`` without blocking; the yield returns ``False`` if full."""
        self._check(mailbox, Mailbox, "try_post")
        return Request(rq.TRY_POST, mailbox, item)

    def take(self, semaphore: Semaphore) -> Request:
        """Decrement ``semaphore``, blocking at zero."""
        self._check(semaphore, Semaphore, "take")
        return Request(rq.TAKE, semaphore)

    def give(self, semaphore: Semaphore) -> Request:
        """Increment ``semaphore`` (or wake its first waiter)."""
        self._check(semaphore, Semaphore, "give")
        return Request(rq.GIVE, semaphore)

    def wait(self, event: Event) -> Request:
        """Block until ``event`` is notified."""
        self._check(event, Event, "wait")
        return Request(rq.WAIT, event)

    def notify(self, event: Event, all: bool = False) -> Request:  # noqa: A002 - TrueTime vocabulary
        """Wake the first waiter of ``event`` (every waiter with ``all=True``)."""
        self._check(event, Event, "notify")
        return Request(rq.NOTIFY, event, bool(all))

    def enter(self, monitor: Monitor) -> Request:
        """Enter ``monitor`` (TrueTime's ``ttEnterMonitor``), blocking while another job holds it."""
        self._check(monitor, Monitor, "enter")
        return Request(rq.ENTER, monitor)

    def exit(self, monitor: Monitor) -> Request:
        """Leave ``monitor`` (TrueTime's ``ttExitMonitor``); its most urgent waiter gets it."""
        self._check(monitor, Monitor, "exit")
        return Request(rq.EXIT, monitor)

    def kill(self, target: "Job | None" = None) -> Request:
        """End ``target`` now (default: this job). Killing this job ends its body at the yield."""
        if target is not None and not isinstance(target, Job):
            raise SimulationError(f"task '{self.task_name}': kill() needs a Job, got {target!r}")
        return Request(rq.KILL, target)

    def _check(self, obj: Any, cls: type, op: str) -> None:
        if not isinstance(obj, cls):
            raise SimulationError(
                f"task '{self.task_name}': {op}() needs a {cls.__name__}, got {type(obj).__name__} {obj!r}"
            )

    def __repr__(self) -> str:
        return f"<Job {self.task_name}#{self.job_id} {self.state} release={self.release}>"
