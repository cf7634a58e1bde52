"""A custom plant: a water tank filled by a pump and drained through an outlet (Torricelli's law).

State ``level`` h in metres, input ``pump`` u (the pump command, 1 = full flow), output ``level``::

    A h' = k u - a sqrt(2 g h)          (h >= 0; the outlet runs dry at h = 0)

A plant plugin is a function registered as ``@register("plant", NAME)`` that returns a netsim plant (here a
:class:`netsim.plant.NonlinearPlant`, integrated exactly between events by an ODE solver), with its parameters in
a pydantic ``Params`` model attached as ``factory.Params`` (``netsim list plant water_tank`` prints them).
"""

from __future__ import annotations

import math

import numpy as np
from pydantic import Field

from netsim.registry import register
from netsim.units import StrictModel

G = 9.81  # m/s^2


class TankParams(StrictModel):
    """Water tank parameters (SI units)."""

    area: float = Field(1.0, gt=0, description="tank cross-section A in m^2")
    pump_flow: float = Field(0.05, gt=0, description="flow k at full pump command in m^3/s")
    outlet: float = Field(0.005, gt=0, description="outlet cross-section a in m^2")


def _dynamics(t: float, x: np.ndarray, u: np.ndarray, p: TankParams) -> np.ndarray:
    level = max(float(x[0]), 0.0)
    inflow = p.pump_flow * float(u[0])
    outflow = p.outlet * math.sqrt(2.0 * G * level)
    rate = (inflow - outflow) / p.area
    return np.array([rate if (level > 0.0 or rate > 0.0) else 0.0])


def _output(t: float, x: np.ndarray, u: np.ndarray, p: TankParams) -> np.ndarray:
    return np.array([max(float(x[0]), 0.0)])


@register("plant", "water_tank", "water tank: pump in, Torricelli outlet out (example plugin)")
def water_tank(params: TankParams | None = None, **kwargs: object):  # -> netsim.plant.NonlinearPlant
    """Build the tank from its parameters."""
    from netsim.plant import NonlinearPlant

    p = params if params is not None else TankParams.model_validate(kwargs)
    return NonlinearPlant(_dynamics, _output, 1, 1, 1, params=p, input_names=["pump"], output_names=["level"],
                          state_names=["level"], name="tank")


water_tank.Params = TankParams  # type: ignore[attr-defined]
