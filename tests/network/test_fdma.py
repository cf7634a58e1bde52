"""FDMA: each sender at its share of the bit rate, no interference, weighted utilization."""

import pytest

from netsim.env import SimEnv
from netsim.errors import ConfigError
from netsim.network import Message, make_network
from netsim.timebase import MS

P = {"nodes": ["a", "b", "c"], "bitrate": "100 kbit/s"}


def test_senders_use_their_share_of_the_bandwidth_in_parallel(bench):
    b = bench("fdma", {**P, "shares": {"a": 0.5, "b": 0.25}})
    b.send_at(0, "a", "c", 100, tag="x")  # 100 bits at 50 kbit/s = 2 ms
    b.send_at(0, "b", "c", 100, tag="y")  # 100 bits at 25 kbit/s = 4 ms
    b.send_at(0, "a", "c", 100, tag="z")  # after x on a's own channel: 2..4 ms
    b.run(20 * MS)
    assert b.deliveries("c") == [(2 * MS, "x"), (4 * MS, "y"), (4 * MS, "z")]
    m = b.net.metrics(20 * MS)
    # a busy 4 ms with 1/2 of the bandwidth, b busy 4 ms with 1/4: (0.5 * 4 + 0.25 * 4) / 20
    assert m["utilization"] == pytest.approx(0.15)


def test_default_shares_are_equal_and_lists_follow_the_node_order(bench):
    b = bench("fdma", P)
    b.send_at(0, "c", "a", 100, tag="x")  # 1/3 of 100 kbit/s -> 3 ms
    b.run(10 * MS)
    assert b.record("x").tx_end_ns == 3 * MS
    b = bench("fdma", {**P, "shares": [0.2, 0.3, 0.5]})
    b.send_at(0, "b", "a", 300, tag="y")  # 30 kbit/s -> 10 ms
    b.run(20 * MS)
    assert b.record("y").tx_end_ns == 10 * MS


def test_sender_without_share_is_an_error():
    net = make_network(SimEnv(), "f", "fdma", {**P, "shares": {"a": 1.0}})
    with pytest.raises(ConfigError, match="'b' sends but has no bandwidth share"):
        net.send(Message("b", "a", None, 10))


def test_shares_above_one_are_rejected():
    with pytest.raises(ConfigError, match="must sum to at most 1"):
        make_network(SimEnv(), "f", "fdma", {**P, "shares": [0.5, 0.5, 0.5]})
