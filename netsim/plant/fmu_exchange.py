"""Model-exchange FMUs as plants (``plant: {type: fmu, interface: model_exchange}``, :mod:`netsim.plant.fmu`).

The FMU gives the right-hand side and the outputs, netsim integrates: the plant is a
:class:`~netsim.plant.nonlinear.NonlinearPlant` whose ``f(t, x, u, params)`` sets the FMU's time, continuous
state and inputs and returns ``fmi2GetDerivatives``, and whose ``h`` returns the output variables. So the
integrator is the scenario's ``plant.integrator`` (scipy's ``solve_ivp`` per segment by default, or fixed-step
RK4), process noise and disturbances work as on any nonlinear plant, and the state is the FMU's continuous state
(started from its initial values, or ``x0``). Only FMUs without event indicators are taken (no state events); the
FMU is instantiated and initialised once when the plant is built.
"""

from __future__ import annotations

import logging
import weakref
from ctypes import POINTER
from pathlib import Path
from typing import Any, Sequence

import numpy as np

__all__ = ["exchange_plant"]

_log = logging.getLogger(__name__)


class _Evaluator:
    """``f`` and ``h`` of the plant: one FMU instance in continuous-time mode used as a function of (t, x, u)."""

    def __init__(self, model: Any, nx: int, vr_in: list[int], vr_out: list[int]) -> None:
        from fmpy.fmi2 import fmi2Real

        self.model, self.nx, self.vr_in, self.vr_out = model, nx, vr_in, vr_out
        self.x = np.zeros(nx)
        self.dx = np.zeros(nx)
        self.px = self.x.ctypes.data_as(POINTER(fmi2Real))
        self.pdx = self.dx.ctypes.data_as(POINTER(fmi2Real))

    def states(self) -> np.ndarray:
        """The FMU's continuous state now (after initialisation: its start values)."""
        self.model.getContinuousStates(self.px, self.nx)
        return self.x.copy()

    def _load(self, t: float, x: Any, u: Any) -> None:
        self.model.setTime(float(t))
        self.x[:] = x
        self.model.setContinuousStates(self.px, self.nx)
        if self.vr_in:
            self.model.setReal(self.vr_in, [float(v) for v in u])

    def f(self, t: float, x: Any, u: Any, params: Any) -> np.ndarray:
        self._load(t, x, u)
        self.model.getDerivatives(self.pdx, self.nx)
        return self.dx.copy()

    def h(self, t: float, x: Any, u: Any, params: Any) -> np.ndarray:
        self._load(t, x, u)
        return np.array(self.model.getReal(self.vr_out), dtype=float)


def _release(model: Any) -> None:
    """Terminate and free the instance (the library stays loaded: see :func:`netsim.plant.fmu._release`)."""
    try:
        model.terminate()
        model.freeInstance()
    except Exception as exc:  # noqa: BLE001 - a finaliser must not raise
        _log.debug("releasing the FMU failed: %s", exc)


def exchange_plant(folder: Path, description: Any, inputs: Sequence[str], outputs: Sequence[str],
                   parameters: dict[str, float] | None = None, *, name: str = "plant") -> Any:
    """A :class:`~netsim.plant.nonlinear.NonlinearPlant` over the model-exchange FMU in ``folder`` (see the module)."""
    from fmpy.fmi2 import FMU2Model

    from netsim.plant.nonlinear import NonlinearPlant

    variables = {v.name: v for v in description.modelVariables}
    model = FMU2Model(guid=description.guid, unzipDirectory=str(folder),
                      modelIdentifier=description.modelExchange.modelIdentifier, instanceName=name)
    model.instantiate()
    model.setupExperiment(startTime=0.0)
    if parameters:
        model.setReal([variables[n].valueReference for n in parameters], [float(v) for v in parameters.values()])
    model.enterInitializationMode()
    model.exitInitializationMode()
    while model.newDiscreteStates()[0]:  # the initial event iteration (newDiscreteStatesNeeded)
        pass
    model.enterContinuousTimeMode()
    states = [d.variable.derivative.name for d in description.derivatives]
    evaluator = _Evaluator(model, len(states), [variables[n].valueReference for n in inputs],
                           [variables[n].valueReference for n in outputs])
    plant = NonlinearPlant(evaluator.f, evaluator.h, len(states), len(inputs), len(outputs), x0=evaluator.states(),
                           input_names=list(inputs), output_names=list(outputs), state_names=states, name=name)
    weakref.finalize(plant, _release, model)
    return plant
