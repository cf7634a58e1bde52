"""The ``fmu`` plant (issue 30): FMI 2.0 and FMI 3.0 FMUs built here from C source, run with FMPy.

The FMUs are the DC motor of ``scenarios/fmu/dc_motor`` (FMI 2.0, ``sources/dc_motor.c``) and of
``scenarios/fmu/dc_motor3`` (FMI 3.0, ``sources/dc_motor3.c`` and ``sources/buildDescription.xml``), both written
for netsim: theta' = omega, omega' = -a omega + k u, exact zero-order-hold steps. The test suite compiles them once
per module into a temporary cache folder (``NETSIM_CACHE_DIR``) with FMPy's CMake project and the machine's C
compiler. The tests of behaviour both versions share are parametrized over the version here; FMI 3.0's own cases
are in :mod:`tests.plant.test_fmu3_plant`.
"""

from __future__ import annotations

import copy
import math
import os
import shutil
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

pytest.importorskip("fmpy")

import netsim  # noqa: E402
from netsim.cli import main  # noqa: E402
from netsim.scenario import check_scenario  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SCENARIO = ROOT / "scenarios" / "dc_servo_fmu.yaml"
SOURCE_FMU = ROOT / "scenarios" / "fmu" / "dc_motor"
#: the shipped scenario and the source FMU of each FMI version
SHIPPED = {"2.0": (SCENARIO, SOURCE_FMU),
           "3.0": (ROOT / "scenarios" / "dc_servo_fmu3.yaml", ROOT / "scenarios" / "fmu" / "dc_motor3")}
VERSIONS = pytest.mark.parametrize("version", sorted(SHIPPED))


@pytest.fixture(scope="module", autouse=True)
def fmu_cache(tmp_path_factory: pytest.TempPathFactory) -> Any:
    """A private cache folder (the FMU is compiled into it once) and no plugin permission from the environment
    or the user's config unless a test gives it."""
    saved = {k: os.environ.get(k) for k in ("NETSIM_CACHE_DIR", "NETSIM_ALLOW_PLUGINS", "XDG_CONFIG_HOME")}
    os.environ["NETSIM_CACHE_DIR"] = str(tmp_path_factory.mktemp("cache"))
    os.environ["XDG_CONFIG_HOME"] = str(tmp_path_factory.mktemp("config"))  # no config.toml: not allowed
    os.environ.pop("NETSIM_ALLOW_PLUGINS", None)
    yield Path(os.environ["NETSIM_CACHE_DIR"])
    for k, v in saved.items():
        if v is None:
            os.environ.pop(k, None)
        else:
            os.environ[k] = v


def _scenario(version: str = "2.0") -> dict[str, Any]:
    scenario, source = SHIPPED[version]
    data = yaml.safe_load(scenario.read_text(encoding="utf-8"))
    data["plant"]["path"] = str(source)  # a mapping has no folder: the path is absolute
    return data


def _ss_twin(data: dict[str, Any], k: float, a: float) -> dict[str, Any]:
    """The same scenario with the plant written as ``type: ss``: theta' = omega, omega' = -a omega + k u."""
    twin = copy.deepcopy(data)
    twin["plant"] = {"type": "ss", "A": [[0, 1], [0, -a]], "B": [0, k], "C": [[1, 0], [0, 1]], "D": 0,
                     "inputs": ["u"], "outputs": ["theta", "omega"], "states": ["theta", "omega"],
                     "x0": data["plant"]["x0"], "record_grid": data["plant"]["record_grid"]}
    return twin


def _plant(params: dict[str, Any], version: str = "2.0") -> Any:
    from netsim.plant.fmu import FmuParams, fmu_plant

    with_trust = {"path": str(SHIPPED[version][1]), **params}
    from netsim.trust import task_permission

    with task_permission(True):
        return fmu_plant(FmuParams.model_validate(with_trust))


# ------------------------------------------------------------------------------------------------ numbers
def _relative_errors(a: Any, b: Any, names: tuple[str, ...]) -> dict[str, float]:
    """max |a - b| over each recorded signal, divided by the signal's largest magnitude in ``b``."""
    out = {}
    for name in names:
        ya, yb = a.signal(name), b.signal(name)
        assert len(ya) == len(yb) > 900
        assert np.array_equal(np.asarray(ya.index), np.asarray(yb.index))
        scale = float(np.nanmax(np.abs(yb.to_numpy())))
        out[name] = float(np.nanmax(np.abs(ya.to_numpy() - yb.to_numpy()))) / scale
    return out


@VERSIONS
def test_a_linear_fmu_equals_the_same_ss_plant_in_a_closed_loop(tmp_path, version):
    # PID loop of dc_servo_ideal (6 ms period, 2 ms execution: the plant is stepped over 1 ms record intervals
    # split at the ADC read and the DAC write) with other motor parameters than the FMU's defaults, so the
    # parameters must reach the FMU; the twin is the same model as an exact LTI plant (matrix exponential).
    k, a = 400.0, 3.0
    data = _scenario(version)
    data["plant"]["parameters"] = {"k": k, "a": a}
    data["plant"]["x0"] = [0.2, -1.0]
    data["duration"] = "1 s"
    fmu = netsim.run(data, out=tmp_path / "fmu", allow_plugins=True)
    lti = netsim.run(_ss_twin(data, k, a), out=tmp_path / "ss")
    errors = _relative_errors(fmu, lti, ("theta", "omega", "u"))
    # measured, both versions: 4.4e-16 (theta), 7.4e-16 (omega), 1.9e-15 (u) of each signal's scale
    assert max(errors.values()) <= 1e-9, errors


@VERSIONS
@pytest.mark.parametrize("integrator", [None, {"method": "rk4", "max_step": "0.5 ms"}])
def test_a_model_exchange_fmu_integrated_by_netsim_follows_the_same_ss_plant(tmp_path, integrator, version):
    # the same FMU through its model exchange interface: netsim integrates fmi2GetDerivatives or
    # fmi3GetContinuousStateDerivatives (solve_ivp with rtol 1e-8, atol 1e-10 per segment, or RK4 with 0.5 ms
    # steps), so the match is to the integrator's accuracy
    k, a = 400.0, 3.0
    data = _scenario(version)
    data["plant"].update(interface="model_exchange", parameters={"k": k, "a": a}, x0=[0.2, -1.0])
    if integrator is not None:
        data["plant"]["integrator"] = integrator
    data["duration"] = "1 s"
    me = netsim.run(data, out=tmp_path / "me", allow_plugins=True)
    lti = netsim.run(_ss_twin(data, k, a), out=tmp_path / "ss")
    errors = _relative_errors(me, lti, ("theta", "omega", "u"))
    # measured: about 3e-15 of the scale with solve_ivp, 3e-13 with RK4 at 0.5 ms
    assert max(errors.values()) <= 1e-9, errors


def test_a_step_disturbance_on_the_fmu_input_switches_exactly_as_on_the_ss_plant(tmp_path):
    # a load step at 0.3037 s (between the record instants and the controller's samples) added to u: the plant
    # splits its doStep at the jump, as the LTI plant splits its matrix exponential
    data = _scenario()
    data["duration"] = "0.6 s"
    data["signals"]["d"] = {"type": "step", "at": "303.7 ms", "value": -0.25}
    data["plant"]["disturbances"] = {"u": "d"}
    fmu = netsim.run(data, out=tmp_path / "fmu", allow_plugins=True)
    twin = _ss_twin(data, 1000.0, 1.0)
    twin["plant"]["disturbances"] = {"u": "d"}
    lti = netsim.run(twin, out=tmp_path / "ss")
    y_fmu, y_ss = fmu.signal("theta").to_numpy(), lti.signal("theta").to_numpy()
    assert float(np.nanmax(np.abs(y_fmu - y_ss))) <= 1e-9 * float(np.nanmax(np.abs(y_ss)))
    no_step = netsim.run({**data, "plant": {**data["plant"], "disturbances": {}}}, out=tmp_path / "none",
                         allow_plugins=True)
    assert float(np.nanmax(np.abs(no_step.signal("theta").to_numpy() - y_fmu))) > 1e-3  # the step mattered


@pytest.mark.parametrize(("version", "interface"), [("2.0", "co_simulation"), ("3.0", "co_simulation"),
                                                   ("3.0", "model_exchange")])
def test_the_step_response_is_the_hand_computed_solution_at_uneven_steps(version, interface):
    # theta' = omega, omega' = -a omega + k u from rest under u = 1 (the solution by hand):
    #   omega(t) = (k / a) (1 - exp(-a t)),  theta(t) = (k / a) (t - (1 - exp(-a t)) / a)
    # co-simulation: doStep's exact step, to 1e-12; model exchange: solve_ivp (rtol 1e-8) over the FMU's
    # derivatives, to 1e-6
    k, a = 1000.0, 1.0
    plant = _plant({"interface": interface, "parameters": {"k": k, "a": a}, "outputs": ["theta", "omega"]}, version)
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
    assert np.allclose(plant.state(t_ns), want, rtol=rtol, atol=0)  # states default to theta, omega


@VERSIONS
def test_x0_sets_the_fmu_state_before_its_first_step(version):
    # free response from theta0 = 1, omega0 = 2, u = 0: omega(t) = 2 exp(-a t), theta(t) = 1 + 2 (1 - exp(-a t)) / a
    a = 2.0
    plant = _plant({"parameters": {"a": a}}, version)
    plant.set_state([1.0, 2.0], 0)
    t = 0.3
    y = plant.output(int(t * 1e9))
    assert np.allclose(y, [1 + 2 * (1 - math.exp(-a * t)) / a, 2 * math.exp(-a * t)], rtol=1e-12, atol=0)
    with pytest.raises(netsim.errors.SimulationError, match="only before its first step"):
        plant.set_state([0.0, 0.0])


@VERSIONS
def test_an_fmu_archive_runs_as_its_folder(tmp_path, version):
    # a .fmu (zip) holding the compiled library (binaries/linux64 for FMI 2.0, binaries/x86_64-linux for 3.0) and
    # no sources is unpacked into the cache and gives the same outputs as the folder it was built from
    from netsim.plant.fmu_files import binary_folder, read_description

    source = SHIPPED[version][1]
    built = binary_folder(source, read_description(source))
    archive = tmp_path / "dc_motor.fmu"
    with zipfile.ZipFile(archive, "w") as z:
        for p in built.rglob("*"):
            if p.is_file() and "sources" not in p.parts:
                z.write(p, p.relative_to(built).as_posix())
    one = _plant({"outputs": ["theta"]}, version)
    two = _plant({"path": str(archive), "outputs": ["theta"]}, version)
    for p in (one, two):
        p.set_input("u", 0.5, 0)
    assert one.output(123_456_789)[0] == two.output(123_456_789)[0] != 0.0


# ------------------------------------------------------------------------------------------------ permission
def _problems(data: Any, **kw: Any) -> list[Any]:
    return [p for p in check_scenario(data, **kw) if p.severity == "error"]


@VERSIONS
def test_without_the_plugin_permission_validate_and_run_refuse_naming_allow_plugins(tmp_path, capsys, version):
    scenario = SHIPPED[version][0]
    code = main(["validate", str(scenario)])
    out = capsys.readouterr().out
    assert code != 0
    lines = [line for line in out.splitlines() if "plant.path" in line]
    assert len(lines) == 1 and "--allow-plugins" in lines[0] and "loads code from the FMU" in lines[0]
    code = main(["run", str(scenario), "--out", str(tmp_path / "run"), "-q"])
    assert code != 0 and "--allow-plugins" in capsys.readouterr().err
    assert not (tmp_path / "run").exists()
    # Python: allow_plugins=False refuses, True allows
    assert [p.path for p in _problems(scenario, allow_plugins=False)] == ["plant.path"]
    assert _problems(scenario, allow_plugins=True) == []


@VERSIONS
def test_with_the_permission_the_shipped_scenario_validates_and_runs_from_any_folder(tmp_path, monkeypatch, capsys,
                                                                                      version):
    scenario = SHIPPED[version][0]
    monkeypatch.chdir(tmp_path)  # the FMU path is relative to the scenario file, not the working folder
    assert main(["validate", str(scenario), "--allow-plugins"]) == 0, capsys.readouterr().err
    assert main(["run", scenario.stem, "--allow-plugins", "--set", "duration=0.1 s", "--out", "run", "-q"]) == 0


def test_a_sweep_over_an_fmu_scenario_finds_the_fmu_beside_its_base(tmp_path, monkeypatch, capsys):
    # the points are validated as mappings in worker processes: the base's relative FMU path is made absolute
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.yaml").write_text(
        f"sweep: fmu_k\nbase: {SCENARIO}\nmode: product\nfactors:\n"
        "  k: {paths: [plant.parameters.k], values: [500, 1000]}\n"
        "  duration: {paths: [duration], values: [0.1 s]}\n", encoding="utf-8")
    code = main(["sweep", "s.yaml", "--allow-plugins", "--workers", "1", "--out", "out", "-q", "--no-progress"])
    assert code == 0, capsys.readouterr()
    import pandas as pd

    summary = pd.read_csv(tmp_path / "out" / "summary.csv")
    assert list(summary["status"]) == ["ok", "ok"]
    assert summary["theta.IAE"].nunique() == 2  # k reached the FMU


# ------------------------------------------------------------------------------------------------ bad input
def _with_description(tmp_path: Path, edit: Any, source: Path = SOURCE_FMU) -> Path:
    """A copy of the source FMU ``source`` whose modelDescription.xml is ``edit(text)``."""
    folder = tmp_path / "edited"
    shutil.copytree(source, folder)
    md = folder / "modelDescription.xml"
    md.write_text(edit(md.read_text(encoding="utf-8")), encoding="utf-8")
    return folder


@pytest.mark.parametrize(("where", "value", "path", "words"), [
    ("path", "no/such/dc_motor.fmu", "plant.path", "FMU not found"),
    ("inputs", ["v"], "plant.inputs", "no Real input 'v'; its inputs are ['u']"),
    ("outputs", ["theta", "speed"], "plant.outputs", "no Real output 'speed'; its outputs are ['theta', 'omega']"),
    ("states", ["x9"], "plant.states", "no Real variable 'x9'"),
    ("parameters", {"J": 1.0}, "plant.parameters", "no Real parameter 'J'"),
])
def test_a_bad_fmu_field_is_one_problem_at_its_path(where, value, path, words):
    data = _scenario()
    data["plant"][where] = value
    problems = _problems(data, allow_plugins=True)
    assert [p.path for p in problems] == [path], problems
    assert words in problems[0].message and "\n" not in problems[0].message


@pytest.mark.parametrize(("edit", "words"), [
    (lambda s: s.replace('fmiVersion="2.0"', 'fmiVersion="1.0"'), "FMI 1.0; the fmu plant runs FMI 2.0 and 3.0 FMUs"),
    (lambda s: s.replace("<ModelVariables>", "<ModelVariables"), "cannot read the FMU's modelDescription.xml"),
])
def test_a_wrong_kind_of_fmu_is_refused_at_plant_path(tmp_path, edit, words):
    data = _scenario()
    data["plant"]["path"] = str(_with_description(tmp_path, edit))
    problems = _problems(data, allow_plugins=True)
    assert [p.path for p in problems] == ["plant.path"], problems
    assert words in problems[0].message


def _without_cosimulation(text: str) -> str:
    start, end = text.index("  <CoSimulation"), text.index("</CoSimulation>") + len("</CoSimulation>\n")
    return text[:start] + text[end:]


def test_a_missing_interface_or_state_events_are_refused_at_plant_interface(tmp_path):
    data = _scenario()
    data["plant"]["path"] = str(_with_description(tmp_path, _without_cosimulation))
    data["plant"]["interface"] = "co_simulation"
    problems = _problems(data, allow_plugins=True)
    assert [(p.path, p.message) for p in problems] == [
        ("plant.interface", "the FMU has no co_simulation interface; it has model_exchange only")]
    data["plant"]["path"] = str(_with_description(tmp_path / "ev", lambda s: s.replace(
        'numberOfEventIndicators="0"', 'numberOfEventIndicators="1"')))
    data["plant"]["interface"] = "model_exchange"
    problems = _problems(data, allow_plugins=True)
    assert [p.path for p in problems] == ["plant.interface"] and "event indicators" in problems[0].message


def test_a_source_fmu_without_a_c_compiler_is_refused_by_validate_saying_so(tmp_path, monkeypatch):
    from netsim.plant import fmu_files

    monkeypatch.setenv("NETSIM_CACHE_DIR", str(tmp_path / "empty_cache"))
    monkeypatch.setattr(fmu_files, "compiler", lambda: None)
    problems = _problems(_scenario(), allow_plugins=True)
    assert [p.path for p in problems] == ["plant.path"], problems
    assert "no C compiler" in problems[0].message


def test_without_fmpy_the_problem_names_the_extra_to_install(monkeypatch):
    import sys

    from netsim.plant import fmu

    monkeypatch.setitem(sys.modules, "fmpy", None)  # import fmpy raises ImportError
    monkeypatch.setattr(fmu, "_DESCRIPTIONS", {})
    problems = _problems(_scenario(), allow_plugins=True)
    assert [p.path for p in problems] == ["plant.path"], problems
    assert "pip install 'netsim[fmu]'" in problems[0].message


def test_state_noise_is_refused_by_an_fmu_plant():
    data = _scenario()
    data["plant"]["process_noise"] = {"states": ["omega"], "sigma": 0.1, "sample": "1 ms"}
    problems = _problems(data, allow_plugins=True)
    assert [p.path for p in problems] == ["plant.process_noise"], problems
    assert "state noise" in problems[0].message


# ------------------------------------------------------------------------------------------------ listing
def test_netsim_list_plants_shows_fmu(capsys):
    assert main(["list", "plant"]) == 0
    out = capsys.readouterr().out
    assert any(line.split()[:1] == ["fmu"] for line in out.splitlines()), out
