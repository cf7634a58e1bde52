"""The simulated real-time kernel (TrueTime semantics with generator bodies).

>>> from netsim.env import SimEnv
>>> from netsim.timebase import MS
>>> env = SimEnv(seed=1)
>>> k = Kernel(env, "ctrl", policy="rm")
>>> def body(job):
...     yield job.execute(2 * MS)
>>> _ = k.create_task("control", body, period=5 * MS)
>>> env.run(10 * MS)
>>> [r.response for r in k.job_records if r.finish is not None]
[2000000, 2000000]

The names below are imported on first use (PEP 562), so a module that needs only the static descriptions
(``from netsim.kernel.task import TaskSpec``, as the scenario schema does) does not load the run time
(simpy, numpy). The scheduling policies register themselves under registry kind ``"policy"`` when
:mod:`netsim.kernel.policies` is imported (by the kernel, or by :func:`netsim.registry.load_plugins`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from netsim.lazy_import import lazy_exports

if TYPE_CHECKING:  # pragma: no cover
    from netsim.kernel.exectime import ExecTime
    from netsim.kernel.job import Job
    from netsim.kernel.kernel import Kernel
    from netsim.kernel.load import PeriodicLoad
    from netsim.kernel.monitor import Monitor
    from netsim.kernel.policies import (DeadlineMonotonic, EarliestDeadlineFirst, FixedPriority,
                                        NonPreemptiveEDF, NonPreemptiveFixedPriority, Policy, RateMonotonic)
    from netsim.kernel.records import JobRecord
    from netsim.kernel.requests import Request
    from netsim.kernel.sync import Event, Mailbox, Semaphore
    from netsim.kernel.task import Handler, HandlerSpec, Task, TaskSpec
    from netsim.kernel.timers import Timer, Trigger

#: Where each public name lives.
_HOMES = {
    "Kernel": "kernel",
    "Job": "job",
    "ExecTime": "exectime",
    "Mailbox": "sync",
    "Semaphore": "sync",
    "Event": "sync",
    "Monitor": "monitor",
    "JobRecord": "records",
    "Policy": "policies",
    "FixedPriority": "policies",
    "RateMonotonic": "policies",
    "DeadlineMonotonic": "policies",
    "EarliestDeadlineFirst": "policies",
    "NonPreemptiveFixedPriority": "policies",
    "NonPreemptiveEDF": "policies",
    "Task": "task",
    "TaskSpec": "task",
    "Handler": "task",
    "HandlerSpec": "task",
    "Timer": "timers",
    "Trigger": "timers",
    "PeriodicLoad": "load",
    "Request": "requests",
}

__all__ = [
    "Kernel",
    "Job",
    "ExecTime",
    "Mailbox",
    "Semaphore",
    "Event",
    "Monitor",
    "JobRecord",
    "Policy",
    "FixedPriority",
    "RateMonotonic",
    "DeadlineMonotonic",
    "EarliestDeadlineFirst",
    "NonPreemptiveFixedPriority",
    "NonPreemptiveEDF",
    "Task",
    "TaskSpec",
    "Handler",
    "HandlerSpec",
    "Timer",
    "Trigger",
    "PeriodicLoad",
    "Request",
]


__getattr__, __dir__ = lazy_exports(__name__, {name: f"netsim.kernel.{home}" for name, home in _HOMES.items()})
