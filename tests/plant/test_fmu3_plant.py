"""The ``fmu`` plant with FMI 3.0 FMUs (issue 30): what FMI 3.0 adds to :mod:`tests.plant.test_fmu_plant`.

That module runs the behaviour both versions share (closed loop and model exchange against the same ``ss`` plant,
the hand-computed step response, x0, archives, the plugin permission) for the FMI 2.0 motor and for the FMI 3.0
motor of ``scenarios/fmu/dc_motor3`` (``sources/dc_motor3.c`` and ``sources/buildDescription.xml``, written for
netsim). Here: the FMI 3.0 description, the equality of the two motors, FMI 3.0's step and event outcomes, and its
bad input (other variable types, arrays, event indicators, clocks). The helpers and the cache fixture (the FMUs
compiled once per module into a temporary cache folder) are that module's.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

pytest.importorskip("fmpy")

import netsim  # noqa: E402
from tests.plant.test_fmu_plant import SHIPPED, _problems, _scenario, _with_description, fmu_cache  # noqa: E402,F401

SOURCE_FMU = SHIPPED["3.0"][1]


# ------------------------------------------------------------------------------------------------ numbers
def test_the_description_is_read_as_fmi3_with_both_interfaces_and_float64_variables():
    from netsim.plant.fmu import FmuParams
    from netsim.trust import task_permission

    with task_permission(True):
        params = FmuParams.model_validate({"path": str(SOURCE_FMU)})
    md = params.description()
    assert md.fmiVersion == "3.0" and md.coSimulation is not None and md.modelExchange is not None
    # the defaults of modelDescription.xml: Float64 input u, outputs theta, omega, states from
    # ModelStructure/ContinuousStateDerivative (der(theta) -> theta, der(omega) -> omega)
    assert params.port_names() == (["u"], ["theta", "omega"], ["theta", "omega"])
    assert params.kind() == "co_simulation"


def test_the_fmi3_scenario_reproduces_the_fmi2_scenario_exactly(tmp_path):
    # the two source FMUs do the same arithmetic in their doStep, and the scenarios differ only in the FMU:
    # every recorded signal is equal bit for bit
    three = netsim.run(_scenario("3.0") | {"duration": "0.5 s"}, out=tmp_path / "three", allow_plugins=True)
    two_data = _scenario("3.0") | {"duration": "0.5 s"}
    two_data["plant"]["path"] = str(SHIPPED["2.0"][1])
    two = netsim.run(two_data, out=tmp_path / "two", allow_plugins=True)
    for name in ("theta", "omega", "u"):
        assert np.array_equal(three.signal(name).to_numpy(), two.signal(name).to_numpy(), equal_nan=True), name
    assert float(np.nanmax(np.abs(three.signal("theta").to_numpy()))) > 0.5  # the servo moved


def test_an_fmi3_step_that_asks_to_terminate_or_returns_early_stops_the_run_with_the_instant():
    # FMPy's doStep result: (eventHandlingNeeded, terminateSimulation, earlyReturn, lastSuccessfulTime)
    from netsim.plant.fmu import _check_fmi3_step

    _check_fmi3_step("plant", 250_000_000, (False, False, False, 0.25))  # a normal step passes
    with pytest.raises(netsim.errors.SimulationError, match=r"terminate the simulation .* t = 0\.25 s"):
        _check_fmi3_step("plant", 250_000_000, (False, True, False, 0.25))
    with pytest.raises(netsim.errors.SimulationError, match=r"returned early at t = 0\.2 s"):
        _check_fmi3_step("plant", 250_000_000, (False, False, True, 0.2))


def test_a_model_exchange_fmi3_fmu_with_a_time_event_at_initialisation_is_refused():
    # fmi3UpdateDiscreteStates answers (discreteStatesNeedUpdate, terminateSimulation, nominalsChanged,
    # valuesChanged, nextEventTimeDefined, nextEventTime): a time event at 0.5 s cannot be handled
    from netsim.errors import ConfigError
    from netsim.plant.fmu_exchange import _event_iteration3

    class Announcing:
        calls = 0

        def updateDiscreteStates(self) -> tuple[bool, bool, bool, bool, bool, float]:
            self.calls += 1
            return (self.calls < 2, False, False, False, self.calls >= 2, 0.5)

        def terminate(self) -> None: ...

        def freeInstance(self) -> None: ...

    with pytest.raises(ConfigError, match=r"announces a time event at t = 0\.5 s"):
        _event_iteration3(Announcing())


# ------------------------------------------------------------------------------------------------ bad input
def _edited(tmp_path: Any, edit: Any) -> str:
    return str(_with_description(tmp_path, edit, SOURCE_FMU))


_U = '<Float64 name="u" valueReference="3" causality="input" start="0" description="input voltage"/>'


def _with_event_indicator(text: str) -> str:
    # a local Float64 z (value reference 8) declared as the FMU's event indicator
    text = text.replace("  </ModelVariables>", '    <Float64 name="z" valueReference="8"/>\n  </ModelVariables>')
    return text.replace("  </ModelStructure>", '    <EventIndicator valueReference="8"/>\n  </ModelStructure>')


@pytest.mark.parametrize(("edit", "where", "value", "path", "words"), [
    (None, "inputs", ["v"], "plant.inputs", "no Float64 input 'v'; its inputs are ['u']"),
    (None, "outputs", ["theta", "speed"], "plant.outputs",
     "no Float64 output 'speed'; its outputs are ['theta', 'omega']"),
    (None, "parameters", {"J": 1.0}, "plant.parameters", "no Float64 parameter 'J'"),
    # u declared Float32: netsim maps Float64 variables only
    (lambda s: s.replace(_U, _U.replace("Float64", "Float32")), "inputs", ["u"], "plant.inputs",
     "no Float64 input 'u' ('u' is Float32: netsim maps Float64 variables only); its inputs are []"),
    # an Int32 parameter n
    (lambda s: s.replace("  </ModelVariables>", '    <Int32 name="n" valueReference="8" causality="parameter" '
                         'variability="fixed" start="3"/>\n  </ModelVariables>'),
     "parameters", {"n": 4}, "plant.parameters", "('n' is Int32: netsim maps Float64 variables only)"),
    # u an array of two
    (lambda s: s.replace(_U, _U.replace('start="0"', 'start="0 0"').replace(
        "/>", '><Dimension start="2"/></Float64>')), "inputs", ["u"], "plant.inputs",
     "('u' is an array of shape (2,): netsim maps scalar variables only)"),
    # state events
    (_with_event_indicator, "interface", "model_exchange", "plant.interface", "has 1 event indicators"),
    # FMI 1.0 is still refused
    (lambda s: s.replace('fmiVersion="3.0"', 'fmiVersion="1.0"', 1), "inputs", ["u"], "plant.path",
     "is FMI 1.0; the fmu plant runs FMI 2.0 and 3.0 FMUs"),
])
def test_a_bad_fmi3_fmu_or_field_is_one_problem_at_its_path(tmp_path, edit, where, value, path, words):
    data = _scenario("3.0")
    if edit is not None:
        data["plant"]["path"] = _edited(tmp_path, edit)
        data["plant"].pop("parameters")
    data["plant"][where] = value
    problems = _problems(data, allow_plugins=True)
    assert [p.path for p in problems] == [path], problems
    assert words in problems[0].message and "\n" not in problems[0].message, problems[0].message


def test_an_fmi3_fmu_with_clocks_is_refused_at_plant_interface(tmp_path):
    clock = ('    <Clock name="tick" valueReference="8" causality="input" intervalVariability="constant" '
             'intervalDecimal="0.1"/>\n  </ModelVariables>')
    data = _scenario("3.0")
    data["plant"]["path"] = _edited(tmp_path, lambda s: s.replace("  </ModelVariables>", clock))
    problems = _problems(data, allow_plugins=True)
    assert [p.path for p in problems] == ["plant.interface"], problems
    assert "clocks ['tick']" in problems[0].message


def test_the_event_indicator_is_accepted_with_co_simulation(tmp_path):
    # the FMU handles its own events inside fmi3DoStep: only model exchange refuses state events
    data = _scenario("3.0")
    data["plant"]["path"] = _edited(tmp_path, _with_event_indicator)
    assert _problems(data, allow_plugins=True) == []
