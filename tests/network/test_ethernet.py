"""Switched Ethernet: full duplex, store and forward, FIFO output ports, finite switch memory."""

from netsim.timebase import MS

P = {"nodes": ["a", "b", "c"], "bitrate": "1 Mbit/s", "min_frame_bits": 1000}  # 1 ms per 1000 bits


def test_store_and_forward_takes_two_transmissions(bench):
    b = bench("ethernet", P)
    b.send_at(0, "a", "b", 1000, tag="x")
    b.run(10 * MS)
    r = b.record("x")
    assert (r.tx_start_ns, r.tx_end_ns, r.delivered_ns) == (0, 2 * MS, 2 * MS)


def test_full_duplex_links_never_collide(bench):
    b = bench("ethernet", P)
    b.send_at(0, "a", "b", 1000, tag="ab")
    b.send_at(0, "b", "a", 1000, tag="ba")
    b.run(10 * MS)
    assert b.record("ab").delivered_ns == b.record("ba").delivered_ns == 2 * MS


def test_output_port_is_fifo(bench):
    b = bench("ethernet", {**P, "switch_delay": "0.1 ms"})
    b.send_at(0, "a", "c", 1000, tag="x")
    b.send_at(0, "b", "c", 2000, tag="y")
    b.run(20 * MS)
    # x in the switch at 1 ms (+0.1), out on c's port 1.1..2.1; y in at 2 ms (+0.1), out 2.1..4.1
    assert b.deliveries("c") == [(2_100_000, "x"), (4_100_000, "y")]


def test_full_switch_drops(bench):
    # 3000 bits of common memory: three 1000-bit frames for c fit, a fourth does not while c's port drains
    b = bench("ethernet", {**P, "nodes": ["a", "b", "c", "d"], "switch_memory_bits": 3000})
    for s in ("a", "b", "d"):
        b.send_at(0, s, "c", 1000, tag=s)
    b.send_at(0, "a", "c", 1000, tag="a2")  # in the switch at 2 ms, when x, y, z still hold 2000 bits
    b.run(20 * MS)
    assert [t for _, t in b.deliveries("c")] == ["a", "b", "d", "a2"]  # 2000 + 1000 fits exactly
    b = bench("ethernet", {**P, "nodes": ["a", "b", "c", "d"], "switch_memory_bits": 2500})
    for s in ("a", "b", "d"):
        b.send_at(0, s, "c", 1000, tag=s)
    b.run(20 * MS)
    # the three copies arrive together at 1 ms: two fit in 2500 bits, the third is dropped
    assert len(b.deliveries("c")) == 2
    assert [r.drop_reason for r in b.net.records if r.dropped] == ["switch_full"]
    m = b.net.metrics(20 * MS)
    assert m["dropped.switch_full"] == 1 and m["switch_memory_max_bits"] == 2000


def test_full_switch_asks_the_sender_to_retransmit(bench):
    b = bench("ethernet", {**P, "nodes": ["a", "b", "c", "d"], "switch_memory_bits": 2500,
                           "overflow": "retransmit"})
    for s in ("a", "b", "d"):
        b.send_at(0, s, "c", 1000, tag=s)
    b.run(20 * MS)
    # all three are in the switch at 1 ms: a and b fit (2000 bits), d's copy is refused and d sends it
    # again on its uplink [1, 2) ms. At 2 ms a has left c's port (1000 bits freed), so d's copy fits;
    # c's port then sends a [1, 2), b [2, 3), d [3, 4) ms.
    m = b.net.metrics(20 * MS)
    assert m["retransmissions"] == 1 and m["dropped"] == 0
    assert b.deliveries("c") == [(2 * MS, "a"), (3 * MS, "b"), (4 * MS, "d")]
    assert b.record("d").tx_start_ns == 0  # the first attempt's start


def test_per_output_buffers_split_the_memory(bench):
    # 8000 bits over 4 ports -> 2000 per port: of three copies reaching c's port together, one is dropped;
    # with one common 8000-bit buffer all three fit
    def run(buffer):
        b = bench("ethernet", {**P, "nodes": ["a", "b", "c", "d"], "switch_memory_bits": 8000,
                               "switch_buffer": buffer})
        for s in ("a", "b", "d"):
            b.send_at(0, s, "c", 1000, tag=s)
        b.send_at(0, "c", "b", 1000, tag="cb")
        b.run(20 * MS)
        return b

    split = run("per_output")
    assert [r.drop_reason for r in split.net.records if r.dropped] == ["switch_full"]
    assert split.record("cb").delivered_ns == 2 * MS
    common = run("common")
    assert common.net.metrics(20 * MS)["dropped"] == 0 and len(common.deliveries("c")) == 3
