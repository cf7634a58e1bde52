"""The pendulum study's estimators that the toolbox does not have, registered for the ``state_feedback`` program.

``pendulum_fd`` (:class:`FdVelocity4`)
    The slides' baseline: each measured angle (``theta``, ``alpha``) with its finite-difference velocity, raw or
    low-pass filtered (two :class:`netsim.control.FiniteDifferenceVelocity`), arranged as the state
    ``[theta, theta_dot, alpha, alpha_dot]``.
``luenberger_printed`` (:class:`PrintedLuenberger`)
    The Luenberger update exactly as the slides print it::

        x_hat[k] = (Ad - Ld C) x_hat[k-1] + Bd u[k-1] + Ld y[k]          (Ld from place(Ad', C', poles))

    The slides state that its error obeys ``e[k] = (Ad - Ld C) e[k-1]``. Substituting ``x[k] = Ad x[k-1] +
    Bd u[k-1]`` and ``y[k] = C x[k]`` gives instead::

        e[k] = (Ad - Ld C) e[k-1] - Ld C (x[k] - x[k-1])

    (the innovation compares ``y[k]`` with ``C x_hat[k-1]``, an output one sample old): the stated property
    holds only while the state does not move. Two consistent forms exist and the toolbox's
    :class:`netsim.control.LuenbergerObserver` has both: the *predictor* form (the same gain, ``y[k-1]`` in the
    update: ``e[k] = (Ad - Ld C) e[k-1]`` exactly) and the *current* form (``y[k]`` against the prediction
    ``Ad x_hat[k-1] + Bd u[k-1]``, gain from ``place(Ad', (C Ad)', poles)``: ``e[k] = (I - Ld C) Ad e[k-1]``).
    The study uses the current form (it uses the newest measurement, as the printed one means to) and keeps
    this one as the option ``luenberger_printed``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from pydantic import Field

from netsim.errors import SimulationError
from netsim.registry import register
from netsim.units import StrictModel

__all__ = ["FdVelocity4", "PrintedLuenberger"]


class FdVelocity4:
    """``[theta, theta_dot, alpha, alpha_dot]`` from two angle measurements by finite differences.

    Parameters
    ----------
    h
        Sampling period (s).
    cutoff_hz
        Cut-off of the first-order low-pass filter on each velocity; ``None`` for the raw difference.
    """

    def __init__(self, h: float, cutoff_hz: float | None = None) -> None:
        from netsim.control import FiniteDifferenceVelocity

        self.h, self.cutoff_hz = float(h), cutoff_hz
        self.fd = [FiniteDifferenceVelocity(h, cutoff_hz=cutoff_hz) for _ in range(2)]

    @property
    def x_hat(self) -> np.ndarray:
        """The estimate ``[theta, theta_dot, alpha, alpha_dot]``."""
        return np.concatenate([self.fd[0].x_hat, self.fd[1].x_hat])

    def correct(self, y: Any) -> bool:
        """Use ``y = [theta, alpha]`` of the current sample."""
        y = np.asarray(y, dtype=float).reshape(-1)
        if y.shape[0] != 2:
            raise SimulationError(f"pendulum_fd: the measurement has {y.shape[0]} entries, expected [theta, alpha]")
        ok = [f.correct(y[i]) for i, f in enumerate(self.fd)]
        return all(ok)

    def predict(self, u: Any = None) -> None:
        """Next sample (the estimate is held)."""
        for f in self.fd:
            f.predict(u)

    def reset(self) -> None:
        """Forget the previous samples."""
        for f in self.fd:
            f.reset()


class PrintedLuenberger:
    """The slides' printed Luenberger update (see the module docstring): ``x_hat[k] = (A - L C) x_hat[k-1] +
    B u[k-1] + L y[k]`` with ``L`` placing ``eig(A - L C)`` at ``poles``.

    Parameters
    ----------
    A, B, C
        Discrete model.
    poles
        Requested eigenvalues of ``A - L C``.
    x0
        Initial estimate (default zeros).
    """

    def __init__(self, A: Any, B: Any, C: Any, poles: Any, x0: Any = None) -> None:
        from netsim.control.luenberger import observer_gain

        self.A, self.B, self.C = (np.asarray(M, dtype=float) for M in (A, B, C))
        self.L = observer_gain(self.A, self.C, poles, "predictor")
        self.n = self.A.shape[0]
        self.x0 = np.zeros(self.n) if x0 is None else np.asarray(x0, dtype=float).reshape(self.n)
        self.reset()

    def reset(self) -> None:
        """Back to the initial estimate."""
        self.x = self.x0.copy()
        self._prev = self.x0.copy()  # x_hat[k-1]
        self._u = np.zeros(self.B.shape[1])  # u[k-1]
        self._started = False

    @property
    def error_matrix(self) -> np.ndarray:
        """``A - L C``: the matrix of the stated error dynamics."""
        return self.A - self.L @ self.C

    @property
    def x_hat(self) -> np.ndarray:
        """Estimate at the current sample."""
        return self.x

    def correct(self, y: Any) -> bool:
        """``x_hat[k] = A x_hat[k-1] + B u[k-1] + L (y[k] - C x_hat[k-1])``; the first sample only stores."""
        y = np.asarray(y, dtype=float).reshape(-1)
        if self._started:
            self.x = self.A @ self._prev + self.B @ self._u + self.L @ (y - self.C @ self._prev)
        return True

    def predict(self, u: Any = None) -> None:
        """Remember ``x_hat[k]`` and ``u[k]``; the estimate at ``k + 1`` without a measurement is the prediction."""
        u = np.zeros(self.B.shape[1]) if u is None else np.asarray(u, dtype=float).reshape(-1)
        self._prev, self._u, self._started = self.x.copy(), u, True
        self.x = self.A @ self._prev + self.B @ u


class _FdParams(StrictModel):
    cutoff_hz: float | None = Field(None, gt=0, description="low-pass cut-off on each velocity (Hz); null: raw")


@register("estimator", "pendulum_fd", "pendulum: [theta, alpha] and their finite-difference velocities (raw or low-pass)")
class FdPart:
    """``estimator: {type: pendulum_fd, cutoff_hz}`` (the measured rows must be ``[theta, alpha]``)."""

    Params = _FdParams

    @classmethod
    def build(cls, params: _FdParams, design: Any) -> FdVelocity4:
        from netsim.errors import ConfigError

        if design.C.shape != (2, 4) or not np.allclose(design.C, [[1, 0, 0, 0], [0, 0, 1, 0]]):
            raise ConfigError("pendulum_fd needs the measured outputs [theta, alpha] of a 4-state pendulum model")
        return FdVelocity4(design.period_s, params.cutoff_hz)


class _PrintedParams(StrictModel):
    poles: list[Any] = Field(description="n poles of A - L C, inside the unit circle (complex as '0.5+0.1j')")
    x0: list[float] | None = Field(None, description="initial estimate (default zeros)")


@register("estimator", "luenberger_printed",
          "the slides' printed Luenberger update x[k] = (A - LC) x[k-1] + B u[k-1] + L y[k] (inconsistent in motion)")
class PrintedPart:
    """``estimator: {type: luenberger_printed, poles, x0}``."""

    Params = _PrintedParams

    @classmethod
    def build(cls, params: _PrintedParams, design: Any) -> PrintedLuenberger:
        poles = [complex(str(p).replace(" ", "")) if isinstance(p, str) else p for p in params.poles]
        return PrintedLuenberger(design.A, design.B, design.C, poles, x0=params.x0)


class _KalmanParams(StrictModel):
    disturbance_std: float = Field(0.05, ge=0, description="std of the white input-voltage disturbance (V)")
    disturbance_hold: float = Field(0.001, gt=0, description="hold time of each disturbance value (s)")
    sensor_std: float | None = Field(None, gt=0, description="angle noise std (rad); null: encoder step / sqrt(12)")
    scale_Q: float = Field(1.0, gt=0, description="factor on Qn (the slides' 'try Qn')")
    scale_R: float = Field(1.0, gt=0, description="factor on Rn (the slides' 'try Rn')")
    history: int = Field(0, ge=0, le=1000, description="samples back a late measurement is fused")


@register("estimator", "pendulum_kalman",
          "pendulum: steady-state Kalman filter, Qn from the voltage disturbance, Rn from the sensor variances")
class KalmanPart:
    """``estimator: {type: pendulum_kalman, disturbance_std, disturbance_hold, sensor_std, scale_Q, scale_R}``.

    ``Qn`` is the white voltage disturbance mapped through the pendulum linearised with the scenario's own
    ``plant.params`` over one period (:func:`netsim.models.pendulum.model.process_noise_cov`), ``Rn = sensor_std^2 I``
    (the slides: "hold the system still ... sample variances ... as initial values for Rn"); the gain is the
    DARE's (the toolbox's :class:`netsim.control.KalmanFilter` with ``steady_state=True``). The plant must be
    the ``furuta_pendulum`` (its parameters reach the design as ``design.nonlinear.params``).
    """

    Params = _KalmanParams

    @classmethod
    def build(cls, params: _KalmanParams, design: Any) -> Any:
        from netsim.models.pendulum.model import SENSOR_STD, PendulumParams, discretise, process_noise_cov
        from netsim.control import KalmanFilter
        from netsim.errors import ConfigError

        plant_params = getattr(getattr(design, "nonlinear", None), "params", None)
        if not isinstance(plant_params, PendulumParams):
            raise ConfigError("pendulum_kalman: the scenario's plant is not the furuta_pendulum, whose parameters "
                              "give Qn; use plant 'furuta_pendulum', or the toolbox's 'kalman' estimator with your Q")
        lin = discretise(plant_params, h=design.period_s)
        Qn = process_noise_cov(lin, params.disturbance_std, params.disturbance_hold) * params.scale_Q
        std = SENSOR_STD if params.sensor_std is None else params.sensor_std
        Rn = np.eye(design.C.shape[0]) * std**2 * params.scale_R
        return KalmanFilter(design.A, design.B, design.C, Qn, Rn, steady_state=True, history=params.history)
