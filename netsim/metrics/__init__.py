"""Metrics computed from a run's tables: the one home of netsim's measures (registry kind ``"metric"``).

``runtime``
    what every run gets (:func:`~netsim.metrics.runtime.generic_metrics`: CPU and network utilization, jobs,
    deadline misses, response times, message delays) and the registered ``control_error`` (ISE, IAE) and
    ``latency`` (sample-to-actuation along a task chain); :func:`~netsim.metrics.runtime.compute_metrics` runs a
    scenario's ``metrics:`` list.
``et``
    the event-triggered measures of Cuenca et al., eqs (20)-(29): Nsc, Uc, Ua, Cc, CS, ISE, ISEP, NE, GPI
    (registered as ``et_control``).

A case study's own measures live with it (e.g. ``models/cart/metrics.py``, registered as ``cart``). A new metric is
a function ``fn(result, params, baseline) -> dict[str, float]`` with an ``@register("metric", NAME)`` line in a
module of this package; names follow ``<scope>.<measure>`` (README, *Metric names*).
"""
