"""A network's own wake-ups are plain call items on the event loop's heap (issue 29: calls per message).

A delayed delivery, the end of a pre-processing delay and a priority output's arbitration each push one entry
``(t, priority, id, (fn, arg))`` whose function is the network's own method: no :class:`netsim.env.Call` object and
no indirection through it, and the entry still does its work at the same instant and row of the same-instant table.
"""

from __future__ import annotations

import sys

from netsim.env import ARBITRATE, NORMAL
from netsim.network import Message
from netsim.timebase import US


def _only_entry(net):
    queue = net.sim._queue
    assert len(queue) == 1
    return queue[0]


def test_a_delayed_copy_is_one_call_item_of_the_network_that_delivers_it(bench):
    b = bench("link", {"nodes": ["a", "b"], "delay": "100 us"})
    b.net.send(Message("a", "b", 1.5, 64, tag="y"))
    t, priority, _, item = _only_entry(b.net)
    # 100 us = the link's constant delay (no bit rate, no post-processing delay)
    assert (t, priority) == (100 * US, NORMAL)
    assert item[0] == b.net._deliver and item[1][0].tag == "y"
    b.run(200 * US)
    assert b.deliveries("b") == [(100 * US, "y")]


def test_a_post_processing_delay_on_a_wired_medium_is_one_call_item(bench):
    # 1 Gbit/s Ethernet uplink and downlink of a 512-bit minimum frame: 512 ns each; post delay 7 us
    b = bench("switched_ethernet", {"nodes": ["a", "b"], "bitrate": "1 Gbit/s", "post_delay": "7 us"})
    b.net.send(Message("a", "b", 0.0, 64, tag="u"))
    b.env.sim.run_until(1024)  # both hops done; the delivery waits for the post-processing delay
    t, priority, _, item = _only_entry(b.net)
    assert (t, priority) == (1024 + 7 * US, NORMAL) and item[0] == b.net._deliver
    b.run(20 * US)
    assert b.deliveries("b") == [(1024 + 7 * US, "u")]


def test_the_end_of_a_pre_processing_delay_is_one_call_item(bench):
    b = bench("link", {"nodes": ["a", "b"], "pre_delay": "3 us"})
    b.net.send(Message("a", "b", 0.0, 64, tag="p"))
    t, priority, _, item = _only_entry(b.net)
    assert (t, priority) == (3 * US, NORMAL) and item[0] == b.net._offer_after_pre
    b.run(10 * US)
    assert b.deliveries("b") == [(3 * US, "p")]  # pre delay, then an ideal link


def test_a_priority_output_arbitrates_through_one_call_item_at_the_arbitration_row(bench):
    # a 1 Mbit/s link whose sender queue is a priority queue: the frames queued in an instant compete at ARBITRATE
    b = bench("link", {"nodes": ["a", "b"], "bitrate": "1 Mbit/s", "queue_discipline": "priority"})
    b.net.send(Message("a", "b", 0.0, 100, priority=5, tag="low"))
    b.net.send(Message("a", "b", 0.0, 100, priority=1, tag="high"))
    t, priority, _, item = _only_entry(b.net)
    assert (t, priority) == (0, ARBITRATE) and item[0] == b.net._tx["a"]._start
    b.run(1000 * US)
    # 100 bits at 1 Mbit/s = 100 us each; the more urgent frame goes first although it was queued second
    assert b.deliveries("b") == [(100 * US, "high"), (200 * US, "low")]


def _network_calls(fn) -> list[str]:
    """The Python functions of netsim.network and of the event loop (netsim.env) called while ``fn()`` runs."""
    names: list[str] = []

    def prof(frame, event, arg):
        if event == "call":
            path = frame.f_code.co_filename.replace("\\", "/")
            name = frame.f_code.co_qualname
            # the network's code and the event loop's (not SimEnv.now, which the fake receiver reads)
            if "/netsim/network/" in path or (path.endswith("/netsim/env.py") and not name.startswith("SimEnv.")):
                names.append(name)

    sys.setprofile(prof)
    try:
        fn()
    finally:
        sys.setprofile(None)
    return names


def test_a_message_on_a_delay_link_takes_send_sent_and_deliver_only(bench):
    b = bench("link", {"nodes": ["a", "b"], "delay": "100 us"})
    b.net.send(Message("a", "b", 0.0, 64, tag="first"))  # the first frame of a size computes its framing
    b.env.sim.run_until(100 * US)  # delivered; the clock stays at 100 us
    msg = Message("a", "b", 1.0, 64, tag="y")
    # send validates and stamps the message and sends the frame at once (no bit rate: _sent is the offer); the
    # loop then calls the delivery's call item: nothing else of the network or the event loop in between
    assert _network_calls(lambda: b.net.send(msg)) == ["Network.send", "Link._sent"]
    assert _network_calls(lambda: b.env.sim.run_until(200 * US)) == ["EventLoop.run_until", "Network._deliver"]
    assert b.deliveries("b") == [(100 * US, "first"), (200 * US, "y")]


def test_a_message_through_an_idle_switch_takes_two_transmissions_and_one_store(bench):
    b = bench("switched_ethernet", {"nodes": ["a", "b"], "bitrate": "1 Gbit/s"})
    b.net.send(Message("a", "b", 0.0, 64, tag="first"))  # the first frame of a size computes its framing
    b.env.sim.run_until(1024)
    msg = Message("a", "b", 1.0, 64, tag="u")
    # the idle uplink takes the frame at once; its end (512 ns: a minimum frame at 1 Gbit/s) stores it in the switch
    # (no switch delay: the uplink hands it over directly), the idle downlink starts, and its end delivers it
    assert _network_calls(lambda: b.net.send(msg)) == ["Network.send", "SwitchedEthernet._offer", "Transmitter.offer",
                                                       "Transmitter._begin"]
    assert _network_calls(lambda: b.env.sim.run_until(2048)) == [
        "EventLoop.run_until",
        "Transmitter._done", "SwitchedEthernet._store", "Transmitter.offer", "Transmitter._begin",
        "Transmitter._done", "SwitchedEthernet._left_switch", "Network._transmitted", "Network._deliver",
    ]
    assert b.deliveries("b") == [(1024, "first"), (2048, "u")]


def test_a_switch_delay_is_one_call_item_before_the_store(bench):
    # uplink 512 ns (minimum frame at 1 Gbit/s), switch delay 2 us, downlink 512 ns
    b = bench("switched_ethernet", {"nodes": ["a", "b"], "bitrate": "1 Gbit/s", "switch_delay": "2 us"})
    b.net.send(Message("a", "b", 1.0, 64, tag="d"))
    b.env.sim.run_until(512)
    t, priority, _, item = _only_entry(b.net)
    assert (t, priority) == (512 + 2 * US, NORMAL) and item[0] == b.net._after_delay
    b.run(10 * US)
    rec = b.record("d")
    assert (rec.tx_start_ns, rec.delivered_ns) == (0, 512 + 2 * US + 512)
