"""Discrete Kalman filter: helpers (steady state by the discrete Riccati equation, one step) and a filter object.

Plain numpy/scipy: the steady-state prior covariance solves the filter DARE
``M = A M A' + W - A M C' (C M C' + V)^-1 C M A'`` with :func:`scipy.linalg.solve_discrete_are`
(the dual of the LQR equation), and the gain used for a correction from a prior is
``K = M C' (C M C' + V)^-1``.

:class:`KalmanFilter` is the general filter of the control toolbox (time-varying or steady-state gain,
prediction-only steps, delayed measurements fused at their sample time); the helper functions are the ones
the HDD study's NUMRE filter uses and are unchanged.
"""

from __future__ import annotations

from collections import deque
from typing import Any

import numpy as np

from netsim.control.design_checks import (
    as_input_matrix,
    as_matrix,
    as_vector,
    check_detectable,
    check_square,
    check_weight,
)
from netsim.control.interface import EstimatorBase, EstimatorCapabilities
from netsim.errors import ConfigError, SimulationError
from netsim.lazy_import import lazy_module

sla = lazy_module("scipy.linalg")  # imported when a filter is designed, not when a scenario is checked

__all__ = ["KalmanFilter", "steady_state_prior", "kalman_gain", "riccati_step"]


def steady_state_prior(A: np.ndarray, C: np.ndarray, W: np.ndarray, V: np.ndarray) -> np.ndarray:
    """Steady-state prior covariance of the filter for ``x+ = A x + w``, ``y = C x + v``.

    Raises
    ------
    ConfigError
        If the Riccati equation has no stabilizing solution (``(A, C)`` not detectable or the noise
        does not excite an unstable mode).
    """
    A = np.atleast_2d(A)
    C = np.atleast_2d(C)
    try:
        M = sla.solve_discrete_are(A.T, C.T, np.atleast_2d(W), np.atleast_2d(V))
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise ConfigError(
            f"Kalman filter: the discrete Riccati equation has no stabilizing solution ({exc}); check that "
            "the model is detectable from the measurement and that V is positive definite"
        ) from exc
    return 0.5 * (M + M.T)


def kalman_gain(M: np.ndarray, C: np.ndarray, V: np.ndarray) -> np.ndarray:
    """Correction gain ``K = M C' (C M C' + V)^-1`` from a prior covariance ``M``."""
    C = np.atleast_2d(C)
    S = C @ M @ C.T + np.atleast_2d(V)
    return np.linalg.solve(S.T, (M @ C.T).T).T


def riccati_step(M: np.ndarray, A: np.ndarray, C: np.ndarray, W: np.ndarray, V: np.ndarray) -> np.ndarray:
    """One step of the prior-covariance recursion (eq 12 of Cuenca et al. with ``A`` = ``A^N``)."""
    C = np.atleast_2d(C)
    S = C @ M @ C.T + np.atleast_2d(V)
    AM = A @ M
    return AM @ A.T + W - AM @ C.T @ np.linalg.solve(S, C @ M @ A.T)


class _Sample:
    """What the filter remembers of one sample ``k``: the prior, the measurements fused at ``k``, the input."""

    __slots__ = ("k", "x_prior", "P_prior", "ys", "u")

    def __init__(self, k: int, x_prior: np.ndarray, P_prior: np.ndarray) -> None:
        self.k = k
        self.x_prior = x_prior
        self.P_prior = P_prior
        self.ys: list[tuple[tuple[int, ...] | None, np.ndarray]] = []  # (rows measured or None: all, values)
        self.u: np.ndarray | None = None

    def has_rows(self, rows: tuple[int, ...] | None) -> bool:
        """True when a measurement fused at this sample already covers one of ``rows`` (``None``: any row)."""
        if not self.ys:
            return False
        if rows is None:
            return True
        for got, _ in self.ys:
            if got is None or not set(got).isdisjoint(rows):
                return True
        return False


class KalmanFilter(EstimatorBase):
    """Discrete Kalman filter for ``x[k+1] = A x[k] + B u[k] + w[k]``, ``y[k] = C x[k] + v[k]``.

    ``w ~ N(0, Q)`` and ``v ~ N(0, R)`` are white and independent. The filter lives on the sampling grid
    ``k = 0, 1, ...``: :meth:`correct` fuses a measurement, :meth:`predict` moves to the next sample with the
    input held over the period (see :mod:`netsim.control.interface` for the order a loop calls them in).

    Parameters
    ----------
    A, B, C
        Discrete model (``n x n``, ``n x m``, ``p x n``). ``B`` may be ``None`` (no input, ``m = 0``).
    Q, R
        Process and measurement noise covariances (``n x n`` positive semidefinite, ``p x p`` positive
        definite); a scalar means a multiple of the identity and a vector a diagonal.
    x0, P0
        Prior mean and covariance of ``x[0]`` (defaults: zeros and the identity; for the steady-state filter
        ``P0`` is ignored).
    steady_state
        ``False`` (default): time-varying filter, the covariance is propagated and the gain recomputed at each
        correction. ``True``: the constant gain ``K = M C' (C M C' + R)^-1`` where ``M`` solves the filter DARE
        (computed once here, :func:`steady_state_prior`); the covariance is not propagated.
    history
        How many samples back a delayed measurement may be fused (0: only measurements of the current sample).

    Notes
    -----
    *Missing measurements.* A sample without :meth:`correct` is a prediction-only step: the estimate is the
    model propagation ``x <- A x + B u`` and (time-varying filter) ``P <- A P A' + Q``.

    *Delayed measurements* (method: re-filtering from a short history). For each of the last ``history``
    samples the filter keeps the prior ``(x, P)`` at that sample, the measurements fused there and the input
    applied after it. A measurement whose sample index ``k_s`` is older than the current sample is fused at
    ``k_s``: the filter goes back to the stored prior at ``k_s``, fuses every measurement of ``k_s`` (the new
    one included), then repeats the predictions with the stored inputs and the corrections already made at
    ``k_s + 1 ... k``. For a linear filter the result equals, to rounding, the filter that had received the
    measurement on time; it costs ``k - k_s`` predictions and corrections per late measurement.

    *Partial measurements* (time-varying filter only). ``correct(y, k, rows=...)`` fuses a measurement of some
    rows of ``C`` only (e.g. one of two sensors with their own rates): the update uses those rows of ``C`` and
    the matching block of ``R``. Fusing the parts of a sample one after the other equals fusing them together
    when ``R`` has no cross-covariance between the parts (independent sensors); see :meth:`independent_rows`.

    *Stale and duplicate measurements* are never fused: each row of ``y`` is fused at most once per sample
    index (a second measurement of a row for the same ``k`` is a duplicate), and one older than ``history``
    samples is stale. Both make :meth:`correct` return ``False`` and are counted in :attr:`duplicates` and
    :attr:`stale`.

    *Inputs learned late* (:meth:`revise_inputs`): the input of a stored sample can be replaced (the actuator's
    report of what the plant really held) and the filter re-run from there, as for a delayed measurement.
    :meth:`start_from` starts the estimate from a measurement (``x0 + pinv(C) (y - C x0)``).

    The feed-through ``D`` is taken as zero (the measurement at ``k`` is taken before ``u[k]`` is computed).
    """

    def __init__(
        self,
        A: Any,
        B: Any,
        C: Any,
        Q: Any,
        R: Any,
        *,
        x0: Any = None,
        P0: Any = None,
        steady_state: bool = False,
        history: int = 0,
    ) -> None:
        self.A = as_matrix("A", A)
        n = check_square("A", self.A)
        self.B = np.zeros((n, 0)) if B is None else as_input_matrix("B", B, n)
        self.C = as_matrix("C", C, (None, n))
        self.n, self.m, self.p = n, self.B.shape[1], self.C.shape[0]
        self.Q = check_weight("Q", Q, n, definite=False)
        self.R = check_weight("R", R, self.p, definite=True)
        if int(history) != history or history < 0:
            raise ConfigError(f"history must be a whole number of samples >= 0, got {history!r}")
        self.history = int(history)
        check_detectable(self.A, self.C)
        self.steady_state = bool(steady_state)
        self.x0 = np.zeros(n) if x0 is None else as_vector("x0", x0, n)
        if self.steady_state:
            M = steady_state_prior(self.A, self.C, self.Q, self.R)
            self.K_ss = kalman_gain(M, self.C, self.R)
            self.M_ss = M
            self.P_ss = M - self.K_ss @ self.C @ M  # posterior covariance in steady state
            self.P0 = M
            closed = (np.eye(n) - self.K_ss @ self.C) @ self.A
            if np.max(np.abs(np.linalg.eigvals(closed))) >= 1.0:
                raise ConfigError(
                    "Kalman filter: the Riccati solution does not give a stable filter; check that Q excites "
                    "every mode of A on the unit circle"
                )
        else:
            self.P0 = np.eye(n) if P0 is None else check_weight("P0", P0, n, definite=False)
        self._I = np.eye(n)
        self.reset()

    # --- state -------------------------------------------------------------------------------------------
    def reset(self, x0: Any = None, P0: Any = None) -> None:
        """Back to sample 0 with the prior ``(x0, P0)`` (the constructor's unless given here)."""
        self.k = 0
        self.x = self.x0.copy() if x0 is None else as_vector("x0", x0, self.n)
        self.P = self.P0.copy() if P0 is None or self.steady_state else check_weight("P0", P0, self.n, definite=False)
        self._hist: deque[_Sample] = deque(maxlen=self.history + 1)
        self._hist.append(_Sample(0, self.x, self.P))
        self.fused = 0
        self.duplicates = 0
        self.stale = 0

    @property
    def x_hat(self) -> np.ndarray:
        """Estimate at the current sample (posterior if a measurement was fused there, prior otherwise)."""
        return self.x

    def dare_prior(self) -> np.ndarray:
        """The steady-state prior covariance of this filter's ``(A, C, Q, R)`` (the filter DARE), solved once per
        filter: the one the steady-state filter uses, the one the time-varying filter's covariance settles to.

        Raises
        ------
        ConfigError
            When the Riccati equation has no stabilising solution (:func:`steady_state_prior`).
        """
        if self.steady_state:
            return self.M_ss
        got = self.__dict__.get("_dare_prior")
        if got is None:
            got = steady_state_prior(self.A, self.C, self.Q, self.R)
            self._dare_prior = got
        return got

    @property
    def gain(self) -> np.ndarray:
        """The gain a correction at the current sample would use."""
        if self.steady_state:
            return self.K_ss
        return kalman_gain(self.P, self.C, self.R)

    # --- the two half-steps ------------------------------------------------------------------------------
    def _fuse(self, x: np.ndarray, P: np.ndarray, y: np.ndarray,
              rows: tuple[int, ...] | None = None) -> tuple[np.ndarray, np.ndarray]:
        if rows is None:
            C, R = self.C, self.R
        else:
            idx = list(rows)
            C, R = self.C[idx], self.R[np.ix_(idx, idx)]
        if self.steady_state:
            return x + self.K_ss @ (y - C @ x), P
        PCt = P @ C.T
        S = C @ PCt + R
        K = np.linalg.solve(S, PCt.T).T
        x = x + K @ (y - C @ x)
        IKC = self._I - K @ C
        P = IKC @ P @ IKC.T + K @ R @ K.T  # Joseph form: stays symmetric positive semidefinite
        return x, P

    @property
    def capabilities(self) -> EstimatorCapabilities:
        """Fuses at a measurement's own sample within ``history``; part of ``y`` when time-varying; starts from a
        first measurement."""
        return EstimatorCapabilities(fuses_at_sample=True, history=self.history, fuses_partial=self.fuses_partial,
                                     starts_from=True)

    @property
    def fuses_partial(self) -> bool:
        """True when :meth:`correct` accepts ``rows`` (the time-varying filter; the steady-state gain is designed
        for the whole measurement)."""
        return not self.steady_state

    def independent_rows(self, groups: list[list[int]]) -> bool:
        """True when ``R`` has no cross-covariance between the row ``groups`` (so fusing them apart is exact)."""
        for i, gi in enumerate(groups):
            for gj in groups[i + 1:]:
                if np.any(self.R[np.ix_(gi, gj)] != 0):
                    return False
        return True

    def _propagate(self, x: np.ndarray, P: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        A = self.A
        x = A @ x + self.B @ u
        if not self.steady_state:
            P = A @ P @ A.T + self.Q
        return x, P

    def _as_u(self, u: Any) -> np.ndarray:
        if self.m == 0:
            return np.zeros(0)
        u = np.asarray(u, dtype=float).reshape(-1)
        if u.shape[0] != self.m:
            raise SimulationError(
                f"Kalman filter: the input has {u.shape[0]} entries, the model B has {self.m} columns"
            )
        return u

    def correct(self, y: Any, k: int | None = None, rows: Any = None) -> bool:
        """Fuse a measurement taken at sample ``k`` (default: the current sample).

        Parameters
        ----------
        y
            Measurement (``p`` entries, or one per row in ``rows``; a scalar when that is 1).
        k
            Sample index at which ``y`` was taken. An older ``k`` (a delayed measurement) is fused at that
            sample and the estimate brought forward again (see the class notes).
        rows
            Which rows of ``C`` ``y`` measures (``None``: all of them). Time-varying filter only.

        Returns
        -------
        bool
            ``True`` when fused; ``False`` for a duplicate (a row already measured at ``k``) or a stale one
            (older than ``history`` samples).

        Raises
        ------
        SimulationError
            ``k`` in the future, ``y`` of the wrong size, ``rows`` out of range or given to the steady-state
            filter.
        """
        y = np.asarray(y, dtype=float).reshape(-1)
        sel = self._rows(rows)
        want = self.p if sel is None else len(sel)
        if y.shape[0] != want:
            raise SimulationError(f"Kalman filter: the measurement has {y.shape[0]} entries, expected {want} "
                                  f"({'the rows of C' if sel is None else f'rows {list(sel)}'})")
        if k is None or k == self.k:
            rec = self._hist[-1]
            if rec.has_rows(sel):
                self.duplicates += 1
                return False
            rec.ys.append((sel, y))
            self.x, self.P = self._fuse(self.x, self.P, y, sel)
            self.fused += 1
            return True
        if k > self.k:
            raise SimulationError(
                f"Kalman filter: a measurement of sample {k} arrived at sample {self.k} (from the future)"
            )
        back = self.k - k
        if back >= len(self._hist):
            self.stale += 1
            return False
        recs = list(self._hist)[-1 - back :]
        if recs[0].has_rows(sel):
            self.duplicates += 1
            return False
        recs[0].ys.append((sel, y))
        self._replay(recs)
        self.fused += 1
        return True

    def _replay(self, recs: list[_Sample]) -> None:
        """Re-filter from the stored prior of ``recs[0]`` to the current sample (stored inputs and measurements)."""
        x, P = recs[0].x_prior, recs[0].P_prior
        for i, rec in enumerate(recs):
            if i > 0:
                u = recs[i - 1].u
                assert u is not None  # every sample before the last was propagated with its input
                x, P = self._propagate(x, P, u)
                rec.x_prior, rec.P_prior = x, P
            for rr, yy in rec.ys:
                x, P = self._fuse(x, P, yy, rr)
        self.x, self.P = x, P

    def revise_inputs(self, inputs: dict[int, Any]) -> int:
        """Replace the inputs of past samples (``{k: u}``) and re-filter to the current sample.

        The input of sample ``k`` is the one its prediction to ``k + 1`` used. This is how an input learned late
        (the actuator's report of what it applied, :class:`~netsim.control.interface.AppliedInputTimeline`)
        reaches the estimate: the stored priors from the earliest revised sample on are recomputed, with the
        measurements already fused there. Samples older than ``history`` are no longer stored and are skipped.

        Returns
        -------
        int
            How many samples' inputs were replaced (an equal input is not counted).
        """
        recs = list(self._hist)
        first = None
        changed = 0
        for i, rec in enumerate(recs[:-1]):  # the current sample has not been predicted yet
            if rec.k in inputs:
                u = self._as_u(inputs[rec.k])
                if rec.u is None or not np.array_equal(rec.u, u):
                    rec.u = u
                    changed += 1
                    first = i if first is None else first
        if first is not None:
            self._replay(recs[first:])
        return changed

    def start_from(self, y: Any, k: int | None = None, rows: Any = None) -> None:
        """Start the estimate from a measurement of sample ``k`` (default: the current sample): the prior there
        becomes ``x0 + pinv(C_rows) (y - C_rows x0)`` (:func:`~netsim.control.interface.first_measurement_estimate`)
        and the filter is brought forward to the current sample with the stored inputs. The covariance stays
        ``P0``. Call it before :meth:`correct` fuses the same measurement (whose innovation is then zero)."""
        sel = self._rows(rows) if rows is not None else None
        back = 0 if k is None else self.k - int(k)
        if back < 0 or back >= len(self._hist):
            return
        recs = list(self._hist)[-1 - back:]
        recs[0].x_prior = self._start_estimate(recs[0].x_prior, np.asarray(y, dtype=float).reshape(-1), sel)
        self._replay(recs)

    def _start_estimate(self, x_prior: np.ndarray, y: np.ndarray, sel: tuple[int, ...] | None) -> np.ndarray:
        from netsim.control.interface import first_measurement_estimate

        return first_measurement_estimate(self.C if sel is None else self.C[list(sel)], y, x_prior)

    def _rows(self, rows: Any) -> tuple[int, ...] | None:
        """``rows`` checked: ``None`` when it means every row, else a tuple of distinct row indices."""
        if rows is None:
            return None
        sel = tuple(int(r) for r in np.atleast_1d(rows))
        if len(set(sel)) != len(sel) or any(r < 0 or r >= self.p for r in sel) or not sel:
            raise SimulationError(f"Kalman filter: rows must be distinct indices of the {self.p} rows of C, "
                                  f"got {list(sel)}")
        if sel == tuple(range(self.p)):
            return None
        if self.steady_state:
            raise SimulationError("Kalman filter: the steady-state filter fuses whole measurements only; use the "
                                  "time-varying filter (steady_state: false) for sensors with their own rates")
        return sel

    def predict(self, u: Any = None) -> None:
        """Move to the next sample: ``x <- A x + B u`` and (time-varying filter) ``P <- A P A' + Q``."""
        u = np.zeros(self.m) if u is None else self._as_u(u)
        self._hist[-1].u = u
        self.x, self.P = self._propagate(self.x, self.P, u)
        self.k += 1
        self._hist.append(_Sample(self.k, self.x, self.P))

    def advance(self, y: Any, u: Any) -> np.ndarray:
        """Correct with ``y`` (``None``: prediction only), return the estimate, then predict with ``u``.

        Convenience for offline use; returns the estimate at the sample before the prediction.
        """
        if y is not None:
            self.correct(y)
        x = self.x
        self.predict(u)
        return x
