"""The fuzzing's last disagreements (issue 31, second session): inputs ``validate`` passed that ``run`` refused, and
messages without a fix. Each is now refused by ``netsim validate`` at its YAML path, with what to change."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

from netsim.scenario import check_scenario
from netsim.scenario.loader import read_yaml

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"
MEASUREMENT = "nodes.controller.tasks[0].params.measurements[0]"


def _raw(name: str = "pendulum_network.yaml") -> dict[str, Any]:
    raw, _ = read_yaml(SCENARIOS / name)
    return copy.deepcopy(raw)


def _errors(raw: dict[str, Any]) -> dict[str, str]:
    return {p.path: p.message for p in check_scenario(raw) if p.severity == "error"}


def test_the_shipped_pendulum_network_scenario_is_valid() -> None:
    assert _errors(_raw()) == {}


def test_a_sensor_sending_fewer_values_than_the_controller_measures_is_refused() -> None:
    """Before: valid, and the run stopped at the first message ("sent 1 values, it measures 2 outputs")."""
    raw = _raw()
    raw["nodes"]["sensor"]["tasks"][0]["params"]["channels"] = ["theta_m"]  # alpha_m deleted
    errors = _errors(raw)
    assert MEASUREMENT in errors, errors
    message = errors[MEASUREMENT]
    assert "sends 1 value per message" in message and "measures 2 outputs" in message
    assert "nodes.sensor.tasks[0].params.channels" in message and "one channel per measured output" in message


def test_a_sensor_sending_to_another_tag_is_not_compared() -> None:
    """Only the sensor tasks whose messages the source takes (same network, receiver and tag) are compared."""
    raw = _raw()
    raw["nodes"]["sensor"]["tasks"].append({**copy.deepcopy(raw["nodes"]["sensor"]["tasks"][0]), "name": "other",
                                            "params": {"channels": ["theta_m"], "network": "sense",
                                                       "to": "controller", "tag": "other"}})
    assert MEASUREMENT not in _errors(raw)


def test_a_delay_mapping_without_dist_names_the_dist_values() -> None:
    """Before: "unable to extract tag using discriminator 'dist'", with no fix."""
    raw = _raw()
    raw["networks"]["act"]["delay"] = {"value": "1 ms"}
    message = _errors(raw)["networks.act.delay"]
    assert "'dist'" in message and "discriminator" not in message
    for name in ("constant", "uniform", "exponential", "shifted_gamma", "empirical"):
        assert name in message


def test_a_misspelt_measurement_sender_gets_a_did_you_mean() -> None:
    raw = _raw()
    raw["nodes"]["controller"]["tasks"][0]["params"]["measurements"][0]["sender"] = "sensr"
    message = _errors(raw)[f"{MEASUREMENT}.sender"]
    assert "did you mean 'sensor'?" in message


def test_validate_refuses_a_metric_that_needs_a_table_the_output_does_not_keep() -> None:
    """Before: validate passed it and run refused it (et_control reads the messages row by row)."""
    raw = _raw("hdd_case1.yaml")
    raw["output"] = {"messages": "summary"}
    message = _errors(raw)["output.messages"]
    assert "(et_control) reads the messages table row by row" in message and "set output.messages: full" in message


def test_the_latency_metric_with_summary_output_is_valid() -> None:
    """latency streams the rows it reads (netsim.metrics.chain)."""
    raw = _raw("dc_servo_can.yaml")
    raw["output"] = {"jobs": "summary", "messages": "summary"}
    assert _errors(raw) == {}
