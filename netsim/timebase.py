"""Simulation time as integer nanoseconds.

Every instant and duration inside netsim is an ``int`` number of nanoseconds. Seconds (floats) appear
only at the plant integrator and at the user interface. Integer time keeps coincidences exact: a 2 ms
and a 3 ms period meet every 6 ms forever, and a 20 us loop is exactly 20 us after a million periods.

Examples
--------
>>> parse_time("20 us")
20000
>>> parse_time("1.5 ms")
1500000
>>> to_seconds(parse_time("2 s"))
2.0
"""

from __future__ import annotations

import difflib
import math
import re
from decimal import ROUND_HALF_EVEN, Decimal
from typing import Final

__all__ = [
    "NS",
    "US",
    "MS",
    "S",
    "UNITS",
    "MAX_TIME",
    "TimeParseError",
    "parse_time",
    "parse_duration",
    "to_seconds",
    "from_seconds",
    "format_time",
    "bare_number_message",
]

NS: Final[int] = 1
US: Final[int] = 1_000
MS: Final[int] = 1_000_000
S: Final[int] = 1_000_000_000

#: Accepted unit spellings and their length in nanoseconds.
UNITS: Final[dict[str, int]] = {
    "ns": NS,
    "us": US,
    "µs": US,
    "μs": US,
    "ms": MS,
    "s": S,
    "min": 60 * S,
    "h": 3600 * S,
}

#: The largest time a scenario may give (any time field, the duration included): 10**18 ns = 1e9 s, about
#: 31.7 years of simulated time. Times are integer nanoseconds and end up in int64 columns (numpy, CSV
#: readers); this limit keeps a sum of a few times (release = offset + k * period, end = start + duration)
#: below the int64 limit of 9.22e18 ns. Anything longer is refused by :func:`parse_time`.
MAX_TIME: Final[int] = 10**18

_PATTERN = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([^\d\s].*?)?\s*$")


class TimeParseError(ValueError):
    """A time string could not be understood; the message says what to change."""


_LONG_NAMES: Final[dict[str, str]] = {
    "nsec": "ns", "nanosecond": "ns", "nanoseconds": "ns",
    "usec": "us", "microsecond": "us", "microseconds": "us", "micros": "us",
    "msec": "ms", "millisecond": "ms", "milliseconds": "ms", "millis": "ms",
    "sec": "s", "secs": "s", "second": "s", "seconds": "s",
    "minute": "min", "minutes": "min", "mins": "min", "hour": "h", "hours": "h", "hr": "h",
}


def _suggest(unit: str) -> str:
    lowered = unit.lower()
    if lowered in _LONG_NAMES:
        return _LONG_NAMES[lowered]
    if lowered in UNITS:
        return lowered
    close = difflib.get_close_matches(lowered, list(UNITS), n=1, cutoff=0.5)
    return close[0] if close else ""


def bare_number_message(value: int | float) -> str:
    """The message refusing a time written without a unit (``5`` -> "add a unit, e.g. '5 ms'")."""
    if not math.isfinite(value):
        return f"time must be finite, got {value!r}"
    example = f"{value:g} {'s' if abs(value) < 1 else 'ms'}"
    return f"time {value!r} has no unit; add a unit, e.g. '{example}' (units: ns, us, ms, s, min, h)"


def parse_time(value: str | int | float, *, allow_negative: bool = False) -> int:
    """Parse a time into integer nanoseconds.

    Parameters
    ----------
    value
        A string with a number and a unit (``"20 us"``, ``"1.5 ms"``, ``"2 s"``, ``"1e-3 s"``). A bare number
        is refused (``period: 5`` could mean 5 s or 5 ms: "add a unit, e.g. '5 ms'"), except ``0``, which is
        zero in every unit.
    allow_negative
        Accept negative values (offsets); durations and periods are non-negative by default.

    Returns
    -------
    int
        The time in nanoseconds, rounded to the nearest nanosecond.

    Raises
    ------
    TimeParseError
        For a bare number other than 0, an unknown unit (with a suggestion), a missing number or unit, a
        negative value when not allowed, or a magnitude beyond :data:`MAX_TIME`.
    """
    if isinstance(value, bool):
        raise TimeParseError(f"expected a time such as '1 ms', got {value!r}")
    if isinstance(value, (int, float)):
        if value == 0:
            return 0
        raise TimeParseError(bare_number_message(value))
    if isinstance(value, str):
        match = _PATTERN.match(value)
        if match is None:
            raise TimeParseError(f"cannot read {value!r} as a time; write a number and a unit, e.g. '1.5 ms'")
        number, unit = match.group(1), (match.group(2) or "").strip()
        if not unit:
            raise TimeParseError(
                f"time {value!r} has no unit; add a unit, e.g. '{number} ms' (units: ns, us, ms, s, min, h)"
            )
        if unit not in UNITS:
            hint = _suggest(unit)
            tip = f"; did you mean '{hint}'?" if hint else "; use one of ns, us, ms, s, min, h"
            raise TimeParseError(f"unknown unit '{unit}'{tip}")
        scale = UNITS[unit]
        # decimal arithmetic: "1.0000005 s" is exactly 1000000500 ns, whatever its length
        amount = Decimal(number)
        if amount.copy_abs() > Decimal(MAX_TIME // scale):  # compared before multiplying: "1e999999 s" stays cheap
            shown = value if len(value) <= 40 else value[:37] + "..."
            raise TimeParseError(
                f"time {shown!r} is beyond netsim's limit of 1e9 s (10^18 ns, about 31.7 years); write a shorter time"
            )
        exact = amount * scale
        ns = int(exact.to_integral_value(rounding=ROUND_HALF_EVEN))
    else:
        raise TimeParseError(f"expected a time such as '1 ms', got {type(value).__name__} {value!r}")
    if ns < 0 and not allow_negative:
        raise TimeParseError(f"time must not be negative, got {value!r}")
    return int(ns)


def parse_duration(value: str | int | float) -> int:
    """Parse a strictly positive duration (a period, a step) into nanoseconds."""
    ns = parse_time(value)
    if ns <= 0:
        raise TimeParseError(f"duration must be positive, got {value!r}")
    return ns


def to_seconds(ns: int) -> float:
    """Convert integer nanoseconds to float seconds."""
    return ns / S


def from_seconds(seconds: float) -> int:
    """Convert float seconds to integer nanoseconds (nearest)."""
    return int(round(seconds * S))


def format_time(ns: int) -> str:
    """Format nanoseconds exactly, with the largest unit that keeps the value readable (``'1.5 ms'``).

    The text parses back to the same integer (``parse_time(format_time(t)) == t``): no digit is rounded away.
    """
    sign = "-" if ns < 0 else ""
    mag = abs(int(ns))
    for unit, scale, digits in (("s", S, 9), ("ms", MS, 6), ("us", US, 3)):
        if mag >= scale:
            whole, frac = divmod(mag, scale)
            text = f"{whole}.{frac:0{digits}d}".rstrip("0").rstrip(".")
            return f"{sign}{text} {unit}"
    return f"{sign}{mag} ns"
