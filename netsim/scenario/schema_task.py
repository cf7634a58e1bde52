"""The scenario fields of a task's arrivals: release jitter, sporadic arrivals and abort on deadline miss.

Kept apart from :mod:`netsim.scenario.schema` (which uses them in its ``TaskSpec``) so that the task-timing
part of the format reads in one place. A distribution is written as the other times of a scenario are:
a time (``"1 ms"``: constant) or a mapping with ``dist``, the forms of ``execution:`` plus ``exponential``
(as a link's ``delay:``)::

    release_jitter: {dist: uniform, low: 0 ms, high: 1 ms}     # each job arrives 0..1 ms after its release
    release: sporadic
    min_interarrival: 10 ms                                    # arrivals at least 10 ms apart ...
    extra_interarrival: {dist: exponential, mean: 5 ms}        # ... plus an exponential gap of mean 5 ms
    abort_on_miss: true                                        # kill a job still unfinished at its deadline
    set_period: keep_armed                                     # a period changed at run time: see SetPeriodRule

The kernel reads them as :class:`~netsim.kernel.exectime.ExecTime` models (:func:`kernel_fields`), drawn from
the task's own random stream ``kernel.<node>.release.<task>``.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import (
    BeforeValidator,
    ConfigDict,
    Discriminator,
    Field,
    Tag,
    model_validator,
)

from netsim.units import Duration, StrictModel, Time

__all__ = [
    "TIME_DISTS",
    "SetPeriodRule",
    "ConstantTime",
    "EmpiricalTime",
    "ExponentialTime",
    "NormalTime",
    "TimeDistribution",
    "UniformTime",
    "kernel_fields",
    "upper_bound_ns",
    "without_unused_arrivals",
]

#: The task fields of this module and their values when unused.
ARRIVAL_DEFAULTS: dict[str, Any] = {"release_jitter": None, "min_interarrival": None, "extra_interarrival": None,
                                    "abort_on_miss": False, "set_period": "next_release"}

#: What a period changed at run time (``kernel.set_period``, TrueTime's ``ttSetPeriod``; the feedback scheduler
#: uses it) does to the release already scheduled. ``next_release`` (default, TrueTime 1.5): it moves to one new
#: period after the last release (at once if that has passed). ``keep_armed`` (TrueTime 2.0): it stays, and the
#: new period counts from it. Period 10 ms, releases at 0 and 10 ms, new period 4 ms set at 12 ms: next releases
#: at 14, 18, 22 ms (next_release) or at 20, 24, 28 ms (keep_armed). :mod:`netsim.kernel.arrivals`.
SetPeriodRule = Literal["next_release", "keep_armed"]


class _Dist(StrictModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class ConstantTime(_Dist):
    """Always ``value`` (same as writing the time itself)."""

    dist: Literal["constant"] = "constant"
    value: Time


class UniformTime(_Dist):
    """Uniform on ``[low, high]`` (integer ns)."""

    dist: Literal["uniform"]
    low: Time
    high: Time

    @model_validator(mode="after")
    def _order(self) -> UniformTime:
        if self.low > self.high:
            raise ValueError("low must not exceed high")
        return self


class NormalTime(_Dist):
    """Normal with ``mean`` and ``std``, clipped to ``[min, max]``."""

    dist: Literal["normal"]
    mean: Time
    std: Time
    min: Time = 0
    max: Time | None = None

    @model_validator(mode="after")
    def _order(self) -> NormalTime:
        if self.max is not None and self.max < self.min:
            raise ValueError("max must not be below min")
        return self


class ExponentialTime(_Dist):
    """``shift`` plus an exponential variable of mean ``mean`` (unbounded: analysis gives no bound with it)."""

    dist: Literal["exponential"]
    mean: Duration
    shift: Time = 0


class EmpiricalTime(_Dist):
    """One of the measured ``values``, each equally likely."""

    dist: Literal["empirical"]
    values: list[Time] = Field(min_length=1)


#: The ``dist`` names a time distribution accepts.
TIME_DISTS = ("constant", "uniform", "normal", "exponential", "empirical")


def _shorthand(value: Any) -> Any:
    if isinstance(value, (str, int, float)) and not isinstance(value, bool):
        return {"dist": "constant", "value": value}
    return value


#: The mark of a union member's tag in a validation error's location (``netsim.scenario.schema.TAG_MARK``,
#: which imports this module): messages drop such parts, so a problem's path is the YAML one
#: (``release_jitter.value``, not ``release_jitter.constant.value``).
_TAG = "§"


def _dist_tag(value: Any) -> str | None:
    """The member of :data:`TimeDistribution` for ``value`` (None: a bad or missing ``dist``, reported as
    ``time_distribution`` with the known names by :mod:`netsim.scenario.messages`)."""
    dist = value.get("dist") if isinstance(value, dict) else getattr(value, "dist", None)
    return f"{_TAG}{dist}" if dist in TIME_DISTS else None


#: A random time of a task's arrivals: a time (constant) or ``{dist: ..}`` (see the module notes).
TimeDistribution = Annotated[
    Annotated[ConstantTime, Tag(f"{_TAG}constant")] | Annotated[UniformTime, Tag(f"{_TAG}uniform")]
    | Annotated[NormalTime, Tag(f"{_TAG}normal")] | Annotated[ExponentialTime, Tag(f"{_TAG}exponential")]
    | Annotated[EmpiricalTime, Tag(f"{_TAG}empirical")],
    Discriminator(_dist_tag, custom_error_type="time_distribution", custom_error_message="bad time distribution"),
    BeforeValidator(_shorthand),
]


def _exec_time(dist: Any) -> Any:
    """The kernel's :class:`~netsim.kernel.exectime.ExecTime` for a distribution model (None stays None)."""
    if dist is None:
        return None
    from netsim.kernel.exectime import ExecTime

    if isinstance(dist, ConstantTime):
        return ExecTime.constant(dist.value)
    if isinstance(dist, UniformTime):
        return ExecTime.uniform(dist.low, dist.high)
    if isinstance(dist, NormalTime):
        return ExecTime.normal(dist.mean, dist.std, dist.min, dist.max)
    if isinstance(dist, ExponentialTime):
        return ExecTime.exponential(dist.mean, dist.shift)
    return ExecTime.empirical(dist.values)


def kernel_fields(fields: dict[str, Any]) -> dict[str, Any]:
    """The kernel ``TaskSpec`` keywords with the distribution models turned into ``ExecTime`` models."""
    out = dict(fields)
    for name in ("release_jitter", "extra_interarrival"):
        out[name] = _exec_time(out.get(name))
    return out


def upper_bound_ns(dist: Any) -> int | None:
    """The largest value of a distribution model in ns (``0`` for None; ``None`` when unbounded)."""
    if dist is None:
        return 0
    if isinstance(dist, ConstantTime):
        return int(dist.value)
    if isinstance(dist, UniformTime):
        return int(dist.high)
    if isinstance(dist, NormalTime):
        return None if dist.max is None else int(dist.max)
    if isinstance(dist, EmpiricalTime):
        return int(max(dist.values))
    return None


def without_unused_arrivals(data: Any) -> Any:
    """A task's dumped data without the arrival fields left at their defaults (so a scenario that uses none
    of them dumps, and hashes, as before they existed)."""
    if isinstance(data, dict):
        for key, default in ARRIVAL_DEFAULTS.items():
            if key in data and data[key] == default:
                del data[key]
    return data
