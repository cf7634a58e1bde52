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

import functools
import re
from typing import Annotated, Any, ClassVar, get_args

from pydantic import BaseModel, BeforeValidator, ConfigDict, PlainSerializer, model_serializer, model_validator

from netsim.quantities import BITRATE, NUMBER_LIMIT, parse_bitrate, quantity_pattern
from netsim.timebase import UNITS, TimeParseError, format_time, parse_duration, parse_time

__all__ = ["NUMBER_LIMIT", "Time", "Duration", "SignedTime", "Bitrate", "StrictModel", "parse_bitrate",
           "TIME_PATTERN", "SIGNED_TIME_PATTERN", "BITRATE_PATTERN"]


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


_TIME_UNITS = "|".join(re.escape(u) for u in sorted(UNITS, key=len, reverse=True))
_DECIMAL = r"(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
#: A regular expression for the text forms of a non-negative time (:func:`netsim.timebase.parse_time`: a number
#: and one of its units), for the JSON Schema; ``0`` may also be written as a number.
TIME_PATTERN = rf"^\s*\+?{_DECIMAL}\s*(?:{_TIME_UNITS})\s*$"
#: The same for a time that may be negative (``SignedTime``).
SIGNED_TIME_PATTERN = rf"^\s*[-+]?{_DECIMAL}\s*(?:{_TIME_UNITS})\s*$"
#: A regular expression for the text forms of a bit rate (:func:`netsim.quantities.parse_bitrate`).
BITRATE_PATTERN = quantity_pattern(BITRATE)


def _as_text(ns: int) -> str:
    return format_time(ns)


#: A non-negative time in ns (``"0 s"``, ``"1.5 ms"``); serialized back as text.
Time = Annotated[int, BeforeValidator(_time), PlainSerializer(_as_text, return_type=str, when_used="json")]
#: A strictly positive duration in ns (periods, steps).
Duration = Annotated[int, BeforeValidator(_duration), PlainSerializer(_as_text, return_type=str, when_used="json")]
#: A time that may be negative (offsets relative to something).
SignedTime = Annotated[int, BeforeValidator(_signed), PlainSerializer(_as_text, return_type=str, when_used="json")]
#: A data rate in bit/s (``"80 kbit/s"``; :mod:`netsim.quantities` reads it, as every quantity other than time).
Bitrate = Annotated[float, BeforeValidator(parse_bitrate)]


def _wants_number(annotation: Any) -> bool:
    """True when a field's type holds ``float`` or ``int`` (alone, optional, in a list or union) and not ``bool``."""
    number, stack = False, [annotation]
    while stack:
        part = stack.pop()
        if part is bool:
            return False
        number = number or part in (float, int)
        stack.extend(get_args(part))
    return number


@functools.cache
def _number_fields(model: type[BaseModel]) -> frozenset[str]:
    return frozenset(name for name, field in model.model_fields.items() if _wants_number(field.annotation))


def _has_bool(value: Any) -> bool:
    return isinstance(value, bool) or (isinstance(value, (list, tuple)) and any(_has_bool(v) for v in value))


def _as_yaml_text(value: Any) -> Any:
    """``value`` with every bool (also in nested lists) replaced by its YAML text, ``"true"`` or ``"false"``."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple)):
        return [_as_yaml_text(v) for v in value]
    return value


class StrictModel(BaseModel):
    """Base of every parameter model: unknown keys are errors, values are validated on assignment, and a float
    field refuses NaN and inf (also written as text, ``"nan"``); a number field (float or int) refuses ``true`` and
    ``false`` (pydantic's lax mode read them as 1 and 0); an integer stays accepted for a float."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True, frozen=False, allow_inf_nan=False)

    @model_validator(mode="before")
    @classmethod
    def _no_bool_for_a_number(cls, data: Any) -> Any:
        """A ``true``/``false`` given to a number field is handed on as its YAML text, so the field refuses it
        (at its own path, a list item at its index) as it refuses any other text where a number is wanted."""
        if isinstance(data, dict):
            for name in _number_fields(cls).intersection(data):
                if _has_bool(data[name]):
                    data = {**data, name: _as_yaml_text(data[name])}
        return data


class QuietDefaultsModel(StrictModel):
    """A :class:`StrictModel` whose fields named in ``_QUIET_DEFAULTS`` are left out of its dump while they hold
    the default given there: a field added later does not change the resolved scenario (its text, its hash, the
    golden digests) of a scenario that does not use it."""

    _QUIET_DEFAULTS: ClassVar[dict[str, Any]] = {}

    @model_serializer(mode="wrap")
    def _without_quiet_defaults(self, handler: Any) -> Any:
        data = handler(self)
        if isinstance(data, dict):
            for key, default in self._QUIET_DEFAULTS.items():
                if key in data and data[key] == default:
                    del data[key]
        return data
