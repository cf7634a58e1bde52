"""Node mobility on a radio channel (issue 20): piecewise-linear paths and constant velocities."""

import math
from pathlib import Path

import pytest

from netsim.env import SimEnv
from netsim.errors import ConfigError
from netsim.network import make_network
from netsim.network.mobility import Motion, Track
from netsim.timebase import S

#: 0 dBm, exponent 3.5, -85 dBm decode threshold: range 10 ** (85 / 35) m
RANGE_M = 10.0 ** (85.0 / 35.0)


def test_a_path_is_followed_in_straight_lines_at_constant_speed_then_held():
    track = Track((0.0, 0.0), Motion.model_validate({"path": {"10 s": [100, 0], "20 s": [100, 50]}}))
    assert track.at(0) == (0.0, 0.0)
    assert track.at(5 * S) == pytest.approx((50.0, 0.0))
    assert track.at(15 * S) == pytest.approx((100.0, 25.0))
    assert track.at(30 * S) == (100.0, 50.0)


def test_a_velocity_moves_the_node_from_its_start():
    track = Track((1.0, 1.0), Motion.model_validate({"velocity": [2, -1]}))
    assert track.at(3 * S) == pytest.approx((7.0, -2.0))


def _broadcasts_received(mobility, until_s=40):
    env = SimEnv()
    net = make_network(env, "n", "802.15.4", {"nodes": ["a", "b"], "positions": {"a": [0, 0], "b": [10, 0]},
                                              "acks": False, "mobility": mobility})
    got = []
    net.attach("a", type("R", (), {"deliver": lambda self, n, m: None})())
    net.attach("b", type("R", (), {"deliver": lambda self, n, m: got.append(env.now)})())
    from netsim.network import Message

    def proc():
        for k in range(until_s):
            net.send(Message("a", None, None, 64, tag=str(k)))
            yield env.timeout(1 * S)

    env.process(proc())
    env.run(until_s * S)
    return net, got


def test_a_node_driving_away_stops_receiving_when_it_leaves_the_range():
    net, got = _broadcasts_received({"b": {"velocity": [10, 0]}})
    # independent: a copy ends at t (its last bit); b is at 10 + 10 t metres then; received iff within range
    ends = [r.tx_end_ns for r in net.records]
    expected = [t for t in ends if 10.0 + 10.0 * t / S <= RANGE_M]
    assert got == expected
    assert 20 < len(got) < 30  # it leaves the 269 m range after about 26 s
    assert net.position("b")[0] == pytest.approx(10.0 + 10.0 * 40)


def test_a_path_out_and_back_loses_then_regains_the_link():
    net, got = _broadcasts_received({"b": {"path": {"10 s": [1000, 0], "20 s": [1000, 0], "30 s": [10, 0]}}})

    def x(t):  # the path by hand
        s = t / S
        if s <= 10:
            return 10 + 99 * s
        if s <= 20:
            return 1000.0
        if s <= 30:
            return 1000 - 99 * (s - 20)
        return 10.0

    expected = [r.tx_end_ns for r in net.records if x(r.tx_end_ns) <= RANGE_M]
    assert got == expected
    assert any(t < 10 * S for t in got) and any(t > 30 * S for t in got) and not any(12 * S < t < 28 * S for t in got)


@pytest.mark.parametrize("mobility, message", [
    ({"b": {"velocity": [1, 0], "path": {"1 s": [0, 0]}}}, "exactly one of 'path'"),
    ({"b": {}}, "exactly one of 'path'"),
    ({"b": {"path": {0: [5, 0]}}}, "after 0 s"),
    ({"b": {"path": {}}}, "at least one waypoint"),
    ({"z": {"velocity": [1, 0]}}, r"mobility: \['z'\] not in the network's nodes"),
    ({"b": {"velocity": [1, 0, 0]}}, "velocity"),
])
def test_bad_mobility_is_named(mobility, message):
    with pytest.raises(ConfigError, match=message):
        make_network(SimEnv(), "n", "802.15.4", {"nodes": ["a", "b"], "positions": {"a": [0, 0], "b": [1, 0]},
                                                 "mobility": mobility})


def test_set_position_ends_a_nodes_motion():
    env = SimEnv()
    net = make_network(env, "n", "802.11b", {"nodes": ["a", "b"], "positions": {"a": [0, 0], "b": [1, 0]},
                                             "mobility": {"b": {"velocity": [5, 0]}}})
    env.run(2 * S)
    assert net.position("b") == pytest.approx((11.0, 0.0))
    net.set_position("b", 3.0, 4.0)
    env.run(4 * S)
    assert net.position("b") == (3.0, 4.0)
    assert net.received_power_dbm("a", "b") == pytest.approx(20.0 - 35.0 * math.log10(5.0))


@pytest.mark.parametrize("change, path, text", [
    ({"mobility": {"sensor": {"path": {0: [1, 1]}}}}, "networks.bus.mobility.sensor", "after 0 s"),
    ({"mobility": {"sensor": {"velocity": [1, "fast"]}}}, "networks.bus.mobility.sensor.velocity[1]", ""),
    ({"mobility": {"ghost": {"velocity": [1, 0]}}}, "networks.bus", "mobility: ['ghost'] not in the network's nodes"),
    ({"carrier_sense_dbm": "loud"}, "networks.bus.carrier_sense_dbm", ""),
])
def test_bad_radio_fields_in_a_scenario_are_refused_at_their_yaml_path_by_validate(tmp_path, change, path, text):
    import yaml

    from netsim.cli import main
    from netsim.scenario import load_scenario
    from netsim.scenario.problems import ScenarioError

    root = Path(__file__).resolve().parents[2]
    raw = yaml.safe_load((root / "scenarios" / "wireless_battery.yaml").read_text(encoding="utf-8"))
    raw["networks"]["bus"].update(change)
    with pytest.raises(ScenarioError) as info:
        load_scenario(raw)
    found = [(p.path, p.message) for p in info.value.problems]
    assert any(p == path and text in m for p, m in found), found
    file = tmp_path / "bad.yaml"
    file.write_text(yaml.safe_dump(raw), encoding="utf-8")
    assert main(["validate", str(file)]) == 1
