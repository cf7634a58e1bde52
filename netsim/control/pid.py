"""Discrete PID controller with a filtered derivative, in TrueTime's parametrisation.

The continuous controller is

    U(s) = K (b R(s) - Y(s)) + K / (Ti s) (R(s) - Y(s)) - K Td s / (1 + s Td / N) Y(s)

(set-point weight ``b`` on the proportional part, derivative on the measurement only, derivative gain limited
to ``N``). It is discretised with sampling period ``h`` as in Åström & Wittenmark, *Computer-Controlled
Systems*: forward difference for the integral, backward difference for the filtered derivative:

    P(k) = K (b r(k) - y(k))
    D(k) = ad D(k-1) - bd (y(k) - y(k-1)),   ad = Td / (Td + N h),  bd = K N ad
    u(k) = P(k) + I(k) + D(k)
    I(k+1) = I(k) + K h / Ti (r(k) - y(k))

With ``Ti = None`` the controller is a PD (no integral). An optional output saturation stops the integrator
from winding up (the integral is not advanced while the output is saturated in the direction of the error).

The object is plain numerics: no simpy, kernel or network inside. :meth:`PID.step` takes ``(r, y)`` (the
order the programs use); :meth:`PID.as_law` gives the same controller behind the toolbox's common interface
``step(y, r) -> u`` (:class:`~netsim.control.interface.ControlLaw`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from pydantic import Field, model_validator

from netsim.control.interface import LawBase
from netsim.registry import register
from netsim.timebase import to_seconds
from netsim.units import Duration, StrictModel

__all__ = ["PID", "PIDLaw", "PIDParams"]


class PIDParams(StrictModel):
    """Parameters of :class:`PID` as they appear in a scenario (``h`` accepts ``"6 ms"``)."""

    K: float = Field(1.0, description="proportional gain K (input units per unit of the measured output)")
    Ti: float | None = Field(None, description="integral time Ti in seconds: I(k+1) = I(k) + K h / Ti (r - y); "
                                               "null: no integral action (PD)", json_schema_extra={"unit": "s"})
    Td: float = Field(0.0, description="derivative time Td in seconds, derivative on -y only (0: no derivative)",
                      json_schema_extra={"unit": "s"})
    N: float = Field(10.0, description="derivative gain limit N (dimensionless): the derivative is filtered by "
                                       "1 / (1 + s Td / N), a first-order filter of time constant Td / N seconds "
                                       "(cut-off N / (2 pi Td) Hz)")
    b: float = Field(1.0, description="set-point weight of the proportional part: P = K (b r - y)")
    h: Duration | None = Field(None, description="sampling period of the discretisation (default: the task period)")
    u_min: float | None = Field(None, description="output lower limit (input units); the integrator is frozen while "
                                                  "saturated in the direction of the error")
    u_max: float | None = Field(None, description="output upper limit (input units); the integrator is frozen while "
                                                  "saturated in the direction of the error")

    @model_validator(mode="after")
    def _check(self) -> "PIDParams":
        if self.Ti is not None and not self.Ti > 0:
            raise ValueError(f"Ti must be positive (or null for no integral action), got {self.Ti}")
        if self.Td < 0:
            raise ValueError(f"Td must be >= 0, got {self.Td}")
        if not self.N > 0:
            raise ValueError(f"N must be positive, got {self.N}")
        if self.u_min is not None and self.u_max is not None and self.u_min >= self.u_max:
            raise ValueError(f"u_min ({self.u_min}) must be below u_max ({self.u_max})")
        return self


@register("controller", "pid", "discrete PID/PD with filtered derivative (TrueTime parameters K, Ti, Td, N, b, h)")
class PID:
    """Discrete PID/PD controller.

    Parameters
    ----------
    K, Ti, Td, N, b
        Gain, integral time (s; ``None`` = no integral), derivative time (s), derivative filter gain,
        set-point weight of the proportional part.
    h
        Sampling period in seconds.
    u_min, u_max
        Optional output limits.
    """

    Params = PIDParams

    def __init__(
        self,
        K: float,
        Ti: float | None = None,
        Td: float = 0.0,
        N: float = 10.0,
        b: float = 1.0,
        h: float = 0.01,
        *,
        u_min: float | None = None,
        u_max: float | None = None,
    ) -> None:
        if not h > 0:
            raise ValueError(f"PID sampling period h must be positive, got {h}")
        self.K = float(K)
        self.Ti = None if Ti is None else float(Ti)
        self.Td = float(Td)
        self.N = float(N)
        self.b = float(b)
        self.h = float(h)
        self.u_min = u_min
        self.u_max = u_max
        self.ad = self.Td / (self.Td + self.N * self.h)
        self.bd = self.K * self.N * self.ad
        self.bi = 0.0 if self.Ti is None else self.K * self.h / self.Ti
        self.reset()

    @classmethod
    def from_params(cls, params: PIDParams, h_ns: int | None = None) -> "PID":
        """Build from a :class:`PIDParams`; ``h_ns`` (e.g. the task period) is used when ``params.h`` is unset."""
        h = params.h if params.h is not None else h_ns
        if h is None:
            raise ValueError("PID needs a sampling period: give 'h' or run it in a periodic task")
        return cls(
            params.K, params.Ti, params.Td, params.N, params.b, to_seconds(h), u_min=params.u_min, u_max=params.u_max
        )

    def reset(self) -> None:
        """Zero the integral, derivative and previous measurement."""
        self.I = 0.0
        self.D = 0.0
        self.y_old: float | None = None
        self.u = 0.0

    def step(self, r: float, y: float) -> float:
        """Compute the control signal for reference ``r`` and measurement ``y``, then update the state.

        The first call takes ``y(k-1) = y(k)`` so a non-zero initial output gives no derivative kick.
        """
        y_old = y if self.y_old is None else self.y_old
        P = self.K * (self.b * r - y)
        self.D = self.ad * self.D - self.bd * (y - y_old)
        v = P + self.I + self.D
        u = v
        if self.u_max is not None and u > self.u_max:
            u = self.u_max
        if self.u_min is not None and u < self.u_min:
            u = self.u_min
        e = r - y
        saturated_same_way = (u < v and e > 0) or (u > v and e < 0)
        if not saturated_same_way:
            self.I += self.bi * e
        self.y_old = y
        self.u = u
        return u

    def as_law(self) -> "PIDLaw":
        """This controller behind the common ``step(y, r) -> u`` interface (same state, same results)."""
        return PIDLaw(self)


class PIDLaw(LawBase):
    """A :class:`PID` with the toolbox's argument order: ``step(y, r) -> u`` (measurement first).

    The wrapped controller keeps its state; ``PIDLaw(pid).step(y, r)`` returns exactly ``pid.step(r, y)``.
    """

    def __init__(self, pid: PID) -> None:
        self.pid = pid

    def step(self, y: Any, r: Any) -> float:
        """Control signal for measurement ``y`` and reference ``r`` (numbers or one-element arrays)."""
        return self.pid.step(_scalar(r), _scalar(y))

    def reset(self) -> None:
        """Reset the wrapped PID."""
        self.pid.reset()


def _scalar(v: Any) -> float:
    """A float from a number, a one-element array or a one-element list."""
    if isinstance(v, float):
        return v
    if isinstance(v, np.ndarray):
        return float(v.item())
    if isinstance(v, (list, tuple)):
        return float(v[0])
    return float(v)
