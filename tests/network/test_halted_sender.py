"""A node whose battery ran out sends nothing more on any medium (issue 31).

Its frames still queued at the instant it halts, or still in its pre-processing delay, are dropped as
``sender_dead`` and counted; only a frame already on the medium finishes. Set-up of every case: node ``a``
draws 1 W whatever it does and has a 10 mJ battery, so it runs out at 10 mJ / 1 W = 10 ms; at 0 s it hands
five 8-bit frames to the network, which at 1 kbit/s take 8 bits / 1000 bit/s = 8 ms each.
"""

from __future__ import annotations

from typing import Any

import pytest

from netsim.energy import EnergyMeter, EnergyModel
from netsim.env import SimEnv
from netsim.kernel import Kernel
from netsim.network import Message, make_network
from netsim.timebase import MS

POWER = {"cpu": {"busy": "1 W", "idle": "1 W"}, "battery": {"capacity": "10 mJ"}}
HALT = 10 * MS  # 10 mJ / 1 W
TX = 8 * MS  # 8 bits at 1 kbit/s

WIRED = {
    "can": {},
    "tdma": {"slot": "8 ms", "schedule": ["a", "b"]},
    "flexray": {"cycle": "20 ms", "static_slot": "8 ms", "static_schedule": ["a", "b"]},
    "csma_cd": {"min_frame_bits": 8},
    "ethernet": {"min_frame_bits": 8},
    "round_robin": {},
    "fdma": {},
    "link": {},
}


class _Sink:
    def __init__(self, env: SimEnv) -> None:
        self.env = env
        self.got: list[int] = []

    def deliver(self, network: str, msg: Message) -> None:
        self.got.append(self.env.now)


def _bench(type_name: str, extra: dict[str, Any], pre_delay: str = "0 s") -> tuple[Any, Any, _Sink, EnergyMeter]:
    env = SimEnv()
    params: dict[str, Any] = {"nodes": ["a", "b"], "bitrate": "1 kbit/s", "pre_delay": pre_delay, **extra}
    if type_name == "ieee802154":
        params.update({"positions": {"a": [0, 0], "b": [5, 0]}, "acks": False, "min_be": 0, "max_be": 0,
                       "turnaround": "1 ns", "cca_time": "1 ns", "ack_timeout": "100 ms", "mac_overhead_bits": 0, "phy_overhead": "1 ns"})
    net = make_network(env, "net", type_name, params)
    env.components["network.net"] = net  # what the scenario wiring does: the meter finds the node's networks there
    sink = _Sink(env)
    net.attach("a", _Sink(env))
    net.attach("b", sink)
    kernel = Kernel(env, "a")
    media = [net] if type_name == "ieee802154" else []
    meter = EnergyMeter(env, "a", kernel, EnergyModel.model_validate(POWER), media)

    def burst():
        for i in range(5):
            net.send(Message("a", "b", None, 8, 1, tag=f"m{i}"))
        yield env.timeout(0)

    env.process(burst())
    return env, net, sink, meter


def test_a_can_node_whose_battery_ran_out_sends_none_of_its_queued_frames():
    env, net, sink, meter = _bench("can", {})
    env.run(100 * MS)
    assert meter.depleted_ns == pytest.approx(HALT, abs=2)
    # frame 0 on the bus 0-8 ms, frame 1 8-16 ms (on the bus when a halts at 10 ms: it finishes); frames 2-4 were
    # queued at 10 ms: dropped. The old code sent them too, at 24, 32 and 40 ms.
    assert sink.got == [TX, 2 * TX]
    m = net.metrics(100 * MS)
    assert m["dropped.sender_dead"] == 3 and m["in_flight"] == 0 and m["delivered"] == 2
    dead = [r for r in net.records if r.drop_reason == "sender_dead"]
    assert [r.tag for r in dead] == ["m2", "m3", "m4"] and all(r.tx_start_ns is None for r in dead)


@pytest.mark.parametrize("type_name", sorted(WIRED))
def test_no_wired_medium_carries_a_frame_of_a_halted_node_that_was_not_on_the_medium(type_name):
    env, net, sink, meter = _bench(type_name, WIRED[type_name])
    env.run(200 * MS)
    assert meter.depleted_ns == pytest.approx(HALT, abs=2)
    started_after = [r.tag for r in net.records if r.tx_start_ns is not None and r.tx_start_ns > meter.depleted_ns]
    assert started_after == []  # nothing of a went on the medium after it halted
    m = net.metrics(200 * MS)
    # every copy is delivered or dropped as sender_dead: none left waiting, and at least the last three were
    # queued at 10 ms on every medium (at most two frames of 8 ms can have started by then)
    assert m["in_flight"] == 0 and m["delivered"] + m["dropped.sender_dead"] == 5
    assert m["dropped.sender_dead"] >= 3 and len(sink.got) <= 2


def test_frames_still_in_the_pre_processing_delay_when_the_node_halts_are_dropped():
    # pre_delay 20 ms: the frames would reach the bus at 20 ms, after a halted at 10 ms: all five dropped then
    env, net, sink, meter = _bench("can", {}, pre_delay="20 ms")
    env.run(100 * MS)
    assert sink.got == [] and net.metrics(100 * MS)["dropped.sender_dead"] == 5


def test_a_halted_radio_drops_its_queued_frames_instead_of_keeping_them():
    # 802.15.4 with no backoff (BE = 0), a 1 ns CCA, a 1 ns turnaround, a 1 ns PHY header, no MAC header and no
    # ACKs: frame 0 on the air from 2 ns to 8 ms + 3 ns, frame 1 from 8 ms + 5 ns (on the air when a halts at 10 ms:
    # it reaches no one, and is dropped at its end); frames 2-4 queued
    env, net, sink, meter = _bench("ieee802154", {})
    env.run(100 * MS)
    assert meter.depleted_ns == pytest.approx(HALT, abs=2)
    assert sink.got == [TX + 3]
    m = net.metrics(100 * MS)
    assert m["in_flight"] == 0 and m["dropped.sender_dead"] == 4
    assert [r.tag for r in net.records if r.drop_reason == "sender_dead"] == ["m1", "m2", "m3", "m4"]
