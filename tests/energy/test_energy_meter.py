"""Energy of nodes (issue 20): CPU and radio power by state, a battery that runs out and stops the node.

Every expected number is computed in the test: energy = power x time, with the times from the schedule by hand.
"""

from __future__ import annotations

import math

import pytest

from netsim.energy import EnergyMeter, EnergyModel
from netsim.env import SimEnv
from netsim.kernel import Kernel
from netsim.network import Message, make_network
from netsim.timebase import MS, S, US


def _exec_body(d):
    def body(job):
        yield job.execute(d)
    return body


def _cpu_node(capacity=None):
    env = SimEnv()
    k = Kernel(env, "n")
    k.create_task("T", _exec_body(2 * MS), period=10 * MS, priority=1)
    model = EnergyModel.model_validate({"cpu": {"busy": "1 W", "idle": "100 mW"},
                                        **({} if capacity is None else {"battery": {"capacity": capacity}})})
    return env, k, EnergyMeter(env, "n", k, model, [])


def test_cpu_energy_is_busy_power_times_busy_time_plus_idle_power_times_the_rest():
    env, k, meter = _cpu_node()
    env.run(1 * S)
    m = meter.metrics(1 * S)
    # 100 jobs of 2 ms: 0.2 s busy at 1 W, 0.8 s idle at 0.1 W
    assert m["cpu_busy_s"] == pytest.approx(0.2)
    assert m["J"] == pytest.approx(0.2 * 1.0 + 0.8 * 0.1, rel=1e-12)
    assert meter.checks == 0 and meter.depleted_ns is None  # no battery: no event


def test_a_battery_runs_out_when_the_energy_reaches_its_capacity_and_the_node_stops():
    env, k, meter = _cpu_node(capacity="99 mJ")
    env.run(1 * S)
    # each 10 ms period uses 2 ms x 1 W + 8 ms x 0.1 W = 2.8 mJ: 35 periods use 98 mJ by 350 ms, and the
    # last 1 mJ goes at 1 W in the first 1 ms of job 35: the battery runs out at 351 ms
    assert meter.depleted_ns == pytest.approx(351 * MS, abs=2)
    recs = k.job_records
    assert len(recs) == 36 and all(not r.killed for r in recs[:35])
    assert recs[35].killed and recs[35].finish == meter.depleted_ns
    m = meter.metrics(1 * S)
    assert m["J"] == pytest.approx(0.099, abs=1e-9) and m["battery_left_J"] < 1e-9
    assert m["depleted_s"] == pytest.approx(0.351, abs=1e-8)
    assert meter.checks < 200


def test_no_battery_means_depleted_is_not_reported_and_a_battery_that_lasts_gives_nan():
    env, k, meter = _cpu_node(capacity="10 J")
    env.run(1 * S)
    m = meter.metrics(1 * S)
    assert math.isnan(m["depleted_s"]) and m["battery_left_J"] == pytest.approx(10 - 0.28)
    env2, _, meter2 = _cpu_node()
    env2.run(10 * MS)
    assert "depleted_s" not in meter2.metrics(10 * MS)


def _radio(listen_a="always", listen_b="always", capacity=None, sends=10):
    """a broadcasts ``sends`` 64-bit frames, one every 10 ms, to b 10 m away (802.15.4, BE = 0: no backoff)."""
    env = SimEnv()
    net = make_network(env, "r", "802.15.4", {"nodes": ["a", "b"], "positions": {"a": [0, 0], "b": [10, 0]},
                                              "acks": False, "min_be": 0, "max_be": 0})
    got = []
    net.attach("a", type("R", (), {"deliver": lambda self, n, m: None})())
    net.attach("b", type("R", (), {"deliver": lambda self, n, m: got.append(env.now)})())
    power = {"tx": "50 mW", "rx": "60 mW", "idle": "40 mW", "sleep": "1 mW"}
    ma = EnergyModel.model_validate({"radio": {**power, "listen": listen_a},
                                     **({} if capacity is None else {"battery": {"capacity": capacity}})})
    mb = EnergyModel.model_validate({"radio": {**power, "listen": listen_b}})
    meters = {"a": EnergyMeter(env, "a", Kernel(env, "a"), ma, [net]),
              "b": EnergyMeter(env, "b", Kernel(env, "b"), mb, [net])}

    def proc():
        for k in range(sends):
            net.send(Message("a", None, None, 64, tag=str(k)))
            yield env.timeout(10 * MS)

    env.process(proc())
    env.run(100 * MS)
    return net, meters, got


#: 192 us PHY overhead + (64 + 88) bits at 250 kbit/s
FRAME = 192 * US + 608 * US
#: CCA + turnaround before each frame (BE = 0: no backoff slots)
ACCESS = 128 * US + 192 * US


def test_radio_time_per_state_and_its_energy():
    net, meters, got = _radio()
    a, b = meters["a"].metrics(100 * MS), meters["b"].metrics(100 * MS)
    assert len(got) == 10
    # a sends 10 frames; b senses (receives) each of them; both listen otherwise
    assert a["radio_tx_s"] == pytest.approx(10 * FRAME / S) and a["radio_rx_s"] == 0
    assert a["radio_idle_s"] == pytest.approx(0.1 - 10 * FRAME / S)
    assert b["radio_rx_s"] == pytest.approx(10 * FRAME / S) and b["radio_tx_s"] == 0
    assert a["radio_J"] == pytest.approx(0.050 * 10 * FRAME / S + 0.040 * (0.1 - 10 * FRAME / S), rel=1e-12)
    assert b["J"] == pytest.approx(0.060 * 10 * FRAME / S + 0.040 * (0.1 - 10 * FRAME / S), rel=1e-12)


def test_a_radio_that_listens_only_for_its_own_frames_sleeps_and_hears_nothing():
    net, meters, got = _radio(listen_a="own_frames", listen_b="own_frames")
    a, b = meters["a"].metrics(100 * MS), meters["b"].metrics(100 * MS)
    # a is awake from taking each frame (CCA, turnaround) to the frame's end; asleep otherwise
    assert a["radio_idle_s"] == pytest.approx(10 * ACCESS / S)
    assert a["radio_tx_s"] == pytest.approx(10 * FRAME / S)
    assert a["radio_sleep_s"] == pytest.approx(0.1 - 10 * (ACCESS + FRAME) / S)
    # b never has a frame: it sleeps all the time and receives nothing
    assert b["radio_sleep_s"] == pytest.approx(0.1) and got == []
    assert {r.drop_reason for r in net.records} == {"out_of_range"}


def test_a_node_whose_battery_ran_out_sends_nothing_more():
    # a uses 40 mW listening: 2 mJ last 50 ms minus what the frames cost over the 40 mW (10 mW x 800 us each)
    net, meters, got = _radio(capacity="2 mJ")
    dead = meters["a"].depleted_ns
    # frames k = 0.. end at k 10 ms + 320 us + 800 us; by then a used 40 mW x t + 10 mW x 800 us per frame
    t = (2e-3 - 5 * 0.010 * FRAME / S) / 0.040  # 5 frames before it (checked below)
    assert dead == pytest.approx(t * S, abs=2)
    assert 40 * MS < dead < 50 * MS
    assert len(got) == 5 and all(x < dead for x in got)
    assert meters["a"].metrics(100 * MS)["J"] == pytest.approx(2e-3, abs=1e-10)


def test_80211b_radio_time_counts_the_frame_and_its_ack_at_both_ends():
    env = SimEnv()
    net = make_network(env, "w", "802.11b", {"nodes": ["a", "b"], "positions": {"a": [0, 0], "b": [10, 0]}})
    for n in ("a", "b"):
        net.attach(n, type("R", (), {"deliver": lambda self, x, m: None})())
    power = {"tx": "1 W", "rx": "0.5 W", "idle": "0.1 W"}
    meters = {n: EnergyMeter(env, n, Kernel(env, n), EnergyModel.model_validate({"radio": power}), [net])
              for n in ("a", "b")}
    env.sim.call_at(1 * MS, lambda: net.send(Message("a", "b", None, 1000)))
    env.run(10 * MS)
    # independent: the frame 192 us + (1000 + 272) bits at 11 Mbit/s, the ACK 192 us + 112 bits, SIFS apart
    frame = (192e-6 + math.ceil((1000 + 272) * 1e9 / 11e6) / 1e9)
    ack = (192e-6 + math.ceil(112 * 1e9 / 11e6) / 1e9)
    a, b = meters["a"].metrics(10 * MS), meters["b"].metrics(10 * MS)
    assert (a["radio_tx_s"], a["radio_rx_s"]) == (pytest.approx(frame), pytest.approx(ack))
    assert (b["radio_tx_s"], b["radio_rx_s"]) == (pytest.approx(ack), pytest.approx(frame))
    assert a["J"] == pytest.approx(1.0 * frame + 0.5 * ack + 0.1 * (0.010 - frame - ack))
