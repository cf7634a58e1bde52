"""The estimators and control laws a scenario names: ``estimator: {type: NAME, ...}``, ``law: {type: NAME, ...}``.

Each entry is registered (kind ``estimator`` or ``controller``) and follows the :class:`EstimatorPart` /
:class:`LawPart` protocol: a ``Params`` model (what ``netsim list estimator kalman`` prints), declared
capabilities (class attributes: what the program and ``netsim validate`` read instead of probing the built
object), and ``build(params, design, rng)``, which makes the plain numeric object of :mod:`netsim.control` from
the parameters and the :class:`Design` (the discrete model the controller program runs on: the plant
discretised at the task period, unless the scenario gives one). A scenario's block validates into a typed spec
(:mod:`netsim.control.part_specs`); a registered part from a plugin subclasses :class:`EstimatorPartBase` or
:class:`LawPartBase` (one written with ``build(params, design)`` still runs, with the default capabilities).

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

Weights and covariances accept a number (times the identity), a list (the diagonal) or a matrix, parsed once
into typed values (:mod:`netsim.control.weights`). Every
constructor check (shapes, symmetry, definiteness, stabilisability, detectability, pole positions, MPC
feasibility of the initial state) raises :class:`~netsim.errors.ConfigError` naming the parameter; the
program adds the YAML path (``nodes.<n>.tasks[i].params.law.Q``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, Literal, Protocol

import numpy as np
from pydantic import BaseModel, Field, model_validator

from netsim.control.interface import EstimatorBase, EstimatorCapabilities
from netsim.control.pid import PIDParams
from netsim.control.weights import MatrixField, WeightField
from netsim.errors import ConfigError
from netsim.registry import register
from netsim.units import StrictModel

__all__ = [
    "BUILTIN_ESTIMATORS",
    "BUILTIN_LAWS",
    "ESTIMATOR_TYPES",
    "LAW_TYPES",
    "ContinuousModel",
    "Design",
    "DirectState",
    "EstimatorPart",
    "EstimatorPartBase",
    "KalmanPart",
    "LQRPart",
    "LawPart",
    "LawPartBase",
    "LuenbergerPart",
    "MPCPart",
    "ModelEKFPart",
    "NoEstimatorPart",
    "PIDPart",
    "StateFeedbackPart",
    "SteadyStateKalmanPart",
]


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
    period_ns
        The sampling period in integer nanoseconds (when the design comes from a task).
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    period_s: float
    Cr: np.ndarray | None = None
    x0: np.ndarray | None = None
    nonlinear: ContinuousModel | None = None
    period_ns: int | None = None


@dataclass(frozen=True)
class ContinuousModel:
    """A plant's continuous model ``x' = f(t, x, u, params)``, ``y = h(t, x, u, params)``, measured ``rows`` of y."""

    f: Any
    h: Any
    params: Any
    n_states: int
    n_inputs: int
    rows: tuple[int, ...]


class DirectState(EstimatorBase):
    """The state is measured (``C`` square and invertible): ``x_hat = C^-1 y``; without a measurement the
    estimate is the model prediction ``A x_hat + B u``."""

    _u_prev: np.ndarray | None  # the last input (None before the first predict)
    _prev_fused: bool
    _fused: bool

    @property
    def capabilities(self) -> EstimatorCapabilities:
        """No history: a measurement of the previous sample is fused one step late (``correct_previous``)."""
        return EstimatorCapabilities(corrects_previous=True)

    def __init__(self, A: np.ndarray, B: np.ndarray, C: np.ndarray) -> None:
        n = A.shape[0]
        if C.shape != (n, n) or np.linalg.matrix_rank(C) < n:
            raise ConfigError(f"estimator type 'none' needs every state measured (C square and invertible, "
                              f"{n}x{n}); the measured outputs give C of shape {C.shape[0]}x{C.shape[1]}: choose "
                              "an estimator (kalman, luenberger)")
        self.A, self.B, self._Cinv = A, B, np.linalg.inv(C)
        self.reset()

    @property
    def x_hat(self) -> np.ndarray:
        return self.x

    def correct(self, y: Any) -> bool:
        self.x = self._Cinv @ np.asarray(y, dtype=float).reshape(-1)
        self._fused = True
        return True

    def correct_previous(self, y: Any) -> bool:
        """``y[k-1]`` fused at ``k``: ``x_hat = A C^-1 y[k-1] + B u[k-1]`` (as if it had come in time); ``False``
        at the first sample or when sample ``k-1`` fused one already (call it before :meth:`correct`)."""
        if self._u_prev is None or self._prev_fused or self._fused:
            return False
        self.x = self.A @ (self._Cinv @ np.asarray(y, dtype=float).reshape(-1)) + self.B @ self._u_prev
        self._prev_fused = True
        return True

    def predict(self, u: Any = None) -> None:
        u = np.zeros(self.B.shape[1]) if u is None else np.asarray(u, dtype=float).reshape(-1)
        self.x = self.A @ self.x + self.B @ u
        self._u_prev, self._prev_fused, self._fused = u, self._fused, False

    def reset(self) -> None:
        self.x = np.zeros(self.A.shape[0])
        self._u_prev = None
        self._prev_fused = self._fused = False


# --------------------------------------------------------------------------------------------- part protocols
class EstimatorPart(Protocol):
    """What ``estimator: {type: NAME, ...}`` names: its parameters, its capabilities, and ``build``.

    Capabilities are declared, never probed: the program and ``netsim validate`` read these attributes.

    Attributes
    ----------
    Params
        The pydantic model of its parameters (``netsim list estimator NAME``).
    needs_nonlinear_model
        Built on the plant's own continuous model (``design.nonlinear``), not only on ``(A, B, C)``.
    input_delay
        ``"any"``: built on the design's ``B``, so ``input_delay`` rebuilds it on ``B = [Gamma0 Gamma1]`` (any
        delay); ``"whole_periods"``: predicted with ``u[k-d]`` (whole periods of delay only).
    late_inputs
        Can be built on ``B = I`` and re-predict past periods from inputs learned late (``applied_input``).
    starts_from_measurement
        ``x0_hat: first_measurement`` is possible (the estimate can start from the first measurement).
    """

    Params: ClassVar[type[BaseModel]]
    needs_nonlinear_model: ClassVar[bool]
    input_delay: ClassVar[Literal["any", "whole_periods"]]
    late_inputs: ClassVar[bool]
    starts_from_measurement: ClassVar[bool]

    @classmethod
    def build(cls, params: Any, design: Design, rng: np.random.Generator) -> Any:
        """The runtime estimator (a :class:`~netsim.control.interface.StateEstimator`) on ``design``."""
        ...


class LawPart(Protocol):
    """What ``law: {type: NAME, ...}`` names: its parameters, whether it is fed the state estimate, ``build``.

    Attributes
    ----------
    Params
        The pydantic model of its parameters (``netsim list controller NAME``).
    fed_state
        ``True``: ``u = law.step(x_hat, r)``; ``False``: the law is fed the first measured output (a PID).
    """

    Params: ClassVar[type[BaseModel]]
    fed_state: ClassVar[bool]

    @classmethod
    def build(cls, params: Any, design: Design, rng: np.random.Generator) -> Any:
        """The runtime law (a :class:`~netsim.control.interface.ControlLaw`) on ``design``."""
        ...


class EstimatorPartBase:
    """Defaults of :class:`EstimatorPart`'s capabilities; a registered estimator subclasses it (or declares them)."""

    Params: ClassVar[type[BaseModel]]
    needs_nonlinear_model: ClassVar[bool] = False
    input_delay: ClassVar[Literal["any", "whole_periods"]] = "any"
    late_inputs: ClassVar[bool] = False
    starts_from_measurement: ClassVar[bool] = False


class LawPartBase:
    """Defaults of :class:`LawPart`'s capabilities; a registered law subclasses it (or declares them)."""

    Params: ClassVar[type[BaseModel]]
    fed_state: ClassVar[bool] = True


# --------------------------------------------------------------------------------------------- estimators
class _KalmanParams(StrictModel):
    Q: WeightField = Field(description="covariance of the process noise w[k] of the discrete model at the task period, "
                                  "x[k+1] = A x[k] + B u[k] + w[k] (n x n, PSD, state units squared; a number: "
                                  "times I, a list: the diagonal)")
    R: WeightField = Field(description="covariance of the measurement noise v[k], y[k] = C x[k] + v[k] (p x p, "
                                       "positive definite, measured outputs' units squared)")
    x0: list[float] | None = Field(None, description="initial estimate x_hat[0|-1], the prior of the first sample "
                                                     "(n numbers, state units; default zeros)")
    P0: WeightField | None = Field(None, description="covariance of x0 (n x n; default identity; ignored by "
                                                     "steady_state_kalman, which starts from the DARE prior)")
    history: int = Field(20, ge=0, le=10_000,
                         description="samples back a delayed measurement is fused at its own sample time (re-filtered "
                                     "from the stored priors); older ones are stale")


@register("estimator", "kalman", "time-varying Kalman filter; delayed measurements fused at their sample time")
class KalmanPart(EstimatorPartBase):
    """``estimator: {type: kalman, Q, R, x0, P0, history}``."""

    Params = _KalmanParams
    late_inputs = True
    starts_from_measurement = True
    steady_state: ClassVar[bool] = False

    @classmethod
    def build(cls, params: _KalmanParams, design: Design, rng: np.random.Generator) -> Any:
        from netsim.control.kalman import KalmanFilter

        return KalmanFilter(design.A, design.B, design.C, params.Q, params.R, x0=params.x0, P0=params.P0,
                            steady_state=cls.steady_state, history=params.history)


@register("estimator", "steady_state_kalman", "Kalman filter with the constant gain from the filter DARE")
class SteadyStateKalmanPart(KalmanPart):
    """``estimator: {type: steady_state_kalman, Q, R, x0, history}``."""

    steady_state = True


class _EKFParams(_KalmanParams):
    substeps: int = Field(4, ge=1, le=1000, description="classic Runge-Kutta 4 steps per task period in the "
                                                        "prediction x[k+1] = phi(x[k], u[k])")


@register("estimator", "ekf", "extended Kalman filter on the plant's own nonlinear model (f, h), RK4 per period")
class ModelEKFPart(EstimatorPartBase):
    """``estimator: {type: ekf, Q, R, x0, P0, substeps, history}``: needs a plant with its own model (f, h)."""

    Params = _EKFParams
    needs_nonlinear_model = True
    input_delay = "whole_periods"
    starts_from_measurement = True

    @classmethod
    def build(cls, params: _EKFParams, design: Design, rng: np.random.Generator) -> Any:
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
    poles: list[Any] = Field(description="n discrete eigenvalues of the estimation error (of A - L C in the predictor "
                                         "form, of (I - L C) A in the current form), inside the unit circle "
                                         "(complex as '0.5+0.1j', in conjugate pairs)")
    form: Literal["predictor", "current"] = Field("current", description="current: x_hat[k] uses y[k] (corrects the "
                                                  "prediction); predictor: x_hat[k] uses y up to y[k-1]")
    x0: list[float] | None = Field(None, description="initial estimate x_hat[0] (n numbers, state units; default "
                                                     "zeros)")


@register("estimator", "luenberger", "Luenberger observer, gain by pole placement, predictor or current form")
class LuenbergerPart(EstimatorPartBase):
    """``estimator: {type: luenberger, poles, form, x0}``."""

    Params = _LuenbergerParams
    starts_from_measurement = True

    @classmethod
    def build(cls, params: _LuenbergerParams, design: Design, rng: np.random.Generator) -> Any:
        from netsim.control.luenberger import LuenbergerObserver

        try:
            poles = [complex(str(p).replace(" ", "")) if isinstance(p, str) else p for p in params.poles]
        except ValueError as exc:
            raise ConfigError(f"poles: {exc}; write complex poles as '0.5+0.1j'") from None
        return LuenbergerObserver(design.A, design.B, design.C, poles, form=params.form, x0=params.x0)


class _NoParams(StrictModel):
    pass


@register("estimator", "none", "no estimator: every state is measured (x_hat = C^-1 y)")
class NoEstimatorPart(EstimatorPartBase):
    """``estimator: {type: none}`` (the measurement is the estimate: it starts from the first one)."""

    Params = _NoParams
    starts_from_measurement = True

    @classmethod
    def build(cls, params: _NoParams, design: Design, rng: np.random.Generator) -> Any:
        return DirectState(design.A, design.B, design.C)


# --------------------------------------------------------------------------------------------- laws
class _Limits(StrictModel):
    u_min: float | list[float] | None = Field(None, description="input lower limit in the plant input's units (one "
                                                                "number, or one per input); u is clipped to it")
    u_max: float | list[float] | None = Field(None, description="input upper limit in the plant input's units (one "
                                                                "number, or one per input); u is clipped to it")


_Q_TEXT = ("state weight of the discrete design (n x n, PSD; a number: times I, a list: the diagonal); may be left "
           "out when Qy is given")
_QY_TEXT = ("weight on the measured outputs y = C x (p x p, PSD, in the order of the task's measured outputs); the "
            "design's state weight is Q + C' Qy C, so a tf plant can be weighted without knowing its realisation")


def _weighted(params: Any) -> Any:
    if params.Q is None and params.Qy is None:
        raise ValueError("give a state weight Q, an output weight Qy (on y = C x), or both")
    return params


class _LQRParams(_Limits):
    Q: WeightField | None = Field(None, description=_Q_TEXT)
    Qy: WeightField | None = Field(None, description=_QY_TEXT)
    R: WeightField = Field(description="input weight (m x m, positive definite, per input unit squared)")
    N: MatrixField | None = Field(None, description="cross weight N of the cost term 2 x' N u (n x m; default zero)")
    integral: bool = Field(False, description="integral action: z[k+1] = z[k] + r[k] - Cr x_hat[k|k] (the estimate, "
                                              "not y), u = ... - Ki z; Ki from the LQR of the model augmented "
                                              "with z (needs a reference)")
    Qi: WeightField | None = Field(None, description="weight of the integrator states z (q x q, one per tracked "
                                                     "output; default identity)")
    feedforward: bool = Field(True, description="add the steady-state feed-forward of an output reference: "
                                                "u = Nu r - K (x_hat - Nx r), with Cr Nx r = r at equilibrium")

    _check_weights = model_validator(mode="after")(_weighted)


@register("controller", "lqr", "discrete LQR state feedback (python-control dlqr at build)")
class LQRPart(LawPartBase):
    """``law: {type: lqr, Q, R, N, integral, Qi, feedforward, u_min, u_max}``."""

    Params = _LQRParams

    @classmethod
    def build(cls, params: _LQRParams, design: Design, rng: np.random.Generator) -> Any:
        from netsim.control.lqr import LQR

        return LQR(design.A, design.B, params.Q, params.R, N=params.N, Cr=design.Cr, integral=params.integral,
                   Qi=params.Qi, feedforward=params.feedforward, u_min=params.u_min, u_max=params.u_max,
                   Qy=params.Qy, C=design.C)


class _StateFeedbackParams(_Limits):
    K: MatrixField = Field(description="state gain (m x n): u = u_ff(r) - K x_hat[k|k] (negative feedback, the "
                                       "sign of control.dlqr's K)")
    Ki: MatrixField | None = Field(None, description="integral gain (m x q): u = ... - Ki z, z[k+1] = z[k] + r[k] - "
                                                     "Cr x_hat[k|k] (needs a reference; the sign of the integrator "
                                                     "block of control.dlqr's gain on the model augmented with z)")
    feedforward: bool = Field(True, description="add the steady-state feed-forward of an output reference: "
                                                "u = Nu r - K (x_hat - Nx r), with Cr Nx r = r at equilibrium")


@register("controller", "state_feedback", "u = u_ff(r) - K x_hat with a given gain K")
class StateFeedbackPart(LawPartBase):
    """``law: {type: state_feedback, K, Ki, feedforward, u_min, u_max}``."""

    Params = _StateFeedbackParams

    @classmethod
    def build(cls, params: _StateFeedbackParams, design: Design, rng: np.random.Generator) -> Any:
        from netsim.control.lqr import StateFeedback

        return StateFeedback(design.A, design.B, params.K, Cr=design.Cr, Ki=params.Ki,
                             feedforward=params.feedforward, u_min=params.u_min, u_max=params.u_max)


class _MPCParams(_Limits):
    horizon: int = Field(ge=1, le=1000, description="prediction horizon N in samples of the task period (inputs "
                                                   "u_0 .. u_{N-1}, states x_1 .. x_N)")
    Q: WeightField | None = Field(None, description=_Q_TEXT)
    Qy: WeightField | None = Field(None, description=_QY_TEXT)
    R: WeightField = Field(description="input weight (m x m, positive definite, per input unit squared)")
    P: WeightField | None = Field(None, description="terminal weight on x_N - x_s (n x n, PSD; default: the LQR "
                                                    "Riccati solution of (A, B, Q + C' Qy C, R))")
    du_min: float | list[float] | None = Field(None, description="lower limit of u_k - u_{k-1} per sample, in input "
                                                                 "units (one number, or one per input; <= 0)")
    du_max: float | list[float] | None = Field(None, description="upper limit of u_k - u_{k-1} per sample, in input "
                                                                 "units (one number, or one per input; >= 0)")
    x_min: list[float | None] | None = Field(None, description="lower limits of the predicted states x_1 .. x_N (n "
                                                               "numbers in state units; null: none)")
    x_max: list[float | None] | None = Field(None, description="upper limits of the predicted states x_1 .. x_N (n "
                                                               "numbers in state units; null: none)")
    solver: Literal["daqp", "clarabel", "osqp", "piqp"] = Field("daqp", description="QP solver of the constrained "
                                                                "steps (the unconstrained optimum is used when it "
                                                                "satisfies every constraint)")
    tol: float = Field(1e-9, gt=0, description="solver tolerance (its primal feasibility / optimality tolerance)")

    _check_weights = model_validator(mode="after")(_weighted)


@register("controller", "mpc", "linear MPC: horizon, input/rate/state box constraints, LQR terminal cost")
class MPCPart(LawPartBase):
    """``law: {type: mpc, horizon, Q, R, P, u_min, u_max, du_min, du_max, x_min, x_max, solver, tol}``.

    The plant's initial state (when the scenario gives ``plant.x0``) is checked against the state limits and
    for feasibility when the law is built, so ``netsim validate`` refuses an MPC whose first problem has no
    solution.
    """

    Params = _MPCParams

    @classmethod
    def build(cls, params: _MPCParams, design: Design, rng: np.random.Generator) -> Any:
        from netsim.control.mpc import LinearMPC

        return LinearMPC(design.A, design.B, params.Q, params.R, params.horizon, P=params.P,
                         u_min=params.u_min, u_max=params.u_max, du_min=params.du_min, du_max=params.du_max,
                         x_min=params.x_min, x_max=params.x_max, Cr=design.Cr, solver=params.solver, tol=params.tol,
                         x0=design.x0, Qy=params.Qy, C=design.C)


class PIDPart(LawPartBase):
    """``law: {type: pid, K, Ti, Td, N, b, h, u_min, u_max}``: the registered :class:`~netsim.control.pid.PID`,
    fed the first measured output (:class:`~netsim.control.pid.PIDLaw`), ``h`` defaulting to the task period."""

    Params = PIDParams
    fed_state = False

    @classmethod
    def build(cls, params: PIDParams, design: Design, rng: np.random.Generator) -> Any:
        from netsim.control.pid import PID, PIDLaw

        return PIDLaw(PID.from_params(params, design.period_ns))


#: netsim's own parts by ``type:`` name (``pid`` is registered as the :class:`~netsim.control.pid.PID` itself).
BUILTIN_ESTIMATORS: dict[str, type[EstimatorPartBase]] = {
    "kalman": KalmanPart, "steady_state_kalman": SteadyStateKalmanPart, "ekf": ModelEKFPart,
    "luenberger": LuenbergerPart, "none": NoEstimatorPart}
BUILTIN_LAWS: dict[str, type[LawPartBase]] = {
    "lqr": LQRPart, "state_feedback": StateFeedbackPart, "mpc": MPCPart, "pid": PIDPart}
#: The estimator and law types a ``state_feedback`` program accepts besides registered ones.
ESTIMATOR_TYPES = tuple(BUILTIN_ESTIMATORS)
LAW_TYPES = tuple(BUILTIN_LAWS)
