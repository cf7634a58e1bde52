"""Running body code: the kernel's answer to each request a task or handler body yields.

:class:`Interpreter` is the part of :class:`~netsim.kernel.kernel.Kernel` (a mixin) that runs a job's
generator while the job holds the CPU (:meth:`~Interpreter._advance`) and carries out what it yields. Each
operation :class:`~netsim.kernel.requests.Op` has one method ``_op_<name>(job, req, now)`` that returns the
value the ``yield`` gives back to the body, or :data:`GAVE_UP` when the job gave up the CPU (it sleeps,
blocks, was killed, or starts a CPU segment). ``execute``, the most frequent request (one per CPU segment),
is answered inline in the loop instead (see :meth:`~Interpreter._advance`); the other requests are looked
up in a table by their operation number.

Zero-time requests are counted per instant: more than ``livelock_limit`` of them at one instant raise a
:class:`~netsim.errors.LivelockError` naming the tasks and handlers involved.
"""

from __future__ import annotations

from types import GeneratorType
from typing import TYPE_CHECKING, Any, Callable

from netsim.errors import LivelockError, SimulationError
from netsim.kernel.events import NORMAL, schedule_call
from netsim.distributions import Constant
from netsim.kernel.exectime import ExecTime
from netsim.kernel.job import Job
from netsim.kernel.requests import EXECUTE, Op, Request
from netsim.kernel.states import BLOCKED, DONE
from netsim.kernel.task import did_you_mean
from netsim.network.message import Message

if TYPE_CHECKING:  # pragma: no cover
    from collections import deque

__all__ = ["Interpreter", "GAVE_UP"]


class _GaveUp:
    """Type of :data:`GAVE_UP`."""

    __slots__ = ()

    def __repr__(self) -> str:
        return "GAVE_UP"


#: What an ``_op_`` method returns when the job no longer holds the CPU or starts a CPU segment.
GAVE_UP = _GaveUp()

_EXECUTE = EXECUTE


class Interpreter:
    """Body execution of a kernel (mixed into :class:`~netsim.kernel.kernel.Kernel`)."""

    # provided by Kernel
    name: str
    trace: bool
    livelock_limit: int
    networks: dict[str, Any]
    _sim: Any
    _exec_rng: Any
    _ain: dict[str, Callable[[int], Any]]
    _aout: dict[str, Callable[[int, Any], None]]
    _inboxes: dict[str, "deque[Message]"]
    _running: Job | None
    _zt_time: int
    _zt_count: int
    _zt_names: dict[str, int]
    _finish: Callable[[Job, int, bool], None]  # Kernel
    _kill: Callable[[Job], None]  # Kernel
    kill_job: Callable[[Job], None]  # Kernel
    _on_sleep_done: Callable[[Any], None]  # Kernel
    _trace: Callable[[Any, "str | None", int], None]  # Tracing

    #: ``_OPS[op]`` is the method answering operation ``op`` (filled below the class; EXECUTE is inline).
    _OPS: tuple[Callable[..., Any], ...] = ()

    def _advance(self, job: Job, now: int) -> None:
        """Run ``job``'s code until it asks for CPU time, blocks or ends (it holds the CPU)."""
        if now != self._zt_time:
            self._zt_time = now
            self._zt_count = 0
            if self._zt_names:
                self._zt_names.clear()
        self._zt_count += 1
        limit = self.livelock_limit - self._zt_count
        if limit < self.livelock_limit // 2:
            names = self._zt_names
            names[job.task_name] = names.get(job.task_name, 0) + 1
        gen = job._gen
        if gen is None:
            gen = job._task.body(job)
            if type(gen) is not GeneratorType:
                self._check_generator(job, gen)
            job._gen = gen
        value = job._value
        job._value = None
        send = gen.send
        n = 0
        while True:
            try:
                req = send(value)
            except StopIteration:
                self._zt_count += n
                if job._state != DONE:
                    self._finish(job, now, False)
                return
            except Exception as exc:
                exc.add_note(f"raised by '{job.task_name}' on node '{self.name}' at t={now} ns")
                raise
            n += 1
            if n > limit:
                self._livelock(job)
            if job._state == DONE:  # killed by its own code (kernel.kill_job)
                gen.close()
                self._zt_count += n
                return
            if type(req) is not Request:
                raise SimulationError(
                    f"node '{self.name}', task '{job.task_name}' yielded {req!r}; yield a request built by the "
                    "job, e.g. `yield job.execute(1000)`")
            op = req.op
            if op == _EXECUTE:  # inline: one per CPU segment, the hottest request
                d = req.a
                if type(d) is not int:
                    d = d.value if type(d) is Constant else self._duration(job, d)
                elif d < 0:
                    raise SimulationError(f"node '{self.name}', task '{job.task_name}': execute({d}) is negative")
                if d:
                    job._remaining = d
                    self._zt_count += n
                    return
                value = None
                continue
            try:
                answer = self._OPS[op]
            except (IndexError, TypeError):
                raise SimulationError(f"node '{self.name}', task '{job.task_name}': unknown request {req!r}; "
                                      "yield a request built by the job, e.g. `yield job.execute(1000)`") from None
            value = answer(self, job, req, now)
            if value is GAVE_UP:
                self._zt_count += n
                return

    # ================================================================= one method per request
    def _op_sleep(self, job: Job, req: Request, now: int) -> Any:
        t = req.a
        if type(t) is not int:
            t = self._time_arg(job, t, "sleep")
        if t < 0:
            raise SimulationError(f"node '{self.name}', task '{job.task_name}': sleep({t}) is negative")
        if t:
            job._wake = schedule_call(self._sim, t, NORMAL, self._on_sleep_done, job)
            self._block(job, job._wake, now)
            return GAVE_UP
        return None

    def _op_sleep_until(self, job: Job, req: Request, now: int) -> Any:
        t = req.a
        if type(t) is not int:
            t = self._time_arg(job, t, "sleep_until")
        if t > now:  # a time already passed: the body continues at once
            job._wake = schedule_call(self._sim, t - now, NORMAL, self._on_sleep_done, job)
            self._block(job, job._wake, now)
            return GAVE_UP
        return None

    def _op_analog_in(self, job: Job, req: Request, now: int) -> Any:
        fn = self._ain.get(req.a)
        if fn is None:
            fn = self._io(self._ain, req.a, job, "analog input")
        return fn(now)

    def _op_analog_out(self, job: Job, req: Request, now: int) -> Any:
        fn = self._aout.get(req.a)
        if fn is None:
            fn = self._io(self._aout, req.a, job, "analog output")
        fn(now, req.b)
        return None

    def _op_send(self, job: Job, req: Request, now: int) -> Any:
        net = self.networks.get(req.a)
        if net is None:
            raise SimulationError(f"node '{self.name}', task '{job.task_name}': send on network '{req.a}', which "
                                  f"is not attached to this node{did_you_mean(str(req.a), self.networks)}")
        to, payload, bits = req.b
        priority, tag = req.c
        if type(bits) is not int or bits < 0:
            if isinstance(bits, bool) or not isinstance(bits, int) or bits < 0:
                raise SimulationError(f"node '{self.name}', task '{job.task_name}': send bits must be a "
                                      f"non-negative int, got {bits!r}")
        # Message(sender, receiver, payload, bits, priority, msg_id, network, sent_ns, seq, tag): positional
        # arguments cost half as much as keywords here (one message per send)
        net.send(Message(self.name, to, payload, bits, priority, -1, "", 0, 0, tag or job.task_name))
        return None

    def _op_receive(self, job: Job, req: Request, now: int) -> Any:
        inbox = self._inboxes.get(req.a)
        return inbox.popleft() if inbox else None

    def _op_receive_newest(self, job: Job, req: Request, now: int) -> Any:
        inbox = self._inboxes.get(req.a)
        if not inbox:
            return None
        newest = inbox.pop()
        inbox.clear()
        return newest

    def _op_fetch(self, job: Job, req: Request, now: int) -> Any:
        ok, value = req.a.try_get()
        if ok:
            return value
        req.a._getters.append(job)
        self._block(job, req.a, now)
        return GAVE_UP

    def _op_post(self, job: Job, req: Request, now: int) -> Any:
        if req.a.try_put(req.b):
            return None
        req.a._putters.append((job, req.b))
        self._block(job, req.a, now)
        return GAVE_UP

    def _op_try_fetch(self, job: Job, req: Request, now: int) -> Any:
        return req.a.try_get()[1]

    def _op_try_post(self, job: Job, req: Request, now: int) -> Any:
        return req.a.try_put(req.b)

    def _op_take(self, job: Job, req: Request, now: int) -> Any:
        if req.a.try_take():
            return None
        req.a._waiters.append(job)
        self._block(job, req.a, now)
        return GAVE_UP

    def _op_give(self, job: Job, req: Request, now: int) -> Any:
        req.a.give()
        return None

    def _op_enter(self, job: Job, req: Request, now: int) -> Any:
        if req.a.enter(job, self):
            return None
        self._block(job, req.a, now)
        return GAVE_UP

    def _op_exit(self, job: Job, req: Request, now: int) -> Any:
        req.a.exit(job, self)
        return None

    def _op_wait(self, job: Job, req: Request, now: int) -> Any:
        req.a._waiters.append(job)
        self._block(job, req.a, now)
        return GAVE_UP

    def _op_notify(self, job: Job, req: Request, now: int) -> Any:
        req.a.notify(req.b)
        return None

    def _op_kill(self, job: Job, req: Request, now: int) -> Any:
        target = job if req.a is None else req.a
        if target is job:
            self._kill(job)
            return GAVE_UP
        self.kill_job(target)
        return None

    def _op_set_speed(self, job: Job, req: Request, now: int) -> Any:
        self.set_speed(req.a)
        return None

    def set_speed(self, speed: float) -> None:
        """Set the CPU speed (TrueTime's ``ttSetCPUScaling``; :mod:`netsim.kernel.speed`). A kernel without speed
        scaling refuses it: :meth:`netsim.kernel.multicore.MulticoreDispatcher.set_speed` is the real one.

        Raises
        ------
        SimulationError
            Always here: the node has no speed scaling (give ``nodes.<n>.speed``, or ``Kernel(..., speed=1.0)``).
        """
        raise SimulationError(f"node '{self.name}': set_speed({speed!r}) on a node without speed scaling; give "
                              f"the node an initial speed (nodes.{self.name}.speed: 1, or Kernel(..., speed=1.0))")

    # ================================================================= helpers
    def _check_generator(self, job: Job, gen: Any) -> None:
        """A body's result that is not a Python generator must at least behave like one."""
        if not (hasattr(gen, "send") and hasattr(gen, "close")):
            raise SimulationError(f"node '{self.name}': body of '{job.task_name}' returned {gen!r}, not a "
                                  "generator; the body must contain `yield job.<request>(...)`")

    def _duration(self, job: Job, d: Any) -> int:
        if isinstance(d, ExecTime):
            return d.draw(self._exec_rng, job)
        return self._time_arg(job, d, "execute")

    def _time_arg(self, job: Job, t: Any, op: str) -> int:
        if isinstance(t, ExecTime):
            return t.draw(self._exec_rng, job)
        try:
            value = int(round(t))
        except (TypeError, ValueError):
            raise SimulationError(f"node '{self.name}', task '{job.task_name}': {op}() needs integer ns or an "
                                  f"ExecTime, got {t!r}") from None
        if value < 0 and op == "execute":
            raise SimulationError(f"node '{self.name}', task '{job.task_name}': execute({t}) is negative")
        return value

    def _io(self, table: dict[str, Any], channel: str, job: Job, what: str) -> Any:
        fn = table.get(channel)
        if fn is None:
            raise SimulationError(f"node '{self.name}', task '{job.task_name}': no {what} '{channel}'"
                                  f"{did_you_mean(str(channel), table)}")
        return fn

    def _block(self, job: Job, on: Any, now: int) -> None:
        job._state = BLOCKED
        job._blocked_on = on
        job._rank = job._base_rank
        self._running = None
        if self.trace:
            self._trace(job._task, "blocked", now)

    def _livelock(self, job: Job) -> None:
        names = dict(self._zt_names)
        names[job.task_name] = names.get(job.task_name, 0) + 1
        involved = sorted(names)
        raise LivelockError(
            f"node '{self.name}': livelock at t={self._sim.now} ns: more than {self.livelock_limit} zero-time "
            f"activities at one instant by {', '.join(repr(n) for n in involved)}; give the loop an execute() "
            "or a sleep() so that time advances", involved)


def _no_method(self: Interpreter, job: Job, req: Request, now: int) -> Any:  # pragma: no cover - EXECUTE is inline
    raise AssertionError(f"{req!r} is answered inline by Interpreter._advance")


Interpreter._OPS = tuple(_no_method if op == _EXECUTE else getattr(Interpreter, f"_op_{op.name.lower()}")
                         for op in Op)
