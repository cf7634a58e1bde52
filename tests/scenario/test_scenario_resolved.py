"""The resolved scenario (every default filled, times as text) and the scenario hash."""

from __future__ import annotations

import hashlib
import json

import pytest
import yaml

from netsim.scenario import dump_resolved, load_scenario, resolved_dict, scenario_hash
from netsim.timebase import MS


def test_resolved_dict_fills_defaults_and_writes_times_as_text(base):
    data = load_scenario(base()).resolved_dict()
    task = data["nodes"]["sensor"]["tasks"][0]
    assert task["period"] == "10 ms" and task["deadline"] == "10 ms" and task["release"] == "periodic"
    assert task["params"] == {"channel": "y", "network": "bus", "to": "controller", "bits": 80, "hold": "0 ns"}
    assert data["networks"]["bus"] == {
        "type": "zzt_bus", "nodes": ["sensor", "controller", "actuator"], "bitrate": 80000.0,
        "min_frame_bits": 0, "slot": None,
    }
    assert data["signals"]["r"] == {"type": "zzt_step", "value": 0.5, "at": "100 ms"}
    assert data["plant"]["params"] == {"gain": 2.0, "pole": 1.0}
    assert data["seed"] == 0 and data["output"] == {"dir": None, "plot": False}
    assert resolved_dict(load_scenario(base())) == data


def test_resolved_scenario_loads_back_equal(tmp_path, base):
    sc = load_scenario(base())
    path = tmp_path / "resolved.yaml"
    path.write_text(dump_resolved(sc))
    again = load_scenario(path)
    assert again.resolved_dict() == sc.resolved_dict()
    assert again.nodes["sensor"].tasks[0].period == 10 * MS
    assert yaml.safe_load(path.read_text()) == sc.resolved_dict()  # plain YAML any reader understands


def test_hash_is_sha256_of_the_canonical_resolved_json_without_output(base):
    sc = load_scenario(base())
    data = sc.resolved_dict()
    del data["output"]
    expected = hashlib.sha256(json.dumps(data, sort_keys=True, separators=(",", ":")).encode()).hexdigest()
    assert scenario_hash(sc) == expected


def test_hash_ignores_spelling_defaults_key_order_and_output(base):
    reference = scenario_hash(base())
    raw = base()
    raw["nodes"]["sensor"]["tasks"][0]["period"] = "0.01 s"
    raw["nodes"]["sensor"]["tasks"][0]["deadline"] = "10000 us"  # = the default (the period)
    raw["nodes"]["sensor"]["tasks"][0]["params"]["bits"] = 80  # = the program's default
    raw["seed"] = 0
    raw["output"] = {"dir": "elsewhere/case1", "plot": True}
    raw = dict(reversed(list(raw.items())))
    assert scenario_hash(raw) == reference
    assert scenario_hash(load_scenario(base())) == reference


@pytest.mark.parametrize(
    ("path", "value"),
    [
        ("seed", 1),
        ("nodes.sensor.tasks[0].params.bits", 81),
        ("nodes.sensor.tasks[0].period", "10.001 ms"),
        ("networks.bus.bitrate", "81 kbit/s"),
        ("description", "other"),
    ],
)
def test_hash_changes_with_anything_that_can_change_results(path, value, base):
    assert scenario_hash(load_scenario(base(), overrides={path: value})) != scenario_hash(base())


def test_resolved_times_keep_every_nanosecond(base):
    sc = load_scenario(base(), overrides={"duration": "1.0000005 s"})
    assert load_scenario(sc.resolved_dict()).duration == 1_000_000_500
