"""The event-based velocity estimators of the cart (Henningsson & Cervin, sections V and VI-B).

All estimators keep ``p_hat``, ``v_hat`` and ``u_bias_hat`` and are stepped once per control period by
:meth:`EventEstimator.update` with the time, the current encoder count and the count, direction and time
stamp of the last encoder edge (as stored by the encoder ISR). An edge whose stamp is later than the
previous update is an *event*. The three development stages compared in the paper:

``BasicEventEstimator`` (VI-B.1)
    No time update; at an event ``p_hat`` jumps to the edge position and ``v_hat = dp/dt`` with ``dt`` the
    time since the previous event (no lower limit). ``u_bias_hat`` mirrors the Pure PI integral:
    ``u_bias_hat += K/Ti (p_hat(k) - p_hat(k-1) - h vref(k))``.
``PositionPredictionEstimator`` (VI-B.2 and 3)
    Adds ``p_hat += dt v_hat`` between updates and uses the correction form of eq. 10
    (``v_hat += dp / max(dt, Tfilter)``), both at events (time update to the event stamp, measurement
    update, time update for the rest of the step) and between events whenever ``p_hat`` leaves the
    interval of the current count (it is moved to the nearest bound). Same ``u_bias_hat`` rule as Basic.
``FullEventEstimator`` (VI-B.4 and 5; eqs 9-11)
    Full time update ``p += h v + h^2/2 (u + u_bias_hat)``, ``v += h (u + u_bias_hat)``; measurement
    updates as above plus ``u_bias_hat += K/Ti dp`` (eq. 11) and the LTI-mode timeout: when measurement
    constraints have been active in every control step for the last ``2 Tfilter``, ``dt = Tfilter`` is
    used (V-C.1).

Time stamps are integer nanoseconds; arithmetic is in seconds. ``u`` is the applied acceleration command
(``Ku * uV`` after saturation) held over the step that ends at this update.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from netsim.models.cart.encoding import Quantizer
from netsim.models.cart.tuning import Tuning

__all__ = [
    "EstimatorState",
    "EventEstimator",
    "BasicEventEstimator",
    "PositionPredictionEstimator",
    "FullEventEstimator",
]

_NS = 1e-9


@dataclass
class EstimatorState:
    """Estimates and history of an event estimator (times in s)."""

    p_hat: float = 0.0
    v_hat: float = 0.0
    u_bias_hat: float = 0.0
    t: float = 0.0  # time of the estimate
    t_event: float = 0.0  # time of the last event (the start counts as one, at p_hat = 0)
    last_stamp_ns: int = -1  # stamp of the last processed edge
    active_since: float | None = None  # start of the current run of steps with active constraints
    n_events: int = 0
    n_between_updates: int = 0
    history: list[tuple[str, float, float, float]] = field(default_factory=list)  # (kind, t, dp, dt) if traced


class EventEstimator:
    """Common part of the three event estimators (see the module docstring).

    Parameters
    ----------
    tuning
        Gains (``K``, ``Ti``, ``Tfilter``) whose ``Tfilter`` sets the ``dt`` limit and the LTI mode.
    quantizer
        Meaning of the encoder counts.
    trace
        Keep a list of the measurement updates in ``state.history`` (tests and plots).
    """

    #: time-update the velocity with the model acceleration (Full Event only)
    full_time_update = False
    #: predict the position between events
    position_prediction = True
    #: apply measurement updates between events when p_hat leaves the count's interval
    between_events = True
    #: lower-limit dt by Tfilter
    dt_limit = True
    #: LTI-mode timeout (dt = Tfilter after 2 Tfilter of active constraints)
    lti_timeout = False
    #: bias update: "pi" (integral of position error vs reference) or "eq11" (measurement updates only)
    bias_rule = "pi"

    def __init__(self, tuning: Tuning, quantizer: Quantizer, trace: bool = False) -> None:
        self.tuning = tuning
        self.quantizer = quantizer
        self.trace = trace
        self._ki = tuning.K / tuning.Ti
        self.state = EstimatorState()

    def reset(self, p0: float = 0.0, t0_ns: int = 0) -> None:
        """Start again at rest at ``p0`` with zero velocity and bias estimates."""
        self.state = EstimatorState(p_hat=p0, t=t0_ns * _NS, t_event=t0_ns * _NS)

    # ----------------------------------------------------------------- pieces
    def _time_update(self, dt: float, u: float) -> None:
        s = self.state
        if dt <= 0.0:
            return
        if self.full_time_update:
            a = u + s.u_bias_hat
            s.p_hat += dt * s.v_hat + 0.5 * dt * dt * a
            s.v_hat += dt * a
        elif self.position_prediction:
            s.p_hat += dt * s.v_hat

    def _lti_mode(self, t_step: float) -> bool:
        s = self.state
        return self.lti_timeout and s.active_since is not None and t_step - s.active_since >= self.tuning.timeout

    def _measurement_update(self, target: float, t: float, lti: bool, kind: str) -> None:
        """Move ``p_hat`` to ``target`` at time ``t`` (eq. 10, plus eq. 11 for the Full Event)."""
        s = self.state
        dp = target - s.p_hat
        dt = t - s.t_event
        if lti:
            dt = self.tuning.Tfilter
        elif self.dt_limit:
            dt = max(dt, self.tuning.Tfilter)
        if self.position_prediction:
            if dt > 0.0:
                s.v_hat += dp / dt
        elif dt > 0.0:  # Basic: no time update, so v_hat is the mean velocity since the last event
            s.v_hat = dp / dt
        s.p_hat = target
        if self.bias_rule == "eq11":
            s.u_bias_hat += self._ki * dp
        if self.trace:
            s.history.append((kind, t, dp, dt))

    # ----------------------------------------------------------------- step
    def update(self, t_ns: int, count: int, direction: int, stamp_ns: int, u: float, vref: float) -> None:
        """Advance the estimate to ``t_ns`` given the encoder state read at ``t_ns``.

        Parameters
        ----------
        t_ns
            Time of this control step (ns).
        count
            Current encoder count.
        direction
            Direction (+1/-1) of the last edge.
        stamp_ns
            Time stamp of the last edge (ns); negative when no edge has been seen.
        u
            Applied acceleration command over the step ending now (m/s^2).
        vref
            Velocity reference now (m/s).
        """
        s = self.state
        t = t_ns * _NS
        t_prev, p_prev = s.t, s.p_hat
        lti = self._lti_mode(t)
        active = False
        if stamp_ns >= 0 and stamp_ns != s.last_stamp_ns:  # the ISR stored a new edge since last step
            te = min(max(stamp_ns * _NS, t_prev), t)
            self._time_update(te - t_prev, u)
            self._measurement_update(self.quantizer.edge_position(count, direction), te, lti, "event")
            s.t_event = te
            s.n_events += 1
            s.last_stamp_ns = stamp_ns
            self._time_update(t - te, u)
            active = True
        else:
            self._time_update(t - t_prev, u)
        if self.between_events:
            lo, hi = self.quantizer.interval(count)
            if s.p_hat > hi or s.p_hat < lo:
                self._measurement_update(hi if s.p_hat > hi else lo, t, lti, "bound")
                s.n_between_updates += 1
                active = True
        if self.bias_rule == "pi":
            s.u_bias_hat += self._ki * (s.p_hat - p_prev - (t - t_prev) * vref)
        if active:
            if s.active_since is None:
                s.active_since = t
        else:
            s.active_since = None
        s.t = t


class BasicEventEstimator(EventEstimator):
    """Basic Event Estimator (VI-B.1): estimates constant between events, ``v_hat = dp/dt`` at events."""

    position_prediction = False
    between_events = False
    dt_limit = False


class PositionPredictionEstimator(EventEstimator):
    """Event Estimator with Position Prediction and measurement updates between events (VI-B.2, 3)."""


class FullEventEstimator(EventEstimator):
    """Full Event Estimator (VI-B.4, 5): eqs 9-11 with the LTI-mode timeout and the ``dt >= Tfilter`` limit."""

    full_time_update = True
    lti_timeout = True
    bias_rule = "eq11"
