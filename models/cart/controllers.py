"""The five cart velocity controllers of Henningsson & Cervin, as plain numeric objects.

Every controller is stepped once per control period with :meth:`CartController.update`
``(t_ns, count, direction, stamp_ns, vref) -> uV`` -- the time, the encoder count, and the direction and
time stamp of the last encoder edge (what the encoder ISR stores) -- and returns the motor command
``uV`` in units of full voltage, saturated to ``|uV| <= 1``. The control law is always

    u = K (beta vref - v_hat) - u_bias_hat,      uV = sat(u / Ku).

``pure_pi``
    Eqs 2-3: ``V = sY/(s Tfilter + 1)``, ``U = K(beta Vref - V) - K (V - Vref)/(s Ti)``, ``beta = 0.5``.
``observer_pi``
    Eqs 4-5: ``V = (sY + Tfilter (U + Ubias))/(s Tfilter + 1)``, ``Ubias = K (sY - V)/(s Ti)``, ``beta = 1``,
    ``Ti' = Ti/4`` (variant ``ti4``) or ``Ti' = Ti/2, Tfilter' = 2 Tfilter`` (``ti2``), ``Ti'`` lower bounded.
``basic_event``, ``position_prediction``, ``full_event``
    The event estimators of :mod:`netsim.models.cart.estimators` with the control law above (``beta = 0.5`` and the
    Pure PI gains for the first two, ``beta = 1`` and the observer gains for the Full Event).

The two PI controllers are the continuous designs discretized exactly at the control period for a held
measured velocity ``(y(k) - y(k-1))/h`` and a held second input (``vref`` or the applied ``u``), with
matrices computed once at construction.
"""

from __future__ import annotations

import abc
import math
import numpy as np
from scipy.linalg import expm

from netsim.models.cart.encoding import Quantizer
from netsim.models.cart.estimators import (
    BasicEventEstimator,
    EventEstimator,
    FullEventEstimator,
    PositionPredictionEstimator,
)
from netsim.models.cart.tuning import Tuning, observer_tuning, pure_pi_tuning
from netsim.errors import ConfigError
from netsim.timebase import format_time

__all__ = [
    "KU",
    "CONTROLLERS",
    "CartController",
    "PurePI",
    "ObserverPI",
    "EventController",
    "make_controller",
    "controller_tuning",
]

#: Motor gain of the cart in m/s^2 per unit of full voltage (paper section II-B).
KU = 25.5

#: Controller names in the order of the paper's development stages.
CONTROLLERS = ("pure_pi", "observer_pi", "basic_event", "position_prediction", "full_event")


class CartController(abc.ABC):
    """Base class: control law, saturation and the memory of the applied command.

    Attributes
    ----------
    v_hat, u_bias_hat : float
        The current estimates (after the last update).
    u : float
        Applied acceleration command ``Ku * uV`` of the last update (m/s^2).
    """

    name = "controller"

    def __init__(self, tuning: Tuning, quantizer: Quantizer, period_ns: int, ku: float = KU) -> None:
        if period_ns <= 0:
            raise ConfigError(f"control period must be positive, got {format_time(period_ns)}")
        if not ku > 0:
            raise ConfigError(f"motor gain Ku must be positive, got {ku}")
        self.tuning = tuning
        self.quantizer = quantizer
        self.period_ns = int(period_ns)
        self.h = period_ns * 1e-9
        self.ku = float(ku)
        self.v_hat = 0.0
        self.u_bias_hat = 0.0
        self.u = 0.0

    def _control(self, vref: float) -> float:
        tn = self.tuning
        u = tn.K * (tn.beta * vref - self.v_hat) - self.u_bias_hat
        uv = min(1.0, max(-1.0, u / self.ku))
        self.u = self.ku * uv
        return uv

    @abc.abstractmethod
    def update(self, t_ns: int, count: int, direction: int, stamp_ns: int, vref: float) -> float:
        """Step the controller at ``t_ns``; return the motor command ``uV`` (|uV| <= 1)."""

    def reset(self) -> None:
        """Back to rest: all estimates and the applied command zero."""
        self.v_hat = self.u_bias_hat = self.u = 0.0


def _zoh(a: np.ndarray, b: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    n, m = a.shape[0], b.shape[1]
    big = np.zeros((n + m, n + m))
    big[:n, :n] = a
    big[:n, n:] = b
    e = expm(big * h)
    return e[:n, :n], e[:n, n:]


class _LTIController(CartController):
    """A continuous PI design discretized exactly for a held velocity measurement.

    The measured velocity over the last period, ``m(k) = (y(k) - y(k-1)) / h``, is held over that period
    (together with the second input), the state ``(v_hat, u_bias_hat)`` is propagated through the period,
    and the control law is applied to the result. For a cart moving at constant speed ``m`` is exact, so the
    estimate carries no gain error (a zero-order hold on ``y`` itself would bias ``v_hat`` by
    ``h/(2 Tfilter)``, 6 % at 40 rad/s).
    """

    def __init__(self, tuning: Tuning, quantizer: Quantizer, period_ns: int, ku: float = KU) -> None:
        super().__init__(tuning, quantizer, period_ns, ku)
        a, b = self._continuous()
        self._phi, self._gam = _zoh(a, b, self.h)
        self._x = np.zeros(2)
        self._y_prev: float | None = None

    @abc.abstractmethod
    def _continuous(self) -> tuple[np.ndarray, np.ndarray]:
        """Continuous-time ``(A, B)`` of the estimator state ``(v_hat, u_bias_hat)``."""

    @abc.abstractmethod
    def _second_input(self, vref: float) -> float:
        """The input held beside the measured velocity over a period."""

    def reset(self) -> None:
        super().reset()
        self._x = np.zeros(2)
        self._y_prev = None

    def update(self, t_ns: int, count: int, direction: int, stamp_ns: int, vref: float) -> float:
        y = self.quantizer.level(count)
        if self._y_prev is not None:
            m = (y - self._y_prev) / self.h
            self._x = self._phi @ self._x + self._gam @ np.array([m, self._second_input(vref)])
        self._y_prev = y
        self.v_hat, self.u_bias_hat = float(self._x[0]), float(self._x[1])
        return self._control(vref)


class PurePI(_LTIController):
    """Pure PI controller (eqs 2-3): ``v_hat' = (m - v_hat)/Tf``, ``u_bias_hat' = K/Ti (v_hat - vref)``.

    ``m = y'`` is the measured velocity; with ``beta = 0.5`` the control law is eq. 3.
    """

    name = "pure_pi"

    def _continuous(self) -> tuple[np.ndarray, np.ndarray]:
        tf, ki = self.tuning.Tfilter, self.tuning.K / self.tuning.Ti
        a = np.array([[-1.0 / tf, 0.0], [ki, 0.0]])
        b = np.array([[1.0 / tf, 0.0], [0.0, -ki]])  # inputs: m, vref
        return a, b

    def _second_input(self, vref: float) -> float:
        return vref


class ObserverPI(_LTIController):
    """Observer-based PI controller (eqs 4-5).

    ``v_hat' = u + u_bias_hat + (m - v_hat)/Tf`` (eq. 5 with ``U + Ubias`` fed forward: anti-windup, ``u``
    the applied saturated command) and ``u_bias_hat' = K/Ti (m - v_hat)`` (eq. 4), ``m = y'``.
    """

    name = "observer_pi"

    def _continuous(self) -> tuple[np.ndarray, np.ndarray]:
        tf, ki = self.tuning.Tfilter, self.tuning.K / self.tuning.Ti
        a = np.array([[-1.0 / tf, 1.0], [-ki, 0.0]])
        b = np.array([[1.0 / tf, 1.0], [ki, 0.0]])  # inputs: m, u
        return a, b

    def _second_input(self, vref: float) -> float:
        return self.u


class EventController(CartController):
    """An event estimator (:mod:`netsim.models.cart.estimators`) followed by the common control law."""

    def __init__(
        self,
        estimator_cls: type[EventEstimator],
        tuning: Tuning,
        quantizer: Quantizer,
        period_ns: int,
        ku: float = KU,
        trace: bool = False,
    ) -> None:
        super().__init__(tuning, quantizer, period_ns, ku)
        self.estimator = estimator_cls(tuning, quantizer, trace=trace)
        self.name = {
            BasicEventEstimator: "basic_event",
            PositionPredictionEstimator: "position_prediction",
            FullEventEstimator: "full_event",
        }.get(estimator_cls, estimator_cls.__name__)

    def reset(self) -> None:
        super().reset()
        self.estimator.reset()

    @property
    def p_hat(self) -> float:
        """Position estimate (m)."""
        return self.estimator.state.p_hat

    def update(self, t_ns: int, count: int, direction: int, stamp_ns: int, vref: float) -> float:
        self.estimator.update(t_ns, count, direction, stamp_ns, self.u, vref)
        st = self.estimator.state
        self.v_hat, self.u_bias_hat = st.v_hat, st.u_bias_hat
        return self._control(vref)


def controller_tuning(name: str, wc: float, *, r: float = 3.0, observer_variant: str = "ti4",
                      ti_floor: float | None = 3.0 / 80.0) -> Tuning:
    """The tuning the paper uses for controller ``name`` at crossover ``wc`` (rad/s)."""
    if name in ("pure_pi", "basic_event", "position_prediction"):
        return pure_pi_tuning(wc, r)
    if name == "observer_pi":
        return observer_tuning(wc, r, variant=observer_variant, ti_floor=ti_floor)
    if name == "full_event":
        return observer_tuning(wc, r, variant="ti4", ti_floor=ti_floor)
    raise ConfigError(f"unknown cart controller {name!r}; choose one of {', '.join(CONTROLLERS)}")


_EVENT = {
    "basic_event": BasicEventEstimator,
    "position_prediction": PositionPredictionEstimator,
    "full_event": FullEventEstimator,
}


def make_controller(
    name: str,
    wc: float,
    quantizer: Quantizer,
    period_ns: int = 1_000_000,
    *,
    ku: float = KU,
    r: float = 3.0,
    observer_variant: str = "ti4",
    ti_floor: float | None = 3.0 / 80.0,
    trace: bool = False,
) -> CartController:
    """Build controller ``name`` (one of :data:`CONTROLLERS`) tuned for crossover ``wc`` in rad/s.

    Raises
    ------
    ConfigError
        For an unknown name, ``wc <= 0`` or a non-positive period.
    """
    if not (isinstance(wc, (int, float)) and math.isfinite(wc) and wc > 0):
        raise ConfigError(f"crossover frequency wc must be > 0 rad/s, got {wc!r}")
    tuning = controller_tuning(name, wc, r=r, observer_variant=observer_variant, ti_floor=ti_floor)
    if name == "pure_pi":
        return PurePI(tuning, quantizer, period_ns, ku)
    if name == "observer_pi":
        return ObserverPI(tuning, quantizer, period_ns, ku)
    return EventController(_EVENT[name], tuning, quantizer, period_ns, ku, trace=trace)

