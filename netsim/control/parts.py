"""The estimators and control laws a scenario names: ``estimator: {type: NAME, ...}``, ``law: {type: NAME, ...}``.

Each entry is registered (kind ``estimator`` or ``controller``) with a ``Params`` model, what ``netsim list
estimator kalman`` prints and ``netsim validate`` checks, and ``build(params, design)``, which makes the plain
numeric object of :mod:`netsim.control` from the parameters and the :class:`Design` (the discrete model the
controller program runs on: the plant discretised at the task period, unless the scenario gives one).

Estimators (:class:`~netsim.control.interface.StateEstimator`)
    ``kalman`` (time-varying :class:`~netsim.control.kalman.KalmanFilter`, delayed measurements fused at their
    sample time within ``history`` samples), ``steady_state_kalman`` (the gain from the filter DARE),
    ``luenberger`` (:class:`~netsim.control.luenberger.LuenbergerObserver`, ``poles`` and ``form``), ``none``
    (the state is measured: ``x_hat = C^-1 y``, predicted with the model when a measurement is missing).
Laws (:class:`~netsim.control.interface.ControlLaw`)
    ``lqr`` (:class:`~netsim.control.lqr.LQR`), ``state_feedback`` (a given gain ``K``), ``mpc``
    (:class:`~netsim.control.mpc.LinearMPC`); ``pid`` is the :class:`~netsim.control.pid.PID` already
    registered under that name (fed the first measured output, through
    :class:`~netsim.control.pid.PIDLaw`).

Weights and covariances accept a number (times the identity), a list (the diagonal) or a matrix. Every
constructor check (shapes, symmetry, definiteness, stabilisability, detectability, pole positions, MPC
feasibility of the initial state) raises :class:`~netsim.errors.ConfigError` naming the parameter; the
program adds the YAML path (``nodes.<n>.tasks[i].params.law.Q``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from pydantic import Field

from netsim.errors import ConfigError
from netsim.registry import register
from netsim.units import StrictModel

__all__ = [
    "ESTIMATOR_TYPES",
    "LAW_TYPES",
    "ContinuousModel",
    "Design",
    "DirectState",
    "KalmanPart",
    "LQRPart",
    "LuenbergerPart",
    "MPCPart",
    "ModelEKFPart",
    "NoEstimatorPart",
    "StateFeedbackPart",
    "SteadyStateKalmanPart",
]

#: A weight or covariance: a number (times the identity), a list (the diagonal) or a matrix.
Weight = Any


@dataclass(frozen=True)
class Design:
    """The discrete model a controller program's estimator and law are designed on.

    Attributes
    ----------
    A, B, C
        ``x[k+1] = A x[k] + B u[k]``, ``y[k] = C x[k]`` at the controller's period (``C``: the measured outputs).
    period_s
        The sampling period in seconds.
    Cr
        Rows of the outputs a reference applies to (``None``: no reference, the law regulates the state to 0).
    x0
        The plant's initial state when known (the MPC checks its feasibility), else ``None``.
    nonlinear
        The plant's own continuous model when it has one (a nonlinear plant), for the ``ekf`` estimator.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    period_s: float
    Cr: np.ndarray | None = None
    x0: np.ndarray | None = None
    nonlinear: ContinuousModel | None = None


@dataclass(frozen=True)
class ContinuousModel:
    """A plant's continuous model ``x' = f(t, x, u, params)``, ``y = h(t, x, u, params)``, measured ``rows`` of y."""

    f: Any
    h: Any
    params: Any
    n_states: int
    n_inputs: int
    rows: tuple[int, ...]


class DirectState:
    """The state is measured (``C`` square and invertible): ``x_hat = C^-1 y``; without a measurement the
    estimate is the model prediction ``A x_hat + B u``."""

    def __init__(self, A: np.ndarray, B: np.ndarray, C: np.ndarray) -> None:
        n = A.shape[0]
        if C.shape != (n, n) or np.linalg.matrix_rank(C) < n:
            raise ConfigError(f"estimator type 'none' needs every state measured (C square and invertible, "
                              f"{n}x{n}); the measured outputs give C of shape {C.shape[0]}x{C.shape[1]}: choose "
                              "an estimator (kalman, luenberger)")
        self.A, self.B, self._Cinv = A, B, np.linalg.inv(C)
        self.x = np.zeros(n)

    @property
    def x_hat(self) -> np.ndarray:
        return self.x

    def correct(self, y: Any) -> bool:
        self.x = self._Cinv @ np.asarray(y, dtype=float).reshape(-1)
        return True

    def predict(self, u: Any = None) -> None:
        u = np.zeros(self.B.shape[1]) if u is None else np.asarray(u, dtype=float).reshape(-1)
        self.x = self.A @ self.x + self.B @ u

    def reset(self) -> None:
        self.x = np.zeros(self.A.shape[0])


# --------------------------------------------------------------------------------------------- estimators
class _KalmanParams(StrictModel):
    Q: Weight = Field(description="process noise covariance of the discrete model (n x n, PSD)")
    R: Weight = Field(description="measurement noise covariance (p x p, positive definite)")
    x0: list[float] | None = Field(None, description="initial estimate (default zeros)")
    P0: Weight = Field(None, description="initial covariance (default identity; ignored in steady state)")
    history: int = Field(20, ge=0, le=10_000,
                         description="samples back a delayed measurement is fused at its sample time")


@register("estimator", "kalman", "time-varying Kalman filter; delayed measurements fused at their sample time")
class KalmanPart:
    """``estimator: {type: kalman, Q, R, x0, P0, history}``."""

    Params = _KalmanParams
    steady_state = False

    @classmethod
    def build(cls, params: _KalmanParams, design: Design) -> Any:
        from netsim.control.kalman import KalmanFilter

        return KalmanFilter(design.A, design.B, design.C, params.Q, params.R, x0=params.x0, P0=params.P0,
                            steady_state=cls.steady_state, history=params.history)


@register("estimator", "steady_state_kalman", "Kalman filter with the constant gain from the filter DARE")
class SteadyStateKalmanPart(KalmanPart):
    """``estimator: {type: steady_state_kalman, Q, R, x0, history}``."""

    steady_state = True


class _EKFParams(_KalmanParams):
    substeps: int = Field(4, ge=1, le=1000, description="Runge-Kutta 4 steps per period for the prediction")


@register("estimator", "ekf", "extended Kalman filter on the plant's own nonlinear model (f, h), RK4 per period")
class ModelEKFPart:
    """``estimator: {type: ekf, Q, R, x0, P0, substeps, history}``: needs a plant with its own model (f, h)."""

    Params = _EKFParams

    @classmethod
    def build(cls, params: _EKFParams, design: Design) -> Any:
        from netsim.control.model_ekf import ModelEKF

        model = design.nonlinear
        if model is None:
            raise ConfigError("type 'ekf' filters the plant's own nonlinear model, and this plant has none (its "
                              "model is linear or not given as f and h): use 'kalman' for a linear plant")
        if model.n_states != design.A.shape[0] or model.n_inputs != design.B.shape[1]:
            raise ConfigError(f"type 'ekf': the plant has {model.n_states} states and {model.n_inputs} inputs, the "
                              f"controller's model {design.A.shape[0]} and {design.B.shape[1]}; make them agree")
        return ModelEKF(model.f, model.h, model.params, model.n_states, model.n_inputs, model.rows,
                        design.period_s, params.Q, params.R, x0=params.x0, P0=params.P0, substeps=params.substeps,
                        history=params.history)


class _LuenbergerParams(StrictModel):
    poles: list[Any] = Field(description="n discrete observer poles, inside the unit circle (complex as '0.5+0.1j')")
    form: Literal["predictor", "current"] = Field("current", description="predictor (y[k-1]) or current (y[k])")
    x0: list[float] | None = Field(None, description="initial estimate (default zeros)")


@register("estimator", "luenberger", "Luenberger observer, gain by pole placement, predictor or current form")
class LuenbergerPart:
    """``estimator: {type: luenberger, poles, form, x0}``."""

    Params = _LuenbergerParams

    @classmethod
    def build(cls, params: _LuenbergerParams, design: Design) -> Any:
        from netsim.control.luenberger import LuenbergerObserver

        try:
            poles = [complex(str(p).replace(" ", "")) if isinstance(p, str) else p for p in params.poles]
        except ValueError as exc:
            raise ConfigError(f"poles: {exc}; write complex poles as '0.5+0.1j'") from None
        return LuenbergerObserver(design.A, design.B, design.C, poles, form=params.form, x0=params.x0)


class _NoParams(StrictModel):
    pass


@register("estimator", "none", "no estimator: every state is measured (x_hat = C^-1 y)")
class NoEstimatorPart:
    """``estimator: {type: none}``."""

    Params = _NoParams

    @classmethod
    def build(cls, params: _NoParams, design: Design) -> Any:
        return DirectState(design.A, design.B, design.C)


# --------------------------------------------------------------------------------------------- laws
class _Limits(StrictModel):
    u_min: float | list[float] | None = Field(None, description="input lower limit (one, or one per input)")
    u_max: float | list[float] | None = Field(None, description="input upper limit (one, or one per input)")


class _LQRParams(_Limits):
    Q: Weight = Field(description="state weight (n x n, PSD)")
    R: Weight = Field(description="input weight (m x m, positive definite)")
    N: Any = Field(None, description="cross weight (n x m)")
    integral: bool = Field(False, description="integral action on the reference error")
    Qi: Weight = Field(None, description="weight of the integrator states (default identity)")
    feedforward: bool = Field(True, description="steady-state feed-forward of the reference")


@register("controller", "lqr", "discrete LQR state feedback (python-control dlqr at build)")
class LQRPart:
    """``law: {type: lqr, Q, R, N, integral, Qi, feedforward, u_min, u_max}``."""

    Params = _LQRParams
    fed_state = True

    @classmethod
    def build(cls, params: _LQRParams, design: Design) -> Any:
        from netsim.control.lqr import LQR

        return LQR(design.A, design.B, params.Q, params.R, N=params.N, Cr=design.Cr, integral=params.integral,
                   Qi=params.Qi, feedforward=params.feedforward, u_min=params.u_min, u_max=params.u_max)


class _StateFeedbackParams(_Limits):
    K: Any = Field(description="state gain (m x n)")
    Ki: Any = Field(None, description="integral gain (m x q), with a reference")
    feedforward: bool = Field(True, description="steady-state feed-forward of the reference")


@register("controller", "state_feedback", "u = u_ff(r) - K x_hat with a given gain K")
class StateFeedbackPart:
    """``law: {type: state_feedback, K, Ki, feedforward, u_min, u_max}``."""

    Params = _StateFeedbackParams
    fed_state = True

    @classmethod
    def build(cls, params: _StateFeedbackParams, design: Design) -> Any:
        from netsim.control.lqr import StateFeedback

        return StateFeedback(design.A, design.B, params.K, Cr=design.Cr, Ki=params.Ki,
                             feedforward=params.feedforward, u_min=params.u_min, u_max=params.u_max)


class _MPCParams(_Limits):
    horizon: int = Field(ge=1, le=1000, description="prediction horizon N (samples)")
    Q: Weight = Field(description="state weight (n x n, PSD)")
    R: Weight = Field(description="input weight (m x m, positive definite)")
    P: Weight = Field(None, description="terminal weight (default: the LQR Riccati solution)")
    du_min: float | list[float] | None = Field(None, description="input rate lower limit per sample")
    du_max: float | list[float] | None = Field(None, description="input rate upper limit per sample")
    x_min: list[float | None] | None = Field(None, description="state lower limits (null: none)")
    x_max: list[float | None] | None = Field(None, description="state upper limits (null: none)")
    solver: Literal["daqp", "clarabel", "osqp", "piqp"] = Field("daqp", description="QP solver")
    tol: float = Field(1e-9, gt=0, description="solver tolerance")


@register("controller", "mpc", "linear MPC: horizon, input/rate/state box constraints, LQR terminal cost")
class MPCPart:
    """``law: {type: mpc, horizon, Q, R, P, u_min, u_max, du_min, du_max, x_min, x_max, solver, tol}``.

    The plant's initial state (when the scenario gives ``plant.x0``) is checked against the state limits and
    for feasibility when the law is built, so ``netsim validate`` refuses an MPC whose first problem has no
    solution.
    """

    Params = _MPCParams
    fed_state = True

    @classmethod
    def build(cls, params: _MPCParams, design: Design) -> Any:
        from netsim.control.mpc import LinearMPC

        return LinearMPC(design.A, design.B, params.Q, params.R, params.horizon, P=params.P,
                         u_min=params.u_min, u_max=params.u_max, du_min=params.du_min, du_max=params.du_max,
                         x_min=params.x_min, x_max=params.x_max, Cr=design.Cr, solver=params.solver, tol=params.tol,
                         x0=design.x0)


#: The estimator and law types a ``state_feedback`` program accepts (``pid`` is the registered PID).
ESTIMATOR_TYPES = ("kalman", "steady_state_kalman", "ekf", "luenberger", "none")
LAW_TYPES = ("lqr", "state_feedback", "mpc", "pid")
