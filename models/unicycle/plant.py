"""The 2WD cart as a netsim plant (registered as kind ``plant``, name ``unicycle``).

Inputs: the wheel speeds ``omega_L, omega_R`` [rad/s] (held by the drive node's DACs). States ``x, y, theta``.
Outputs: ``z_front, z_side`` (noiseless wall distances of eqs 8-9 with the side offset as the text states it,
:data:`~netsim.models.unicycle.model.SIDE_DERIVED`; the IR sensors' noise is added by their ADCs) and the pose
``x, y, theta`` (for recording the truth).

Between input changes the pose moves along an exact arc (:func:`~netsim.models.unicycle.model.arc`, not the filter's
Euler step). Process noise: at every instant ``k * noise_period`` the pose jumps by ``w ~ N(0,
diag(process_noise))`` (stream ``plant.unicycle.process``), the truth of eq (10)'s ``w_k``: with
``noise_period`` equal to the filter period and ``process_noise`` equal to the filter's ``Q``, the filter's noise
model matches the truth. The initial pose is ``pose0 + N(0, diag(pose0_var))`` (stream
``plant.unicycle.initial``), drawn when the plant is bound: with ``pose0_var`` equal to the filter's ``P0`` the
initial estimate's error has the distribution the filter assumes.

The pose is kept as three floats (the plant is stepped some 2000 times a run; numpy's per-call overhead on
3-vectors was most of its cost) and the noise is drawn :data:`NOISE_BLOCK` jumps at a time.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from pydantic import Field

from netsim.models.unicycle.ekf import Sensor
from netsim.models.unicycle.model import (
    FRONT_OFFSET, HALF_WHEELBASE, WALL_FRONT, WALL_SIDE, WHEEL_RADIUS, XI0_HAT, arc_floats, side_offset,
    wheels_to_body,
)
from netsim.errors import BuildError
from netsim.plant import Plant
from netsim.registry import register
from netsim.units import Duration, StrictModel

if TYPE_CHECKING:
    from netsim.env import SimEnv

__all__ = ["UnicycleParams", "UnicyclePlant", "unicycle", "NOISE_BLOCK"]

#: Process-noise jumps drawn per call of the generator (the same normals, in the same order, as one call per
#: jump: a ``Generator``'s ``standard_normal`` fills its output from the stream in order).
NOISE_BLOCK = 256


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
        self._x: tuple[float, float, float] = tuple(float(v) for v in self.p.pose0)  # type: ignore[assignment]
        self._side = side_offset(self.p.side)
        self._sd = tuple(math.sqrt(v) for v in self.p.process_noise)
        self._noisy = any(v > 0 for v in self._sd)
        self._rng: Any = None
        self._noise: list[list[float]] = []  # drawn ahead, NOISE_BLOCK jumps at a time (module docstring)
        self._vw = (0.0, 0.0)
        self._front = Sensor(FRONT_OFFSET, WALL_FRONT, 1.0)
        self._side_sensor = Sensor(self._side, WALL_SIDE, 1.0)

    def _bind_streams(self, env: SimEnv) -> None:
        var0 = np.array(self.p.pose0_var, dtype=float)
        if np.any(var0 > 0):
            x0 = np.array(self._x) + np.sqrt(var0) * env.rng(f"plant.{self.name}.initial").standard_normal(3)
            self._x = tuple(float(v) for v in x0)  # type: ignore[assignment]
        self._rng = env.rng(f"plant.{self.name}.process")
        self._noise = []

    def _check_source(self, src: Any) -> None:
        if src.kind not in ("piecewise", "held"):
            raise BuildError(f"plant {self.name}: disturbances must be piecewise constant, got {src.kind}")

    def _update_effective_input(self, t: int) -> None:
        u = self._piecewise_input()
        self._vw = wheels_to_body(float(u[0]), float(u[1]), self.p.wheel_radius, self.p.half_wheelbase)

    def _jump(self) -> list[float]:
        """The next process-noise jump ``sd * N(0, 1)`` (the stream's normals in order, drawn a block ahead)."""
        if not self._noise:
            if self._rng is None:
                raise BuildError(f"plant {self.name}: bind(env) before running with process noise")
            self._noise = (self._rng.standard_normal((NOISE_BLOCK, 3)) * np.array(self._sd)).tolist()[::-1]
        return self._noise.pop()

    def _step(self, t: int) -> bool:
        grid = int(self.p.noise_period)
        noisy = False
        v, w = self._vw
        x, y, th = self._x
        now = self._t
        while now < t:
            nxt = (now // grid + 1) * grid
            end = min(t, nxt)
            x, y, th = arc_floats(x, y, th, v, w, (end - now) * 1e-9)
            now = end
            if end == nxt and self._noisy:
                q = self._jump()
                x, y, th = x + q[0], y + q[1], th + q[2]
                noisy = True
        self._x, self._t = (x, y, th), now
        bound = self.divergence_bound
        if not (abs(x) < bound and abs(y) < bound and abs(th) < bound):
            self._diverged(t, np.array(self._x))
        return noisy

    def _output_now(self) -> np.ndarray:
        x, y, th = self._x
        return np.array([self._front.h(x, y, th), self._side_sensor.h(x, y, th), x, y, th])

    def _state_now(self) -> np.ndarray:
        return np.array(self._x)

    def _set_state_now(self, x: np.ndarray) -> None:
        self._x = tuple(float(v) for v in np.asarray(x, dtype=float).reshape(3))  # type: ignore[assignment]


@register("plant", "unicycle", "2WD cart (seed 001): wheel speeds in, exact arcs, IR wall distances and pose out")
def unicycle(params: UnicycleParams | None = None, **kwargs: Any) -> UnicyclePlant:
    """Build the :class:`UnicyclePlant` from its parameters."""
    p = params if params is not None else UnicycleParams.model_validate(kwargs)
    return UnicyclePlant(p)


unicycle.Params = UnicycleParams  # type: ignore[attr-defined]
