"""Integer-nanosecond time: parsing, unit errors, exact accumulation."""

import re

import pytest

from netsim.timebase import MS, NS, S, US, TimeParseError, format_time, from_seconds, parse_duration, parse_time, to_seconds


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("20 us", 20 * US),
        ("20us", 20 * US),
        ("1.5 ms", 1_500_000),
        ("2 s", 2 * S),
        ("1e-3 s", 1 * MS),
        ("7 ns", 7 * NS),
        ("20 µs", 20 * US),
        ("1 min", 60 * S),
        (0, 0),  # zero is zero in every unit: the one number allowed without a unit
        (0.0, 0),
    ],
)
def test_parse_time_reads_number_and_unit(text, expected):
    assert parse_time(text) == expected
    assert isinstance(parse_time(text), int)


@pytest.mark.parametrize(
    ("text", "suggestion"),
    [("3 usec", "us"), ("1 sec", "s"), ("2 seconds", "s"), ("5 msec", "ms"), ("4 MS", "ms")],
)
def test_unknown_unit_error_suggests_the_closest_unit(text, suggestion):
    with pytest.raises(TimeParseError, match=f"did you mean '{suggestion}'"):
        parse_time(text)


@pytest.mark.parametrize("text", ["5", "ms", "x ms", "", "nan s", "inf ms"])
def test_malformed_times_are_rejected(text):
    with pytest.raises(TimeParseError):
        parse_time(text)


@pytest.mark.parametrize(("value", "example"), [(5, "5 ms"), (2.0e-5, "2e-05 s"), (-3, "-3 ms"), (1e300, "1e+300 ms")])
def test_a_bare_number_is_refused_with_a_unit_to_add(value, example):
    # issue 13 C: `period: 5` could be 5 s or 5 ms; netsim used to read it as seconds
    with pytest.raises(TimeParseError, match=re.escape(f"add a unit, e.g. '{example}'")):
        parse_time(value, allow_negative=True)


def test_negative_time_rejected_unless_allowed():
    with pytest.raises(TimeParseError, match="negative"):
        parse_time("-1 ms")
    assert parse_time("-1 ms", allow_negative=True) == -MS


def test_duration_must_be_positive():
    with pytest.raises(TimeParseError, match="positive"):
        parse_duration("0 s")


def test_twenty_microsecond_loop_is_exact_after_a_million_periods():
    # the point of integer time: 10^6 periods of 20 us are exactly 20 s
    t = 0
    period = parse_time("20 us")
    for _ in range(1_000_000):
        t += period
    assert t == 20 * S
    assert to_seconds(t) == 20.0


def test_seconds_round_trip_and_formatting():
    assert from_seconds(0.0015) == 1_500_000
    assert to_seconds(1_500_000) == pytest.approx(0.0015)
    assert format_time(1_500_000) == "1.5 ms"
    assert format_time(2 * S) == "2 s"
    assert format_time(999) == "999 ns"


def test_formatted_time_parses_back_to_the_same_nanoseconds():
    # exactness of the text form: resolved scenarios and scenario hashes depend on it
    import random

    rng = random.Random(1)
    samples = [1_000_000_500, 123_456_789_012, 3_600 * S + 1, -1_500_000] + [rng.randrange(10**15) for _ in range(2000)]
    for t in samples:
        assert parse_time(format_time(t), allow_negative=True) == t
    assert format_time(1_000_000_500) == "1.0000005 s"


def test_a_time_beyond_the_limit_is_refused_and_the_limit_parses_exactly():
    # 1e300 s was once parsed exactly (10**309 ns) and then overflowed at run; the limit is MAX_TIME = 10**18 ns
    with pytest.raises(TimeParseError, match="beyond netsim's limit of 1e9 s"):
        parse_time("1e300 s")
    assert parse_time("999999999.999999999 s") == 10**18 - 1
