"""Round robin (token bus): one frame per turn in node order, token passing time between turns."""

from netsim.timebase import MS, US

P = {"nodes": ["a", "b", "c", "d"], "bitrate": "80 kbit/s", "min_frame_bits": 80}  # 1 ms frames and passes


def test_nodes_take_turns_one_frame_each(bench):
    b = bench("round_robin", P)
    for k in range(2):
        b.send_at(0, "a", "d", 80, tag=f"a{k}")
        b.send_at(0, "c", "d", 80, tag=f"c{k}")
    b.run(30 * MS)
    # token at a at t=0: a0 [0,1); pass 1 ms -> b at 2 (empty) -> c at 3: c0 [3,4); pass -> d at 5 (empty)
    # -> a at 6: a1 [6,7); -> b at 8 -> c at 9: c1 [9,10)
    assert b.deliveries("d") == [(1 * MS, "a0"), (4 * MS, "c0"), (7 * MS, "a1"), (10 * MS, "c1")]


def test_idle_token_keeps_circulating(bench):
    b = bench("round_robin", P)
    b.send_at(5500 * US, "c", "a", 80, tag="x")
    b.run(30 * MS)
    # nobody sends before 5.5 ms: the token visits a,b,c,d at 0,1,2,3 ms, a at 4, b at 5, c at 6 ms
    assert b.record("x").tx_start_ns == 6 * MS


def test_arrival_exactly_at_the_token_visit_is_served(bench):
    b = bench("round_robin", P)
    b.send_at(2 * MS, "c", "a", 80, tag="x")  # the token reaches c at exactly 2 ms
    b.send_at(2 * MS + 1, "b", "a", 80, tag="y")  # b was visited at 1 ms; next at 5 ms (after c's frame)
    b.run(30 * MS)
    assert b.record("x").tx_start_ns == 2 * MS
    # c sends [2,3); pass -> d at 4 -> a at 5 -> b at 6 ms
    assert b.record("y").tx_start_ns == 6 * MS


def test_token_pass_time_can_be_set(bench):
    b = bench("round_robin", {**P, "token_pass": "10 us"})
    b.send_at(0, "b", "a", 80, tag="x")
    b.send_at(0, "d", "a", 80, tag="y")
    b.run(30 * MS)
    # token at a (empty) -> b at 10 us: [10 us, 1.01 ms); pass -> c at 1.02 ms -> d at 1.03 ms
    assert (b.record("x").tx_start_ns, b.record("y").tx_start_ns) == (10 * US, 1030 * US)
