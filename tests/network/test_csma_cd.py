"""CSMA/CD: carrier sense, collisions within the window, binary exponential backoff."""

import pytest

from netsim.timebase import MS, US

P = {"nodes": ["a", "b", "c"], "bitrate": "80 kbit/s", "min_frame_bits": 80}  # 1 ms frames and slots


def test_lone_sender_never_collides(bench):
    b = bench("csma_cd", P)
    b.send_at(0, "a", "c", 80, tag="x")
    b.send_at(500 * US, "a", "c", 160, tag="y")  # queued behind x
    b.run(10 * MS)
    assert b.deliveries("c") == [(1 * MS, "x"), (3 * MS, "y")]
    assert b.net.metrics(10 * MS)["collisions"] == 0


def test_start_outside_the_collision_window_waits_for_the_medium(bench):
    b = bench("csma_cd", P)
    b.send_at(0, "a", "c", 80, tag="x")
    b.send_at(1500, "b", "c", 80, tag="y")  # 1.5 us after a started: carrier sensed, waits
    b.run(10 * MS)
    assert b.record("y").tx_start_ns == b.record("x").tx_end_ns == 1 * MS
    assert b.net.metrics(10 * MS)["collisions"] == 0


def test_start_inside_the_collision_window_collides(bench):
    b = bench("csma_cd", P)
    b.send_at(0, "a", "c", 80, tag="x")
    b.send_at(500, "b", "c", 80, tag="y")  # 0.5 us later: within the 1 us window
    b.run(20 * MS)
    m = b.net.metrics(20 * MS)
    assert m["collisions"] >= 1 and m["delivered"] == 2
    x, y = b.record("x"), b.record("y")
    # the collision occupied [0, 1 us]; both retried after backoffs on the 1 ms slot grid
    assert min(x.tx_start_ns, y.tx_start_ns) >= 1 * US
    assert x.tx_end_ns <= y.tx_start_ns or y.tx_end_ns <= x.tx_start_ns


def test_nodes_waiting_for_the_medium_collide_when_it_goes_idle(bench):
    b = bench("csma_cd", P)
    b.send_at(0, "a", "c", 80, tag="first")
    b.send_at(300 * US, "b", "c", 80, tag="p")
    b.send_at(600 * US, "c", "a", 80, tag="q")
    b.run(50 * MS)
    m = b.net.metrics(50 * MS)
    assert m["collisions"] >= 1 and m["delivered"] == 3
    assert min(b.record("p").tx_start_ns, b.record("q").tx_start_ns) > 1 * MS


def test_collision_counts_follow_binary_exponential_backoff(bench):
    # Two frames started together: the first collision is certain; after k collisions each node draws
    # R in 0 .. 2^k - 1 and they collide again only if they draw the same R (probability 2^-k).
    # P(exactly 1 collision) = 1/2; P(exactly 2) = 1/2 * 3/4 = 3/8. 600 seeded runs: sigma ~ 0.02.
    counts = []
    for seed in range(600):
        b = bench("csma_cd", P, seed=seed)
        b.send_at(0, "a", "c", 80)
        b.send_at(0, "b", "c", 80)
        b.run(100 * MS)
        m = b.net.metrics(100 * MS)
        assert m["delivered"] == 2
        counts.append(m["collisions"])
    n = len(counts)
    assert counts.count(1) / n == pytest.approx(0.5, abs=0.07)
    assert counts.count(2) / n == pytest.approx(0.375, abs=0.07)


def test_collision_time_counts_as_busy(bench):
    b = bench("csma_cd", {**P, "collision_window": "100 us"})
    b.send_at(0, "a", "c", 80)
    b.send_at(0, "b", "c", 80)
    b.run(100 * MS)
    m = b.net.metrics(100 * MS)
    # two 1 ms frames plus 0.1 ms per collision
    assert m["utilization"] * 100 * MS == pytest.approx(2 * MS + m["collisions"] * 100 * US)


def test_max_attempts_drops_after_too_many_collisions(bench):
    b = bench("csma_cd", {**P, "max_attempts": 1})
    b.send_at(0, "a", "c", 80)
    b.send_at(0, "b", "c", 80)
    b.run(10 * MS)
    assert [r.drop_reason for r in b.net.records] == ["collisions", "collisions"]


def test_backoff_draws_come_from_the_networks_own_stream(bench):
    def trace(seed, name):
        b = bench("csma_cd", P, seed=seed, name=name)
        for k in range(3):
            for s in ("a", "b", "c"):
                b.send_at(k * 3 * MS, s, "a" if s != "a" else "b", 80)
        b.run(200 * MS)
        return [(r.sender, r.tx_start_ns) for r in b.net.records]

    assert trace(1, "lan") == trace(1, "lan")
    assert trace(1, "lan") != trace(1, "lan2")  # another network name, another stream
