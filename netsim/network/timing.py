"""Small event helpers shared by the network models: scheduled calls and transmission times.

Networks are driven by call items on the event loop's heap (see :mod:`netsim.env`) rather than by one process
per message, which keeps the cost per message to one or two heap operations. Their priorities come from the
run's one same-instant table (:mod:`netsim.env`): ends of wired transmissions, interface delays and
deliveries are ``NORMAL``; radio transmissions go on and off the air at ``AIR``; media decide who sends at
``ARBITRATE``, after every ordinary event, every kernel dispatch and every air change at *t*, including
those created while *t* is being processed. So every frame queued "in the same instant" takes part, also one
sent by a task released at *t* (CAN priority arbitration, CSMA/CD collisions of simultaneous starts, TDMA
slot starts, token visits, priority queues of serial outputs).
"""

from __future__ import annotations

import math

from simpy.events import Event

from netsim.env import ARBITRATE, Call, EventLoop
from netsim.timebase import S

__all__ = ["Call", "call_later", "arbitration_event", "tx_time_ns"]

#: ``call_later(sim, delay_ns, fn, *args, priority=NORMAL) -> Call``: call ``fn(*args)`` after ``delay_ns``
#: (0: later in this instant), with a ``priority`` of the same-instant table of :mod:`netsim.env`
#: (``ARBITRATE`` for a medium's decision among the frames queued by then: after every release, delivery and
#: dispatch of that instant); :meth:`Call.cancel` drops it. It is :meth:`netsim.env.EventLoop.call_later`.
call_later = EventLoop.call_later


def tx_time_ns(bits: int, rate_bps: float) -> int:
    """Time to put ``bits`` on a medium of ``rate_bps`` bit/s, rounded up to whole nanoseconds.

    >>> tx_time_ns(80, 80_000.0)
    1000000
    """
    if bits <= 0:
        return 0
    irate = int(rate_bps)
    if irate == rate_bps:
        return -((-bits * S) // irate)
    return max(1, math.ceil(bits * S / rate_bps - 1e-6))


def arbitration_event(sim: EventLoop, delay_ns: int = 0) -> Event:
    """An event (for a process to yield) processed at ``ARBITRATE`` priority at ``now + delay_ns``."""
    return sim.event_at(delay_ns, ARBITRATE)
