"""A carrier-sense threshold apart from the decode threshold (issue 20): sensed-but-not-decoded frames defer."""

import math

import pytest

from netsim.timebase import US

#: 0 dBm, path-loss exponent 3.5, d0 = 1 m: the power c (400 m from a) gets from a's frames
A_AT_C_DBM = -35.0 * math.log10(400.0)  # -91.07 dBm: below the -85 dBm decode threshold


def _params(**extra):
    # a and b 10 m apart, c and d 10 m apart, 400 m from a; no random backoff (BE = 0: a CCA every 128 us) and
    # enough CCAs for c to wait out a's frame; no ACKs
    return {"nodes": ["a", "b", "c", "d"],
            "positions": {"a": [0, 0], "b": [10, 0], "c": [400, 0], "d": [410, 0]},
            "acks": False, "min_be": 0, "max_be": 0, "max_csma_backoffs": 60, **extra}


def _c_start(bench, **extra):
    b = bench("802.15.4", _params(**extra))
    b.send_at(0, "a", "b", 840, tag="long")  # 928 wire bits: 192 us + 3712 us on the air
    b.send_at(500 * US, "c", "d", 64, tag="short")
    b.run(100_000 * US)
    assert not b.record("long").dropped and not b.record("short").dropped
    return b.record("long"), b.record("short"), b.net.metrics(100_000 * US)


def test_a_frame_sensed_but_not_decoded_defers_the_sender(bench):
    assert -95.0 < A_AT_C_DBM < -85.0  # sensed at -95 dBm, not decodable at -85 dBm
    long, short, m = _c_start(bench, carrier_sense_dbm=-95.0)
    # a: CCA 128 us + turnaround 192 us, then 3904 us on the air: [320, 4224) us
    assert (long.tx_start_ns, long.tx_end_ns) == (320 * US, 4224 * US)
    # c's CCAs end at 500 + 128 k us; busy for k = 1 .. 29 (<= 4212 us), idle at k = 30 (4340 us), then the
    # turnaround: c transmits at 4532 us
    assert short.tx_start_ns == 4532 * US
    assert m["busy_ccas"] == 29


@pytest.mark.parametrize("cs", [None, -90.0])
def test_a_frame_neither_sensed_nor_decoded_does_not_defer(bench, cs):
    assert A_AT_C_DBM < -90.0
    extra = {} if cs is None else {"carrier_sense_dbm": cs}
    long, short, m = _c_start(bench, **extra)
    # c's first CCA (628 us) finds the channel idle: it transmits after the turnaround, during a's frame
    assert short.tx_start_ns == 500 * US + 128 * US + 192 * US
    assert short.tx_start_ns < long.tx_end_ns and m["busy_ccas"] == 0


def test_80211b_defers_to_a_frame_it_only_senses(bench):
    # 20 dBm, exponent 3.5: at 1200 m a's power is 20 - 35 log10(1200) = -87.8 dBm (decode threshold -82 dBm)
    p_c = 20.0 - 35.0 * math.log10(1200.0)
    assert -90.0 < p_c < -82.0
    params = {"nodes": ["a", "b", "c", "d"], "acks": False,
              "positions": {"a": [0, 0], "b": [10, 0], "c": [1200, 0], "d": [1210, 0]}}
    starts = {}
    for cs in (None, -90.0):
        b = bench("802.11b", {**params, **({} if cs is None else {"carrier_sense_dbm": cs})})
        b.send_at(1000 * US, "a", "b", 8000, tag="long")  # 192 us + 8272 bits / 11 Mbit/s = 945 us
        b.send_at(1100 * US, "c", "d", 64, tag="short")
        b.run(50_000 * US)
        starts[cs] = (b.record("long").tx_end_ns, b.record("short").tx_start_ns)
    # not sensed: the medium idle for DIFS at c, it sends at once
    assert starts[None][1] == 1100 * US
    # sensed: c waits until a's frame ends, then DIFS (50 us) and its backoff (slots of 20 us)
    end, start = starts[-90.0]
    assert start >= end + 50 * US and (start - end - 50 * US) % (20 * US) == 0
