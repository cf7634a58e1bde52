"""An extended Kalman filter on a continuous nonlinear model: the plant's own equations, discretised per period.

Model (the plant's, ``t`` not used: the model must be time-invariant)::

    x' = f(x, u)          integrated over one period with u held (classic Runge-Kutta 4, ``substeps`` steps)
    y  = h(x)[rows]       the measured outputs

which gives the discrete transition ``x[k+1] = phi(x[k], u[k]) + w[k]`` with ``w ~ N(0, Q)`` (``Q``: the process
noise of one period, as for the linear filter) and ``y[k] = h(x[k]) + v[k]``, ``v ~ N(0, R)``.

Prediction: ``x <- phi(x, u)``, ``P <- F P F' + Q`` with ``F = d phi / dx`` at the previous estimate. Correction:
``H = d h / dx`` at the prior, then the Joseph-form update. Both Jacobians are central differences
(:func:`netsim.control.ekf.numerical_jacobian`), so any plant that gives ``f`` and ``h`` can be filtered from YAML
without writing Python: ``estimator: {type: ekf, Q, R, substeps}``.

The filter is a :class:`~netsim.control.kalman.KalmanFilter` with its two half-steps replaced, so it keeps what
that class does on the sampling grid: prediction-only steps, a delayed measurement fused at its own sample by
re-filtering from the stored priors (re-linearising along the way), a part of ``y`` (one sensor of several)
fused on its own, and never a measurement twice.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from netsim.control.design_checks import as_vector, check_weight
from netsim.control.ekf import numerical_jacobian
from netsim.control.kalman import KalmanFilter
from netsim.errors import ConfigError, SimulationError

__all__ = ["ModelEKF", "rk4_transition"]

Fn = Callable[..., Any]


def rk4_transition(f: Fn, params: Any, period_s: float, substeps: int) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """The map ``x[k] -> x[k+1]`` of ``x' = f(t, x, u, params)`` over ``period_s`` with ``u`` held.

    Classic fourth-order Runge-Kutta with ``substeps`` equal steps; ``t`` is passed as 0 (time-invariant model).
    """
    dt = period_s / substeps

    def phi(x: np.ndarray, u: np.ndarray) -> np.ndarray:
        for _ in range(substeps):
            k1 = np.asarray(f(0.0, x, u, params), dtype=float)
            k2 = np.asarray(f(0.0, x + 0.5 * dt * k1, u, params), dtype=float)
            k3 = np.asarray(f(0.0, x + 0.5 * dt * k2, u, params), dtype=float)
            k4 = np.asarray(f(0.0, x + dt * k3, u, params), dtype=float)
            x = x + (dt / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        return x

    return phi


class ModelEKF(KalmanFilter):
    """EKF on ``x' = f(t, x, u, params)``, ``y = h(t, x, u, params)[rows]`` (see the module docstring).

    Parameters
    ----------
    f, h, params
        The continuous model in the plant's form (``netsim.plant.NonlinearPlant``'s ``f``, ``h``, ``params``).
    n_states, n_inputs
        Dimensions of ``x`` and ``u``.
    rows
        The outputs of ``h`` that are measured, in the order of ``y``.
    period_s
        The sampling period (s).
    Q, R
        Process noise covariance over one period (``n x n`` PSD) and measurement noise covariance (``p x p`` PD);
        a number means a multiple of the identity, a list the diagonal.
    x0, P0
        Initial estimate (default zeros) and covariance (default identity).
    substeps
        Runge-Kutta steps per period.
    history
        How many samples back a delayed measurement may be fused.

    Raises
    ------
    ConfigError
        A bad covariance, ``substeps`` or ``history``, or a model function that raises or returns the wrong
        number of values at ``x0`` (named ``f`` or ``h``).
    """

    def __init__(self, f: Fn, h: Fn, params: Any, n_states: int, n_inputs: int, rows: Sequence[int],
                 period_s: float, Q: Any, R: Any, *, x0: Any = None, P0: Any = None, substeps: int = 4,
                 history: int = 0) -> None:
        if not callable(f) or not callable(h):
            raise ConfigError("ekf: the model needs functions f(t, x, u, params) and h(t, x, u, params)")
        if isinstance(substeps, bool) or int(substeps) != substeps or substeps < 1:
            raise ConfigError(f"substeps must be a whole number >= 1, got {substeps!r}")
        if int(history) != history or history < 0:
            raise ConfigError(f"history must be a whole number of samples >= 0, got {history!r}")
        n, m = int(n_states), int(n_inputs)
        self.n, self.m = n, m
        self.rows = [int(r) for r in rows]
        self.p = len(self.rows)
        self.Q = check_weight("Q", Q, n, definite=False)
        self.R = check_weight("R", R, self.p, definite=True)
        self.history = int(history)
        self.steady_state = False
        self.x0 = np.zeros(n) if x0 is None else as_vector("x0", x0, n)
        self.P0 = np.eye(n) if P0 is None else check_weight("P0", P0, n, definite=False)
        self.substeps = int(substeps)
        self._f, self._h, self._params = f, h, params
        self._phi = rk4_transition(f, params, float(period_s), self.substeps)
        self._u0 = np.zeros(m)
        self._checked_call(lambda: self._measure(self.x0), (self.p,), "h", ConfigError, "at x0")
        self._checked_call(lambda: self._phi(self.x0, self._u0), (n,), "f", ConfigError, "at x0 and u = 0")
        self._I = np.eye(n)
        self.reset()

    # --- the model ---------------------------------------------------------------------------------------
    def _measure(self, x: np.ndarray) -> np.ndarray:
        y = np.asarray(self._h(0.0, x, self._u0, self._params), dtype=float).reshape(-1)
        return y[self.rows]

    @staticmethod
    def _checked_call(call: Callable[[], np.ndarray], shape: tuple[int, ...], name: str,
                      err: type[ConfigError] | type[SimulationError], where: str) -> np.ndarray:
        try:
            out = np.asarray(call(), dtype=float)
        except (ConfigError, SimulationError):
            raise
        except Exception as exc:  # any error of model code becomes a message naming the function
            raise err(f"ekf: the model's {name} raised {type(exc).__name__}: {exc} ({where})") from exc
        if out.shape != shape:
            raise err(f"ekf: the model's {name} gives shape {out.shape}, expected {shape} ({where})")
        if not np.all(np.isfinite(out)):
            fix = ("check x0, and raise 'substeps' (Runge-Kutta steps per period) if the period is long for the "
                   "model's dynamics" if name == "f" else "check x0")
            raise err(f"ekf: the model's {name} gave NaN or infinite values ({where}); the estimate diverged "
                      f"or the model is wrong: {fix}")
        return out

    @property
    def gain(self) -> np.ndarray:
        """The gain a correction of the whole ``y`` at the current sample would use."""
        H = numerical_jacobian(self._measure, self.x, self.p)
        PHt = self.P @ H.T
        return np.linalg.solve(H @ PHt + self.R, PHt.T).T

    # --- the two half-steps of KalmanFilter, nonlinear ---------------------------------------------------
    def _fuse(self, x: np.ndarray, P: np.ndarray, y: np.ndarray,
              rows: tuple[int, ...] | None = None) -> tuple[np.ndarray, np.ndarray]:
        where = f"at sample {self.k}"
        yhat = self._checked_call(lambda: self._measure(x), (self.p,), "h", SimulationError, where)
        H = numerical_jacobian(self._measure, x, self.p)
        R = self.R
        if rows is not None:
            idx = list(rows)
            yhat, H, R = yhat[idx], H[idx], R[np.ix_(idx, idx)]
        PHt = P @ H.T
        K = np.linalg.solve(H @ PHt + R, PHt.T).T
        x = x + K @ (y - yhat)
        IKH = self._I - K @ H
        return x, IKH @ P @ IKH.T + K @ R @ K.T

    def _propagate(self, x: np.ndarray, P: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        where = f"at sample {self.k}"
        x_next = self._checked_call(lambda: self._phi(x, u), (self.n,), "f", SimulationError, where)
        F = numerical_jacobian(lambda z: self._phi(z, u), x, self.n)
        return x_next, F @ P @ F.T + self.Q

    def _start_estimate(self, x_prior: np.ndarray, y: np.ndarray, sel: tuple[int, ...] | None) -> np.ndarray:
        """One Gauss-Newton step from the prior towards ``h(x) = y``: ``x0 + pinv(H) (y - h(x0))``, ``H`` the
        Jacobian of the measured rows at the prior (the linear rule of
        :func:`~netsim.control.interface.first_measurement_estimate` with ``h`` linearised)."""
        yhat = self._checked_call(lambda: self._measure(x_prior), (self.p,), "h", SimulationError, "at x0")
        H = numerical_jacobian(self._measure, x_prior, self.p)
        if sel is not None:
            yhat, H = yhat[list(sel)], H[list(sel)]
        return x_prior + np.linalg.pinv(H) @ (y - yhat)
