"""Model-exchange FMUs as plants (``plant: {type: fmu, interface: model_exchange}``, :mod:`netsim.plant.fmu`).

The FMU gives the right-hand side and the outputs, netsim integrates: the plant is a
:class:`~netsim.plant.nonlinear.NonlinearPlant` whose ``f(t, x, u, params)`` sets the FMU's time, continuous
state and inputs and returns ``fmi2GetDerivatives`` (FMI 3.0: ``fmi3GetContinuousStateDerivatives``), and whose
``h`` returns the output variables. So the
integrator is the scenario's ``plant.integrator`` (scipy's ``solve_ivp`` per segment by default, or fixed-step
RK4), process noise and disturbances work as on any nonlinear plant, and the state is the FMU's continuous state
(started from its initial values, or ``x0``). Only FMUs without event indicators are taken (no state events); the
FMU is instantiated and initialised once when the plant is built (FMI 3.0: its start values set before
``fmi3EnterInitializationMode``, then the event iteration of ``fmi3UpdateDiscreteStates`` until it needs no more;
an FMU that announces a time event or asks to terminate there is refused).
"""

from __future__ import annotations

import logging
import weakref
from ctypes import POINTER, c_double
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from netsim.errors import ConfigError

__all__ = ["exchange_plant"]

_log = logging.getLogger(__name__)


class _Evaluator:
    """``f`` and ``h`` of the plant: one FMU instance in continuous-time mode used as a function of (t, x, u)."""

    def __init__(self, model: Any, nx: int, vr_in: list[int], vr_out: list[int], fmi3: bool = False) -> None:
        self.model, self.nx, self.vr_in, self.vr_out = model, nx, vr_in, vr_out
        self.x = np.zeros(nx)
        self.dx = np.zeros(nx)
        self.px = self.x.ctypes.data_as(POINTER(c_double))  # fmi2Real and fmi3Float64 are both C doubles
        self.pdx = self.dx.ctypes.data_as(POINTER(c_double))
        self.get = model.getFloat64 if fmi3 else model.getReal
        self.set = model.setFloat64 if fmi3 else model.setReal
        self.derivatives = model.getContinuousStateDerivatives if fmi3 else model.getDerivatives

    def states(self) -> np.ndarray:
        """The FMU's continuous state now (after initialisation: its start values)."""
        self.model.getContinuousStates(self.px, self.nx)
        return self.x.copy()

    def _load(self, t: float, x: Any, u: Any) -> None:
        self.model.setTime(float(t))
        self.x[:] = x
        self.model.setContinuousStates(self.px, self.nx)
        if self.vr_in:
            self.set(self.vr_in, [float(v) for v in u])

    def f(self, t: float, x: Any, u: Any, params: Any) -> np.ndarray:
        self._load(t, x, u)
        self.derivatives(self.pdx, self.nx)
        return self.dx.copy()

    def h(self, t: float, x: Any, u: Any, params: Any) -> np.ndarray:
        self._load(t, x, u)
        return np.array(self.get(self.vr_out), dtype=float)


def _release(model: Any) -> None:
    """Terminate and free the instance (the library stays loaded: see :func:`netsim.plant.fmu._release`)."""
    try:
        model.terminate()
        model.freeInstance()
    except Exception as exc:  # noqa: BLE001 - a finaliser must not raise
        _log.debug("releasing the FMU failed: %s", exc)


def exchange_plant(folder: Path, description: Any, inputs: Sequence[str], outputs: Sequence[str],
                   parameters: dict[str, float] | None = None, *, name: str = "plant") -> Any:
    """A :class:`~netsim.plant.nonlinear.NonlinearPlant` over the model-exchange FMU in ``folder`` (see the module).

    Raises
    ------
    ConfigError
        When an FMI 3.0 FMU announces a time event or asks to terminate during its initial event iteration.
    """
    from netsim.plant.nonlinear import NonlinearPlant

    variables = {v.name: v for v in description.modelVariables}
    fmi3 = description.fmiVersion != "2.0"
    model = _initialised(folder, description, parameters, name)
    states = [d.variable.derivative.name for d in description.derivatives]
    evaluator = _Evaluator(model, len(states), [variables[n].valueReference for n in inputs],
                           [variables[n].valueReference for n in outputs], fmi3)
    plant = NonlinearPlant(evaluator.f, evaluator.h, len(states), len(inputs), len(outputs), x0=evaluator.states(),
                           input_names=list(inputs), output_names=list(outputs), state_names=states, name=name)
    weakref.finalize(plant, _release, model)
    return plant


def _initialised(folder: Path, description: Any, parameters: dict[str, float] | None, name: str) -> Any:
    """FMPy's ``FMU2Model`` or ``FMU3Model`` of the FMU, instantiated, initialised and in continuous-time mode.

    FMI 2.0 takes the start time in ``setupExperiment``, FMI 3.0 in ``enterInitializationMode`` (its start values
    are set before). After initialisation the FMU is in event mode: ``newDiscreteStates`` (FMI 3.0:
    ``updateDiscreteStates``) is called until it needs no further update."""
    fmi3 = description.fmiVersion != "2.0"
    if fmi3:
        from fmpy.fmi3 import FMU3Model as Model
    else:
        from fmpy.fmi2 import FMU2Model as Model
    variables = {v.name: v for v in description.modelVariables}
    model = Model(guid=description.guid, unzipDirectory=str(folder),
                  modelIdentifier=description.modelExchange.modelIdentifier, instanceName=name)
    model.instantiate()
    given = parameters or {}
    vrs, values = [variables[n].valueReference for n in given], [float(v) for v in given.values()]
    if fmi3:
        if vrs:
            model.setFloat64(vrs, values)
        model.enterInitializationMode(startTime=0.0)
        model.exitInitializationMode()
        _event_iteration3(model)
    else:
        model.setupExperiment(startTime=0.0)
        if vrs:
            model.setReal(vrs, values)
        model.enterInitializationMode()
        model.exitInitializationMode()
        while model.newDiscreteStates()[0]:  # the initial event iteration (newDiscreteStatesNeeded)
            pass
    model.enterContinuousTimeMode()
    return model


def _event_iteration3(model: Any) -> None:
    """FMI 3.0's initial event iteration; an FMU that asks to terminate or announces a time event is refused."""
    while True:
        again, terminate, _, _, time_event, at = model.updateDiscreteStates()
        if terminate or time_event:
            _release(model)
            why = "asks to terminate" if terminate else f"announces a time event at t = {at:.9g} s"
            raise ConfigError(f"the FMU's model exchange interface {why} during initialisation; netsim integrates "
                              "model-exchange FMUs without events: use its co-simulation interface "
                              "(interface: co_simulation)")
        if not again:
            return
