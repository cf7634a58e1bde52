"""The JSON Schema (``netsim schema``) against ``netsim validate`` on a corpus of single-file mistakes.

Each case takes a shipped scenario or sweep file, makes one mistake that needs no cross-reference (a misspelt key at
some level, an unknown plugin name or parameter, a bad unit, a wrong type or enum value, a malformed matrix) and
checks it with both. ``validate`` must refuse every case (else the case is no mistake); the schema must refuse at
least 90 % of them, accept every shipped file, and report a scenario's mistake without a sweep file's required keys.
"""

from __future__ import annotations

import copy
import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any, Callable

import pytest
import yaml

jsonschema = pytest.importorskip("jsonschema")

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = ROOT / "scenarios"


@pytest.fixture(scope="module")
def schema() -> dict[str, Any]:
    # a fresh process: plugins the tests register in this one stay out of the enums
    env = {**os.environ, "NETSIM_ALLOW_PLUGINS": "0"}
    done = subprocess.run([sys.executable, "-m", "netsim", "schema"], cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=300, check=True)
    return json.loads(done.stdout)


@pytest.fixture(scope="module")
def validator(schema):
    cls = jsonschema.validators.validator_for(schema)
    cls.check_schema(schema)
    return cls(schema)


def _read(name: str) -> dict[str, Any]:
    from netsim.scenario.loader import read_yaml

    return copy.deepcopy(read_yaml(SCENARIOS / name)[0])


def _set(path: str, value: Any) -> Callable[[dict[str, Any]], None]:
    """A mutation setting the dotted ``path`` (``nodes.sensor.tasks.0.period``) to ``value``."""
    def apply(data: dict[str, Any]) -> None:
        *parents, last = path.split(".")
        node: Any = data
        for key in parents:
            node = node[int(key)] if isinstance(node, list) else node[key]
        if isinstance(node, list):
            node[int(last)] = value
        else:
            node[last] = value
    return apply


def _rename(path: str, new: str) -> Callable[[dict[str, Any]], None]:
    """A mutation renaming the key at the dotted ``path`` to ``new`` (a misspelt key), keeping its value."""
    def apply(data: dict[str, Any]) -> None:
        *parents, last = path.split(".")
        node: Any = data
        for key in parents:
            node = node[int(key)] if isinstance(node, list) else node[key]
        node[new] = node.pop(last)
    return apply


CAN = "dc_servo_can.yaml"
SS = "dc_servo_lqr_kalman.yaml"  # a described state-space plant (1-D B and C), the state_feedback program
BATTERY = "wireless_battery.yaml"
SWEEP = "hdd_gpi_sweep.yaml"
HDD = "hdd_case2.yaml"  # interrupt handlers, a baseline
SENSOR = "nodes.sensor.tasks.0"

#: (case id, file, mutation): one mistake each, none needing a cross-reference to another part of the file.
CORPUS: list[tuple[str, str, Callable[[dict[str, Any]], None]]] = [
    # misspelt keys at several levels
    ("top-level key", CAN, _rename("duration", "duraton")),
    ("node key", CAN, _rename("nodes.sensor.policy", "polcy")),
    ("task key", CAN, _rename(f"{SENSOR}.period", "perid")),
    ("plant key", CAN, _rename("plant.record_grid", "record_gird")),
    ("io channel key", CAN, _rename("io.y.output", "ouput")),
    ("described plant key", SS, _rename("plant.process_noise", "proces_noise")),
    ("sweep key", SWEEP, _rename("factors", "factor")),
    ("sweep factor key", SWEEP, _rename("factors.sigma_s.paths", "path")),
    # unknown plugin names
    ("plant model", CAN, _set("plant.model", "dc_servoo")),
    ("described plant type", SS, _set("plant.type", "sss")),
    ("program", CAN, _set(f"{SENSOR}.program", "samplr")),
    ("policy", CAN, _set("nodes.sensor.policy", "edff")),
    ("network type", CAN, _set("networks.can.type", "cann")),
    ("signal type", CAN, _set("signals.r.type", "squar")),
    ("metric type", CAN, _set("metrics.0.type", "control_eror")),
    ("estimator type", SS, _set("nodes.controller.tasks.0.params.estimator.type", "kalmn")),
    ("control law type", SS, _set("nodes.controller.tasks.0.params.law.type", "lqrr")),
    # unknown plugin parameters
    ("program param", CAN, _set(f"{SENSOR}.params.chanel", "y")),
    ("plant param", CAN, _set("plant.params.gian", 1000)),
    ("described plant param", SS, _set("plant.AA", [[0, 1], [0, -1]])),
    ("network param", CAN, _set("networks.can.bitrat", "80 kbit/s")),
    ("signal param", CAN, _set("signals.r.amplitud", 1.0)),
    ("metric param", CAN, _set("metrics.0.params.refrence", "r")),
    ("estimator param", SS, _set("nodes.controller.tasks.0.params.estimator.QQ", [0, 1])),
    ("control law param", SS, _set("nodes.controller.tasks.0.params.law.RR", 0.1)),
    ("energy key", BATTERY, _set("nodes.sensor.energy.cpu.turbo", "2 W")),
    # bad units
    ("time unit", CAN, _set("duration", "2 sec")),
    ("time without unit", CAN, _set(f"{SENSOR}.period", 10)),
    ("task time unit", CAN, _set(f"{SENSOR}.execution", "0.5 msec")),
    ("negative time", CAN, _set(f"{SENSOR}.execution", "-0.5 ms")),
    ("signal time unit", CAN, _set("signals.r.period", "1 sek")),
    ("bit rate unit", CAN, _set("networks.can.bitrate", "80 kbyte/s")),
    ("power unit", BATTERY, _set("nodes.sensor.energy.cpu.busy", "30 mV")),
    ("energy unit", BATTERY, _set("nodes.sensor.energy.battery.capacity", "0.2 W")),
    # wrong types
    ("seed type", CAN, _set("seed", "one")),
    ("record type", CAN, _set("record", {"r": 1})),
    ("tasks type", CAN, _set("nodes.sensor.tasks", {"name": "sample"})),
    ("priority type", CAN, _set("nodes.interference.tasks.0.priority", "high")),
    ("program param type", CAN, _set("nodes.controller.tasks.0.params.K", "one")),
    ("plant param type", CAN, _set("plant.params.gain", [1000])),
    ("sweep replicates type", SWEEP, _set("replicates", "five")),
    ("negative sweep seed", SWEEP, _set("seed", -1)),
    # bad enum values
    ("io channel type", CAN, _set("io.y.type", "adcc")),
    ("radio listen", BATTERY, _set("nodes.sensor.energy.radio.listen", "sometimes")),
    ("sweep mode", SWEEP, _set("mode", "random")),
    ("sweep runs", SWEEP, _set("runs", "some")),
    ("handler key", HDD, _rename("nodes.sensor.handlers.0.trigger", "triger")),
    ("handler trigger key", HDD, _rename("nodes.sensor.handlers.0.trigger.timer.period", "perod")),
    ("handler program", HDD, _set("nodes.sensor.handlers.0.program", "et_sensr")),
    ("handler program param", HDD, _set("nodes.sensor.handlers.0.params.sigma", 1e-5)),
    ("baseline key", HDD, _rename("baseline.overrides", "override")),
    ("sweep surface key", SWEEP, _rename("surface.z", "zz")),
    ("sweep logspace type", SWEEP, _set("factors.sigma_s.logspace.num", "many")),
    ("task deadline without unit", CAN, _set("nodes.controller.tasks.0.deadline", 10)),
    ("signal param type", CAN, _set("signals.r.amplitude", "big")),
    ("metric param type", CAN, _set("metrics.1.params.chain", {"first": "sensor.sample"})),
    ("network nodes type", CAN, _set("networks.can.nodes", 3)),
    ("plant x0 type", CAN, _set("plant.x0", "zero")),
    ("estimator param type", SS, _set("nodes.controller.tasks.0.params.estimator.R", "small")),
    # malformed matrices (no cross-reference: the shape of the value alone is wrong)
    ("matrix of three levels", SS, _set("plant.A", [[[0, 1]], [[0, -1]]])),
    ("matrix as text", SS, _set("plant.A", "identity")),
    ("matrix entry as text", SS, _set("plant.B", [0, "k"])),
]


def _sweep_on_shipped_base(data: dict[str, Any]) -> dict[str, Any]:
    if "sweep" in data and isinstance(data.get("base"), str):
        data["base"] = str(SCENARIOS / data["base"])
    return data


def _validate_refuses(tmp_path: Path, name: str, data: dict[str, Any]) -> list[str]:
    from netsim.scenario import check_scenario
    from netsim.sweep.check import check_sweep

    file = tmp_path / name
    file.write_text(yaml.safe_dump(_sweep_on_shipped_base(data), sort_keys=False), encoding="utf-8")
    problems = check_sweep(file) if "sweep" in data else check_scenario(file)
    return [f"{p.path}: {p.message}" for p in problems if p.is_error]


def _schema_refuses(validator, data: dict[str, Any]) -> list[str]:
    return [f"{'.'.join(map(str, e.absolute_path))}: {e.message}" for e in validator.iter_errors(data)]


def test_the_corpus_has_at_least_30_mistakes_each_refused_by_validate(tmp_path):
    assert len(CORPUS) >= 30
    for case, name, mutate in CORPUS:
        data = _read(name)
        mutate(data)
        assert _validate_refuses(tmp_path, name, data), f"validate accepts the case {case!r}: not a mistake"


def test_the_schema_catches_at_least_90_percent_of_what_validate_catches(validator):
    missed = []
    for case, name, mutate in CORPUS:
        data = _read(name)
        mutate(data)
        if not _schema_refuses(validator, data):
            missed.append(case)
    caught = len(CORPUS) - len(missed)
    assert caught >= 0.9 * len(CORPUS), f"the schema caught {caught} of {len(CORPUS)}; missed {missed}"


def test_every_shipped_scenario_and_sweep_file_is_valid_under_the_schema(validator):
    files = sorted(SCENARIOS.glob("*.yaml"))
    assert len(files) >= 30
    for path in files:
        errors = _schema_refuses(validator, _read(path.name))
        assert errors == [], (path.name, errors[:5])


def _every_message(validator, data: dict[str, Any]) -> list[str]:
    """Every error message, those of the alternatives an ``anyOf`` tried included (what an editor lists)."""
    out, todo = [], list(validator.iter_errors(data))
    while todo:
        error = todo.pop()
        out.append(error.message)
        todo += list(error.context or [])
    return out


def test_a_scenario_s_mistake_is_not_also_reported_as_a_sweep_file_s_missing_keys(validator):
    data = _read(CAN)
    data["duraton"] = data.pop("duration")
    errors = _every_message(validator, data)
    assert errors and not any("sweep" in e for e in errors), errors
    sweep = _read(SWEEP)
    sweep["factor"] = sweep.pop("factors")
    errors = _every_message(validator, sweep)
    assert errors and not any("'duration'" in e or "'nodes'" in e for e in errors), errors


def test_the_one_dimensional_matrix_forms_validate_accepts_are_valid(tmp_path, validator):
    data = _read(SS)  # B: [0, 1000] is one column, C: [1, 0] one row
    assert isinstance(data["plant"]["B"][0], (int, float)) and isinstance(data["plant"]["C"][0], (int, float))
    data["plant"]["D"] = 0  # a scalar 0: zeros
    assert _validate_refuses(tmp_path, SS, copy.deepcopy(data)) == []
    assert _schema_refuses(validator, data) == []


def test_a_scenario_with_its_own_plugin_files_is_checked_at_its_top_level_only(validator):
    # names its plugin files register are unknown to the schema: no false positive on them, a top-level typo
    # is still refused
    data = _read(CAN)
    data["plugins"] = ["my_plugins.py"]
    data["nodes"]["sensor"]["tasks"][0]["program"] = "my_sampler"
    assert _schema_refuses(validator, data) == []
    data["duraton"] = data.pop("duration")
    assert _schema_refuses(validator, data)


def test_every_resolved_shipped_scenario_is_valid_under_the_schema(validator):
    # the resolved form (every default written out, times as text) is what a run folder's scenario.yaml holds
    from netsim.scenario import load_scenario

    for path in sorted(SCENARIOS.glob("*.yaml")):
        if "sweep" in _read(path.name):
            continue
        resolved = load_scenario(path, allow_plugins=True).resolved_dict()  # dc_servo_fmu loads an FMU
        errors = _schema_refuses(validator, resolved)
        assert errors == [], (path.name, errors[:5])
