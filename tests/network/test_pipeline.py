"""The pipeline every medium shares: padding, interface delays, stamping, broadcast, loss, bounds, stats."""

import pytest

from netsim.errors import ConfigError
from netsim.network import Message, make_network
from netsim.env import SimEnv
from netsim.timebase import MS, US

CAN3 = {"nodes": ["a", "b", "c"], "bitrate": "80 kbit/s", "min_frame_bits": 80}


def test_short_frames_are_padded_to_the_minimum_frame(bench):
    b = bench("can", CAN3)
    b.send_at(0, "a", "b", 8, tag="short")  # 8 bits padded to 80 -> 80 / 80 kbit/s = 1 ms
    b.send_at(5 * MS, "a", "b", 120, tag="long")  # 120 bits -> 1.5 ms
    b.run(20 * MS)
    assert b.deliveries("b") == [(1 * MS, "short"), (6500 * US, "long")]


def test_pre_and_post_delays_are_per_node(bench):
    params = {**CAN3, "pre_delay": "100 us", "post_delay": "50 us",
              "node_delays": {"b": {"post_delay": "200 us"}}}
    b = bench("can", params)
    b.send_at(0, "a", "b", 80, tag="ab")
    b.send_at(10 * MS, "a", "c", 80, tag="ac")
    b.run(30 * MS)
    # pre 0.1 ms + 1 ms on the bus + post (b: 0.2 ms override, c: 0.05 ms default)
    rec = b.record("ab")
    assert (rec.tx_start_ns, rec.tx_end_ns, rec.delivered_ns) == (100 * US, 1100 * US, 1300 * US)
    assert b.record("ac").delivered_ns == 10 * MS + 1150 * US
    assert rec.delay_ns == 1300 * US


def test_attach_overrides_interface_delays():
    env = SimEnv()
    net = make_network(env, "can", "can", CAN3)
    got = []

    class R:
        def deliver(self, network, msg):
            got.append((env.now, network))

    net.attach("a", R(), pre_delay=2 * MS)
    net.attach("b", R(), post_delay=3 * MS)

    def p():
        yield env.timeout(0)
        net.send(Message("a", "b", None, 80))

    env.process(p())
    env.run(20 * MS)
    assert got == [(6 * MS, "can")]  # 2 ms pre + 1 ms frame + 3 ms post


def test_send_stamps_network_time_id_and_per_pair_sequence():
    env = SimEnv()
    env.next_id("msg")  # someone else already took id 0
    net = make_network(env, "bus", "can", CAN3)
    got = []

    class R:
        def deliver(self, network, msg):
            got.append(msg)

    for n in CAN3["nodes"]:
        net.attach(n, R())
    sent = [Message("a", "b", i, 80) for i in range(3)] + [Message("a", "c", 9, 80)]

    def p():
        yield env.timeout(5 * US)
        for m in sent:
            net.send(m)

    env.process(p())
    env.run(20 * MS)
    assert [m.msg_id for m in sent] == [1, 2, 3, 4]
    assert [m.seq for m in sent] == [0, 1, 2, 0]  # separate counters per (sender, receiver)
    assert all(m.network == "bus" and m.sent_ns == 5 * US for m in sent)
    assert [m.payload for m in got] == [0, 1, 2, 9]
    assert all(m.delivered_ns is not None and m.tx_end_ns == m.delivered_ns for m in got)


def test_broadcast_reaches_every_other_attached_node_with_separate_copies(bench):
    b = bench("can", CAN3)
    b.send_at(0, "a", None, 80, tag="all")
    b.run(10 * MS)
    assert b.deliveries("a") == []
    assert b.deliveries("b") == [(1 * MS, "all")] and b.deliveries("c") == [(1 * MS, "all")]
    mb, mc = b.rx["b"].got[0][1], b.rx["c"].got[0][1]
    assert mb is not mc and mb.msg_id == mc.msg_id and (mb.receiver, mc.receiver) == ("b", "c")
    assert sorted(r.receiver for r in b.net.records) == ["b", "c"]
    # one frame on the bus for both copies
    assert b.net.metrics(10 * MS)["utilization"] == pytest.approx(0.1)


def test_lost_frames_still_use_the_medium(bench):
    b = bench("can", {**CAN3, "loss_probability": 1.0})
    for k in range(5):
        b.send_at(k * 2 * MS, "a", "b", 80)
    b.run(20 * MS)
    assert b.deliveries("b") == []
    m = b.net.metrics(20 * MS)
    assert m["dropped.lost"] == 5 and m["loss_rate"] == 1.0
    assert m["utilization"] == pytest.approx(5 * MS / (20 * MS))  # 5 frames of 1 ms each
    assert all(r.dropped and r.drop_reason == "lost" and r.tx_end_ns is not None for r in b.net.records)


def test_full_sender_queue_drops_and_reports_it(bench):
    b = bench("can", {**CAN3, "queue_limit": 3})
    for k in range(10):  # 10 frames in the same instant, only 3 fit in a's queue
        b.send_at(0, "a", "b", 80, tag=f"m{k}")
    b.run(20 * MS)
    assert [tag for _, tag in b.deliveries("b")] == ["m0", "m1", "m2"]
    m = b.net.metrics(20 * MS)
    assert m["dropped.queue_full"] == 7 and m["queue_max.a"] == 3
    assert {r.drop_reason for r in b.net.records if r.dropped} == {"queue_full"}


def test_overload_keeps_queues_bounded_and_shows_in_metrics(bench):
    # offered load 2x the capacity for 1 s: one 1 ms frame every 0.5 ms
    b = bench("can", {**CAN3, "queue_limit": 20})
    env, net = b.env, b.net

    def src():
        for _ in range(2000):
            net.send(Message("a", "b", None, 80))
            yield env.timeout(500 * US)

    env.process(src())
    env.run(1000 * MS)
    m = net.metrics(1000 * MS)
    assert m["queue_max.a"] == 20 and len(net.queues["a"]) <= 20
    assert m["dropped.queue_full"] > 900  # about half of the 2000 frames cannot be carried
    assert m["utilization"] == pytest.approx(1.0, abs=1e-3)
    assert m["delivered"] + m["dropped"] + m["in_flight"] == m["copies"] == 2000


def test_message_to_node_without_receiver_is_dropped():
    env = SimEnv()
    net = make_network(env, "n", "can", CAN3)
    net.attach("a", type("R", (), {"deliver": lambda self, n, m: None})())

    def p():
        yield env.timeout(0)
        net.send(Message("a", "c", None, 80))

    env.process(p())
    env.run(5 * MS)
    assert [r.drop_reason for r in net.records] == ["no_receiver"]


def test_metrics_agree_with_records_and_series(bench):
    b = bench("can", {**CAN3, "utilization_bin": "10 ms"})
    for k in range(4):
        b.send_at(k * 3 * MS, "a", "c", 80)
    b.send_at(25 * MS, "b", "c", 160)
    b.run(40 * MS)
    m = b.net.metrics(40 * MS)
    delays = [r.delay_ns for r in b.net.records]
    assert m["mean_delay_s"] == pytest.approx(sum(delays) / len(delays) / 1e9)
    assert m["max_delay_s"] == pytest.approx(max(delays) / 1e9)
    series = b.net.utilization_series(40 * MS)
    # bins [0,10): frames at 0,3,6,9 ms -> 4 ms busy; [10,20): none; [20,30): 2 ms frame at 25 ms
    assert series == [(0, 0.4), (10 * MS, 0.0), (20 * MS, 0.2), (30 * MS, 0.0)]
    assert m["utilization"] == pytest.approx(6 / 40)


def test_records_can_be_switched_off_without_losing_metrics(bench):
    b = bench("can", {**CAN3, "record_messages": False})
    b.send_at(0, "a", "b", 80)
    b.run(5 * MS)
    assert b.net.records == [] and b.net.metrics(5 * MS)["delivered"] == 1


# ------------------------------------------------------------------------------------------------ bad input
def _sender_raises(net_type, params, msg, match):
    env = SimEnv()
    net = make_network(env, "n", net_type, params)
    for n in params["nodes"]:
        net.attach(n, type("R", (), {"deliver": lambda self, a, b: None})())
    with pytest.raises(ConfigError, match=match):
        net.send(msg)


def test_unknown_receiver_is_an_error_naming_it():
    _sender_raises("can", CAN3, Message("a", "zz", None, 8), "unknown receiver 'zz'")


def test_sender_not_on_the_network_is_an_error():
    _sender_raises("can", CAN3, Message("zz", "a", None, 8), "sender 'zz' is not on this network")


def test_message_larger_than_the_medium_names_sender_and_size():
    _sender_raises("can", {**CAN3, "max_frame_bits": 128}, Message("b", "a", None, 200),
                   r"'b' sent a 200-bit message .* at most 128 bits")
    _sender_raises("can", {**CAN3, "frame_format": "standard"}, Message("b", "a", None, 72),
                   r"72-bit message .* at most 64 bits")
    _sender_raises("ethernet", {"nodes": ["a", "b"], "bitrate": "100 Mbit/s"}, Message("a", "b", None, 20000),
                   "at most 12144 bits")


def test_negative_size_is_an_error():
    _sender_raises("can", CAN3, Message("a", "b", None, -1), "bits")


@pytest.mark.parametrize(
    "type_name, params, match",
    [
        ("can", {**CAN3, "loss_probability": 1.5}, "loss_probability"),
        ("can", {**CAN3, "loss_probability": -0.1}, "loss_probability"),
        ("link", {"nodes": ["a", "b"], "loss": {"model": "bernoulli", "p": 2}}, r"loss\.bernoulli\.p"),
        ("link", {"nodes": ["a", "b"], "loss": {"model": "gilbert_elliott", "p_good_to_bad": 0.1,
                                                "p_bad_to_good": -1}}, "p_bad_to_good"),
        ("tdma", {**CAN3, "slot": "1 ms", "schedule": ["a", "x", None]}, r"schedule\[1\] names 'x'"),
        ("fdma", {**CAN3, "shares": {"a": 0.6, "b": 0.5}}, "sum to 1.1"),
        ("fdma", {**CAN3, "shares": {"q": 0.5}}, "'q' is not one of the network's nodes"),
        ("csma_cd", {**CAN3, "min_frame_bits": 0}, "min_frame_bits"),
        ("can", {**CAN3, "bitrate": "80 kbps/s"}, "bitrate"),
        ("can", {**CAN3, "typo_field": 1}, "typo_field"),
        ("can", {**CAN3, "node_delays": {"q": {"pre_delay": "1 ms"}}}, "node_delays"),
        ("can", {**CAN3, "nodes": ["a", "a"]}, "listed twice"),
    ],
)
def test_bad_parameters_are_config_errors_with_the_field(type_name, params, match):
    with pytest.raises(ConfigError, match=match) as info:
        make_network(SimEnv(), "net1", type_name, params)
    assert info.value.path == "networks.net1"


def test_unknown_network_type_suggests_a_name():
    with pytest.raises(ConfigError, match="did you mean 'tdma'"):
        make_network(SimEnv(), "n", "tdmaa", CAN3)


def test_attaching_a_node_not_on_the_network_is_an_error():
    net = make_network(SimEnv(), "n", "can", CAN3)
    with pytest.raises(ConfigError, match="not in the network's nodes"):
        net.attach("zz", type("R", (), {"deliver": lambda self, a, b: None})())


def test_params_model_instances_are_accepted():
    from netsim.network.can import CanBus

    p = CanBus.Params(nodes=["a", "b"], bitrate="1 Mbit/s", pre_delay="3 us")
    net = make_network(SimEnv(), "n", "can", p)
    assert net.params is p and net.params.pre_delay == 3 * US


@pytest.mark.parametrize("type_name", ["link", "ideal", "can", "tdma", "csma_cd", "ethernet", "round_robin", "fdma"])
def test_params_round_trip_through_their_json_dump(type_name):
    # the resolved scenario.yaml holds model_dump(mode="json"); reading it back must give the same params
    from netsim.network import network_class

    extra = {"tdma": {"slot": "1 ms", "schedule": ["a", None, "b"]}, "fdma": {"shares": [0.2, 0.3, 0.5]},
             "link": {"delay": {"dist": "shifted_gamma", "shape": 2, "scale": "1 ms"},
                      "loss": {"model": "gilbert_elliott", "p_good_to_bad": 0.1, "p_bad_to_good": 0.5}}}
    P = network_class(type_name).Params
    p = P.model_validate({**CAN3, "pre_delay": "1.5 us", **extra.get(type_name, {})})
    assert P.model_validate(p.model_dump(mode="json")) == p


def test_framing_is_computed_per_size_and_sender_and_an_oversized_message_fails_every_time():
    env = SimEnv()
    net = make_network(env, "n", "fdma", {"nodes": ["a", "b", "c"], "bitrate": "100 kbit/s",
                                          "shares": {"a": 0.5, "b": 0.25}, "max_frame_bits": 1000})
    for n in ("a", "b", "c"):
        net.attach(n, type("R", (), {"deliver": lambda self, a, b: None})())
    for _ in range(2):  # the second send of each size and sender uses what the first computed
        for sender in ("a", "b"):
            for bits in (100, 300):
                net.send(Message(sender, "c", None, bits))
    env.run(100 * MS)
    tx = {(r.sender, r.bits): r.tx_end_ns - r.tx_start_ns for r in net.records}
    # bits / (share * 100 kbit/s), in ns
    assert tx == {("a", 100): 2 * MS, ("a", 300): 6 * MS, ("b", 100): 4 * MS, ("b", 300): 12 * MS}
    for _ in range(2):  # an oversized message is refused each time, never remembered as a size that was fine
        with pytest.raises(ConfigError, match="at most 1000 bits"):
            net.send(Message("a", "c", None, 2000))
