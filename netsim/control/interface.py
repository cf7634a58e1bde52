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
:func:`sample_index` turns its sample time in nanoseconds into that sample index. An estimator
without history may offer ``correct_previous(y)`` for a measurement of the previous sample read at this one
(the Luenberger observer and ``none`` re-filter that one step exactly). Everything here is plain numerics: no simpy, kernel or network.

*The input the plant really holds* (issue 26 section 5). By default ``predict(u)`` assumes that ``u[k]`` acts on
the plant over the whole period ``[t_k, t_k + h)``. When the input reaches the plant later, the model of one
period is the exact zero-order-hold split of that period at the instant the input changes. For a continuous
model ``x' = Ac x + Bc u`` and an input that changes from ``u_old`` to ``u_new`` at ``t_k + tau'``
(``0 <= tau' < h``)::

    x[k+1] = Phi x[k] + Gamma1(tau') u_old + Gamma0(tau') u_new
    Phi = e^(Ac h),  Gamma0(tau') = int_0^(h - tau') e^(Ac s) ds Bc,  Gamma1(tau') = e^(Ac (h - tau')) int_0^tau' e^(Ac s) ds Bc

(:func:`zoh_split`; ``Gamma0 + Gamma1 = Gamma(h)``, the plain ZOH input matrix). Two uses:

* a known constant delay ``tau = d h + tau'`` (:class:`InputDelayLine`): ``u_old = u[k-d-1]``,
  ``u_new = u[k-d]``. This is the model of Astrom & Wittenmark (Computer-Controlled Systems, ch. 2) whose
  augmented state is ``[x[k]; u[k-d-1]; ...; u[k-1]]``. The delayed inputs in that state are known exactly (the
  controller computed them), so the augmented filter's covariance has no weight on them and its estimate of
  ``x`` equals the filter on ``x`` alone predicted with ``[Gamma0 Gamma1] [u[k-d]; u[k-d-1]]``; that is how it
  is computed here (the estimator is built on ``B = [Gamma0 Gamma1]`` and fed the two delayed inputs).
* inputs reported by the actuator with their application times (:class:`AppliedInputTimeline`): the input held
  over period ``k`` is piecewise constant with any number of changes; its effect
  ``w[k] = sum_i e^(Ac (h - b_i)) Gamma(b_i - a_i) u_i`` over the pieces ``[a_i, b_i)`` is computed from the
  matrix exponential (cached per piece length) and the estimator is built on ``B = I`` and fed ``w[k]``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, Protocol, runtime_checkable

import numpy as np

__all__ = ["ControlLaw", "StateEstimator", "OutputFeedback", "sample_index", "zoh_split", "InputDelayLine",
           "AppliedInputTimeline", "first_measurement_estimate", "EstimatorCapabilities", "EstimatorBase",
           "LawBase", "SolverReport", "capabilities_of"]


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


@dataclass(frozen=True)
class EstimatorCapabilities:
    """What a state estimator can do beyond ``correct(y)`` / ``predict(u)`` / ``x_hat``, declared by it.

    Attributes
    ----------
    fuses_at_sample
        ``correct(y, k, rows=None)`` fuses a measurement at its own sample ``k`` (re-filtering from ``history``
        stored samples); the estimator counts its samples in ``k`` and the measurements it refused in ``stale``
        and ``duplicates``.
    history
        Samples back a delayed measurement (or a late input, ``revise_inputs``) is still fused.
    fuses_partial
        ``correct(y, k, rows=...)`` fuses part of ``y``; ``independent_rows(groups)`` says when that is exact.
    corrects_previous
        ``correct_previous(y)`` fuses a measurement of sample ``k-1`` read at ``k`` (estimators without history).
    starts_from, starts_previous
        ``start_from(y[, k, rows])`` / ``start_previous(y)`` start the estimate from a first measurement.
    """

    fuses_at_sample: bool = False
    history: int = 0
    fuses_partial: bool = False
    corrects_previous: bool = False
    starts_from: bool = False
    starts_previous: bool = False


class EstimatorBase:
    """Base of netsim's estimators: they declare their :class:`EstimatorCapabilities` (read, never probed)."""

    @property
    def capabilities(self) -> EstimatorCapabilities:
        """What this estimator can do (see :class:`EstimatorCapabilities`)."""
        return EstimatorCapabilities()


class LawBase:
    """Base of netsim's control laws: what a law declares beyond ``step`` and ``reset``.

    Attributes
    ----------
    reports_solver
        The law solves an optimisation per step and reports it: ``last_iterations``, ``last_solve_time_s`` and
        ``metrics()`` (``fallbacks``, ``solver_calls``, ``solver_iterations``).
    """

    reports_solver: ClassVar[bool] = False


class SolverReport(Protocol):
    """What a law with :attr:`LawBase.reports_solver` set has (for the type checker)."""

    last_iterations: int
    last_solve_time_s: float

    def metrics(self) -> dict[str, float]:
        """``fallbacks``, ``solver_calls``, ``solver_iterations`` among others."""


def capabilities_of(estimator: Any) -> EstimatorCapabilities:
    """The declared capabilities of ``estimator``; for an object of a registered estimator written before
    :class:`EstimatorBase` (no declaration), the ones its methods show (this compatibility path is the one place
    that looks at an estimator's methods)."""
    if isinstance(estimator, EstimatorBase):
        return estimator.capabilities
    import inspect

    correct = getattr(estimator, "correct", None)
    at_sample = callable(correct) and "k" in inspect.signature(correct).parameters
    return EstimatorCapabilities(
        fuses_at_sample=at_sample, history=int(getattr(estimator, "history", 0)),
        fuses_partial=bool(getattr(estimator, "fuses_partial", False)),
        corrects_previous=callable(getattr(estimator, "correct_previous", None)),
        starts_from=callable(getattr(estimator, "start_from", None)),
        starts_previous=callable(getattr(estimator, "start_previous", None)))


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


# --------------------------------------------------------------------------- the input the plant really holds
def _phi_gamma(Ac: np.ndarray, Bc: np.ndarray, t_s: float) -> tuple[np.ndarray, np.ndarray]:
    """``(e^(Ac t), int_0^t e^(Ac s) ds Bc)`` from one matrix exponential of the augmented matrix."""
    from scipy.linalg import expm  # build time, or once per new piece length (cached by the callers)

    n, m = Bc.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n] = Ac
    M[:n, n:] = Bc
    E = expm(M * t_s)
    return E[:n, :n], E[:n, n:]


def zoh_split(Ac: Any, Bc: Any, h_s: float, tau_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Phi, Gamma0, Gamma1)`` of one period ``h_s`` whose input changes at ``tau_s`` (``0 <= tau_s < h_s``).

    ``x(h) = Phi x(0) + Gamma1 u_old + Gamma0 u_new`` when ``u_old`` is held on ``[0, tau_s)`` and ``u_new`` on
    ``[tau_s, h_s)`` (see the module docstring). ``tau_s = 0`` gives ``Gamma1 = 0`` and the plain ZOH ``Gamma0``.
    """
    Ac = np.atleast_2d(np.asarray(Ac, dtype=float))
    Bc = np.asarray(Bc, dtype=float).reshape(Ac.shape[0], -1)
    if not 0.0 <= tau_s < h_s:
        raise ValueError(f"the switching instant must lie in [0, {h_s}) s, got {tau_s}")
    phi_rest, gamma_rest = _phi_gamma(Ac, Bc, h_s - tau_s)
    phi_tau, gamma_tau = _phi_gamma(Ac, Bc, tau_s)
    return phi_rest @ phi_tau, gamma_rest, phi_rest @ gamma_tau


class InputDelayLine:
    """A known constant input delay ``tau = d h + tau'``: which computed inputs act on the plant in each period.

    Parameters
    ----------
    m
        Number of inputs.
    d
        Whole periods of the delay.
    u_init
        The input on the plant before the first computed one arrives (default zeros).

    Notes
    -----
    :meth:`push` takes ``u[k]`` (the input computed at sample ``k``) and returns ``[u[k-d]; u[k-d-1]]``, the
    input vector of the model ``B = [Gamma0 Gamma1]`` (:func:`zoh_split`) over the period ``[t_k, t_k + h)``.
    """

    def __init__(self, m: int, d: int, u_init: Any = None) -> None:
        from collections import deque

        if int(d) != d or d < 0:
            raise ValueError(f"d must be a whole number of periods >= 0, got {d!r}")
        u0 = np.zeros(m) if u_init is None else np.asarray(u_init, dtype=float).reshape(m)
        self.m, self.d = int(m), int(d)
        self._line = deque([u0.copy() for _ in range(self.d + 2)], maxlen=self.d + 2)  # u[k-d-1] ... u[k]

    def push(self, u: Any) -> np.ndarray:
        """Record ``u[k]``; return ``[u[k-d]; u[k-d-1]]``."""
        self._line.append(np.asarray(u, dtype=float).reshape(self.m))
        return np.concatenate([self._line[1], self._line[0]])


class AppliedInputTimeline:
    """The piecewise-constant input on the plant, from the actuator's reports, and its effect per period.

    Parameters
    ----------
    Ac, Bc
        Continuous model ``x' = Ac x + Bc u``.
    period_ns, offset_ns
        The estimator's grid: sample ``k`` is at ``offset_ns + k * period_ns``.
    u_init
        The input on the plant before the first report (default zeros).

    Notes
    -----
    :meth:`report` adds ``(t_ns, u)``: ``u`` is on the plant from ``t_ns`` on. :meth:`effect` gives, for
    period ``k``, ``w[k] = int_{t_k}^{t_k + h} e^(Ac (t_k + h - s)) Bc u(s) ds`` for the input known so far
    (after the last report the last reported value is taken as held), so ``x[k+1] = Phi x[k] + w[k]``.
    The matrix exponentials are cached per piece length in ns.
    """

    def __init__(self, Ac: Any, Bc: Any, period_ns: int, offset_ns: int = 0, u_init: Any = None) -> None:
        self.Ac = np.atleast_2d(np.asarray(Ac, dtype=float))
        self.Bc = np.asarray(Bc, dtype=float).reshape(self.Ac.shape[0], -1)
        self.n, self.m = self.Bc.shape
        self.period, self.offset = int(period_ns), int(offset_ns)
        u0 = np.zeros(self.m) if u_init is None else np.asarray(u_init, dtype=float).reshape(self.m)
        self.times: list[int] = []
        self.values: list[np.ndarray] = []
        self._u0 = u0
        self._cache: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def _pg(self, t_ns: int) -> tuple[np.ndarray, np.ndarray]:
        got = self._cache.get(t_ns)
        if got is None:
            if t_ns == 0:
                got = (np.eye(self.n), np.zeros((self.n, self.m)))
            else:
                got = _phi_gamma(self.Ac, self.Bc, t_ns * 1e-9)
            if len(self._cache) < 4096:
                self._cache[t_ns] = got
        return got

    def report(self, t_ns: int, u: Any) -> None:
        """The actuator applied ``u`` at ``t_ns`` (reports may come in any order)."""
        import bisect

        t = int(t_ns)
        i = bisect.bisect_right(self.times, t)
        self.times.insert(i, t)
        self.values.insert(i, np.asarray(u, dtype=float).reshape(self.m))

    def value_at(self, t_ns: int) -> np.ndarray:
        """The input on the plant at ``t_ns`` as known from the reports."""
        import bisect

        i = bisect.bisect_right(self.times, int(t_ns))
        return self._u0 if i == 0 else self.values[i - 1]

    def effect(self, k: int) -> np.ndarray:
        """``w[k]``: the effect over period ``k`` of the input known to be on the plant (see the class notes)."""
        import bisect

        t0 = self.offset + k * self.period
        t1 = t0 + self.period
        i = bisect.bisect_right(self.times, t0)
        cuts = [t0]
        vals = [self._u0 if i == 0 else self.values[i - 1]]
        while i < len(self.times) and self.times[i] < t1:
            if self.times[i] == cuts[-1]:
                vals[-1] = self.values[i]
            else:
                cuts.append(self.times[i])
                vals.append(self.values[i])
            i += 1
        cuts.append(t1)
        w = np.zeros(self.n)
        for a, b, u in zip(cuts[:-1], cuts[1:], vals):
            phi_after, _ = self._pg(t1 - b)
            _, gamma = self._pg(b - a)
            w += phi_after @ (gamma @ u)
        return w

    def forget_before(self, t_ns: int) -> None:
        """Drop reports superseded before ``t_ns`` (keeps the one in force at ``t_ns``)."""
        import bisect

        i = bisect.bisect_right(self.times, int(t_ns)) - 1
        if i > 0:
            self._u0 = self.values[i - 1] if i - 1 >= 0 else self._u0
            del self.times[:i]
            del self.values[:i]


def first_measurement_estimate(C: Any, y: Any, x_prior: Any) -> np.ndarray:
    """The estimate started from a measurement: the prior moved by the least change that explains ``y``.

    ``x = x_prior + pinv(C) (y - C x_prior)``: the minimum-norm least-squares solution of ``C dx = y - C x_prior``.
    A state measured directly (a row of ``C`` that is a unit vector, no other row touching it) takes its measured
    value; a direction ``C`` does not see keeps the prior (zero by default).
    """
    C = np.atleast_2d(np.asarray(C, dtype=float))
    x_prior = np.asarray(x_prior, dtype=float).reshape(C.shape[1])
    y = np.asarray(y, dtype=float).reshape(C.shape[0])
    return x_prior + np.linalg.pinv(C) @ (y - C @ x_prior)
