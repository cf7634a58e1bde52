"""Error messages write times with their unit, never as raw nanoseconds (issue 21)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from netsim.errors import ConfigError
from netsim.scenario import check_scenario

ROOT = Path(__file__).resolve().parents[1]
RAW_NS = re.compile(r"\d{4,} ns")  # e.g. "544000 ns": a time a reader has to count digits in


def test_a_radio_whose_ack_cannot_arrive_says_so_in_microseconds():
    problems = check_scenario(ROOT / "scenarios" / "dc_servo_zigbee.yaml", {"networks.bus.ack_timeout": "1 us"})
    text = "\n".join(str(p) for p in problems)
    # ACK: ack_delay 192 us + 40 bits at 250 kbit/s (160 us) + the PHY overhead 192 us = 544 us
    assert "ack_timeout (1 us) is shorter than ack_delay + the ACK frame (544 us)" in text
    assert not RAW_NS.search(text)


def test_cart_timing_errors_use_units():
    from netsim.models.cart.controllers import EventController

    with pytest.raises(ConfigError) as err:
        EventController(None, None, None, -1_500_000)  # a period of -1.5 ms
    assert "got -1.5 ms" in str(err.value) and not RAW_NS.search(str(err.value))
