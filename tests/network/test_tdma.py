"""TDMA: slots, resumption of long frames in the owner's next slot, utilization of the schedule."""

import pytest

from netsim.env import SimEnv
from netsim.errors import ConfigError
from netsim.network import Message, make_network
from netsim.timebase import MS, US

NODES = ["a", "b", "c"]
RATE = 80_000  # 80 kbit/s: 1 ms per 80 bits


def test_frame_longer_than_a_slot_completes_in_the_owners_next_slot(bench):
    # slot 1 ms, schedule a | b | c (cycle 3 ms). A 120-bit frame of a needs 1.5 ms: 1 ms in slot [0, 1),
    # the remaining 0.5 ms in a's next slot [3, 4) -> done at 3.5 ms. b's frame fits in its slot [1, 2).
    b = bench("tdma", {"nodes": NODES, "bitrate": RATE, "slot": "1 ms", "schedule": ["a", "b", "c"]})
    b.send_at(0, "a", "c", 120, tag="long")
    b.send_at(0, "b", "c", 80, tag="fits")
    b.run(10 * MS)
    long = b.record("long")
    assert (long.tx_start_ns, long.tx_end_ns) == (0, 3500 * US)
    assert b.deliveries("c") == [(2 * MS, "fits"), (3500 * US, "long")]


def test_frame_waits_for_its_slot_and_slots_can_be_given_in_bits(bench):
    # slot_bits 40 at 80 kbit/s = 0.5 ms; schedule [a, idle, b]: b owns [1.0, 1.5) ms of each 1.5 ms cycle
    b = bench("tdma", {"nodes": NODES, "bitrate": RATE, "slot_bits": 40, "schedule": ["a", None, "b"]})
    b.send_at(200 * US, "b", "a", 40, tag="x")  # 0.5 ms frame, fits exactly in one slot
    b.send_at(1200 * US, "b", "a", 40, tag="y")  # arrives inside b's slot [1.0, 1.5) with 0.3 ms left
    b.run(10 * MS)
    x, y = b.record("x"), b.record("y")
    assert (x.tx_start_ns, x.tx_end_ns) == (1000 * US, 1500 * US)
    # y waits for x, which fills b's slot, and goes in b's next slot [2.5, 3.0) ms
    assert (y.tx_start_ns, y.tx_end_ns) == (2500 * US, 3000 * US)


def test_frame_arriving_inside_the_owners_slot_starts_at_once(bench):
    b = bench("tdma", {"nodes": NODES, "bitrate": RATE, "slot_bits": 40, "schedule": ["a", None, "b"]})
    b.send_at(4200 * US, "b", "a", 40, tag="z")  # b's slot [4.0, 4.5) ms has 0.3 ms left
    b.run(10 * MS)
    z = b.record("z")
    # 0.3 ms now, the remaining 0.2 ms in b's next slot [5.5, 6.0) ms
    assert (z.tx_start_ns, z.tx_end_ns) == (4200 * US, 5700 * US)


def test_utilization_equals_the_share_of_owned_slots_when_saturated(bench):
    # schedule a | b | idle | a: 3 of 4 slots owned; with full queues the medium is busy 3/4 of the time
    b = bench("tdma", {"nodes": NODES, "bitrate": RATE, "slot": "1 ms", "schedule": ["a", "b", None, "a"],
                       "queue_limit": 5, "utilization_bin": "8 ms"})
    env, net = b.env, b.net

    def flood(node):
        while True:
            for _ in range(5 - len(net.queues[node])):
                net.send(Message(node, "c", None, 56))  # 0.7 ms frames: they straddle slot edges
            yield env.timeout(100 * US)

    env.process(flood("a"))
    env.process(flood("b"))
    env.run(400 * MS)
    m = net.metrics(400 * MS)
    assert m["utilization"] == pytest.approx(3 / 4, abs=1e-6)
    assert m["schedule_share"] == 3 / 4
    # bins of two 4 ms cycles each: every bin is 3/4 busy
    series = [v for _, v in net.utilization_series(400 * MS)]
    assert len(series) == 50 and all(v == pytest.approx(0.75, abs=1e-9) for v in series)


def test_sender_without_a_slot_is_an_error():
    net = make_network(SimEnv(), "t", "tdma", {"nodes": NODES, "bitrate": RATE, "slot": "1 ms",
                                               "schedule": ["a", "b"]})
    with pytest.raises(ConfigError, match="'c' sends but owns no slot"):
        net.send(Message("c", "a", None, 10))


def test_slot_or_slot_bits_exactly_one():
    with pytest.raises(ConfigError, match="exactly one of slot"):
        make_network(SimEnv(), "t", "tdma", {"nodes": NODES, "bitrate": RATE, "schedule": ["a"]})
