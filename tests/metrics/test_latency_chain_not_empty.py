"""The ``latency`` metric's chain needs at least one task, from Python as from YAML (fuzz figures: a direct
``LatencyParams(chain=[])`` was accepted, and the metric then reported 'worst -')."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from pydantic import ValidationError

from netsim.metrics.runtime import LatencyParams
from netsim.scenario.loader import check_scenario

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "dc_servo_can.yaml"


def test_a_direct_call_with_an_empty_chain_is_refused_with_what_to_list():
    with pytest.raises(ValidationError, match="list the tasks of the chain as 'node.task'"):
        LatencyParams(chain=[])


def test_the_schema_of_the_chain_asks_for_one_task_at_least():
    assert LatencyParams.model_json_schema()["properties"]["chain"]["minItems"] == 1


def test_yaml_gives_one_message_at_the_chain_path():
    raw = yaml.safe_load(SCENARIO.read_text())
    (i,) = [i for i, m in enumerate(raw["metrics"]) if m["type"] == "latency"]
    raw["metrics"][i]["params"]["chain"] = []
    errs = [(p.path, p.message) for p in check_scenario(raw) if p.severity == "error"]
    assert errs == [(f"metrics[{i}].params.chain", "'chain' is empty; list the tasks of the chain as 'node.task', "
                                                   "e.g. [sensor.sample, controller.control]")]
