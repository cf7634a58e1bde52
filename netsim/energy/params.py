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

from typing import Literal

from pydantic import Field, model_validator

from netsim.quantities import Energy, Power, parse_energy, parse_power
from netsim.units import StrictModel

__all__ = ["CpuPower", "RadioPower", "Battery", "EnergyModel", "parse_power", "parse_energy"]

# Powers and energies are read by netsim.quantities (one SI-prefix parser for every quantity other than time):
# '52 mW', '60 nW', '5 uJ', '300 mWh', '1 kWh', or a bare number in W or J.


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
