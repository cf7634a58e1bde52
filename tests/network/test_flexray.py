"""FlexRay (issue 30): static TDMA slots and a dynamic segment of minislots, against a cycle computed by hand.

The bus of every test here (``PARAMS``), worked out by hand:

* 10 Mbit/s: a frame of b bits takes b / 10 Mbit/s = b x 0.1 us (200 bits: 20 us; 400 bits: 40 us).
* cycle 5 ms = 10 static slots of 50 us (0-500 us) + 100 minislots of 5 us (500-1000 us) + 4 ms network idle time.
* static slots: 1 (0-50 us) is a's, 3 (100-150 us) is b's; the others are free.
* dynamic frame IDs run from 11 (after the 10 static slots): c has 11, d has 13, e has 14; 12 has no owner.
  Each ID takes one minislot when it sends nothing, ceil(frame time / 5 us) minislots when it sends.
"""

from __future__ import annotations

import pytest

from netsim.errors import ConfigError
from netsim.scenario.loader import check_scenario
from netsim.timebase import MS, US

PARAMS = {
    "nodes": ["a", "b", "c", "d", "e", "sink"],
    "bitrate": "10 Mbit/s",
    "cycle": "5 ms",
    "static_slot": "50 us",
    "static_schedule": ["a", None, "b", None, None, None, None, None, None, None],
    "minislot": "5 us",
    "minislots": 100,
    "dynamic_ids": {"c": 11, "d": 13, "e": 14},
}
CYCLE = 5 * MS


def test_a_static_frame_goes_at_its_owners_slot_start(bench):
    b = bench("flexray", PARAMS)
    b.send_at(0, "b", "sink", 200, tag="early")  # waits for slot 3 at 100 us, 20 us on the bus: 120 us
    b.send_at(100 * US, "a", "sink", 200, tag="a")  # a's slot 1 has passed: next cycle's, 5 ms + 20 us
    b.run(20 * MS)
    assert b.record("early").delivered_ns == 120 * US
    assert b.record("a").delivered_ns == CYCLE + 20 * US


def test_static_worst_case_latency_is_one_cycle_plus_the_frame(bench):
    b = bench("flexray", PARAMS)
    b.send_at(100 * US, "b", "sink", 200, tag="at_slot")  # queued at the slot start: takes part, 100-120 us
    b.send_at(100 * US + 1, "b", "sink", 200, tag="just_after")  # 1 ns later: the next cycle's slot, 5.1 ms
    b.run(20 * MS)
    assert b.record("at_slot").delay_ns == 20 * US
    # worst case = cycle + frame time - 1 ns: 5 ms + 20 us - 1 ns (delivered at 5.1 ms + 20 us = 5.12 ms)
    just_after = b.record("just_after")
    assert just_after.delivered_ns == CYCLE + 100 * US + 20 * US
    assert just_after.delay_ns == CYCLE + 20 * US - 1


def test_one_static_frame_per_slot_per_cycle(bench):
    b = bench("flexray", PARAMS)
    for i in range(3):
        b.send_at(0, "b", "sink", 200, tag=f"m{i}")
    b.run(20 * MS)
    # slot 3 of cycles 0, 1 and 2: 100 us + k x 5 ms, each frame 20 us
    assert [b.record(f"m{i}").delivered_ns for i in range(3)] == [k * CYCLE + 120 * US for k in range(3)]


def test_dynamic_frames_go_in_frame_id_order_each_using_its_minislots(bench):
    b = bench("flexray", PARAMS)
    b.send_at(0, "e", "sink", 100, tag="e")
    b.send_at(0, "d", "sink", 100, tag="d")
    b.send_at(0, "c", "sink", 400, tag="c")
    b.run(20 * MS)
    # ID 11 (c): minislot 0, at 500 us; 40 us = 8 minislots: ends 540 us, next minislot 8
    # ID 12 (no owner): minislot 8 -> 9
    # ID 13 (d): minislot 9, at 500 + 9 x 5 = 545 us; 10 us = 2 minislots: ends 555 us, next minislot 11
    # ID 14 (e): minislot 11, at 500 + 11 x 5 = 555 us; ends 565 us
    assert b.record("c").delivered_ns == 540 * US
    assert b.record("d").delivered_ns == 555 * US
    assert b.record("e").delivered_ns == 565 * US
    assert b.net.metrics(20 * MS)["dynamic_frames"] == 3


def test_a_dynamic_frame_that_does_not_fit_before_the_segment_end_waits_for_the_next_cycle(bench):
    b = bench("flexray", PARAMS)
    b.send_at(0, "c", "sink", 4000, tag="long")  # 400 us = 80 minislots
    b.send_at(0, "e", "sink", 2000, tag="pushed")  # 200 us = 40 minislots
    b.run(20 * MS)
    # cycle 0: ID 11 (c) at minislot 0, 500-900 us, next minislot 80; ID 12: 81; ID 13 (d, nothing): 82;
    # ID 14 (e) at minislot 82 needs 40: 82 + 40 = 122 > 100 minislots, so it waits for cycle 1.
    # cycle 1: IDs 11, 12, 13 send nothing (one minislot each): e at minislot 3, 5 ms + 500 us + 3 x 5 us =
    # 5.515 ms, 200 us on the bus: delivered at 5.715 ms
    assert b.record("long").delivered_ns == 900 * US
    pushed = b.record("pushed")
    assert pushed.tx_start_ns == CYCLE + 515 * US and pushed.delivered_ns == CYCLE + 715 * US
    assert b.net.metrics(20 * MS)["deferred"] == 1


def test_a_dynamic_frame_queued_after_its_ids_turn_waits_a_cycle(bench):
    b = bench("flexray", PARAMS)
    # an idle segment: ID 13 (d) has its turn at minislot 2, 500 + 2 x 5 = 510 us
    b.send_at(510 * US, "d", "sink", 100, tag="on_time")  # queued at its turn: 510-520 us
    b.send_at(510 * US + 1, "c", "sink", 100, tag="late_c")  # ID 11's turn (500 us) has passed: cycle 1, 5.5 ms
    b.run(20 * MS)
    assert b.record("on_time").delivered_ns == 520 * US
    # cycle 1: ID 11 (c) at minislot 0: 5.5 ms, 10 us: 5.51 ms. Worst case for ID 11 with an idle bus:
    # cycle + frame time - 1 ns after its turn
    assert b.record("late_c").delivered_ns == CYCLE + 510 * US


def test_the_static_segment_is_not_disturbed_by_dynamic_traffic(bench):
    b = bench("flexray", PARAMS)
    for k in range(4):
        b.send_at(k * CYCLE, "c", "sink", 4000, tag=f"c{k}")  # 400 us of dynamic traffic in every cycle
        b.send_at(k * CYCLE, "b", "sink", 200, tag=f"b{k}")
    b.run(30 * MS)
    assert [b.record(f"b{k}").delivered_ns for k in range(4)] == [k * CYCLE + 120 * US for k in range(4)]
    assert [b.record(f"c{k}").delivered_ns for k in range(4)] == [k * CYCLE + 900 * US for k in range(4)]


def test_a_frame_longer_than_a_static_slot_is_refused(bench):
    b = bench("flexray", PARAMS)
    b.send_at(0, "b", "sink", 600, tag="long")  # 60 us > the 50 us slot
    with pytest.raises(ConfigError) as err:
        b.run(1 * MS)
    assert err.value.path == "networks.net.static_slot" and "longer than a static slot" in str(err.value)


def test_a_sender_with_no_slot_and_no_frame_id_is_refused(bench):
    b = bench("flexray", PARAMS)
    b.send_at(0, "sink", "a", 80)
    with pytest.raises(ConfigError, match="owns no static slot and no dynamic frame ID"):
        b.run(1 * MS)


def _scenario(**net) -> dict:
    return {
        "name": "fr", "duration": "10 ms",
        "nodes": {"a": {}, "b": {}},
        "networks": {"bus": {"type": "flexray", "nodes": ["a", "b"], "bitrate": "10 Mbit/s", "cycle": "1 ms",
                             "static_slot": "50 us", "static_schedule": ["a", "b"], **net}},
    }


def _errors(raw: dict) -> list[tuple[str, str]]:
    return [(p.path, p.message) for p in check_scenario(raw) if p.severity == "error"]


def test_a_valid_flexray_network_has_no_problem():
    assert _errors(_scenario(minislot="5 us", minislots=10, dynamic_ids={"b": 3})) == []


def test_a_slot_table_longer_than_the_cycle_is_refused_at_cycle():
    # 10 static slots of 50 us (500 us) + 100 minislots of 5 us (500 us) = 1 ms > a 900 us cycle
    errs = _errors(_scenario(cycle="900 us", static_schedule=["a", "b"] + [None] * 8, minislot="5 us",
                             minislots=100))
    assert len(errs) == 1 and errs[0][0] == "networks.bus.cycle"
    assert "take 1 ms, longer than the cycle (900 us)" in errs[0][1]


def test_an_unknown_node_in_the_slot_table_or_the_frame_ids_is_refused_at_its_path():
    errs = _errors(_scenario(static_schedule=["a", "z"]))
    assert [p for p, _ in errs] == ["networks.bus.static_schedule"] and "'z'" in errs[0][1]
    errs = _errors(_scenario(minislot="5 us", minislots=10, dynamic_ids={"q": 3}))
    assert [p for p, _ in errs] == ["networks.bus.dynamic_ids"] and "'q'" in errs[0][1]


def test_a_dynamic_frame_id_inside_the_static_segment_is_refused():
    errs = _errors(_scenario(minislot="5 us", minislots=10, dynamic_ids={"b": 2}))
    assert [p for p, _ in errs] == ["networks.bus.dynamic_ids"] and "run from 3" in errs[0][1]


def test_times_without_a_unit_are_refused():
    errs = _errors(_scenario(static_slot=50))
    assert [p for p, _ in errs] == ["networks.bus.static_slot"] and "unit" in errs[0][1]


def test_random_traffic_keeps_every_frame_inside_its_segment_and_never_overlaps(bench):
    import random

    rnd = random.Random(7)
    b = bench("flexray", PARAMS)
    sizes = {"a": (80, 500), "b": (80, 500), "c": (40, 3000), "d": (40, 3000), "e": (40, 3000)}
    for k in range(300):
        node = rnd.choice("abcde")
        lo, hi = sizes[node]
        b.send_at(rnd.randrange(0, 40 * MS), node, "sink", rnd.randrange(lo, hi), tag=f"m{k}")
    b.run(2000 * MS)  # at most one frame per node and cycle: a backlog of about 60 frames per node takes 0.3 s
    recs = sorted((r for r in b.net.records if r.tx_start_ns is not None), key=lambda r: r.tx_start_ns)
    assert len(recs) == 300 and all(r.delivered_ns is not None for r in recs)
    for r, nxt in zip(recs, recs[1:]):
        assert r.tx_end_ns <= nxt.tx_start_ns  # one frame at a time on the bus
    for r in recs:
        t0, t1 = r.tx_start_ns % CYCLE, r.tx_start_ns % CYCLE + (r.tx_end_ns - r.tx_start_ns)
        if r.sender in ("a", "b"):  # at the start of its own slot (a: 0 us, b: 100 us), within 50 us
            assert t0 == {"a": 0, "b": 100 * US}[r.sender] and t1 <= t0 + 50 * US
        else:  # inside the dynamic segment (500-1000 us), on a minislot boundary
            assert 500 * US <= t0 and t1 <= 1000 * US and (t0 - 500 * US) % (5 * US) == 0


def test_a_node_with_a_static_slot_and_a_dynamic_id_sends_at_its_first_turn(bench):
    b = bench("flexray", {**PARAMS, "dynamic_ids": {**PARAMS["dynamic_ids"], "a": 12}})
    b.send_at(0, "a", "sink", 200, tag="first")
    b.send_at(0, "a", "sink", 200, tag="second")
    b.run(20 * MS)
    # first: a's static slot 1 at 0 us, 20 us; second: ID 12 in an otherwise idle dynamic segment, after ID 11's
    # one empty minislot: 500 + 1 x 5 = 505 us, 20 us on the bus
    assert b.record("first").delivered_ns == 20 * US
    assert b.record("second").delivered_ns == 525 * US


def test_a_minimum_or_maximum_frame_longer_than_a_static_slot_is_refused_at_static_slot():
    # 10 Mbit/s: 600 bits take 60 us, longer than the 50 us slot
    for field in ("min_frame_bits", "max_frame_bits"):
        errs = _errors(_scenario(**{field: 600}))
        assert [p for p, _ in errs] == ["networks.bus.static_slot"], errs
        assert f"{field} = 600 bits takes 60 us" in errs[0][1]
    assert _errors(_scenario(max_frame_bits=500)) == []  # 50 us: fits exactly
