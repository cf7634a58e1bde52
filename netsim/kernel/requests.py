"""The requests a task or handler body yields to its kernel.

A body never builds these itself: it calls a method of its :class:`~netsim.kernel.job.Job`
(``job.execute(...)``, ``job.fetch(mb)`` ...) and yields what that returns. The kernel carries the request
out when it is yielded. Zero-time requests (``analog_in``, ``send``, ``try_fetch`` ...) are answered at
once, without a trip through the simpy event queue; only ``execute``, ``sleep`` and requests that block
(``fetch`` on an empty mailbox, ``take`` of a zero semaphore, ``wait``, ``enter`` of a held monitor) give up the CPU or take time.

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
    ENTER = 16
    EXIT = 17
    SET_SPEED = 18
    RECEIVE_NEWEST = 19


# The operations as plain ints (``Request(RECEIVE, "net")`` in programs that prebuild their requests). Requests
# carry these, not the enum members: comparing and indexing with an exact int is what CPython's specialized
# bytecode does fastest (an IntEnum member costs about 100 machine instructions more per comparison).
EXECUTE = Op.EXECUTE.value
SLEEP_UNTIL = Op.SLEEP_UNTIL.value
ANALOG_IN = Op.ANALOG_IN.value
ANALOG_OUT = Op.ANALOG_OUT.value
SEND = Op.SEND.value
RECEIVE = Op.RECEIVE.value
FETCH = Op.FETCH.value
POST = Op.POST.value
TRY_FETCH = Op.TRY_FETCH.value
TRY_POST = Op.TRY_POST.value
TAKE = Op.TAKE.value
GIVE = Op.GIVE.value
WAIT = Op.WAIT.value
NOTIFY = Op.NOTIFY.value
KILL = Op.KILL.value
SLEEP = Op.SLEEP.value
ENTER = Op.ENTER.value
EXIT = Op.EXIT.value
SET_SPEED = Op.SET_SPEED.value
RECEIVE_NEWEST = Op.RECEIVE_NEWEST.value

#: The name of each operation (the name of its ``Job`` method).
OP_NAMES: dict[int, str] = {op.value: op.name.lower() for op in Op}


class Request:
    """One request: an operation code and up to three arguments.

    Attributes
    ----------
    op : int
        The operation: an :class:`Op` value (the module's constants ``EXECUTE``, ``SEND`` ...).
    a, b, c
        Operation arguments (a duration, a mailbox and an item, ...).
    """

    __slots__ = ("op", "a", "b", "c")

    def __init__(self, op: int, a: Any = None, b: Any = None, c: Any = None) -> None:
        self.op = op
        self.a = a
        self.b = b
        self.c = c

    def __repr__(self) -> str:
        return f"Request({OP_NAMES.get(self.op, self.op)}, {self.a!r}, {self.b!r}, {self.c!r})"
