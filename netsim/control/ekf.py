"""Extended Kalman filter with user model functions and several measurement sources.

Model (discrete, on the sampling grid of the filter)::

    x[k+1] = f(x[k], u[k]) + w[k],      w ~ N(0, Q)
    y_s[k] = h_s(x[k]) + v_s[k],        v_s ~ N(0, R_s)   for each measurement source s

Prediction: ``x <- f(x, u)``, ``P <- F P F' + Q`` with ``F = df/dx`` at the previous estimate. Correction with
source ``s``: ``H = dh_s/dx`` at the prior, ``K = P H' (H P H' + R_s)^-1``, ``x <- x + K (y - h_s(x))``,
``P <- (I - K H) P (I - K H)' + K R_s K'`` (Joseph form).

Jacobians are the user's functions when given, otherwise central finite differences with the step
``eps^(1/3) * max(1, |x_i|)`` (``2 n`` calls of the function per Jacobian). Each source has its own noise and
its own rate: a source is simply not corrected at a sample where it has no measurement, and several sources
may be corrected at one sample (sequentially, each at most once). A model function that raises or returns
the wrong shape is reported at construction (it is called once at ``x0``) as a
:class:`~netsim.errors.ConfigError` naming the function, and during a run as a
:class:`~netsim.errors.SimulationError` naming the function and the sample.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from netsim.control.design_checks import as_vector, check_weight
from netsim.errors import ConfigError, NetsimError, SimulationError

__all__ = ["ExtendedKalmanFilter", "MeasurementSource", "numerical_jacobian"]

_FD_STEP = float(np.finfo(float).eps) ** (1.0 / 3.0)


def numerical_jacobian(fun: Callable[[np.ndarray], np.ndarray], x: np.ndarray, fx_size: int) -> np.ndarray:
    """Central-difference Jacobian of ``fun`` at ``x`` (``fx_size x len(x)``)."""
    n = x.shape[0]
    J = np.empty((fx_size, n))
    for i in range(n):
        d = _FD_STEP * max(1.0, abs(x[i]))
        xp = x.copy()
        xm = x.copy()
        xp[i] += d
        xm[i] -= d
        J[:, i] = (np.asarray(fun(xp), dtype=float).reshape(-1) - np.asarray(fun(xm), dtype=float).reshape(-1)) / (
            xp[i] - xm[i]
        )
    return J


@dataclass
class MeasurementSource:
    """One measurement source of an :class:`ExtendedKalmanFilter`.

    Parameters
    ----------
    h
        Measurement function ``h(x) -> y`` (``p`` numbers).
    R
        Its noise covariance (``p x p`` positive definite; scalar or diagonal vector accepted).
    H
        Optional Jacobian ``H(x) -> p x n``; finite differences when ``None``.
    """

    h: Callable[[np.ndarray], Any]
    R: Any
    H: Callable[[np.ndarray], Any] | None = None


class ExtendedKalmanFilter:
    """EKF for ``x+ = f(x, u) + w``, ``y_s = h_s(x) + v_s`` (see the module docstring).

    Parameters
    ----------
    f
        Discrete transition ``f(x, u) -> x_next``.
    sources
        Measurement sources by name: :class:`MeasurementSource` objects or dicts with keys ``h``, ``R``, ``H``.
    Q
        Process noise covariance (``n x n`` positive semidefinite).
    x0, P0
        Initial estimate and covariance (``P0`` default identity).
    n_inputs
        Number of inputs ``m`` (``u`` is checked against it; ``0`` for none).
    F
        Optional Jacobian ``F(x, u) -> n x n``; finite differences when ``None``.

    Raises
    ------
    ConfigError
        A covariance of the wrong size or not positive (semi)definite, no source, or a user function that
        raises, returns the wrong shape or non-finite numbers when called at ``x0`` (and ``u = 0``).
    """

    def __init__(
        self,
        f: Callable[[np.ndarray, np.ndarray], Any],
        sources: Mapping[str, MeasurementSource | Mapping[str, Any]],
        Q: Any,
        x0: Any,
        *,
        P0: Any = None,
        n_inputs: int = 1,
        F: Callable[[np.ndarray, np.ndarray], Any] | None = None,
    ) -> None:
        if not callable(f):
            raise ConfigError(f"f must be a function f(x, u) -> x_next, got {f!r:.80}")
        if F is not None and not callable(F):
            raise ConfigError(f"F must be a function F(x, u) -> n x n Jacobian or None, got {F!r:.80}")
        self.x0 = np.array(x0, dtype=float).reshape(-1)
        n = self.x0.shape[0]
        if n == 0 or not np.all(np.isfinite(self.x0)):
            raise ConfigError("x0 must be a non-empty vector of finite numbers")
        if int(n_inputs) != n_inputs or n_inputs < 0:
            raise ConfigError(f"n_inputs must be a whole number >= 0, got {n_inputs!r}")
        self.n, self.m = n, int(n_inputs)
        self.f, self.F = f, F
        self.Q = check_weight("Q", Q, n, definite=False)
        self.P0 = np.eye(n) if P0 is None else check_weight("P0", P0, n, definite=False)
        if not sources:
            raise ConfigError("sources: give at least one measurement source (name: {h, R})")
        self.sources: dict[str, MeasurementSource] = {}
        self._R: dict[str, np.ndarray] = {}
        self._p: dict[str, int] = {}
        u0 = np.zeros(self.m)
        for name, src in sources.items():
            if isinstance(src, Mapping):
                unknown = set(src) - {"h", "R", "H"}
                if unknown:
                    raise ConfigError(f"sources.{name}: unknown key(s) {sorted(unknown)}; use h, R and H")
                if "h" not in src or "R" not in src:
                    raise ConfigError(f"sources.{name}: needs h (the measurement function) and R (its noise)")
                src = MeasurementSource(src["h"], src["R"], src.get("H"))
            if not callable(src.h) or (src.H is not None and not callable(src.H)):
                raise ConfigError(f"sources.{name}: h (and H, if given) must be functions of x")
            y0 = self._checked(src.h, (self.x0,), None, f"sources.{name}.h", ConfigError, "at x0")
            p = y0.shape[0]
            self.sources[name] = src
            self._p[name] = p
            self._R[name] = check_weight(f"sources.{name}.R", src.R, p, definite=True)
            if src.H is not None:
                self._checked(src.H, (self.x0,), (p, n), f"sources.{name}.H", ConfigError, "at x0")
        self._checked(f, (self.x0, u0), (n,), "f", ConfigError, "at x0 and u = 0")
        if F is not None:
            self._checked(F, (self.x0, u0), (n, n), "F", ConfigError, "at x0 and u = 0")
        self._only = next(iter(self.sources)) if len(self.sources) == 1 else None
        self._I = np.eye(n)
        self.reset()

    @staticmethod
    def _checked(
        fun: Callable[..., Any],
        args: tuple[Any, ...],
        shape: tuple[int, ...] | None,
        name: str,
        err: type[NetsimError],
        where: str,
    ) -> np.ndarray:
        try:
            out = np.asarray(fun(*args), dtype=float)
        except Exception as exc:  # any error of user code becomes a message naming the function
            raise err(f"{name} raised {type(exc).__name__}: {exc} ({where}); fix the function") from exc
        if shape is None:
            out = out.reshape(-1)
            if out.size == 0:
                raise err(f"{name} returned no values ({where})")
        elif out.shape != shape:
            if len(shape) == 1 and out.size == shape[0]:
                out = out.reshape(shape)
            else:
                want = "x".join(str(s) for s in shape)
                raise err(f"{name} must return {want} values, returned shape {out.shape} ({where})")
        if not np.all(np.isfinite(out)):
            raise err(f"{name} returned NaN or infinite values ({where})")
        return out

    def reset(self, x0: Any = None, P0: Any = None) -> None:
        """Back to the initial estimate and covariance."""
        self.x = self.x0.copy() if x0 is None else as_vector("x0", x0, self.n)
        self.P = self.P0.copy() if P0 is None else check_weight("P0", P0, self.n, definite=False)
        self.k = 0
        self._done: set[str] = set()
        self.duplicates = 0

    @property
    def x_hat(self) -> np.ndarray:
        """Estimate at the current sample."""
        return self.x

    def correct(self, y: Any, source: str | None = None) -> bool:
        """Fuse a measurement of ``source`` taken at the current sample.

        ``source`` may be omitted when the filter has one source. Returns ``False`` (and counts a duplicate)
        when that source was already fused at this sample.

        Raises
        ------
        SimulationError
            Unknown source, ``y`` of the wrong size, or ``h``/``H`` raising or returning a wrong shape.
        """
        if source is None:
            if self._only is None:
                raise SimulationError(f"EKF: name the measurement source, one of {sorted(self.sources)}")
            source = self._only
        src = self.sources.get(source)
        if src is None:
            raise SimulationError(f"EKF: unknown measurement source {source!r}; the filter has {sorted(self.sources)}")
        if source in self._done:
            self.duplicates += 1
            return False
        p = self._p[source]
        y = np.asarray(y, dtype=float).reshape(-1)
        if y.shape[0] != p:
            raise SimulationError(f"EKF: a measurement of source {source!r} has {y.shape[0]} entries, h gives {p}")
        where = f"at sample {self.k}"
        x, P = self.x, self.P
        yhat = self._checked(src.h, (x,), (p,), f"sources.{source}.h", SimulationError, where)
        if src.H is not None:
            H = self._checked(src.H, (x,), (p, self.n), f"sources.{source}.H", SimulationError, where)
        else:
            H = numerical_jacobian(
                lambda z: self._checked(src.h, (z,), (p,), f"sources.{source}.h", SimulationError, where), x, p
            )
        PHt = P @ H.T
        S = H @ PHt + self._R[source]
        K = np.linalg.solve(S, PHt.T).T
        self.x = x + K @ (y - yhat)
        IKH = self._I - K @ H
        self.P = IKH @ P @ IKH.T + K @ self._R[source] @ K.T
        self._done.add(source)
        return True

    def predict(self, u: Any = None) -> None:
        """Move to the next sample: ``x <- f(x, u)``, ``P <- F P F' + Q``."""
        u = np.zeros(self.m) if u is None else np.asarray(u, dtype=float).reshape(-1)
        if u.shape[0] != self.m:
            raise SimulationError(
                f"EKF: the input has {u.shape[0]} entries, the filter was built with n_inputs={self.m}"
            )
        where = f"at sample {self.k}"
        x = self.x
        n = self.n
        if self.F is not None:
            F = self._checked(self.F, (x, u), (n, n), "F", SimulationError, where)
        else:
            F = numerical_jacobian(lambda z: self._checked(self.f, (z, u), (n,), "f", SimulationError, where), x, n)
        self.x = self._checked(self.f, (x, u), (n,), "f", SimulationError, where)
        self.P = F @ self.P @ F.T + self.Q
        self.k += 1
        self._done = set()
