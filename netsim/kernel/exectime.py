"""Execution-time models: how long a piece of task code occupies the CPU.

An execution time is a member of netsim's one family of random times, :class:`netsim.distributions.Distribution`
(``ExecTime`` is that class). It is handed to ``job.execute(...)``; every call draws one duration in integer
nanoseconds from the node's execution-time stream ``env.rng(f"kernel.{node}.exec")`` (the kernel passes it
in), so a run is reproducible from its seed.

Examples
--------
>>> import numpy as np
>>> ExecTime.constant(500_000).draw(np.random.default_rng(0))
500000
>>> ExecTime.from_spec("0.5 ms").draw(np.random.default_rng(0))
500000
>>> spec = {"dist": "uniform", "low": "0.4 ms", "high": "0.6 ms"}
>>> 400_000 <= ExecTime.from_spec(spec).draw(np.random.default_rng(0)) <= 600_000
True
"""

from __future__ import annotations

from netsim.distributions import Distribution as ExecTime

__all__ = ["ExecTime"]
