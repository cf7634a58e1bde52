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

Importing this package registers the scheduling policies under registry kind ``"policy"``.
"""

from netsim.kernel.exectime import ExecTime
from netsim.kernel.job import Job
from netsim.kernel.kernel import Kernel
from netsim.kernel.load import PeriodicLoad
from netsim.kernel.policies import (DeadlineMonotonic, EarliestDeadlineFirst, FixedPriority,
                                    NonPreemptiveEDF, NonPreemptiveFixedPriority, Policy, RateMonotonic)
from netsim.kernel.records import JobRecord
from netsim.kernel.requests import Request
from netsim.kernel.sync import Event, Mailbox, Semaphore
from netsim.kernel.task import Handler, HandlerSpec, Task, TaskSpec
from netsim.kernel.timers import Timer, Trigger

__all__ = [
    "Kernel",
    "Job",
    "ExecTime",
    "Mailbox",
    "Semaphore",
    "Event",
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
