"""CPU speed scaling (DVS): execution times stretched by the speed, in exact integer nanoseconds.

A node with a ``speed`` (``nodes.<n>.speed``, ``Kernel(..., speed=0.5)``) runs at a fraction ``s`` of its
nominal clock, ``0 < s <= 1``; execution times are written for ``s = 1``. A program changes the speed at run
time with ``yield job.set_speed(s)`` (or ``kernel.set_speed(s)``: TrueTime's ``ttSetCPUScaling``); with
``speed_levels`` only those speeds are accepted.

Arithmetic
----------
The speed is kept as an exact fraction ``s = num / den`` (``0.3`` is ``3/10``, from its decimal text). Only
``execute`` work is stretched; a context switch, a migration and a handler's ISR latency are kernel times
that take as long at any speed.

- A segment of work ``w`` ns started at ``t`` ends at ``t + ceil(w * den / num)`` (rounded up: the work is
  never done early).
- A segment cut after ``e`` ns (a preemption, a kill, or a speed change) did ``min(w, floor(e * num / den))``
  ns of work: what is left is planned again from there (at the new speed after a change). A cut can so lose
  less than 1 ns of work; at the planned end ``floor(ceil(w/s) * s) >= w``, so a segment that runs to its end
  does exactly ``w``.
- The job's ``cpu_time`` (and the node's busy time) is the wall time its segments took, ``e``; its WCET
  budget counts work.

Energy (:mod:`netsim.energy`): the busy time is kept per speed (``Kernel.busy_by_speed``) and a busy core
draws ``P_busy(s) = static + (busy - static) * s ** exponent`` (:class:`netsim.energy.params.CpuPower`).
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any, Sequence

from netsim.errors import BuildError

__all__ = ["speed_fraction", "check_levels", "work_time", "work_done"]

#: Largest denominator of a speed's fraction (a speed given as a float is read from its decimal text).
MAX_DEN = 1_000_000


def speed_fraction(speed: Any, where: str) -> Fraction:
    """``speed`` as an exact fraction in ``(0, 1]``.

    Raises
    ------
    BuildError
        Naming ``where`` when it is not a number in ``(0, 1]``.
    """
    if isinstance(speed, bool) or not isinstance(speed, (int, float, Fraction)):
        raise BuildError(f"{where}: speed must be a number in (0, 1] (a fraction of the nominal clock), got {speed!r}")
    frac = Fraction(speed) if isinstance(speed, (int, Fraction)) else Fraction(repr(float(speed)))
    frac = frac.limit_denominator(MAX_DEN)
    if not 0 < frac <= 1:
        raise BuildError(f"{where}: speed {speed!r} is outside (0, 1]; execution times are given at speed 1, the "
                         "fastest clock")
    return frac


def check_levels(levels: Sequence[Any] | None, where: str) -> tuple[Fraction, ...] | None:
    """The allowed speeds as fractions (``None``: any speed in (0, 1])."""
    if levels is None:
        return None
    if not levels:
        raise BuildError(f"{where}: speed_levels is empty; list the speeds the CPU offers, e.g. [0.5, 1]")
    return tuple(speed_fraction(s, where) for s in levels)


def work_time(work: int, num: int, den: int) -> int:
    """Wall time (ns) of ``work`` ns of execution at speed ``num/den``: ``ceil(work * den / num)``."""
    return -(-work * den // num)


def work_done(elapsed: int, num: int, den: int, planned: int) -> int:
    """Work (ns at speed 1) done in ``elapsed`` ns at speed ``num/den`` of a segment planned for ``planned``."""
    done = elapsed * num // den
    return planned if done > planned else done
