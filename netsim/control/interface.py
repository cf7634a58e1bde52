"""The small interfaces shared by controllers and estimators, and the loop that joins them.

A **control law** maps what it is fed (a state estimate ``x_hat`` for state feedback, a measurement ``y`` for
PID) and a reference ``r`` to the control signal: ``u = law.step(z, r)``. A **state estimator** keeps an
estimate ``x_hat`` of the plant state on the controller's sampling grid ``k = 0, 1, ...``; at each sample the
loop calls, in this order:

1. ``estimator.correct(y)`` for each measurement that arrived (skipped when none did: the step is then
   prediction only);
2. ``u = law.step(estimator.x_hat, r)``;
3. ``estimator.predict(u)``, which moves the estimate to the next sample with the input held over the period.

:class:`OutputFeedback` does exactly this and is itself a control law fed with ``y``, so any estimator feeds
any state-feedback law. A delayed measurement is fused at its own sample (``KalmanFilter.correct(y, k=...)``);
:func:`sample_index` turns its sample time in nanoseconds into that sample index. Everything here is plain numerics: no simpy, kernel or network.
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np

__all__ = ["ControlLaw", "StateEstimator", "OutputFeedback", "sample_index"]


def sample_index(t_ns: int, period_ns: int, start_ns: int = 0) -> int:
    """Index ``k`` of the sample ``start_ns + k * period_ns`` nearest to a measurement's sample time ``t_ns``.

    Estimators count samples; a measurement message carries its sample time in integer nanoseconds. A
    time-triggered sensor on the controller's grid maps exactly; a measurement taken between two samples is
    attributed to the nearest one (half-way rounds up), an error of at most half a period.

    Raises
    ------
    ValueError
        When ``period_ns`` is not positive or ``t_ns`` lies more than half a period before ``start_ns``.
    """
    if period_ns <= 0:
        raise ValueError(f"period_ns must be positive, got {period_ns}")
    k = (int(t_ns) - int(start_ns) + period_ns // 2) // period_ns
    if k < 0:
        raise ValueError(f"sample time {t_ns} ns is before the first sample at {start_ns} ns")
    return k


@runtime_checkable
class ControlLaw(Protocol):
    """Anything with ``step(z, r) -> u`` and ``reset()``."""

    def step(self, z: Any, r: Any) -> Any:
        """Control signal for the estimate or measurement ``z`` and the reference ``r``."""
        ...

    def reset(self) -> None:
        """Forget the internal state (integrators, previous inputs)."""
        ...


@runtime_checkable
class StateEstimator(Protocol):
    """A state estimator on a sampling grid: ``correct`` with measurements, then ``predict`` with the input."""

    @property
    def x_hat(self) -> np.ndarray:
        """The estimate a state-feedback law uses at the current sample."""
        ...

    def correct(self, y: Any) -> bool:
        """Fuse a measurement taken at the current sample; ``False`` when it was not used."""
        ...

    def predict(self, u: Any) -> None:
        """Advance the estimate to the next sample with input ``u`` held over the period."""
        ...


class OutputFeedback:
    """An estimator feeding a state-feedback law: a control law fed with measurements.

    Parameters
    ----------
    estimator
        Any :class:`StateEstimator`.
    law
        Any :class:`ControlLaw` taking the state estimate.

    Notes
    -----
    ``step(y, r)`` runs ``estimator.correct(y)`` (unless ``y`` is ``None``: a lost or missing measurement makes the
    step prediction only), ``u = law.step(estimator.x_hat, r)``, then ``estimator.predict(u)``, and returns ``u``.
    """

    def __init__(self, estimator: StateEstimator, law: ControlLaw) -> None:
        self.estimator = estimator
        self.law = law

    def step(self, y: Any, r: Any) -> Any:
        """One sample of the loop: correct with ``y`` (if any), compute ``u``, predict; return ``u``."""
        if y is not None:
            self.estimator.correct(y)
        u = self.law.step(self.estimator.x_hat, r)
        self.estimator.predict(u)
        return u

    def reset(self) -> None:
        """Reset the law and, when it has a ``reset``, the estimator."""
        self.law.reset()
        reset = getattr(self.estimator, "reset", None)
        if callable(reset):
            reset()
