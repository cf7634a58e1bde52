"""The requests a task or handler body yields to its kernel.

A body never builds these itself: it calls a method of its :class:`~netsim.kernel.job.Job`
(``job.execute(...)``, ``job.fetch(mb)`` ...) and yields what that returns. The kernel carries the request
out when it is yielded. Zero-time requests (``analog_in``, ``send``, ``try_fetch`` ...) are answered at
once, without a trip through the simpy event queue; only ``execute``, ``sleep`` and requests that block
(``fetch`` on an empty mailbox, ``take`` of a zero semaphore, ``wait``) give up the CPU or take time.

A request is an immutable value: the kernel only reads it. A program that yields the same request at every
job (``job.receive("net")``, ``job.execute(exec_time)``) may build it once, ``Request(RECEIVE, "net")``, and
yield that object each time; it saves two Python calls per request in the hot loop.
"""

from __future__ import annotations

from enum import IntEnum
from typing import Any

__all__ = ["Op", "Request", "OP_NAMES"]


class Op(IntEnum):
    """The operation of a request. The kernel answers each one with its method ``Kernel._op_<name>``
    (:mod:`netsim.kernel.interpreter`), except ``EXECUTE``, the most frequent, which it handles inline."""

    EXECUTE = 0
    SLEEP_UNTIL = 1
    ANALOG_IN = 2
    ANALOG_OUT = 3
    SEND = 4
    RECEIVE = 5
    FETCH = 6
    POST = 7
    TRY_FETCH = 8
    TRY_POST = 9
    TAKE = 10
    GIVE = 11
    WAIT = 12
    NOTIFY = 13
    KILL = 14
    SLEEP = 15


# The operations as module constants (``Request(RECEIVE, "net")`` in programs that prebuild their requests).
EXECUTE = Op.EXECUTE
SLEEP_UNTIL = Op.SLEEP_UNTIL
ANALOG_IN = Op.ANALOG_IN
ANALOG_OUT = Op.ANALOG_OUT
SEND = Op.SEND
RECEIVE = Op.RECEIVE
FETCH = Op.FETCH
POST = Op.POST
TRY_FETCH = Op.TRY_FETCH
TRY_POST = Op.TRY_POST
TAKE = Op.TAKE
GIVE = Op.GIVE
WAIT = Op.WAIT
NOTIFY = Op.NOTIFY
KILL = Op.KILL
SLEEP = Op.SLEEP

#: The name of each operation (the name of its ``Job`` method).
OP_NAMES: dict[int, str] = {op: op.name.lower() for op in Op}


class Request:
    """One request: an operation code and up to three arguments.

    Attributes
    ----------
    op : Op
        The operation.
    a, b, c
        Operation arguments (a duration, a mailbox and an item, ...).
    """

    __slots__ = ("op", "a", "b", "c")

    def __init__(self, op: Op, a: Any = None, b: Any = None, c: Any = None) -> None:
        self.op = op
        self.a = a
        self.b = b
        self.c = c

    def __repr__(self) -> str:
        return f"Request({OP_NAMES.get(self.op, self.op)}, {self.a!r}, {self.b!r}, {self.c!r})"
