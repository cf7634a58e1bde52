"""The energy model of a node, as a scenario writes it (``nodes.<n>.energy``): pure data.

::

    energy:
      cpu: {busy: 0.030, idle: 0.003}                          # W
      radio: {tx: 0.052, rx: 0.056, idle: 0.056, sleep: 6.0e-5, listen: own_frames}   # W
      battery: {capacity: 20 J}

The powers are constant per state (TrueTime's kernel and radio power by state). ``cpu.busy`` is drawn while
the node's CPU runs anything (tasks, handlers, context switches, ISR latencies), ``cpu.idle`` otherwise.
``radio`` applies to the node's radio on each wireless network it is on (:mod:`netsim.network.wireless`:
``tx`` while it transmits a frame or an ACK, ``rx`` while it senses other transmissions, ``idle`` while it
listens to a quiet channel, ``sleep`` while a radio with ``listen: own_frames`` has no frame to send).
A ``battery`` of ``capacity`` joules runs out when the energy used reaches it: the node stops
(:meth:`netsim.kernel.Kernel.halt`: its jobs are killed, nothing more is released, receptions are ignored) and its
radios neither send nor receive (:meth:`~netsim.network.wireless.WirelessMedium.radio_off`). On a wired network the
frames already queued at the node's controller still go out.
"""

from __future__ import annotations

import re
from typing import Annotated, Any, Literal

from pydantic import BeforeValidator, Field, WithJsonSchema, model_validator

from netsim.units import NUMBER_LIMIT, StrictModel

__all__ = ["CpuPower", "RadioPower", "Battery", "EnergyModel", "parse_power", "parse_energy"]

_POWER_UNITS = {"W": 1.0, "mW": 1e-3, "uW": 1e-6, "µW": 1e-6}
_ENERGY_UNITS = {"J": 1.0, "mJ": 1e-3, "kJ": 1e3, "Wh": 3600.0, "mWh": 3.6}
_QUANTITY = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([A-Za-zµ]+)?\s*$")


def _quantity(value: Any, units: dict[str, float], what: str, example: str) -> float:
    if isinstance(value, bool):
        raise ValueError(f"expected a {what}, e.g. {example}, got {value!r}")
    if isinstance(value, (int, float)):
        x = float(value)
    elif isinstance(value, str) and (m := _QUANTITY.match(value)):
        unit = m.group(2)
        if unit is not None and unit not in units:
            raise ValueError(f"unknown {what} unit '{unit}' in {value!r}; use one of {', '.join(units)}")
        x = float(m.group(1)) * (units[unit] if unit else 1.0)
    else:
        raise ValueError(f"expected a {what}, e.g. {example}, got {value!r}")
    if not (0.0 <= x <= NUMBER_LIMIT):
        raise ValueError(f"a {what} must be a finite number >= 0, got {value!r}")
    return x


def parse_power(value: Any) -> float:
    """A power in watts: a number (W) or text with a unit (``"52 mW"``, ``"3 uW"``)."""
    return _quantity(value, _POWER_UNITS, "power", "'52 mW' or 0.052 (W)")


def parse_energy(value: Any) -> float:
    """An energy in joules: a number (J) or text with a unit (``"20 J"``, ``"1.5 Wh"``, ``"300 mWh"``)."""
    return _quantity(value, _ENERGY_UNITS, "energy", "'20 J', '1.5 Wh' or 20 (J)")


#: A power in W (``"52 mW"`` text accepted; the JSON Schema says so, for editors).
Power = Annotated[float, BeforeValidator(parse_power), WithJsonSchema(
    {"anyOf": [{"type": "number", "minimum": 0}, {"type": "string", "description": "a power: 52 mW, 3 uW, 0.1 W"}]})]
#: An energy in J (``"1.5 Wh"`` text accepted).
Energy = Annotated[float, BeforeValidator(parse_energy), WithJsonSchema(
    {"anyOf": [{"type": "number", "exclusiveMinimum": 0},
               {"type": "string", "description": "an energy: 20 J, 300 mWh, 1.5 Wh"}]})]


class CpuPower(StrictModel):
    """CPU power (W) by state."""

    busy: Power = Field(description="W while the CPU runs a task, a handler or a context switch")
    idle: Power = Field(0.0, description="W while the CPU idles")


class RadioPower(StrictModel):
    """Radio power (W) by state, for the node's radio on each wireless network it is on."""

    tx: Power = Field(description="W while it transmits (frames and ACKs)")
    rx: Power = Field(description="W while it senses other transmissions (receiving)")
    idle: Power = Field(description="W while it listens to a quiet channel")
    sleep: Power = Field(0.0, description="W while it sleeps (listen: own_frames, no frame to send)")
    listen: Literal["always", "own_frames"] = Field(
        "always", description="always: it listens whenever it does not transmit; own_frames: it sleeps while "
                              "its MAC has no frame (it then receives nothing)")


class Battery(StrictModel):
    """A battery: the node stops when the energy it used reaches ``capacity``."""

    capacity: Energy = Field(gt=0, description="J (or '1.5 Wh', '300 mWh')")


class EnergyModel(StrictModel):
    """A node's energy model: CPU and radio power by state, and optionally a battery."""

    cpu: CpuPower | None = None
    radio: RadioPower | None = None
    battery: Battery | None = None

    @model_validator(mode="after")
    def _something(self) -> "EnergyModel":
        if self.cpu is None and self.radio is None:
            raise ValueError("give 'cpu' and/or 'radio' powers (an energy model without them uses nothing)")
        return self
