"""Dotted paths into raw scenario data (``nodes.sensor.tasks[0].period``)."""

from __future__ import annotations

import pytest

from netsim.errors import ConfigError
from netsim.scenario.paths import format_path, get_path, parse_override, parse_path, parse_value, set_path


def _raw() -> dict:
    return {
        "networks": {"can": {"bitrate": "80 kbit/s", "nodes": ["a", "b"]}},
        "nodes": {"sensor": {"tasks": [{"name": "sample", "period": "10 ms"}, {"name": "log"}]}},
        "plant": {"model": "m"},
    }


def test_parse_path_splits_keys_and_indices():
    assert parse_path("nodes.sensor.tasks[1].params.sigma_s") == ["nodes", "sensor", "tasks", 1, "params", "sigma_s"]
    assert parse_path("metrics[0]") == ["metrics", 0]
    assert parse_path("plant.x0[1][0]") == ["plant", "x0", 1, 0]


@pytest.mark.parametrize("bad", ["", "a..b", "a.", "a[", "a[]", ".a"])
def test_parse_path_rejects_malformed_paths(bad):
    with pytest.raises(ConfigError):
        parse_path(bad)


def test_format_path_inverts_parse_path():
    text = "nodes.sensor.handlers[0].params.delta_s"
    assert format_path(parse_path(text)) == text


def test_get_path_reads_nested_values():
    assert get_path(_raw(), "nodes.sensor.tasks[0].period") == "10 ms"
    assert get_path(_raw(), "networks.can.nodes[1]") == "b"


def test_get_path_suggests_the_closest_key():
    with pytest.raises(ConfigError) as info:
        get_path(_raw(), "netwroks.can.bitrate")
    assert info.value.message == "no key 'netwroks' in 'the top level'; did you mean 'networks'?"
    assert info.value.path == "netwroks.can.bitrate"


def test_get_path_suggests_the_index_for_a_named_list_item():
    with pytest.raises(ConfigError) as info:
        get_path(_raw(), "nodes.sensor.tasks[log].name")
    assert info.value.message == (
        "list items are addressed by index; did you mean 'nodes.sensor.tasks[1]' (the item named 'log')?"
    )


def test_get_path_reports_index_out_of_range():
    with pytest.raises(ConfigError) as info:
        get_path(_raw(), "nodes.sensor.tasks[5]")
    assert info.value.message == "index 5 out of range: 'nodes.sensor.tasks' has 2 item(s)"


def test_set_path_replaces_existing_values_in_place():
    raw = _raw()
    set_path(raw, "nodes.sensor.tasks[0].period", "5 ms")
    set_path(raw, "networks.can.nodes[0]", "z")
    assert raw["nodes"]["sensor"]["tasks"][0]["period"] == "5 ms"
    assert raw["networks"]["can"]["nodes"] == ["z", "b"]


def test_set_path_creates_missing_keys_for_defaulted_parameters():
    raw = _raw()
    set_path(raw, "plant.params.gain", 3.0)
    set_path(raw, "nodes.sensor.tasks[1].period", "1 ms")
    assert raw["plant"]["params"] == {"gain": 3.0}
    assert raw["nodes"]["sensor"]["tasks"][1]["period"] == "1 ms"


def test_set_path_treats_a_near_miss_intermediate_key_as_a_typo():
    raw = _raw()
    with pytest.raises(ConfigError) as info:
        set_path(raw, "nodes.sensr.tasks[0].period", "1 ms")
    assert info.value.message == "no key 'sensr' in 'nodes'; did you mean 'sensor'?"
    assert "sensr" not in raw["nodes"]


def test_set_path_never_creates_list_items():
    with pytest.raises(ConfigError):
        set_path(_raw(), "nodes.sensor.tasks[2].period", "1 ms")


@pytest.mark.parametrize(
    ("text", "value"),
    [("1 Mbit/s", "1 Mbit/s"), ("0.5", 0.5), ("7", 7), ("[1, 0]", [1, 0]), ("{a: 1}", {"a": 1}),
     ("null", None), ("true", True), ("1e-3", 0.001), ("10 ms", "10 ms")],
)
def test_parse_value_reads_yaml_scalars_and_flow_collections(text, value):
    assert parse_value(text) == value


def test_parse_override_splits_at_the_first_equals_sign():
    assert parse_override("plant.x0=[1,0]") == ("plant.x0", [1, 0])
    assert parse_override("a.b=x=y") == ("a.b", "x=y")


def test_parse_override_without_equals_sign_is_an_error():
    with pytest.raises(ConfigError) as info:
        parse_override("plant.x0")
    assert "write key.path=value" in info.value.message
