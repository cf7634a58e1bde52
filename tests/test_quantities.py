"""One SI-prefix parser for every quantity other than time (netsim.quantities): powers, energies, bit rates and
frequencies, read exactly (the float nearest to the decimal value), with messages that list the accepted units."""

from __future__ import annotations

from fractions import Fraction

import pytest

from netsim.quantities import BITRATE, ENERGY, FREQUENCY, POWER, parse_quantity


# Expected values: the Python float literal of the decimal value (float literals are correctly rounded, so each
# is the nearest float to the exact decimal), or an exact fraction converted once.
@pytest.mark.parametrize(("text", "quantity", "expected"), [
    ("52 mW", POWER, 0.052),  # 52 * 1e-3 in floats is 0.052000000000000005: not the nearest float
    ("60 uW", POWER, 6e-05),  # 60 * 1e-6 in floats is 5.9999999999999995e-05
    ("60 nW", POWER, 6e-08),
    ("3 µW", POWER, 3e-06),
    ("0.1 W", POWER, 0.1),
    ("5 uJ", ENERGY, 5e-06),
    ("1 kWh", ENERGY, 3_600_000.0),  # 1000 W * 3600 s
    ("300 mWh", ENERGY, 1080.0),  # 0.3 W h = 0.3 * 3600 J
    ("1.5 Wh", ENERGY, 5400.0),
    ("20 J", ENERGY, 20.0),
    ("80 kbit/s", BITRATE, 80_000.0),
    ("1 Mbit/s", BITRATE, 1_000_000.0),
    ("10 Mbps", BITRATE, 10_000_000.0),
    ("1 Gbit/s", BITRATE, 1e9),
    ("250 Kbps", BITRATE, 250_000.0),  # the capital K the bit-rate parser always took
    ("10 kHz", FREQUENCY, 10_000.0),
    ("2.5 MHz", FREQUENCY, 2_500_000.0),
    (0.052, POWER, 0.052),  # a bare number is in the base unit
    (80000, BITRATE, 80_000.0),
])
def test_a_quantity_with_an_si_prefix_is_the_nearest_float_to_its_decimal_value(text, quantity, expected):
    assert parse_quantity(text, quantity) == expected


def test_sub_unit_values_round_once():
    # 0.1 nWh = 3.6e-7 J has no exact float; the parser rounds the exact fraction once
    assert parse_quantity("0.1 nWh", ENERGY) == float(Fraction(1, 10) * Fraction(1, 10**9) * 3600)


@pytest.mark.parametrize(("text", "quantity", "listed"), [
    ("3 V", POWER, ["pW", "nW", "uW", "mW", "W", "kW"]),
    ("1 kW", ENERGY, ["uJ", "J", "mWh", "kWh"]),
    ("80 kbyte/s", BITRATE, ["bit/s", "kbit/s", "Mbit/s"]),
    ("10 rpm", FREQUENCY, ["Hz", "kHz", "MHz"]),
])
def test_an_unknown_unit_is_refused_with_the_units_the_field_accepts(text, quantity, listed):
    with pytest.raises(ValueError) as info:
        parse_quantity(text, quantity)
    message = str(info.value)
    assert message.startswith(f"cannot read {text!r} as a {quantity.name}: unknown {quantity.name} unit")
    for unit in listed:
        assert f" {unit}," in message or f" {unit} " in message, (unit, message)


def test_a_bit_rate_takes_no_sub_unit_prefix_and_a_miscased_unit_gets_a_suggestion():
    with pytest.raises(ValueError, match="did you mean 'Mbps'"):
        parse_quantity("1 mbps", BITRATE)  # not a millibit per second
    with pytest.raises(ValueError, match="did you mean 'kHz'"):
        parse_quantity("10 khz", FREQUENCY)


@pytest.mark.parametrize(("value", "quantity"), [
    ("-1 mW", POWER), (-1, ENERGY), ("0 kbit/s", BITRATE), (float("nan"), POWER), ("inf W", POWER),
    (True, POWER), ([1], ENERGY), ("2e15 W", POWER), ("1e999999 J", ENERGY), ("fast", BITRATE),
])
def test_negative_non_finite_huge_and_unreadable_values_are_refused(value, quantity):
    with pytest.raises(ValueError):
        parse_quantity(value, quantity)


def test_every_quantity_field_reads_through_the_one_parser():
    from netsim import quantities, units
    from netsim.energy import params as energy

    assert units.parse_bitrate is quantities.parse_bitrate
    assert energy.parse_power is quantities.parse_power and energy.parse_energy is quantities.parse_energy
    model = energy.EnergyModel(cpu={"busy": "52 mW", "idle": "60 nW"}, battery={"capacity": "5 uJ"})
    assert (model.cpu.busy, model.cpu.idle, model.battery.capacity) == (0.052, 6e-08, 5e-06)
    big = energy.Battery(capacity="1 kWh")
    assert big.capacity == 3_600_000.0


def test_a_network_bit_rate_field_takes_the_same_prefixes():
    from pydantic import TypeAdapter

    from netsim.units import Bitrate

    assert TypeAdapter(Bitrate).validate_python("1 Mbit/s") == 1e6
    with pytest.raises(ValueError, match="kbit/s"):
        TypeAdapter(Bitrate).validate_python("1 Mbyte/s")


def test_a_power_in_dbm_is_not_a_power_field_s_unit():
    # dBm is a log scale: the wireless networks' *_dbm fields stay plain numbers; a power field refuses it
    with pytest.raises(ValueError, match="unknown power unit 'dBm'"):
        parse_quantity("0 dBm", POWER)
