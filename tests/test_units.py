"""Pydantic field types with units."""

import pytest
from pydantic import ValidationError

from netsim.units import Bitrate, Duration, StrictModel, Time, parse_bitrate


class _Params(StrictModel):
    period: Duration
    offset: Time = 0
    rate: Bitrate = 1e6


def test_time_fields_become_integer_nanoseconds():
    p = _Params(period="1.5 ms", offset="20 us", rate="80 kbit/s")
    assert (p.period, p.offset, p.rate) == (1_500_000, 20_000, 80_000.0)


def test_every_problem_is_reported_with_its_field():
    with pytest.raises(ValidationError) as info:
        _Params(period="3 usec", offset="-1 ms", colour="red")
    errors = {tuple(e["loc"]): e["msg"] for e in info.value.errors()}
    assert "did you mean 'us'" in errors[("period",)]
    assert "negative" in errors[("offset",)]
    assert ("colour",) in errors  # unknown key
    assert len(errors) == 3


def test_json_dump_renders_times_as_text():
    assert _Params(period="2 ms").model_dump(mode="json")["period"] == "2 ms"


@pytest.mark.parametrize(("text", "rate"), [("80 kbit/s", 80e3), ("1 Mbps", 1e6), ("10 Mbit/s", 10e6), (500, 500.0)])
def test_bitrate_parsing(text, rate):
    assert parse_bitrate(text) == rate


@pytest.mark.parametrize("text", ["fast", "-3 kbit/s", "0", "80 kbyte/s"])
def test_bad_bitrates_are_rejected(text):
    with pytest.raises(ValueError):
        parse_bitrate(text)
