"""Delay distributions of simple links: constant, uniform, exponential, shifted gamma, empirical.

A link's ``delay:`` is either a time (``"2 ms"``: constant) or a mapping with ``dist``::

    delay: {dist: uniform, low: 1 ms, high: 3 ms}
    delay: {dist: exponential, mean: 2 ms, shift: 0.5 ms}
    delay: {dist: shifted_gamma, shape: 2.0, scale: 1 ms, shift: 0.5 ms}
    delay: {dist: empirical, file: delays.csv, column: delay, unit: ms}   # or values: [1 ms, 2 ms]

Samplers return integer nanoseconds drawn from the stream the link gives them.
"""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Annotated, Any, Callable, Literal, Union

import numpy as np
from pydantic import BeforeValidator, Field, model_validator

from netsim.errors import ConfigError
from netsim.timebase import UNITS
from netsim.units import Duration, StrictModel, Time

__all__ = [
    "ConstantDelay",
    "UniformDelay",
    "ExponentialDelay",
    "ShiftedGammaDelay",
    "EmpiricalDelay",
    "DelaySpec",
    "make_delay_sampler",
    "load_delays_csv",
]


class ConstantDelay(StrictModel):
    """Always ``value``."""

    dist: Literal["constant"] = "constant"
    value: Time = 0


class UniformDelay(StrictModel):
    """Uniform on ``[low, high]``."""

    dist: Literal["uniform"] = "uniform"
    low: Time
    high: Time

    @model_validator(mode="after")
    def _ordered(self) -> "UniformDelay":
        if self.high < self.low:
            raise ValueError("high must be >= low")
        return self


class ExponentialDelay(StrictModel):
    """``shift`` plus an exponential variable of mean ``mean``."""

    dist: Literal["exponential"] = "exponential"
    mean: Duration
    shift: Time = 0


class ShiftedGammaDelay(StrictModel):
    """``shift`` plus a gamma variable of ``shape`` and ``scale`` (mean ``shape * scale``)."""

    dist: Literal["shifted_gamma", "gamma"] = "shifted_gamma"
    shape: float = Field(gt=0)
    scale: Duration
    shift: Time = 0


class EmpiricalDelay(StrictModel):
    """Resampled (with replacement) from measured delays: inline ``values`` or a CSV ``file``.

    ``column`` names the CSV column (a header name, or an index when the file has no header); ``unit`` is
    the unit of the numbers in the file (default seconds).
    """

    dist: Literal["empirical"] = "empirical"
    values: list[Time] | None = None
    file: str | None = None
    column: str | int = 0
    unit: Literal["ns", "us", "ms", "s"] = "s"

    @model_validator(mode="after")
    def _one_source(self) -> "EmpiricalDelay":
        if (self.values is None) == (self.file is None):
            raise ValueError("give exactly one of 'values' (a list of times) or 'file' (a CSV of delays)")
        if self.values is not None and not self.values:
            raise ValueError("'values' is empty")
        return self


def _constant_shorthand(value: Any) -> Any:
    if isinstance(value, (str, int, float)) and not isinstance(value, bool):
        return {"dist": "constant", "value": value}
    return value


#: A delay distribution in a link's parameters.
DelaySpec = Annotated[
    Union[ConstantDelay, UniformDelay, ExponentialDelay, ShiftedGammaDelay, EmpiricalDelay],
    Field(discriminator="dist"),
    BeforeValidator(_constant_shorthand),
]


def load_delays_csv(path: str | Path, column: str | int = 0, unit: str = "s") -> np.ndarray:
    """Read measured delays from a CSV file into integer nanoseconds.

    Raises
    ------
    ConfigError
        If the file is missing, the column unknown, a value not a number or negative, or no value found.
    """
    p = Path(path)
    if not p.is_file():
        raise ConfigError(f"delay file '{p}' does not exist; give a CSV of measured delays")
    with p.open(newline="") as fh:
        rows = [row for row in csv.reader(fh) if row and any(c.strip() for c in row)]
    if not rows:
        raise ConfigError(f"delay file '{p}' is empty")
    header = rows[0]
    try:
        [float(c) for c in header if c.strip()]
        has_header = False
    except ValueError:
        has_header = True
    if isinstance(column, str):
        if not has_header or column not in [h.strip() for h in header]:
            known = ", ".join(h.strip() for h in header) if has_header else "no header row"
            raise ConfigError(f"delay file '{p}' has no column '{column}' ({known})")
        idx = [h.strip() for h in header].index(column)
    else:
        idx = int(column)
    body = rows[1:] if has_header else rows
    scale = UNITS[unit]
    out = []
    for lineno, row in enumerate(body, start=2 if has_header else 1):
        if idx >= len(row):
            raise ConfigError(f"delay file '{p}' line {lineno} has no column {idx}")
        try:
            v = float(row[idx])
        except ValueError:
            raise ConfigError(f"delay file '{p}' line {lineno}: {row[idx]!r} is not a number") from None
        if not np.isfinite(v) or v < 0:
            raise ConfigError(f"delay file '{p}' line {lineno}: delay {v} must be finite and >= 0")
        out.append(int(round(v * scale)))
    if not out:
        raise ConfigError(f"delay file '{p}' holds no delays")
    return np.asarray(out, dtype=np.int64)


def make_delay_sampler(spec: Any, rng: np.random.Generator) -> Callable[[], int]:
    """A function drawing one delay (ns) from ``spec`` with ``rng`` (constant delays draw nothing)."""
    if isinstance(spec, ConstantDelay):
        value = int(spec.value)
        return lambda: value
    if isinstance(spec, UniformDelay):
        lo, hi = int(spec.low), int(spec.high)
        if lo == hi:
            return lambda: lo
        integers = rng.integers
        return lambda: int(integers(lo, hi + 1))
    if isinstance(spec, ExponentialDelay):
        mean, shift = float(spec.mean), int(spec.shift)
        expo = rng.exponential
        return lambda: shift + int(round(expo(mean)))
    if isinstance(spec, ShiftedGammaDelay):
        shape, scale, shift = float(spec.shape), float(spec.scale), int(spec.shift)
        gamma = rng.gamma
        return lambda: shift + int(round(gamma(shape, scale)))
    if isinstance(spec, EmpiricalDelay):
        values = (
            np.asarray(spec.values, dtype=np.int64)
            if spec.values is not None
            else load_delays_csv(spec.file or "", spec.column, spec.unit)
        )
        n = len(values)
        integers = rng.integers
        table = values.tolist()
        return lambda: table[int(integers(n))]
    raise TypeError(f"unknown delay spec {spec!r}")
