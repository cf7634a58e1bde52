"""Physical quantities other than time, written with an SI prefix and a unit: ``"52 mW"``, ``"1 kWh"``,
``"80 kbit/s"``, ``"10 kHz"``.

One grammar and one parser (:func:`parse_quantity`) for every such field of a scenario: a number (decimal, sign,
exponent), optional spaces, then an SI prefix (``p n u µ μ m k M G T``) glued to the unit the field measures. The
value is computed exactly (the decimal number times the prefix's power of ten, as a fraction) and rounded once to
the nearest float: ``"52 mW"`` is the float nearest to 0.052, the same float as the literal ``0.052``. A bare
number is read in the base unit (W, J, bit/s, Hz). An unknown unit is refused with the units the field accepts.

Times are not quantities of this module: they are integer nanoseconds, read by :mod:`netsim.timebase`. Powers in
dBm (the wireless networks' ``transmit_power_dbm``) are plain numbers on a log scale and stay so.

Examples
--------
>>> parse_quantity("52 mW", POWER)
0.052
>>> parse_quantity("1 kWh", ENERGY)
3600000.0
>>> parse_quantity("80 kbit/s", BITRATE)
80000.0
>>> parse_quantity("10 kHz", FREQUENCY)
10000.0
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from decimal import Decimal, InvalidOperation
from fractions import Fraction
from typing import Annotated, Any, Final

from pydantic import BeforeValidator, WithJsonSchema

__all__ = [
    "NUMBER_LIMIT",
    "PREFIXES",
    "Quantity",
    "POWER",
    "ENERGY",
    "BITRATE",
    "FREQUENCY",
    "QUANTITIES",
    "parse_quantity",
    "parse_power",
    "parse_energy",
    "parse_bitrate",
    "parse_frequency",
    "quantity_pattern",
    "Power",
    "Energy",
    "Frequency",
]

#: The largest magnitude of a number in a scenario (gains, rates, positions, initial states, noise levels):
#: ``|x| <= 1e15``. Larger values overflow the float arithmetic of plants and controllers (a square of 1e160
#: is already inf); NaN and inf are refused everywhere. Checked for every number of a scenario by
#: :mod:`netsim.scenario.validate` (re-exported by :mod:`netsim.units`).
NUMBER_LIMIT: Final[float] = 1e15

#: SI prefixes and their exact factors (``u``, ``µ`` (micro sign) and ``μ`` (Greek mu) all mean 1e-6).
PREFIXES: Final[dict[str, Fraction]] = {
    "p": Fraction(1, 10**12), "n": Fraction(1, 10**9), "u": Fraction(1, 10**6), "µ": Fraction(1, 10**6),
    "μ": Fraction(1, 10**6), "m": Fraction(1, 10**3), "": Fraction(1), "k": Fraction(10**3),
    "M": Fraction(10**6), "G": Fraction(10**9), "T": Fraction(10**12),
}

#: The number part, the same as the time parser's (:mod:`netsim.timebase`).
_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_TEXT = re.compile(rf"^\s*({_NUMBER})\s*(\S.*?)?\s*$")


@dataclass(frozen=True)
class Quantity:
    """What one kind of field measures and how it may be written.

    Parameters
    ----------
    name
        The quantity in words, for messages (``"power"``).
    units
        Each base unit spelling and its value in the base unit (``{"J": 1, "Wh": 3600}``); every SI prefix may
        precede each of them.
    example
        Examples for messages (``"'52 mW' or 0.052 (W)"``).
    positive
        Refuse 0 (a bit rate); otherwise 0 is accepted. Negative values are always refused.
    prefixes
        The SI prefixes that may precede a unit (all of :data:`PREFIXES` by default; a bit rate takes no
        sub-unit prefix, so ``"1 mbps"`` is not read as a millibit per second).
    extra
        Further spellings with their exact value, beyond prefix + unit (the bit rate's ``K`` for kilo).
    """

    name: str
    units: dict[str, Fraction]
    example: str
    positive: bool = False
    prefixes: tuple[str, ...] = tuple(PREFIXES)
    extra: dict[str, Fraction] = field(default_factory=dict)

    @property
    def spellings(self) -> dict[str, Fraction]:
        """Every accepted unit spelling (prefix + unit, and :attr:`extra`) and its factor to the base unit."""
        out = {p + u: PREFIXES[p] * s for u, s in self.units.items() for p in self.prefixes}
        return {**out, **self.extra}

    @property
    def base(self) -> str:
        """The base unit (the first of :attr:`units`): what a bare number is read in."""
        return next(iter(self.units))

    def accepted(self) -> str:
        """The accepted units, for messages: ``"pW, nW, uW, mW, W, kW, MW, GW, TW (or a number in W)"``; the
        prefixes of a second spelling of the base unit are implied (``bps, b/s`` for ``bit/s``)."""
        units = [u for u, s in self.units.items() if s != 1 or u == self.base]
        shown = [p + u for u in units for p in self.prefixes if p not in ("µ", "μ")]
        same = [u for u, s in self.units.items() if s == 1 and u != self.base]
        also = f"; {', '.join(same)} for {self.base}" if same else ""
        return f"{', '.join(shown)} (or a number in {self.base}{also})"


POWER: Final = Quantity("power", {"W": Fraction(1)}, "'52 mW' or 0.052 (W)")
ENERGY: Final = Quantity("energy", {"J": Fraction(1), "Wh": Fraction(3600)}, "'20 J', '300 mWh' or 20 (J)")
BITRATE: Final = Quantity(
    "bit rate", {"bit/s": Fraction(1), "bps": Fraction(1), "b/s": Fraction(1)}, "'80 kbit/s', '1 Mbit/s' or 80000",
    positive=True, prefixes=("", "k", "M", "G", "T"), extra={"K" + u: Fraction(1000) for u in ("bit/s", "bps", "b/s")})
FREQUENCY: Final = Quantity("frequency", {"Hz": Fraction(1)}, "'10 kHz' or 10000 (Hz)",
                            prefixes=("u", "µ", "μ", "m", "", "k", "M", "G", "T"))

#: Every quantity, by name.
QUANTITIES: Final[dict[str, Quantity]] = {q.name: q for q in (POWER, ENERGY, BITRATE, FREQUENCY)}


def _suggest(unit: str, quantity: Quantity) -> str:
    """A close spelling of ``unit`` (case aside: ``mw`` -> ``mW``), or empty."""
    folded = [s for s in quantity.spellings if s.lower() == unit.lower()]
    return folded[0] if len(folded) == 1 else ""


def parse_quantity(value: Any, quantity: Quantity) -> float:
    """Read ``value`` as a ``quantity`` in its base unit.

    Parameters
    ----------
    value
        A number (in the base unit: W, J, bit/s, Hz) or text: a number, optional spaces, an SI prefix and a unit
        (``"52 mW"``, ``"1.5 Wh"``, ``"80 kbit/s"``, ``"10 kHz"``).
    quantity
        What the field measures (:data:`POWER`, :data:`ENERGY`, :data:`BITRATE`, :data:`FREQUENCY`).

    Returns
    -------
    float
        The nearest float to the exact value (decimal number times the exact unit factor).

    Raises
    ------
    ValueError
        For text that is not a number and a unit, a unit the quantity does not accept (the message lists the
        accepted ones), a negative value (or zero where it must be positive), or a magnitude beyond
        :data:`NUMBER_LIMIT`, NaN or inf.
    """
    what = quantity.name
    if isinstance(value, bool):
        raise ValueError(f"expected a {what}, e.g. {quantity.example}, got {value!r}")
    if isinstance(value, (int, float)):
        if not math.isfinite(value):
            raise ValueError(f"a {what} must be finite, got {value!r}")
        exact = Fraction(value)
    elif isinstance(value, str):
        match = _TEXT.match(value)
        if match is None:
            raise ValueError(f"cannot read {value!r} as a {what}; write e.g. {quantity.example}")
        unit = match.group(2) or ""
        spellings = quantity.spellings
        if unit and unit not in spellings:
            hint = _suggest(unit, quantity)
            tip = f"did you mean '{hint}'? " if hint else ""
            raise ValueError(f"cannot read {value!r} as a {what}: unknown {what} unit '{unit}'; {tip}"
                             f"a {what} takes {quantity.accepted()}")
        try:
            number = Decimal(match.group(1))
        except InvalidOperation:  # pragma: no cover - the pattern admits only decimal numbers
            raise ValueError(f"cannot read {value!r} as a {what}; write e.g. {quantity.example}") from None
        if number.copy_abs() > Decimal(10) ** 40:  # before the exact product: '1e999999 W' stays cheap
            raise ValueError(f"a {what} must be at most {NUMBER_LIMIT:g} {quantity.base}, got {value!r}")
        exact = Fraction(number) * spellings.get(unit, Fraction(1))
    else:
        raise ValueError(f"expected a {what}, e.g. {quantity.example}, got {type(value).__name__} {value!r}")
    if exact < 0 or (quantity.positive and exact == 0):
        sign = ">" if quantity.positive else ">="
        raise ValueError(f"a {what} must be a finite number {sign} 0, got {value!r}")
    if exact > Fraction(NUMBER_LIMIT):
        raise ValueError(f"a {what} must be at most {NUMBER_LIMIT:g} {quantity.base}, got {value!r}")
    return float(exact)  # Fraction -> float rounds once, to the nearest float


def parse_power(value: Any) -> float:
    """A power in W: a number (W) or text with a unit (``"52 mW"``, ``"60 nW"``, ``"3 uW"``)."""
    return parse_quantity(value, POWER)


def parse_energy(value: Any) -> float:
    """An energy in J: a number (J) or text with a unit (``"5 uJ"``, ``"20 J"``, ``"300 mWh"``, ``"1 kWh"``)."""
    return parse_quantity(value, ENERGY)


def parse_bitrate(value: Any) -> float:
    """A data rate in bit/s: a number, or ``"80 kbit/s"``, ``"1 Mbps"``, ``"10 Mbit/s"``."""
    return parse_quantity(value, BITRATE)


def parse_frequency(value: Any) -> float:
    """A frequency in Hz: a number (Hz) or text with a unit (``"10 kHz"``, ``"50 Hz"``)."""
    return parse_quantity(value, FREQUENCY)


def quantity_pattern(quantity: Quantity) -> str:
    """A regular expression (JSON Schema ``pattern``) matching the text forms :func:`parse_quantity` reads
    for ``quantity`` (the sign and the range are checked by the parser, not by the pattern)."""
    spellings = sorted(quantity.spellings, key=len, reverse=True)
    units = "|".join(re.escape(s) for s in spellings)
    return rf"^\s*{_NUMBER}\s*(?:{units})?\s*$"


def _json(quantity: Quantity, minimum: str) -> dict[str, Any]:
    return {"anyOf": [{"type": "number", minimum: 0},
                      {"type": "string", "pattern": quantity_pattern(quantity),
                       "description": f"a {quantity.name}: {quantity.example}"}]}


#: A power in W (``"52 mW"`` text accepted; the JSON Schema says so, for editors).
Power = Annotated[float, BeforeValidator(parse_power), WithJsonSchema(_json(POWER, "minimum"))]
#: An energy in J (``"1.5 Wh"`` text accepted).
Energy = Annotated[float, BeforeValidator(parse_energy), WithJsonSchema(_json(ENERGY, "minimum"))]
#: A frequency in Hz (``"10 kHz"`` text accepted).
Frequency = Annotated[float, BeforeValidator(parse_frequency), WithJsonSchema(_json(FREQUENCY, "minimum"))]
