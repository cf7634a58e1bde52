"""The 2WD cart as a netsim plant (registered as kind ``plant``, name ``unicycle``).

Inputs: the wheel speeds ``omega_L, omega_R`` [rad/s] (held by the drive node's DACs). States ``x, y, theta``.
Outputs: ``z_front, z_side`` (noiseless wall distances of eqs 8-9 with the side offset as the text states it,
:data:`~models.unicycle.model.SIDE_DERIVED`; the IR sensors' noise is added by their ADCs) and the pose
``x, y, theta`` (for recording the truth).

Between input changes the pose moves along an exact arc (:func:`~models.unicycle.model.arc`, not the filter's
Euler step). Process noise: at every instant ``k * noise_period`` the pose jumps by ``w ~ N(0,
diag(process_noise))`` (stream ``plant.unicycle.process``), the truth of eq (10)'s ``w_k``: with
``noise_period`` equal to the filter period and ``process_noise`` equal to the filter's ``Q``, the filter's noise
model matches the truth. The initial pose is ``pose0 + N(0, diag(pose0_var))`` (stream
``plant.unicycle.initial``), drawn when the plant is bound: with ``pose0_var`` equal to the filter's ``P0`` the
initial estimate's error has the distribution the filter assumes.
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from pydantic import Field

from models.unicycle.model import (
    FRONT_OFFSET, HALF_WHEELBASE, WALL_FRONT, WALL_SIDE, WHEEL_RADIUS, XI0_HAT, arc, measure, side_offset,
    wheels_to_body,
)
from netsim.errors import BuildError
from netsim.plant import Plant
from netsim.registry import register
from netsim.units import Duration, StrictModel

__all__ = ["UnicycleParams", "UnicyclePlant", "unicycle"]


class UnicycleParams(StrictModel):
    """Parameters of the ``unicycle`` plant."""

    wheel_radius: float = Field(WHEEL_RADIUS, gt=0, description="wheel radius r in m (our choice)")
    half_wheelbase: float = Field(HALF_WHEELBASE, gt=0, description="half wheelbase a in m (our choice)")
    side: Literal["derived", "printed"] = Field("derived", description="side sensor offset: derived (-Y', the "
                                                "report's text) or printed (+Y', its eq 6)")
    pose0: list[float] = Field(default_factory=lambda: XI0_HAT.tolist(), min_length=3, max_length=3,
                               description="mean initial pose [x m, y m, theta rad]")
    pose0_var: list[float] = Field(default_factory=lambda: [0.0, 0.0, 0.0], min_length=3, max_length=3,
                                   description="variances of the initial pose (report's P0: 1e-3, 1e-3, 7.6e-3)")
    process_noise: list[float] = Field(default_factory=lambda: [0.0, 0.0, 0.0], min_length=3, max_length=3,
                                       description="variances of the pose jump at each noise_period instant")
    noise_period: Duration = Field(10_000_000, description="grid of the process-noise jumps")


class UnicyclePlant(Plant):
    """The unicycle of eq (3) driven by wheel speeds (eq 1), exact arcs, pose-jump process noise."""

    _cache_output = True

    def __init__(self, params: UnicycleParams | None = None, name: str = "unicycle") -> None:
        super().__init__(3, 2, 5, input_names=["omega_L", "omega_R"],
                         output_names=["z_front", "z_side", "x", "y", "theta"],
                         state_names=["x", "y", "theta"], name=name, divergence_bound=1e6)
        self.p = params if params is not None else UnicycleParams()
        if any(v < 0 for v in self.p.pose0_var) or any(v < 0 for v in self.p.process_noise):
            raise BuildError("plant unicycle: pose0_var and process_noise are variances, give numbers >= 0")
        if self.p.noise_period <= 0:
            raise BuildError("plant unicycle: noise_period must be positive")
        self._x = np.array(self.p.pose0, dtype=float)
        self._side = side_offset(self.p.side)
        self._sd = np.sqrt(np.array(self.p.process_noise, dtype=float))
        self._noisy = bool(np.any(self._sd > 0))
        self._rng: Any = None
        self._vw = (0.0, 0.0)

    def _bind_streams(self, env: Any) -> None:
        var0 = np.array(self.p.pose0_var, dtype=float)
        if np.any(var0 > 0):
            self._x = self._x + np.sqrt(var0) * env.rng(f"plant.{self.name}.initial").standard_normal(3)
        self._rng = env.rng(f"plant.{self.name}.process")

    def _check_source(self, src: Any) -> None:
        if src.kind not in ("piecewise", "held"):
            raise BuildError(f"plant {self.name}: disturbances must be piecewise constant, got {src.kind}")

    def _update_effective_input(self, t: int) -> None:
        u = self._piecewise_input()
        self._vw = wheels_to_body(float(u[0]), float(u[1]), self.p.wheel_radius, self.p.half_wheelbase)

    def _step(self, t: int) -> bool:
        grid = int(self.p.noise_period)
        noisy = False
        v, w = self._vw
        while self._t < t:
            nxt = (self._t // grid + 1) * grid
            end = min(t, nxt)
            self._x = arc(self._x, v, w, (end - self._t) * 1e-9)
            self._t = end
            if end == nxt and self._noisy:
                if self._rng is None:
                    raise BuildError(f"plant {self.name}: bind(env) before running with process noise")
                self._x = self._x + self._sd * self._rng.standard_normal(3)
                noisy = True
        if not np.all(np.abs(self._x) < self.divergence_bound):
            self._diverged(t, self._x)
        return noisy

    def _output_now(self) -> np.ndarray:
        x = self._x
        return np.array([measure(x, FRONT_OFFSET, WALL_FRONT), measure(x, self._side, WALL_SIDE), x[0], x[1], x[2]])

    def _state_now(self) -> np.ndarray:
        return self._x.copy()

    def _set_state_now(self, x: np.ndarray) -> None:
        self._x = np.asarray(x, dtype=float).copy()


@register("plant", "unicycle", "2WD cart (seed 001): wheel speeds in, exact arcs, IR wall distances and pose out")
def unicycle(params: UnicycleParams | None = None, **kwargs: Any) -> UnicyclePlant:
    """Build the :class:`UnicyclePlant` from its parameters."""
    p = params if params is not None else UnicycleParams.model_validate(kwargs)
    return UnicyclePlant(p)


unicycle.Params = UnicycleParams  # type: ignore[attr-defined]
