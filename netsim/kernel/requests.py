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

from typing import Any

__all__ = ["Request", "OP_NAMES"]

# Operation codes, ordered roughly by how often they occur (the kernel tests them in this order).
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

OP_NAMES: dict[int, str] = {
    EXECUTE: "execute",
    SLEEP_UNTIL: "sleep_until",
    ANALOG_IN: "analog_in",
    ANALOG_OUT: "analog_out",
    SEND: "send",
    RECEIVE: "receive",
    FETCH: "fetch",
    POST: "post",
    TRY_FETCH: "try_fetch",
    TRY_POST: "try_post",
    TAKE: "take",
    GIVE: "give",
    WAIT: "wait",
    NOTIFY: "notify",
    KILL: "kill",
    SLEEP: "sleep",
}


class Request:
    """One request: an operation code and up to three arguments.

    Attributes
    ----------
    op : int
        The operation (see :data:`OP_NAMES`).
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
