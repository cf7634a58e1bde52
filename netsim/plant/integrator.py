"""How a :class:`~netsim.plant.nonlinear.NonlinearPlant` is integrated between events: the ``plant.integrator`` key.

Two methods (the scenario key is validated by :class:`netsim.scenario.schema_integrator.IntegratorSpec`)::

    plant:
      integrator: {method: solve_ivp, rtol: 1e-8, atol: 1e-10}   # the default: scipy's adaptive RK45 per segment
      integrator: {method: rk4, max_step: 1 ms}                  # classical Runge-Kutta, fixed steps

``solve_ivp`` calls :func:`scipy.integrate.solve_ivp` once per inter-event segment (about 0.5 ms of overhead per
call before any right-hand-side work). ``rk4`` splits every segment ``[t0, t1]`` into ``ceil((t1 - t0) /
max_step)`` equal steps of the classical fourth-order Runge-Kutta scheme, written in numpy on preallocated
buffers (no scipy call): the state at every read instant (a sample, an actuation, a disturbance jump, a record
grid point) is the end of an RK4 step, so the recorder and the encoders see the integrator's own values. Its
local error is ``O(h^5)`` per step, the global one ``O(h^4)`` (``tests/plant/test_rk4_integrator.py`` measures
both against the matrix exponential of a linear plant and the pendulum against ``solve_ivp`` at ``rtol 1e-10``).

Guards (mode switches, the exact encoders' band crossings) are located on the cubic Hermite interpolant of the
step in which a guard changes sign (its end values and derivatives), by bisection to 1 ns.
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

__all__ = ["Rk4Buffers", "rk4_steps", "hermite", "steps_for"]


Rhs = Callable[[float, np.ndarray], np.ndarray]


class Rk4Buffers:
    """Preallocated work arrays of one plant's RK4 steps (``n`` states)."""

    __slots__ = ("stage", "acc")

    def __init__(self, n: int) -> None:
        self.stage = np.empty(n)
        self.acc = np.empty(n)


def rk4_steps(rhs: Rhs, t0: float, x: np.ndarray, h: float, n: int, buf: Rk4Buffers) -> np.ndarray:
    """``n`` classical RK4 steps of length ``h`` seconds from ``(t0, x)``; returns the new state (a fresh array).

    ``rhs(t, x)`` must not keep or return its ``x`` argument (a work buffer overwritten by the next stage); it
    may return any array-like of the state's length.
    """
    x = np.array(x, dtype=float)  # our own copy, updated in place
    stage, acc = buf.stage, buf.acc
    h2, h6 = 0.5 * h, h / 6.0
    mul, add, copyto = np.multiply, np.add, np.copyto
    for i in range(n):
        t = t0 + i * h
        k = rhs(t, x)  # acc collects k1 + 2 k2 + 2 k3 + k4
        copyto(acc, k)
        mul(k, h2, out=stage)
        add(stage, x, out=stage)
        k = rhs(t + h2, stage)
        add(acc, k, out=acc)
        add(acc, k, out=acc)
        mul(k, h2, out=stage)
        add(stage, x, out=stage)
        k = rhs(t + h2, stage)
        add(acc, k, out=acc)
        add(acc, k, out=acc)
        mul(k, h, out=stage)
        add(stage, x, out=stage)
        add(acc, rhs(t + h, stage), out=acc)
        mul(acc, h6, out=acc)
        add(x, acc, out=x)
    return x


def hermite(x0: np.ndarray, f0: np.ndarray, x1: np.ndarray, f1: np.ndarray, h: float, s: float) -> np.ndarray:
    """The cubic Hermite interpolant of a step of length ``h`` at fraction ``s`` in ``[0, 1]`` (end values
    ``x0, x1``, end derivatives ``f0, f1``)."""
    s2, s3 = s * s, s * s * s
    return ((2 * s3 - 3 * s2 + 1) * x0 + (s3 - 2 * s2 + s) * h * f0 + (3 * s2 - 2 * s3) * x1
            + (s3 - s2) * h * f1)


def steps_for(dt_ns: int, max_step_ns: int) -> int:
    """Number of equal RK4 steps that cut ``dt_ns`` into steps of at most ``max_step_ns``."""
    return max(1, -(-dt_ns // max_step_ns))
