"""Timers and external trigger inputs: the interrupt sources a kernel owns besides network receive."""

from __future__ import annotations

from typing import Any

__all__ = ["Timer", "Trigger"]


class Timer:
    """A periodic or one-shot timer that invokes a handler."""

    __slots__ = ("name", "handler", "period", "start", "data", "active", "fired", "invoker")

    def __init__(self, name: str, handler: str, period: int | None, start: int, data: Any) -> None:
        self.name = name
        self.handler = handler
        self.period = period
        self.start = start
        self.data = data
        self.active = True
        self.fired = 0
        self.invoker = f"timer:{name}"


class Trigger:
    """An external interrupt input with a minimum inter-arrival time (earlier edges are ignored)."""

    __slots__ = ("name", "handler", "min_interarrival", "last", "accepted", "ignored")

    def __init__(self, name: str, handler: str, min_interarrival: int) -> None:
        self.name = name
        self.handler = handler
        self.min_interarrival = min_interarrival
        self.last: int | None = None
        self.accepted = 0
        self.ignored = 0
