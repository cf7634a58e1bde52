"""validate refuses a metric that reads a plant output no one records (no ``plant.record_grid``), as run would.

Before, hdd_case5 without ``plant.record_grid`` passed ``netsim validate`` and then ``netsim run`` exited 2 after
simulating ("et_control: signal 'y' was not recorded"): the plant records its outputs only on that grid.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from netsim.scenario import check_scenario, load_scenario
from netsim.scenario.problems import ScenarioError

ROOT = Path(__file__).resolve().parents[2]


def _servo(record_grid: str | None = None, record_as: str = "u_cmd", io_name: str = "ys") -> dict:
    plant = {"model": "dc_servo", "params": {"gain": 1000, "a": 1}}
    if record_grid is not None:
        plant["record_grid"] = record_grid
    return {
        "name": "grid_check", "duration": "0.05 s", "plant": plant,
        "io": {io_name: {"type": "adc", "output": 0}, "u": {"type": "dac", "input": 0}},
        "signals": {"r": {"type": "square", "amplitude": 1.0, "period": "1 s"}},
        "nodes": {"computer": {"policy": "fp", "tasks": [{
            "name": "pid", "program": "periodic_controller", "period": "6 ms", "priority": 1, "execution": "2 ms",
            "params": {"channel": io_name, "output_channel": "u", "reference": "r", "K": 0.96, "Ti": 0.12,
                       "Td": 0.049, "N": 10, "b": 0.5, "record_as": record_as}}]}},
        "metrics": [{"type": "control_error", "params": {"reference": "r", "output": "y"}}],
    }


def _errors(raw) -> dict[str, str]:
    return {p.path: p.message for p in check_scenario(raw) if p.is_error}


def test_a_metric_reading_a_plant_output_without_the_record_grid_is_refused_at_its_yaml_path():
    assert _errors(_servo()) == {
        "metrics[0].params.output": "metric 'control_error' reads the plant output 'y', which is recorded only on "
                                    "the plant's record grid, and 'plant:' sets no 'record_grid'; add e.g. "
                                    "'record_grid: 1 ms' under 'plant:'"}
    with pytest.raises(ScenarioError, match="sets no 'record_grid'"):
        load_scenario(_servo())


def test_the_record_grid_or_another_recorder_of_that_name_makes_it_valid():
    assert _errors(_servo(record_grid="1 ms")) == {}
    assert _errors(_servo(record_as="y")) == {}  # a program records under the name
    assert _errors(_servo(io_name="y")) == {}  # the ADC channel 'y' is recorded when read


def test_hdd_case5_without_its_record_grid_is_refused_with_the_metric_period_as_the_fix():
    problems = [p for p in check_scenario(ROOT / "scenarios" / "hdd_case5.yaml", {"plant.record_grid": None})
                if p.is_error]
    assert [(p.path, p.message) for p in problems] == [(
        "metrics[0].params.output",
        "metric 'et_control' reads the plant output 'y', which is recorded only on the plant's record grid, and "
        "'plant:' sets no 'record_grid'; add e.g. 'record_grid: 20 us' under 'plant:'")]
