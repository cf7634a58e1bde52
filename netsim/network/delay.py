"""Delay distributions of simple links: a link's ``delay:`` is a member of netsim's one family of random times.

A link's ``delay:`` is either a time (``"2 ms"``: constant) or a mapping with ``dist``
(:mod:`netsim.distributions`)::

    delay: {dist: uniform, low: 1 ms, high: 3 ms}
    delay: {dist: exponential, mean: 2 ms, shift: 0.5 ms}
    delay: {dist: shifted_gamma, shape: 2.0, scale: 1 ms, shift: 0.5 ms}
    delay: {dist: empirical, file: delays.csv, column: delay, unit: ms}   # or values: [1 ms, 2 ms]

Samplers return integer nanoseconds drawn from the stream the link gives them.
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from netsim.distributions import Constant as ConstantDelay
from netsim.distributions import DistributionSpec as DelaySpec
from netsim.distributions import load_delays_csv

__all__ = ["ConstantDelay", "DelaySpec", "make_delay_sampler", "load_delays_csv"]


def make_delay_sampler(spec: Any, rng: np.random.Generator) -> Callable[[], int]:
    """A function drawing one delay (ns) from ``spec`` with ``rng`` (constant delays draw nothing).

    Raises
    ------
    TypeError
        When ``spec`` is not a distribution.
    """
    sampler = getattr(spec, "sampler", None)
    if sampler is None:
        raise TypeError(f"unknown delay spec {spec!r}")
    return sampler(rng)
