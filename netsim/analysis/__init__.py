"""Analytic cross-checks beside the simulation.

- :mod:`netsim.analysis.rta`: response-time analysis of fixed-priority preemptive task sets (blocking and
  release-jitter terms) and the EDF processor-demand test.
- :mod:`netsim.analysis.blocking`: the blocking term ``B_i`` of tasks sharing monitors under priority
  inheritance or a priority ceiling (for :class:`RTATask`'s ``blocking``).
- :mod:`netsim.analysis.can`: worst-case response times of CAN messages (non-preemptive fixed priority,
  blocking by one lower-priority frame).
- :mod:`netsim.analysis.lqg`: the expected quadratic cost of a sampled LTI loop under random input-output delay
  and sampling jitter (Jitterbug-style covariance computation; imported on its own, it needs scipy).
- :mod:`netsim.analysis.platform`: what a node's CPU changes: speed scaling, partitioned and global multicore
  scheduling (the GFB test for global EDF), CBS/TBS servers, time-triggered slots.
- :mod:`netsim.analysis.from_scenario`: a scenario's tasks, handlers and CAN message streams as the types above.
- :mod:`netsim.analysis.loops`: a scenario's PID and static state-feedback loops and the expected ISE of each over
  a run, from :mod:`netsim.analysis.lqg` with the run's timing (imported on its own, as lqg).
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
