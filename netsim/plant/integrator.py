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

``solve_ivp`` with scipy's explicit Runge-Kutta methods (RK45, the default, RK23, DOP853) on a segment without
guards does not go through :func:`scipy.integrate.solve_ivp` itself: :class:`RkSegments` keeps one scipy solver
object per plant and re-arms it for each segment exactly as its constructor would arm a new one (the initial
derivative, the initial step from scipy's own ``select_initial_step``), then calls its ``step()`` until the
segment's end. The steps taken, and so every state, are bit for bit those of ``solve_ivp`` (the test
``tests/plant/test_solver_reuse.py`` compares them); what goes is the per-call work of ``solve_ivp`` and of
building a solver (argument checks, tolerance validation, result arrays), about half of the non-right-hand-side
time of a short segment.
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

__all__ = ["Rk4Buffers", "RkSegments", "rk4_steps", "hermite", "steps_for"]


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


class RkSegments:
    """One scipy explicit Runge-Kutta solver (RK45, RK23 or DOP853) of a plant, re-armed for every segment.

    :meth:`integrate` gives the state ``solve_ivp(fun, (t0, t1), y, method, rtol=..., atol=..., max_step=...)``
    ends with (``sol.y[:, -1]``), bit for bit, without a ``solve_ivp`` call or a new solver object.

    Parameters
    ----------
    method
        scipy's method name; :meth:`make` returns None for the others (implicit solvers, LSODA, classes).
    n
        Number of states (at least one).
    rtol, atol, max_step
        The solver's settings, validated once by scipy's constructor here.
    """

    __slots__ = ("solver", "_max_step")

    def __init__(self, method: str, n: int, rtol: float, atol: float, max_step: float) -> None:
        from scipy.integrate import DOP853, RK23, RK45

        cls = {"RK45": RK45, "RK23": RK23, "DOP853": DOP853}[method]
        # built once the ordinary way (on a dummy problem): scipy checks the settings and allocates its stage arrays
        self.solver = cls(_zero_rhs, 0.0, np.zeros(n), 1.0, rtol=rtol, atol=atol, max_step=max_step)
        self._max_step = max_step  # the constructor hands the unvalidated value to select_initial_step

    @staticmethod
    def make(method: Any, n: int, rtol: float, atol: float, max_step: float) -> "RkSegments | None":
        """A re-armable solver for ``method``, or None when segments must go through ``solve_ivp``."""
        if not isinstance(method, str) or method not in ("RK45", "RK23", "DOP853") or n < 1:
            return None
        return RkSegments(method, n, rtol, atol, max_step)

    def solve(self, fun: Rhs, t0: float, t1: float, y: np.ndarray) -> "SegmentResult":
        """Integrate ``fun`` over ``[t0, t1]`` (``t0 < t1``) from ``y``, as ``solve_ivp`` without events would.

        The result has the fields of ``solve_ivp``'s that a plant reads: ``t[-1]`` and ``y[:, -1]`` (where the
        integration ended: ``t1``, or the last step reached when the solver failed), ``status`` (0, or -1 when it
        failed) and ``message``.
        """
        from scipy.integrate._ivp.common import select_initial_step

        s = self.solver
        # what OdeSolver.__init__ and RungeKutta.__init__ set for a new problem (scipy 1.17), in their order
        y = np.asarray(y).astype(float, copy=False)
        if y.ndim != 1:
            raise ValueError("`y0` must be 1-dimensional.")
        if not np.isfinite(y).all():
            raise ValueError("All components of the initial state `y0` must be finite.")
        s.t_old = None
        s.t = t0
        s.y = y
        s.t_bound = t1
        s.direction = np.sign(t1 - t0) if t1 != t0 else 1
        s.status = "running"

        def wrapped(t: float, y: np.ndarray, fun: Rhs = fun) -> np.ndarray:  # scipy's own wrapper of the user's fun
            return np.asarray(fun(t, y), dtype=float)

        s.fun = wrapped
        s.y_old = None
        s.f = f = wrapped(t0, y)
        s.h_abs = select_initial_step(wrapped, t0, y, t1, self._max_step, f, s.direction, s.error_estimator_order,
                                      s.rtol, s.atol)
        s.h_previous = None
        step = s.step
        while True:  # solve_ivp's loop, without the arrays it collects
            message = step()
            if s.status == "finished":
                return SegmentResult(s.t, s.y, 0, "The solver successfully reached the end of the integration interval.")
            if s.status == "failed":
                return SegmentResult(s.t, s.y, -1, message)


class SegmentResult:
    """What :meth:`RkSegments.solve` returns: the fields of ``solve_ivp``'s result a plant reads."""

    __slots__ = ("t", "y", "status", "message")

    def __init__(self, t: float, y: np.ndarray, status: int, message: Any) -> None:
        self.t = (float(t),)
        self.y = y[:, None]  # a column: y[:, -1] is the state, as in solve_ivp's result
        self.status = status
        self.message = message


def _zero_rhs(t: float, y: np.ndarray) -> np.ndarray:
    return np.zeros_like(y)
