"""Reference and disturbance signals: functions of integer-nanosecond time.

A scenario names its signals under ``signals:``; each entry has a ``type`` (a registered kind ``"signal"``)
and that type's parameters::

    signals:
      r:    {type: square, amplitude: 1.0, period: 2 s}
      load: {type: step, at: 1 s, value: 0.1}

:func:`make_signal` turns such a spec into a :class:`Signal`: a callable ``t_ns -> float`` that also knows
where it jumps (:meth:`Signal.breakpoints`), so a plant disturbance input can be switched exactly at the
jump instants instead of on a polling grid.

Examples
--------
>>> from netsim.timebase import MS
>>> r = make_signal({"type": "square", "amplitude": 1.0, "period": "10 ms"})
>>> r(0), r(5 * MS), r(10 * MS)
(1.0, -1.0, 1.0)
>>> r.breakpoints(0, 20 * MS)
[5000000, 10000000, 15000000, 20000000]
"""

from __future__ import annotations

import abc

import math
from typing import Any, Callable, ClassVar, Literal

import numpy as np
from pydantic import ValidationError, model_validator

from netsim.errors import ConfigError
from netsim.registry import lookup, register
from netsim.timebase import S, to_seconds
from netsim.units import Duration, SignedTime, StrictModel, Time

__all__ = [
    "Signal",
    "Constant",
    "Step",
    "Square",
    "Sine",
    "Ramp",
    "Table",
    "make_signal",
    "signal_params_model",
]


class Signal(abc.ABC):
    """Base class of signals: call with ``t_ns`` to get the value.

    Attributes
    ----------
    piecewise_constant : bool
        True when the signal only changes at its breakpoints (then holding it between breakpoints is exact).
    """

    Params: ClassVar[type[StrictModel]]
    piecewise_constant: ClassVar[bool] = True

    @abc.abstractmethod
    def __call__(self, t_ns: int) -> float:
        """The signal's value at ``t_ns``."""

    def breakpoints(self, t0_ns: int, t1_ns: int) -> list[int]:
        """Instants in ``(t0_ns, t1_ns]`` where the value jumps, ascending."""
        return []


@register("signal", "constant", "a constant value")
class Constant(Signal):
    """A constant ``value``."""

    class Params(StrictModel):
        value: float = 0.0

    def __init__(self, params: Params) -> None:
        self.value = float(params.value)

    def __call__(self, t_ns: int) -> float:
        return self.value


@register("signal", "step", "initial before `at`, value from `at` on")
class Step(Signal):
    """``initial`` before ``at``, ``value`` from ``at`` on (the value at ``at`` is the new one)."""

    class Params(StrictModel):
        at: Time = 0
        value: float = 1.0
        initial: float = 0.0

    def __init__(self, params: Params) -> None:
        self.at = int(params.at)
        self.value = float(params.value)
        self.initial = float(params.initial)

    def __call__(self, t_ns: int) -> float:
        return self.value if t_ns >= self.at else self.initial

    def breakpoints(self, t0_ns: int, t1_ns: int) -> list[int]:
        return [self.at] if t0_ns < self.at <= t1_ns else []


@register("signal", "square", "bias +/- amplitude, high for duty*period from start")
class Square(Signal):
    """A square wave: ``bias + amplitude`` during the first ``duty`` fraction of each period, then
    ``bias - amplitude``. Before ``start`` the value is ``bias + amplitude`` as well (the wave is periodic
    in both directions)."""

    class Params(StrictModel):
        amplitude: float = 1.0
        period: Duration
        duty: float = 0.5
        bias: float = 0.0
        start: SignedTime = 0

        @model_validator(mode="after")
        def _duty(self) -> "Square.Params":
            if not 0.0 < self.duty < 1.0:
                raise ValueError(f"duty must lie strictly between 0 and 1, got {self.duty}")
            return self

    def __init__(self, params: Params) -> None:
        self.amplitude = float(params.amplitude)
        self.period = int(params.period)
        self.high_ns = int(round(params.duty * self.period))
        self.bias = float(params.bias)
        self.start = int(params.start)

    def __call__(self, t_ns: int) -> float:
        phase = (t_ns - self.start) % self.period
        return self.bias + (self.amplitude if phase < self.high_ns else -self.amplitude)

    def breakpoints(self, t0_ns: int, t1_ns: int) -> list[int]:
        out: list[int] = []
        k = (t0_ns - self.start) // self.period
        while True:
            base = self.start + k * self.period
            for t in (base + self.high_ns, base + self.period):
                if t > t1_ns:
                    return out
                if t > t0_ns:
                    out.append(t)
            k += 1


@register("signal", "sine", "bias + amplitude*sin(2*pi*frequency*t + phase)")
class Sine(Signal):
    """``bias + amplitude * sin(2 pi frequency t + phase)``, ``frequency`` in Hz, ``phase`` in radians."""

    piecewise_constant = False

    class Params(StrictModel):
        amplitude: float = 1.0
        frequency: float
        phase: float = 0.0
        bias: float = 0.0

    def __init__(self, params: Params) -> None:
        self.amplitude = float(params.amplitude)
        self.omega = 2.0 * math.pi * float(params.frequency)
        self.phase = float(params.phase)
        self.bias = float(params.bias)

    def __call__(self, t_ns: int) -> float:
        return self.bias + self.amplitude * math.sin(self.omega * to_seconds(t_ns) + self.phase)


@register("signal", "ramp", "initial until start, then rising with slope per second")
class Ramp(Signal):
    """``initial`` until ``start``, then ``initial + slope * (t - start)`` (``slope`` per second)."""

    piecewise_constant = False

    class Params(StrictModel):
        slope: float = 1.0
        start: Time = 0
        initial: float = 0.0

    def __init__(self, params: Params) -> None:
        self.slope = float(params.slope)
        self.start = int(params.start)
        self.initial = float(params.initial)

    def __call__(self, t_ns: int) -> float:
        if t_ns <= self.start:
            return self.initial
        return self.initial + self.slope * (t_ns - self.start) / S


@register("signal", "table", "values at given times, held or linearly interpolated")
class Table(Signal):
    """A table of ``(times, values)``: held from each time to the next (``interpolation: hold``) or joined
    linearly (``linear``). Before the first time the first value holds; after the last, the last."""

    class Params(StrictModel):
        times: list[Time]
        values: list[float]
        interpolation: Literal["hold", "linear"] = "hold"

        @model_validator(mode="after")
        def _shape(self) -> "Table.Params":
            if len(self.times) != len(self.values):
                raise ValueError(
                    f"times and values must have the same length, got {len(self.times)} and {len(self.values)}"
                )
            if not self.times:
                raise ValueError("a table needs at least one (time, value) pair")
            if any(b <= a for a, b in zip(self.times, self.times[1:])):
                raise ValueError("times must be strictly increasing")
            return self

    def __init__(self, params: Params) -> None:
        self.times = np.asarray(params.times, dtype=np.int64)
        self.values = np.asarray(params.values, dtype=float)
        self.linear = params.interpolation == "linear"
        self.piecewise_constant = not self.linear  # type: ignore[misc]

    def __call__(self, t_ns: int) -> float:
        if self.linear:
            return float(np.interp(float(t_ns), self.times.astype(float), self.values))
        i = int(np.searchsorted(self.times, t_ns, side="right")) - 1
        return float(self.values[max(i, 0)])

    def breakpoints(self, t0_ns: int, t1_ns: int) -> list[int]:
        if self.linear:
            return []
        return [int(t) for t in self.times[1:] if t0_ns < t <= t1_ns]


def _split(spec: Any) -> tuple[str, dict[str, Any]]:
    if hasattr(spec, "model_dump"):
        spec = spec.model_dump()
    if not isinstance(spec, dict):
        raise ConfigError(f"a signal is a mapping with a 'type' key, got {spec!r}")
    body = dict(spec)
    type_name = body.pop("type", None)
    if not isinstance(type_name, str):
        raise ConfigError("a signal needs a 'type' (constant, step, square, sine, ramp, table)")
    # A nested ``params:`` mapping is accepted as well as flat keys.
    if set(body) == {"params"} and isinstance(body["params"], dict):
        body = dict(body["params"])
    return type_name, body


def signal_params_model(type_name: str) -> type[StrictModel]:
    """The ``Params`` model of the signal type ``type_name`` (for scenario validation)."""
    return lookup("signal", type_name).Params


def make_signal(spec: Any) -> Signal | Callable[[int], float]:
    """Build a signal from ``{"type": name, **params}`` (or ``{"type": name, "params": {...}}``).

    A plain callable ``t_ns -> float`` is returned unchanged, so code can pass functions too.

    Raises
    ------
    ConfigError
        Unknown type or invalid parameters (the message names the parameter).
    """
    if callable(spec) and not isinstance(spec, dict):
        return spec
    type_name, body = _split(spec)
    cls = lookup("signal", type_name)
    try:
        params = cls.Params.model_validate(body)
    except ValidationError as exc:
        problems = "; ".join(
            f"{'.'.join(str(p) for p in err['loc']) or type_name}: {err['msg']}" for err in exc.errors()
        )
        raise ConfigError(f"signal of type '{type_name}': {problems}") from None
    return cls(params)
