"""Wireless media (802.15.4 and 802.11b): path loss, range, interference, CSMA/CA timing, ACKs and retries."""

import math

import numpy as np
import pytest

from netsim.errors import ConfigError
from netsim.network import Message, make_network
from netsim.network.wireless import received_dbm
from netsim.env import SimEnv, stream_seed
from netsim.timebase import MS, US


def _line(*xs):
    """Nodes a, b, c ... on the x axis at the given abscissas (metres)."""
    names = [chr(ord("a") + i) for i in range(len(xs))]
    return {"nodes": names, "positions": {n: [x, 0.0] for n, x in zip(names, xs)}}


def _backoff_stream(seed, name="net"):
    """The network's backoff stream, drawn independently of the network (same seed and stream name)."""
    return np.random.Generator(np.random.PCG64(stream_seed(seed, f"network.{name}.backoff")))


def test_received_power_follows_log_distance_path_loss():
    # P_rx = P_tx - 10 a log10(d / d0): 20 dBm at 100 m with a = 3 loses 60 dB
    assert received_dbm(20.0, 100.0, 3.0) == pytest.approx(-40.0)
    assert received_dbm(20.0, 0.5, 3.0) == 20.0  # closer than d0 = 1 m: no loss
    env = SimEnv()
    net = make_network(env, "n", "802.11b", {**_line(0, 30), "path_loss_exponent": 2.0})
    assert net.received_power_dbm("a", "b") == pytest.approx(20.0 - 20.0 * math.log10(30.0))


def test_802154_unicast_on_an_idle_channel_takes_backoff_cca_turnaround_and_frame(bench):
    b = bench("802.15.4", _line(0, 10), seed=3)
    b.send_at(0, "a", "b", 64, tag="x")
    b.run(50 * MS)
    # independent computation: slots in 0..2**3-1 from the backoff stream, 320 us each; CCA 128 us;
    # turnaround 192 us; frame = 192 us PHY overhead + (64 + 88 MAC bits) at 250 kbit/s = 608 us
    slots = int(_backoff_stream(3).integers(0, 8))
    start = slots * 320 * US + 128 * US + 192 * US
    assert b.record("x").tx_start_ns == start
    assert b.deliveries("b") == [(start + 192 * US + 608 * US, "x")]
    m = b.net.metrics(50 * MS)
    assert (m["attempts"], m["acks"], m["retransmissions"]) == (1.0, 1.0, 0.0)


def test_80211b_frame_on_an_idle_medium_goes_at_once_and_lasts_preamble_plus_bits(bench):
    b = bench("802.11b", _line(0, 10))
    b.send_at(1 * MS, "a", "b", 1000, tag="x")
    b.run(20 * MS)
    # the medium was idle for more than DIFS: immediate access; 192 us + (1000 + 272) bits / 11 Mbit/s
    tx = 192 * US + math.ceil((1000 + 272) * 1e9 / 11e6)
    assert b.deliveries("b") == [(1 * MS + tx, "x")]


def test_a_node_beyond_range_gets_no_broadcast_and_a_unicast_to_it_is_retried_then_dropped(bench):
    # 0 dBm, a = 3.5, threshold -85 dBm: range 10**(85 / 35) = 269 m; c at 400 m is out of range
    b = bench("802.15.4", _line(0, 100, 400))
    b.send_at(0, "a", None, 64, tag="bc")
    b.send_at(100 * MS, "a", "c", 64, tag="uc")
    b.run(1000 * MS)
    recs = {(r.tag, r.receiver): r for r in b.net.records}
    assert not recs[("bc", "b")].dropped
    assert recs[("bc", "c")].drop_reason == "out_of_range"
    assert recs[("uc", "c")].drop_reason == "no_ack"
    m = b.net.metrics(1000 * MS)
    # the broadcast once, the unicast 1 + max_retries (3) times
    assert m["attempts"] == 1 + 4 and m["retransmissions"] == 3 and m["dropped.no_ack"] == 1


def test_hidden_terminals_collide_at_the_receiver_and_recover_by_retrying(bench):
    # a and c are 400 m apart (out of each other's carrier sense), b in the middle hears both
    b = bench("802.11b", {**_line(0, 200, 400), "path_loss_exponent": 4.0})
    assert b.net.received_power_dbm("a", "c") < -82.0 < b.net.received_power_dbm("a", "b")
    b.send_at(1 * MS, "a", "b", 800, tag="x")
    b.send_at(1 * MS, "c", "b", 800, tag="y")
    b.run(200 * MS)
    m = b.net.metrics(200 * MS)
    assert m["retransmissions"] >= 2  # both first attempts were lost at b
    assert sorted(tag for _, tag in b.deliveries("b")) == ["x", "y"]
    # neither was received from its first attempt (which ended at 1 ms + frame time)
    first_end = 1 * MS + 192 * US + math.ceil((800 + 272) * 1e9 / 11e6)
    assert all(t > first_end for t, _ in b.deliveries("b"))


def test_a_much_stronger_signal_is_captured_despite_an_overlapping_weak_one(bench):
    # 20 dBm, a = 3.5, threshold -82 dBm: range 10**(102 / 35) = 821 m. a (0 m) and c (900 m) are hidden from
    # each other; b (100 m) gets a at 20 - 35 log10(100) = -50 dBm and c at 20 - 35 log10(800) = -81.6 dBm:
    # a's SINR is 31.6 dB >= 10 dB, c's is below 0 dB
    params = {"nodes": ["a", "b", "c"], "positions": {"a": [0, 0], "b": [100, 0], "c": [900, 0]}, "acks": False}
    b = bench("802.11b", params)
    assert b.net.received_power_dbm("a", "c") < -82.0 <= b.net.received_power_dbm("c", "b")
    b.send_at(1 * MS, "a", "b", 800, tag="strong")
    b.send_at(1 * MS, "c", "b", 800, tag="weak")
    b.run(20 * MS)
    recs = {r.tag: r for r in b.net.records}
    assert not recs["strong"].dropped
    assert recs["weak"].drop_reason == "interference"


def test_a_node_that_transmits_cannot_receive(bench):
    # min_be = max_be = 0: no random backoff, so b and c both find the channel idle at their CCA (128 us) and
    # both transmit after the turnaround (320 us): c's frame to b arrives while b sends (half duplex). a hears b
    # at 10 m and c at 60 m: 35 log10(6) = 27 dB of SINR, so b's frame gets through
    b = bench("802.15.4", {**_line(0, 10, 60), "acks": False, "min_be": 0, "max_be": 0})
    b.send_at(1 * MS, "c", "b", 64, tag="to_b")
    b.send_at(1 * MS, "b", "a", 64, tag="from_b")
    b.run(20 * MS)
    recs = {r.tag: r for r in b.net.records}
    assert recs["to_b"].tx_start_ns == recs["from_b"].tx_start_ns == 1 * MS + 320 * US
    assert recs["to_b"].drop_reason == "interference"
    assert not recs["from_b"].dropped


def test_80211b_second_sender_defers_then_sends_after_difs_and_its_backoff(bench):
    b = bench("802.11b", _line(0, 10, 20), seed=5)
    b.send_at(1 * MS, "a", "b", 1000, tag="x")
    b.send_at(1 * MS + 50 * US, "c", "b", 1000, tag="y")  # the medium is busy with x: c draws a backoff
    b.run(20 * MS)
    tx = 192 * US + math.ceil((1000 + 272) * 1e9 / 11e6)
    ack = 192 * US + math.ceil(112 * 1e9 / 11e6)
    x_end = 1 * MS + tx
    # c counts DIFS (50 us) + its slots (20 us each) from the end of b's ACK, sent SIFS (10 us) after x;
    # a's post-backoff is drawn after c's (c's contention began first), so c's slots are the stream's first draw
    slots = int(_backoff_stream(5).integers(0, 32))
    y_start = x_end + 10 * US + ack + 50 * US + slots * 20 * US
    recs = {r.tag: r for r in b.net.records}
    assert recs["y"].tx_start_ns == y_start
    assert b.deliveries("b") == [(x_end, "x"), (y_start + tx, "y")]


def test_moving_a_node_out_of_range_loses_its_messages(bench):
    b = bench("802.15.4", {**_line(0, 50), "acks": False})
    b.send_at(0, "a", "b", 64, tag="near")
    b.run(20 * MS)
    b.net.set_position("b", 1000.0, 0.0)
    b.send_at(30 * MS, "a", "b", 64, tag="far")
    b.run(60 * MS)
    recs = {r.tag: r for r in b.net.records}
    assert not recs["near"].dropped and recs["far"].drop_reason == "out_of_range"


def test_wireless_runs_are_reproducible_from_the_seed(bench):
    def run(seed):
        b = bench("802.15.4", _line(0, 10, 20, 30), seed=seed)
        for k in range(20):
            b.send_at(k * 2 * MS, "abcd"[k % 4], "abcd"[(k + 1) % 4], 200, tag=str(k))
        b.run(500 * MS)
        return [(r.tag, r.tx_start_ns, r.delivered_ns, r.drop_reason) for r in b.net.records]

    assert run(7) == run(7)
    assert run(7) != run(8)


def test_bad_wireless_parameters_are_named():
    with pytest.raises(ConfigError, match=r"positions: no position for \['c'\]"):
        make_network(SimEnv(), "n", "802.15.4", {"nodes": ["a", "b", "c"], "positions": {"a": [0, 0], "b": [1, 0]}})
    with pytest.raises(ConfigError, match="ack_timeout .* shorter than ack_delay"):
        make_network(SimEnv(), "n", "802.11b", {**_line(0, 1), "ack_timeout": "100 us"})
    with pytest.raises(ConfigError, match=r"min_be \(6\) is larger than max_be \(5\)"):
        make_network(SimEnv(), "n", "802.15.4", {**_line(0, 1), "min_be": 6})
    with pytest.raises(ConfigError, match="at most 928 bits"):
        net = make_network(SimEnv(), "n", "802.15.4", _line(0, 1))
        for n in ("a", "b"):
            net.attach(n, type("R", (), {"deliver": lambda self, a, b: None})())
        net.send(Message("a", "b", None, 1000))
