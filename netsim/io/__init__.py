"""What connects the plant and the kernels: ADC/DAC channels, quantizers and sensor noise, encoders, signals.

``channels`` (:class:`ADC`, :class:`DAC`, saturation and quantization), ``encoder`` (:class:`Encoder`: quantized
position with time-stamped edges, exact or polled), ``signals`` (reference and disturbance signals a scenario
names under ``signals:``: constant, step, square, sine, ramp, table; imported on its own, ``netsim.io.signals``).
"""

from __future__ import annotations

from netsim.io.channels import ADC, DAC, quantize, saturation_limits
from netsim.io.encoder import Encoder, encoder_step

__all__ = ["ADC", "DAC", "Encoder", "encoder_step", "quantize", "saturation_limits"]
