"""The ``fmu`` plant with FMI 3.0 FMUs (issue 30): co-simulation and model exchange through FMPy's FMU3Slave and
FMU3Model.

The FMU is the DC motor of ``scenarios/fmu/dc_motor3`` (``sources/dc_motor3.c`` and ``sources/buildDescription.xml``,
written for netsim: theta' = omega, omega' = -a omega + k u, exact zero-order-hold steps), compiled once per module
into a temporary cache folder with FMPy's CMake project and the FMI 3 headers FMPy ships. The helpers and the cache
fixture are those of :mod:`tests.plant.test_fmu_plant` (the FMI 2.0 motor).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

pytest.importorskip("fmpy")

import netsim  # noqa: E402
from netsim.cli import main  # noqa: E402
from tests.plant.test_fmu_plant import ROOT, _problems, _ss_twin, _with_description, fmu_cache  # noqa: E402,F401

SCENARIO = ROOT / "scenarios" / "dc_servo_fmu3.yaml"
SOURCE_FMU = ROOT / "scenarios" / "fmu" / "dc_motor3"


def _scenario() -> dict[str, Any]:
    data = yaml.safe_load(SCENARIO.read_text(encoding="utf-8"))
    data["plant"]["path"] = str(SOURCE_FMU)  # a mapping has no folder: the path is absolute
    return data


def _plant(params: dict[str, Any]) -> Any:
    from netsim.plant.fmu import FmuParams, fmu_plant
    from netsim.trust import task_permission

    with task_permission(True):
        return fmu_plant(FmuParams.model_validate({"path": str(SOURCE_FMU), **params}))


def _relative_errors(a: Any, b: Any, names: tuple[str, ...]) -> dict[str, float]:
    """max |a - b| over each signal, divided by the signal's largest magnitude in ``b``."""
    out = {}
    for name in names:
        ya, yb = a.signal(name), b.signal(name)
        assert len(ya) == len(yb) > 200
        assert np.array_equal(np.asarray(ya.index), np.asarray(yb.index))
        scale = float(np.nanmax(np.abs(yb.to_numpy())))
        out[name] = float(np.nanmax(np.abs(ya.to_numpy() - yb.to_numpy()))) / scale
    return out


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


@pytest.mark.parametrize("interface", ["co_simulation", "model_exchange"])
def test_the_step_response_is_the_hand_computed_solution_at_uneven_steps(interface):
    # theta' = omega, omega' = -a omega + k u from rest under u = 1 (the solution by hand):
    #   omega(t) = (k / a) (1 - exp(-a t)),  theta(t) = (k / a) (t - (1 - exp(-a t)) / a)
    # co-simulation: fmi3DoStep's exact step, to 1e-12; model exchange: solve_ivp (rtol 1e-8) over
    # fmi3GetContinuousStateDerivatives, to 1e-6
    k, a = 1000.0, 1.0
    plant = _plant({"interface": interface, "parameters": {"k": k, "a": a}, "outputs": ["theta", "omega"]})
    plant.set_input("u", 1.0, 0)
    t_ns = 0
    for h in (1, 999, 250_000, 3_000_000, 96_749_000, 400_000_000):  # uneven steps, 1 ns to 0.4 s
        t_ns += h
        plant.advance_to(t_ns)
    t = t_ns / 1e9
    assert t == pytest.approx(0.5)
    want = np.array([(k / a) * (t - (1 - math.exp(-a * t)) / a), (k / a) * (1 - math.exp(-a * t))])
    # theta(0.5) = 1000 (0.5 - 0.393469...) = 106.5306..., omega(0.5) = 393.4693...
    rtol = 1e-12 if interface == "co_simulation" else 1e-6
    assert np.allclose(plant.output(t_ns), want, rtol=rtol, atol=0)
    assert np.allclose(plant.state(t_ns), want, rtol=rtol, atol=0)


def test_a_linear_fmi3_fmu_equals_the_same_ss_plant_in_a_closed_loop(tmp_path):
    # dc_servo_ideal's PID loop over 1 s (6 ms period, 2 ms execution, 1 ms record grid: steps split at the ADC
    # read and the DAC write), motor parameters other than the FMU's start values and x0 given, so that both
    # reach the FMU; the twin is the same model as an exact LTI plant (matrix exponential)
    k, a = 400.0, 3.0
    data = _scenario()
    data["plant"]["parameters"] = {"k": k, "a": a}
    data["plant"]["x0"] = [0.2, -1.0]
    data["duration"] = "1 s"
    fmu = netsim.run(data, out=tmp_path / "fmu", allow_plugins=True)
    lti = netsim.run(_ss_twin(data, k, a), out=tmp_path / "ss")
    errors = _relative_errors(fmu, lti, ("theta", "omega", "u"))
    assert max(errors.values()) <= 1e-9, errors  # measured: about 1e-15 of each signal's scale


@pytest.mark.parametrize("integrator", [None, {"method": "rk4", "max_step": "0.5 ms"}])
def test_a_model_exchange_fmi3_fmu_integrated_by_netsim_equals_the_same_ss_plant(tmp_path, integrator):
    # netsim integrates fmi3GetContinuousStateDerivatives (solve_ivp with rtol 1e-8, atol 1e-10 per segment, or RK4
    # with 0.5 ms steps); the FMI 2.0 motor's model exchange reached 3e-15 (solve_ivp) and 3e-13 (RK4) here
    k, a = 400.0, 3.0
    data = _scenario()
    data["plant"].update(interface="model_exchange", parameters={"k": k, "a": a}, x0=[0.2, -1.0])
    if integrator is not None:
        data["plant"]["integrator"] = integrator
    data["duration"] = "1 s"
    me = netsim.run(data, out=tmp_path / "me", allow_plugins=True)
    lti = netsim.run(_ss_twin(data, k, a), out=tmp_path / "ss")
    errors = _relative_errors(me, lti, ("theta", "omega", "u"))
    assert max(errors.values()) <= 1e-9, errors


def test_the_fmi3_scenario_reproduces_the_fmi2_scenario_exactly(tmp_path):
    # the two source FMUs do the same arithmetic in their doStep, and the scenarios differ only in the FMU:
    # every recorded signal is equal bit for bit
    three = netsim.run(_scenario() | {"duration": "0.5 s"}, out=tmp_path / "three", allow_plugins=True)
    two_data = _scenario() | {"duration": "0.5 s"}
    two_data["plant"]["path"] = str(ROOT / "scenarios" / "fmu" / "dc_motor")
    two = netsim.run(two_data, out=tmp_path / "two", allow_plugins=True)
    for name in ("theta", "omega", "u"):
        assert np.array_equal(three.signal(name).to_numpy(), two.signal(name).to_numpy(), equal_nan=True), name
    assert float(np.nanmax(np.abs(three.signal("theta").to_numpy()))) > 0.5  # the servo moved


def test_x0_sets_the_fmi3_state_before_its_first_step():
    # free response from theta0 = 1, omega0 = 2, u = 0: omega(t) = 2 exp(-a t), theta(t) = 1 + 2 (1 - exp(-a t)) / a
    a = 2.0
    plant = _plant({"parameters": {"a": a}})
    plant.set_state([1.0, 2.0], 0)
    t = 0.3
    y = plant.output(int(t * 1e9))
    assert np.allclose(y, [1 + 2 * (1 - math.exp(-a * t)) / a, 2 * math.exp(-a * t)], rtol=1e-12, atol=0)
    with pytest.raises(netsim.errors.SimulationError, match="only before its first step"):
        plant.set_state([0.0, 0.0])


def test_an_fmi3_fmu_archive_runs_as_its_folder(tmp_path):
    # a .fmu (zip) holding the compiled library under binaries/<FMI 3 platform tuple> is unpacked into the cache
    # and gives the same outputs as the source folder it was built from
    import zipfile

    from netsim.plant.fmu_files import binary_folder, read_description

    built = binary_folder(SOURCE_FMU, read_description(SOURCE_FMU))
    archive = tmp_path / "dc_motor3.fmu"
    with zipfile.ZipFile(archive, "w") as z:
        for p in built.rglob("*"):
            if p.is_file() and "sources" not in p.parts:  # a binary FMU: no sources to build from
                z.write(p, p.relative_to(built).as_posix())
    one = _plant({"outputs": ["theta"]})
    two = _plant({"path": str(archive), "outputs": ["theta"]})
    for p in (one, two):
        p.set_input("u", 0.5, 0)
    assert one.output(123_456_789)[0] == two.output(123_456_789)[0] != 0.0


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


# ------------------------------------------------------------------------------------------------ permission
def test_without_the_plugin_permission_an_fmi3_fmu_is_refused_by_validate_and_run(tmp_path, capsys):
    code = main(["validate", str(SCENARIO)])
    out = capsys.readouterr().out
    assert code != 0
    lines = [line for line in out.splitlines() if "plant.path" in line]
    assert len(lines) == 1 and "--allow-plugins" in lines[0] and "loads code from the FMU" in lines[0]
    code = main(["run", str(SCENARIO), "--out", str(tmp_path / "run"), "-q"])
    assert code != 0 and "--allow-plugins" in capsys.readouterr().err
    assert not (tmp_path / "run").exists()
    assert [p.path for p in _problems(SCENARIO, allow_plugins=False)] == ["plant.path"]
    assert _problems(SCENARIO, allow_plugins=True) == []


def test_with_the_permission_the_shipped_fmi3_scenario_runs_by_name(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)  # the FMU path is relative to the scenario file, not the working folder
    assert main(["run", "dc_servo_fmu3", "--allow-plugins", "--set", "duration=0.1 s", "--out", "run", "-q"]) == 0, \
        capsys.readouterr().err


# ------------------------------------------------------------------------------------------------ bad input
def _edited(tmp_path: Path, edit: Any) -> str:
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
    data = _scenario()
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
    data = _scenario()
    data["plant"]["path"] = _edited(tmp_path, lambda s: s.replace("  </ModelVariables>", clock))
    problems = _problems(data, allow_plugins=True)
    assert [p.path for p in problems] == ["plant.interface"], problems
    assert "clocks ['tick']" in problems[0].message


def test_the_event_indicator_is_accepted_with_co_simulation(tmp_path):
    # the FMU handles its own events inside fmi3DoStep: only model exchange refuses state events
    data = _scenario()
    data["plant"]["path"] = _edited(tmp_path, _with_event_indicator)
    assert _problems(data, allow_plugins=True) == []
