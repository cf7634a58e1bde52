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

The kernel draws from the validated distributions themselves (:mod:`netsim.distributions`), with the task's own
random stream ``kernel.<node>.release.<task>``.
"""

from __future__ import annotations

from typing import Any

from netsim.distributions import DISTS, TAG_MARK, DistributionSpec
from netsim.kernel.task import SetPeriodRule as KernelSetPeriodRule
from netsim.kernel.task import TaskSpec as KernelTaskSpec

__all__ = [
    "TIME_DISTS",
    "SetPeriodRule",
    "TimeDistribution",
    "without_unused_arrivals",
]

#: The task fields of this module, left out of a resolved task while at the kernel's default (which
#: :class:`netsim.kernel.task.TaskSpec` defines).
ARRIVAL_FIELDS = ("release_jitter", "min_interarrival", "extra_interarrival", "abort_on_miss", "set_period")

#: What a period changed at run time (``kernel.set_period``, TrueTime's ``ttSetPeriod``; the feedback scheduler
#: uses it) does to the release already scheduled. ``next_release`` (default, TrueTime 1.5): it moves to one new
#: period after the last release (at once if that has passed). ``keep_armed`` (TrueTime 2.0): it stays, and the
#: new period counts from it. Period 10 ms, releases at 0 and 10 ms, new period 4 ms set at 12 ms: next releases
#: at 14, 18, 22 ms (next_release) or at 20, 24, 28 ms (keep_armed). :mod:`netsim.kernel.arrivals`.
SetPeriodRule = KernelSetPeriodRule


#: The ``dist`` names a time distribution accepts (:data:`netsim.distributions.DISTS`).
TIME_DISTS = DISTS

#: The mark of a union member's tag in a validation error's location (the same as
#: ``netsim.scenario.schema.TAG_MARK``): messages drop such parts, so a problem's path is the YAML one.
_TAG = TAG_MARK

#: A random time of a task's arrivals: a time (constant) or ``{dist: ..}``, netsim's one family of random times
#: (:mod:`netsim.distributions`), which the kernel draws from as it is.
TimeDistribution = DistributionSpec


def without_unused_arrivals(data: Any) -> Any:
    """A task's dumped data without the arrival fields left at their defaults (so a scenario that uses none
    of them dumps, and hashes, as before they existed)."""
    if isinstance(data, dict):
        for key in ARRIVAL_FIELDS:
            if key in data and data[key] == KernelTaskSpec.model_fields[key].default:
                del data[key]
    return data
