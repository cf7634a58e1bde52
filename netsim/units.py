"""Pydantic field types for scenario parameters with units.

Every plugin (network, program, plant, trigger) describes its parameters as a pydantic model with
``extra="forbid"``; time fields use these types so ``"20 us"`` becomes ``20000`` (ns) and a typo such as
``"20 usec"`` is reported with its YAML path and a suggestion. A bare number (``period: 5``) is refused with
"add a unit, e.g. '5 ms'" (only ``0`` may be written without a unit).

Examples
--------
>>> from pydantic import BaseModel
>>> class P(BaseModel):
...     period: Duration
>>> P(period="1.5 ms").period
1500000
"""

from __future__ import annotations

import math
import re
from typing import Annotated, Any, Final

from pydantic import BaseModel, BeforeValidator, ConfigDict, PlainSerializer

from netsim.timebase import TimeParseError, format_time, parse_duration, parse_time

__all__ = ["NUMBER_LIMIT", "Time", "Duration", "SignedTime", "Bitrate", "StrictModel", "parse_bitrate"]

#: The largest magnitude of a number in a scenario (gains, rates, positions, initial states, noise levels):
#: ``|x| <= 1e15``. Larger values overflow the float arithmetic of plants and controllers (a square of 1e160
#: is already inf); NaN and inf are refused everywhere. Checked for every number of a scenario by
#: :mod:`netsim.scenario.validate`.
NUMBER_LIMIT: Final[float] = 1e15


def _time(value: Any) -> int:
    try:
        return parse_time(value)
    except TimeParseError as exc:
        raise ValueError(str(exc)) from None


def _duration(value: Any) -> int:
    try:
        return parse_duration(value)
    except TimeParseError as exc:
        raise ValueError(str(exc)) from None


def _signed(value: Any) -> int:
    try:
        return parse_time(value, allow_negative=True)
    except TimeParseError as exc:
        raise ValueError(str(exc)) from None


_BITRATE = re.compile(r"^\s*([0-9.eE+-]+)\s*([kKMG]?)(?:bit/s|bps|b/s)\s*$")
_BITRATE_SCALE = {"": 1.0, "k": 1e3, "K": 1e3, "M": 1e6, "G": 1e9}


def parse_bitrate(value: Any) -> float:
    """Parse a data rate in bit/s: a number, or ``"80 kbit/s"``, ``"1 Mbps"``, ``"10 Mbit/s"``."""
    if isinstance(value, bool):
        raise ValueError(f"expected a bit rate such as '80 kbit/s', got {value!r}")
    if isinstance(value, (int, float)):
        rate = float(value)
    elif isinstance(value, str):
        m = _BITRATE.match(value)
        if m is None:
            raise ValueError(f"cannot read {value!r} as a bit rate; write e.g. '80 kbit/s', '1 Mbit/s' or 80000")
        rate = float(m.group(1)) * _BITRATE_SCALE[m.group(2)]
    else:
        raise ValueError(f"expected a bit rate such as '80 kbit/s', got {value!r}")
    if not math.isfinite(rate) or not 0 < rate <= NUMBER_LIMIT:
        raise ValueError(f"bit rate must be positive and at most {NUMBER_LIMIT:g} bit/s, got {value!r}")
    return rate


def _as_text(ns: int) -> str:
    return format_time(ns)


#: A non-negative time in ns (``"0 s"``, ``"1.5 ms"``); serialized back as text.
Time = Annotated[int, BeforeValidator(_time), PlainSerializer(_as_text, return_type=str, when_used="json")]
#: A strictly positive duration in ns (periods, steps).
Duration = Annotated[int, BeforeValidator(_duration), PlainSerializer(_as_text, return_type=str, when_used="json")]
#: A time that may be negative (offsets relative to something).
SignedTime = Annotated[int, BeforeValidator(_signed), PlainSerializer(_as_text, return_type=str, when_used="json")]
#: A data rate in bit/s.
Bitrate = Annotated[float, BeforeValidator(parse_bitrate)]


class StrictModel(BaseModel):
    """Base of every parameter model: unknown keys are errors, values are validated on assignment, and a float
    field refuses NaN and inf (also written as text, ``"nan"``)."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True, frozen=False, allow_inf_nan=False)
