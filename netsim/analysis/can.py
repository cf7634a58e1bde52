"""Worst-case response times of CAN messages (non-preemptive fixed priority, Davis et al. 2007).

The revised CAN schedulability analysis of Davis, Burns, Bril and Lukkien ("Controller Area Network (CAN)
schedulability analysis: refuted, revisited and revised", Real-Time Systems 35, 2007), for messages queued
periodically (or sporadically with minimum inter-arrival ``period``) with queuing jitter:

* blocking ``B_m``: the longest lower-priority frame (it may have started just before ``m`` was queued);
* level-m busy period ``t_m = B_m + sum_{k in hep(m)} ceil((t_m + J_k) / T_k) C_k``;
* for each instance ``q = 0 .. ceil((t_m + J_m) / T_m) - 1``, the queuing delay
  ``w(q) = B_m + q C_m + sum_{k in hp(m)} ceil((w(q) + J_k + tau) / T_k) C_k`` and the response
  ``R(q) = J_m + w(q) - q T_m + C_m``; ``R_m = max_q R(q)``.

``tau`` is the arbitration resolution: on a real bus one bit time (a frame queued within a bit of the bus
going idle still competes); netsim's CAN model arbitrates among everything queued up to and including the
instant the bus goes idle, which the default ``tau_ns = 1`` (one nanosecond tick) reproduces exactly.
Equal priorities are treated pessimistically: the other messages of the same priority count as higher.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

__all__ = ["CanMessage", "CanResponse", "can_analysis", "can_response_times"]


@dataclass(frozen=True)
class CanMessage:
    """A CAN message stream for the analysis (times in integer nanoseconds).

    Attributes
    ----------
    name
        Label used in the results.
    priority
        Lower value = more urgent (the CAN identifier).
    period_ns
        Period or minimum inter-arrival time ``T``.
    tx_ns
        Worst-case transmission time ``C`` (with stuff bits and padding).
    jitter_ns
        Queuing jitter ``J``.
    deadline_ns
        Relative deadline (default: the period).
    """

    name: str
    priority: int
    period_ns: int
    tx_ns: int
    jitter_ns: int = 0
    deadline_ns: int | None = None


@dataclass(frozen=True)
class CanResponse:
    """Analysis result of one message.

    ``response_ns`` is ``None`` when the busy period does not end (load of the message's priority level and
    above reaches 1) or exceeds ``horizon_ns``; ``schedulable`` compares it with the deadline.
    """

    name: str
    response_ns: int | None
    blocking_ns: int
    busy_period_ns: int | None
    instances: int
    schedulable: bool


def _ceil_div(a: int, b: int) -> int:
    return -(-a // b)


def can_analysis(
    messages: Sequence[CanMessage], *, tau_ns: int = 1, horizon_ns: int | None = None
) -> list[CanResponse]:
    """Worst-case response time of every message (see the module docstring).

    Parameters
    ----------
    messages
        The message set (names unique; periods and transmission times > 0).
    tau_ns
        Arbitration resolution (one bit time on a real bus; 1 ns reproduces netsim's CAN model).
    horizon_ns
        Give up (``response_ns=None``) when a busy period or queuing delay exceeds this (default:
        100 times the longest period).

    Raises
    ------
    ValueError
        Non-positive periods or transmission times, or duplicate names.
    """
    names = [m.name for m in messages]
    if len(set(names)) != len(names):
        raise ValueError("message names must be unique")
    for m in messages:
        if m.period_ns <= 0 or m.tx_ns <= 0 or m.jitter_ns < 0:
            raise ValueError(f"message '{m.name}': period and tx time must be > 0 and jitter >= 0")
    if not messages:
        return []
    limit = horizon_ns if horizon_ns is not None else 100 * max(m.period_ns for m in messages)
    out = []
    for m in messages:
        hp = [k for k in messages if k is not m and k.priority <= m.priority]
        lp = [k for k in messages if k.priority > m.priority]
        blocking = max((k.tx_ns for k in lp), default=0)
        deadline = m.deadline_ns if m.deadline_ns is not None else m.period_ns
        # level-m busy period
        t = m.tx_ns
        busy: int | None = None
        while t <= limit:
            nxt = blocking + sum(_ceil_div(t + k.jitter_ns, k.period_ns) * k.tx_ns for k in hp + [m])
            if nxt == t:
                busy = t
                break
            t = nxt
        if busy is None:
            out.append(CanResponse(m.name, None, blocking, None, 0, False))
            continue
        q_max = _ceil_div(busy + m.jitter_ns, m.period_ns)
        worst: int | None = 0
        for q in range(q_max):
            w = blocking + q * m.tx_ns
            while True:
                nxt = blocking + q * m.tx_ns + sum(
                    _ceil_div(w + k.jitter_ns + tau_ns, k.period_ns) * k.tx_ns for k in hp
                )
                if nxt == w:
                    break
                w = nxt
                if w > limit:
                    worst = None
                    break
            if worst is None:
                break
            worst = max(worst, m.jitter_ns + w - q * m.period_ns + m.tx_ns)
        ok = worst is not None and worst <= deadline
        out.append(CanResponse(m.name, worst, blocking, busy, q_max, ok))
    return out


def can_response_times(
    messages: Sequence[CanMessage], *, tau_ns: int = 1, horizon_ns: int | None = None
) -> dict[str, int | None]:
    """Worst-case response time (ns) of each message by name; ``None`` where unbounded."""
    return {r.name: r.response_ns for r in can_analysis(messages, tau_ns=tau_ns, horizon_ns=horizon_ns)}
