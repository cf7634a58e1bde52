"""Same-instant order through the real kernel: a frame sent at the instant a medium goes idle takes part.

The issue's case (issue 13 B): on CAN, L (id 3) holds the bus until 4.0 ms, M (id 2) waits since 1 ms, and H
(id 1) is sent at exactly 4.0 ms by a task released then. The arbitration at 4.0 ms must see H: H first.
The order must not depend on how the task's release at 4.0 ms was scheduled (an entry pushed before or after
the end of L's frame), so every test runs the sender of the urgent frame in three ways:

``offset``  a periodic task whose first release is at 4.0 ms (its release entry exists before the run);
``period``  a periodic task of period 2 ms that sends only in its job released at 4.0 ms (that release entry
            is pushed at 2.0 ms, after the end of L's frame was scheduled);
``sleep``   a task released at 3.0 ms that sleeps until 4.0 ms, then sends (its wake-up is pushed at 3.0 ms,
            after every other entry of 4.0 ms: ends of frames, slot starts, token visits).
"""

from __future__ import annotations

import math
from typing import Any

import pytest

from netsim.env import SimEnv
from netsim.kernel import Kernel, Mailbox
from netsim.network import make_network
from netsim.timebase import MS, US

ROUTES = ["offset", "period", "sleep"]
T_IDLE = 4 * MS  # the instant the medium goes idle and the urgent frame is sent


def _sender_at(kernel: Kernel, route: str, net: str, to: str, bits: int, priority: int, tag: str) -> None:
    """A task on ``kernel`` that sends one frame at exactly ``T_IDLE``, released there by ``route``."""
    if route == "offset":
        def body(job):
            yield job.send(net, to, tag, bits, priority=priority, tag=tag)

        kernel.create_task(tag, body, period=100 * MS, offset=T_IDLE, priority=1)
    elif route == "period":
        def body(job):
            if job.now == T_IDLE:
                yield job.send(net, to, tag, bits, priority=priority, tag=tag)

        kernel.create_task(tag, body, period=2 * MS, priority=1)
    else:
        def body(job):
            yield job.sleep_until(T_IDLE)
            yield job.send(net, to, tag, bits, priority=priority, tag=tag)

        kernel.create_task(tag, body, period=100 * MS, offset=3 * MS, priority=1)


def _send_once(kernel: Kernel, at: int, net: str, to: str, bits: int, priority: int, tag: str) -> None:
    def body(job):
        yield job.send(net, to, tag, bits, priority=priority, tag=tag)

    kernel.create_task(tag, body, period=100 * MS, offset=at, priority=2)


def _build(net_type: str, nodes: list[str], params: dict[str, Any]) -> tuple[SimEnv, Any, dict[str, Kernel],
                                                                              list[tuple[int, str]]]:
    """Kernels on ``nodes`` + a receiving kernel ``rx`` whose task logs (time, tag) of every arrival."""
    env = SimEnv(seed=1)
    net = make_network(env, "net", net_type, {"nodes": [*nodes, "rx"], **params})
    kernels = {n: Kernel(env, n, policy="fp") for n in [*nodes, "rx"]}
    for n, k in kernels.items():
        k.attach_network(net)
        net.attach(n, k)
    got: list[tuple[int, str]] = []

    def receiver(job):
        msg = yield job.receive("net")
        got.append((job.now, msg.tag))

    kernels["rx"].create_task("receive", receiver, priority=1)
    kernels["rx"].bind_receive("net", "receive")
    return env, net, kernels, got


def _spans(net: Any) -> dict[str, tuple[int, int]]:
    return {r.tag: (r.tx_start_ns, r.tx_end_ns) for r in net.records}


@pytest.mark.parametrize("route", ROUTES)
def test_can_frame_sent_as_the_bus_goes_idle_wins_the_arbitration(route):
    # 500 kbit/s: 2 us per bit. L: 2000 bits = 4.0 ms on [0, 4.0]; M (queued at 1 ms): 1000 bits = 2.0 ms;
    # H (sent at 4.0 ms): 500 bits = 1.0 ms. The arbitration at 4.0 ms sees M and H; H (id 1) beats M (id 2):
    # H on [4.0, 5.0] ms, then M on [5.0, 7.0] ms (M first would be M [4, 6], H [6, 7]).
    env, net, k, got = _build("can", ["L", "M", "H"], {"bitrate": "500 kbit/s"})
    _send_once(k["L"], 0, "net", "rx", 2000, 3, "L")
    _send_once(k["M"], 1 * MS, "net", "rx", 1000, 2, "M")
    _sender_at(k["H"], route, "net", "rx", 500, 1, "H")
    env.run(10 * MS)
    assert _spans(net) == {"L": (0, 4 * MS), "H": (4 * MS, 5 * MS), "M": (5 * MS, 7 * MS)}
    assert got == [(4 * MS, "L"), (5 * MS, "H"), (7 * MS, "M")]


@pytest.mark.parametrize("route", ROUTES)
@pytest.mark.parametrize("net_type", ["ethernet", "fdma", "link"])
def test_priority_queue_of_a_serial_output_sees_a_frame_sent_as_it_goes_idle(net_type, route):
    # One sender 'a' with a priority sender queue, on its own output (Ethernet uplink; link with a bit rate;
    # FDMA: a's sub-channel, half of 2 Mbit/s shared equally by 'a' and 'rx'). 1 Mbit/s on a's output: 1 us
    # per bit.
    # 'busy' (4000 bits = 4.0 ms) holds the output on [0, 4.0] ms; 'low' (priority 5, 1000 bits) waits since
    # 1 ms; 'high' (priority 1, 1000 bits) is sent at 4.0 ms. 'high' goes on [4.0, 5.0], then 'low' [5.0, 6.0].
    rate = "2 Mbit/s" if net_type == "fdma" else "1 Mbit/s"
    params: dict[str, Any] = {"bitrate": rate, "queue_discipline": "priority", "min_frame_bits": 0}
    if net_type == "ethernet":
        params["max_frame_bits"] = None
    env, net, k, got = _build(net_type, ["a"], params)
    _send_once(k["a"], 0, "net", "rx", 4000, 9, "busy")
    _send_once(k["a"], 1 * MS, "net", "rx", 1000, 5, "low")
    _sender_at(k["a"], route, "net", "rx", 1000, 1, "high")
    env.run(20 * MS)
    spans = _spans(net)
    assert spans["busy"][0] == 0 and spans["high"][0] == 4 * MS and spans["low"][0] == 5 * MS
    assert [tag for _, tag in got] == ["busy", "high", "low"]


@pytest.mark.parametrize("route", ROUTES)
def test_tdma_slot_start_sees_a_frame_sent_at_that_instant(route):
    # 1 Mbit/s (1 us per bit), slot 2 ms, schedule [a, rx]: a owns [0, 2), [4, 6) ... ms. 'fill' (2000 bits =
    # 2.0 ms) fills a's slot [0, 2); 'low' (priority 5, 1000 bits = 1.0 ms) waits since 1 ms; a's next slot
    # starts at 4.0 ms, where 'high' (priority 1, 1000 bits) is sent: 'high' on [4.0, 5.0], 'low' on [5.0, 6.0].
    env, net, k, got = _build("tdma", ["a"], {"bitrate": "1 Mbit/s", "slot": "2 ms", "schedule": ["a", "rx"],
                                              "queue_discipline": "priority"})
    _send_once(k["a"], 0, "net", "rx", 2000, 9, "fill")
    _send_once(k["a"], 1 * MS, "net", "rx", 1000, 5, "low")
    _sender_at(k["a"], route, "net", "rx", 1000, 1, "high")
    env.run(20 * MS)
    assert _spans(net) == {"fill": (0, 2 * MS), "high": (4 * MS, 5 * MS), "low": (5 * MS, 6 * MS)}
    assert got == [(2 * MS, "fill"), (5 * MS, "high"), (6 * MS, "low")]


@pytest.mark.parametrize("route", ROUTES)
def test_round_robin_visit_sees_a_frame_sent_as_the_token_arrives(route):
    # 1 Mbit/s, token_pass 1 ms, token order [a, rx]. 'fill' (2000 bits) goes at 0 on [0, 2.0] ms; the token
    # reaches rx at 3.0 (rx has nothing) and a again at 4.0 ms, where a holds 'low' (priority 5, queued at 1 ms)
    # and 'high' (priority 1, 1000 bits = 1.0 ms) is sent: 'high' on [4.0, 5.0]; the token is at rx at 6.0 and
    # back at a at 7.0 ms: 'low' on [7.0, 8.0].
    env, net, k, got = _build("round_robin", ["a"], {"bitrate": "1 Mbit/s", "token_pass": "1 ms",
                                                     "queue_discipline": "priority"})
    _send_once(k["a"], 0, "net", "rx", 2000, 9, "fill")
    _send_once(k["a"], 1 * MS, "net", "rx", 1000, 5, "low")
    _sender_at(k["a"], route, "net", "rx", 1000, 1, "high")
    env.run(20 * MS)
    assert _spans(net) == {"fill": (0, 2 * MS), "high": (4 * MS, 5 * MS), "low": (7 * MS, 8 * MS)}
    assert got == [(2 * MS, "fill"), (5 * MS, "high"), (8 * MS, "low")]


@pytest.mark.parametrize("route", ROUTES)
@pytest.mark.parametrize("window", ["0 s", "1 us"])
def test_csma_cd_frame_sent_as_the_medium_goes_idle_collides_with_the_waiting_one(window, route):
    # 1 Mbit/s. L (4000 bits) on [0, 4.0] ms; M (1000 bits, queued at 1 ms) waits for the medium; H sends at
    # 4.0 ms. M and H both start when the medium goes idle at 4.0 ms, so they collide (TrueTime's model: nodes
    # waiting for the medium start together): exactly one collision, after which each draws one backoff.
    # With collision_window 0 only starts at the very same instant collide, so this needs H's frame to be
    # at the MAC when the medium is contended at 4.0 ms; with 1 us it collides even if M started first.
    env, net, k, got = _build("csma_cd", ["L", "M", "H"], {"bitrate": "1 Mbit/s", "collision_window": window})
    _send_once(k["L"], 0, "net", "rx", 4000, 0, "L")
    _send_once(k["M"], 1 * MS, "net", "rx", 1000, 0, "M")
    _sender_at(k["H"], route, "net", "rx", 1000, 0, "H")
    env.run(50 * MS)
    assert (net.collisions, net.backoffs) == (1, 2)
    assert sorted(tag for _, tag in got) == ["H", "L", "M"]


def test_job_finishing_on_a_frame_that_arrives_at_its_deadline_meets_it():
    # A zero-length CAN frame (0 bits: 0 ns on the wire) sent at 4.0 ms is arbitrated, ends and is delivered
    # at 4.0 ms; the receive handler posts to a mailbox and task T (released at 0, deadline 4.0 ms), blocked on
    # it, finishes at 4.0 ms: response 4.0 ms = deadline, met (R <= D), so the deadline handler must not fire.
    env = SimEnv(seed=1)
    net = make_network(env, "net", "can", {"nodes": ["s", "rx"], "bitrate": "500 kbit/s"})
    kernels = {n: Kernel(env, n, policy="fp") for n in ["s", "rx"]}
    for n, k in kernels.items():
        k.attach_network(net)
        net.attach(n, k)
    box = Mailbox("box")
    fired: list[int] = []

    def on_message(job):
        msg = yield job.receive("net")
        yield job.post(box, msg.tag)

    def waiter(job):
        yield job.fetch(box)

    kernels["rx"].create_handler("on_message", on_message)
    kernels["rx"].bind_receive("net", "on_message")
    kernels["rx"].create_task("T", waiter, period=100 * MS, deadline=T_IDLE, priority=1,
                              deadline_handler=lambda job: fired.append(job.now))
    _send_once(kernels["s"], T_IDLE, "net", "rx", 0, 1, "zero")
    env.run(10 * MS)
    assert _spans(net) == {"zero": (T_IDLE, T_IDLE)}
    rec = next(r for r in kernels["rx"].job_records if r.task == "T")
    assert (rec.finish, rec.deadline) == (T_IDLE, T_IDLE)
    assert fired == []


# ---------------------------------------------------------------------------------------------- wireless
# The radios decide at instants (a CCA ends, a backoff expires, a frame finds the medium idle for DIFS) while
# transmissions start and end at instants: a decision at t sees the medium as it was just before t (carrier
# sense cannot detect a start at the very instant it senses; a CCA ending as a transmission ends sensed it).
# Positions: a at 0 m, c at 10 m, b at 20 m, so a and b reach c with equal power (neither captures the other).

def _radio(bench: Any, typ: str, **extra: Any) -> Any:
    return bench(typ, {"nodes": ["a", "b", "c"], "positions": {"a": [0, 0], "c": [10, 0], "b": [20, 0]},
                       **extra})


def test_802154_cca_ending_as_another_transmission_starts_finds_the_channel_idle(bench):
    # min_be = max_be = 0: no backoff slots. a sends at 0: CCA 128 us, turnaround 192 us -> on air at 320 us
    # for 192 us + (64 + 88) bits * 4 us = 800 us. b sends at 192 us: its CCA ends at 320 us, as a starts:
    # idle, so b is on air at 320 + 192 = 512 us, and the two collide at c.
    b = _radio(bench, "802.15.4", min_be=0, max_be=0, acks=False)
    b.send_at(0, "a", "c", 64, tag="a")
    b.send_at(192 * US, "b", "c", 64, tag="b")
    b.run(10 * MS)
    ra, rb = b.record("a"), b.record("b")
    assert (ra.tx_start_ns, rb.tx_start_ns) == (320 * US, 512 * US)
    assert b.net.busy_ccas == 0
    assert (ra.drop_reason, rb.drop_reason) == ("interference", "interference")


def test_802154_cca_ending_as_another_transmission_ends_finds_the_channel_busy(bench):
    # a on air [320, 1120] us (as above). b sends at 1120 - 128 = 992 us: its CCA ends at 1120 us, as a's frame
    # ends: busy (the CCA's 128 us window overlapped it). b backs off 0 slots, its second CCA ends at 1248 us:
    # idle, on air at 1248 + 192 = 1440 us. (Seeing the end first would put b on air at 1312 us.)
    b = _radio(bench, "802.15.4", min_be=0, max_be=0, acks=False)
    b.send_at(0, "a", "c", 64, tag="a")
    b.send_at(992 * US, "b", "c", 64, tag="b")
    b.run(10 * MS)
    assert (b.record("a").tx_start_ns, b.record("b").tx_start_ns) == (320 * US, 1440 * US)
    assert b.net.busy_ccas == 1
    assert b.deliveries("c") == [(1120 * US, "a"), (2240 * US, "b")]


def test_80211b_frames_arriving_together_on_an_idle_medium_both_go_at_once_and_collide(bench):
    # The medium has been idle for DIFS: a frame goes at once (DCF basic access). a and b both get one at
    # 1 ms: both start at 1 ms, collide at c, get no ACK and are retried.
    b = _radio(bench, "802.11b")
    b.send_at(1 * MS, "a", "c", 1000, tag="a")
    b.send_at(1 * MS, "b", "c", 1000, tag="b")
    b.run(50 * MS)
    assert (b.record("a").tx_start_ns, b.record("b").tx_start_ns) == (1 * MS, 1 * MS)
    assert b.net.metrics(50 * MS)["retransmissions"] >= 2


def test_80211b_backoffs_expiring_in_the_same_slot_collide(bench):
    # cw_min = cw_max = 0: every backoff is 0 slots. c broadcasts at 0 (idle medium: at once) for
    # 192 us + ceil((1000 + 272) bits / 11 Mbit/s) = 192 000 + 115 637 ns. a and b get broadcasts at 100 us,
    # medium busy: each waits for the medium, then DIFS (10 + 2 * 20 = 50 us) + 0 slots: both expire together
    # and transmit together; each is lost at c (equal powers), and at the other sender (half duplex).
    tx_c = 192 * US + math.ceil((1000 + 272) * 1e9 / 11e6)
    b = _radio(bench, "802.11b", cw_min=0, cw_max=0)
    b.send_at(0, "c", None, 1000, tag="c")
    b.send_at(100 * US, "a", None, 1000, tag="a")
    b.send_at(100 * US, "b", None, 1000, tag="b")
    b.run(10 * MS)
    starts = {r.tag: r.tx_start_ns for r in b.net.records}
    assert starts == {"c": 0, "a": tx_c + 50 * US, "b": tx_c + 50 * US}
    lost = {(r.tag, r.receiver): r.drop_reason for r in b.net.records if r.tag in "ab"}
    assert lost == {("a", "c"): "interference", ("a", "b"): "interference",
                    ("b", "c"): "interference", ("b", "a"): "interference"}


def test_radio_frame_ending_as_a_bus_goes_idle_is_forwarded_into_that_arbitration():
    # A gateway g forwards what it receives on an 802.15.4 radio onto CAN with id 1. Radio (min_be = max_be
    # = 0, no ACKs): a sends at 0, on air [320, 1120] us (as above), delivered to g at 1120 us. CAN at
    # 500 kbit/s (2 us per bit): L (560 bits) on [0, 1120] us, M (id 2, 100 bits) waiting since 100 us. The
    # arbitration at 1120 us sees the forwarded frame (100 bits): 'fwd' on [1120, 1320], M on [1320, 1520] us.
    env = SimEnv(seed=1)
    radio = make_network(env, "radio", "802.15.4", {"nodes": ["a", "g"], "positions": {"a": [0, 0], "g": [10, 0]},
                                                     "min_be": 0, "max_be": 0, "acks": False})
    can = make_network(env, "can", "can", {"nodes": ["g", "L", "M", "rx"], "bitrate": "500 kbit/s"})
    kernels = {n: Kernel(env, n, policy="fp") for n in ["a", "g", "L", "M", "rx"]}
    for net in (radio, can):
        for n in net.nodes:
            kernels[n].attach_network(net)
            net.attach(n, kernels[n])

    def forward(job):
        msg = yield job.receive("radio")
        yield job.send("can", "rx", msg.payload, 100, priority=1, tag="fwd")

    def send_radio(job):
        yield job.send("radio", "g", None, 64, tag="r")

    kernels["g"].create_handler("forward", forward)
    kernels["g"].bind_receive("radio", "forward")
    kernels["a"].create_task("s", send_radio, period=100 * MS, priority=1)
    _send_once(kernels["L"], 0, "can", "rx", 560, 3, "L")
    _send_once(kernels["M"], 100 * US, "can", "rx", 100, 2, "M")
    env.run(10 * MS)
    assert radio.records[0].delivered_ns == 1120 * US
    assert _spans(can) == {"L": (0, 1120 * US), "fwd": (1120 * US, 1320 * US), "M": (1320 * US, 1520 * US)}
