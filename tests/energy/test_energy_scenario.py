"""Energy from YAML (issue 20): nodes.<n>.energy in a scenario, its metrics, and what validate and run refuse."""

from __future__ import annotations

import copy
import math
from pathlib import Path

import pytest
import yaml

import netsim
from netsim.cli import main
from netsim.scenario import load_scenario
from netsim.scenario.problems import ScenarioError

ROOT = Path(__file__).resolve().parents[2]

BASE = {
    "name": "cpu_battery",
    "duration": "1 s",
    "nodes": {"n": {"policy": "fp",
                    "energy": {"cpu": {"busy": "1 W", "idle": "100 mW"}, "battery": {"capacity": "99 mJ"}},
                    "tasks": [{"name": "T", "program": "idle", "period": "10 ms", "execution": "2 ms",
                               "priority": 1}]}},
}


def test_a_battery_node_from_yaml_reports_its_energy_and_when_it_ran_out():
    result = netsim.run(copy.deepcopy(BASE), write=False)
    m = result.metrics
    # by hand: 2.8 mJ per 10 ms period (2 ms at 1 W, 8 ms at 0.1 W); 35 periods use 98 mJ, the last 1 mJ takes
    # 1 ms at 1 W: empty at 351 ms; job 35 is killed then, no job after it
    assert m["energy.n.depleted_s"] == pytest.approx(0.351, abs=1e-8)
    assert m["energy.n.J"] == pytest.approx(0.099, abs=1e-9)
    assert (m["task.n.T.jobs"], m["task.n.T.killed"]) == (36, 1)
    assert m["energy.n.cpu_busy_s"] == pytest.approx(35 * 0.002 + 0.001)


def test_a_node_without_a_battery_only_reports_its_energy():
    raw = copy.deepcopy(BASE)
    del raw["nodes"]["n"]["energy"]["battery"]
    m = netsim.run(raw, write=False).metrics
    assert m["energy.n.J"] == pytest.approx(0.2 * 1.0 + 0.8 * 0.1)
    assert "energy.n.depleted_s" not in m


def test_a_scenario_without_energy_models_has_no_energy_metrics_and_resolves_without_the_key():
    raw = copy.deepcopy(BASE)
    del raw["nodes"]["n"]["energy"]
    assert not any(k.startswith("energy.") for k in netsim.run(raw, write=False).metrics.index)
    assert "energy" not in load_scenario(raw).resolved_dict()["nodes"]["n"]


def test_the_resolved_energy_model_loads_back_equal():
    sc = load_scenario(copy.deepcopy(BASE))
    again = load_scenario(sc.resolved_dict())
    assert again.resolved_dict() == sc.resolved_dict()
    assert again.nodes["n"].energy.battery.capacity == pytest.approx(0.099)


def _problems(raw):
    with pytest.raises(ScenarioError) as info:
        load_scenario(raw)
    return [(p.path, p.message) for p in info.value.problems]


@pytest.mark.parametrize("energy, path, text", [
    ({}, "nodes.n.energy", "give 'cpu' and/or 'radio'"),
    ({"cpu": {"busy": "5 parsecs"}}, "nodes.n.energy.cpu.busy", "unknown power unit 'parsecs'"),
    ({"cpu": {"busy": -1}}, "nodes.n.energy.cpu.busy", "finite number >= 0"),
    ({"cpu": {"busy": "1 W", "turbo": "2 W"}}, "nodes.n.energy.cpu.turbo", ""),
    ({"cpu": {"busy": "1 W"}, "battery": {"capacity": 0}}, "nodes.n.energy.battery.capacity", ""),
    ({"radio": {"tx": "1 mW", "rx": "1 mW", "idle": "1 mW"}}, "nodes.n.energy.radio", "on no wireless network"),
    ({"radio": {"tx": "1 mW", "rx": "1 mW", "idle": "1 mW", "listen": "sometimes"}}, "nodes.n.energy.radio.listen",
     ""),
])
def test_bad_energy_models_are_refused_at_their_yaml_path_by_validate_and_run(tmp_path, energy, path, text):
    raw = copy.deepcopy(BASE)
    raw["nodes"]["n"]["energy"] = energy
    problems = _problems(raw)
    assert any(p == path and text in msg for p, msg in problems), problems
    file = tmp_path / "bad.yaml"
    file.write_text(yaml.safe_dump(raw), encoding="utf-8")
    assert main(["validate", str(file)]) == 1
    with pytest.raises(ScenarioError):
        netsim.run(file, write=False)


def test_the_shipped_battery_scenario_runs_out_after_the_sensor_left_the_range():
    result = netsim.run(ROOT / "scenarios" / "wireless_battery.yaml", write=False)
    m = result.metrics
    # the sensor leaves the 269 m range (0 dBm, exponent 3.5, -85 dBm) at 1 s + (10 ** (85 / 35) - 10) / 50 s
    leaves = 1.0 + (10 ** (85 / 35) - 10) / 50.0
    assert leaves < m["energy.sensor.depleted_s"] < 8.0
    assert m["energy.sensor.J"] == pytest.approx(0.2, abs=1e-9)
    assert m["net.bus.dropped.no_ack"] > 0
    # energy = power x time in each state, summed by hand from the reported times
    cpu = 0.030 * m["energy.sensor.cpu_busy_s"] + 0.003 * (m["energy.sensor.depleted_s"] - m["energy.sensor.cpu_busy_s"])
    radio = (0.052 * m["energy.sensor.radio_tx_s"] + 0.056 * (m["energy.sensor.radio_rx_s"] + m["energy.sensor.radio_idle_s"])
             + 60e-6 * m["energy.sensor.radio_sleep_s"])
    assert m["energy.sensor.cpu_J"] == pytest.approx(cpu, rel=1e-9)
    assert m["energy.sensor.radio_J"] == pytest.approx(radio, rel=1e-9)
    states = sum(m[f"energy.sensor.radio_{k}_s"] for k in ("tx", "rx", "idle", "sleep"))
    assert states == pytest.approx(m["energy.sensor.depleted_s"], abs=1e-9)  # the radio's states cover its life
    assert math.isnan(m.get("energy.controller.depleted_s", math.nan))


def test_a_radio_that_sleeps_between_its_own_frames_cannot_be_a_receiver():
    raw = yaml.safe_load((ROOT / "scenarios" / "wireless_battery.yaml").read_text(encoding="utf-8"))
    raw["nodes"]["controller"]["energy"]["radio"]["listen"] = "own_frames"
    problems = _problems(raw)
    assert any(p == "nodes.controller.energy.radio.listen" and "task 'control' is released by messages" in m
               for p, m in problems), problems
