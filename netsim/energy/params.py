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
(:meth:`netsim.kernel.Kernel.halt`: its jobs are killed, nothing more is released, receptions are ignored) and it
sends nothing more on any network it is on (:meth:`netsim.network.pipeline.Network.halt_node`, and
:meth:`~netsim.network.wireless.WirelessMedium.halt_node` on a radio): its queued frames and those still in
their pre-processing delay are dropped as ``sender_dead`` (on a radio also the frame its MAC holds), a frame on
the air ends, and its radios receive nothing.
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field, model_serializer, model_validator

from netsim.quantities import Energy, Power, parse_energy, parse_power
from netsim.units import StrictModel

__all__ = ["CpuPower", "RadioPower", "Battery", "EnergyModel", "parse_power", "parse_energy"]

# Powers and energies are read by netsim.quantities (one SI-prefix parser for every quantity other than time):
# '52 mW', '60 nW', '5 uJ', '300 mWh', '1 kWh', or a bare number in W or J.


class CpuPower(StrictModel):
    """CPU power (W) by state, per core.

    On a node with speed scaling (``nodes.<n>.speed``, :mod:`netsim.kernel.speed`) a busy core at speed ``s``
    draws ``P_busy(s) = static + (busy - static) * s ** exponent``: ``busy`` at full speed, ``static`` the part
    that does not scale (leakage), the rest dynamic power (CMOS: ``P ~ f V^2``, with ``V ~ f`` the cube of the
    speed, hence ``exponent: 3`` by default). Without speed scaling ``s = 1`` and a busy core draws ``busy``.
    """

    busy: Power = Field(description="W while the CPU runs a task, a handler or a context switch (at full speed)")
    idle: Power = Field(0.0, description="W while the CPU idles")
    static: Power | None = Field(None, description="W of the busy power that does not scale with the speed "
                                 "(default 0: all of it scales)")
    exponent: float | None = Field(None, gt=0, description="the busy power's dynamic part scales as "
                                   "speed ** exponent (default 3)")

    @model_validator(mode="after")
    def _static_below_busy(self) -> "CpuPower":
        if self.static is not None and self.static > self.busy:
            raise ValueError(f"static {self.static} W exceeds busy {self.busy} W (static is the part of the busy "
                             "power that does not scale with the speed)")
        return self

    @model_serializer(mode="wrap")
    def _without_unset_scaling(self, handler: Any) -> Any:
        data = handler(self)  # an energy model without the speed law dumps (and hashes) as before it existed
        if isinstance(data, dict):
            for key in ("static", "exponent"):
                if data.get(key, 0) is None:
                    del data[key]
        return data

    def busy_at(self, speed: float) -> float:
        """``P_busy(speed)`` in W (see the class docstring)."""
        if speed == 1:
            return float(self.busy)
        static = 0.0 if self.static is None else float(self.static)
        exponent = 3.0 if self.exponent is None else float(self.exponent)
        return static + (float(self.busy) - static) * speed ** exponent


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
