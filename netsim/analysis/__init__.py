"""Analytic cross-checks beside the simulation.

- :mod:`netsim.analysis.rta`: response-time analysis of fixed-priority preemptive task sets (blocking and
  release-jitter terms) and the EDF processor-demand test.
- :mod:`netsim.analysis.blocking`: the blocking term ``B_i`` of tasks sharing monitors under priority
  inheritance or a priority ceiling (for :class:`RTATask`'s ``blocking``).
- :mod:`netsim.analysis.can`: worst-case response times of CAN messages (non-preemptive fixed priority,
  blocking by one lower-priority frame).
- :mod:`netsim.analysis.lqg`: the expected quadratic cost of a sampled LTI loop under random input-output delay
  and sampling jitter (Jitterbug-style covariance computation; imported on its own, it needs scipy).
"""

from netsim.analysis.blocking import CriticalSection, blocking_terms
from netsim.analysis.can import CanMessage, CanResponse, can_analysis, can_response_times
from netsim.analysis.rta import (
    RTATask,
    busy_period,
    deadline_monotonic,
    edf_demand,
    edf_schedulable,
    fp_schedulable,
    hyperperiod,
    rate_monotonic,
    response_times,
    utilization,
)

__all__ = [
    "RTATask",
    "response_times",
    "fp_schedulable",
    "rate_monotonic",
    "deadline_monotonic",
    "utilization",
    "hyperperiod",
    "busy_period",
    "edf_demand",
    "edf_schedulable",
    "CriticalSection",
    "blocking_terms",
    "CanMessage",
    "CanResponse",
    "can_analysis",
    "can_response_times",
]
