"""What connects plants and kernels: ADC and DAC channels and encoders.

A kernel attaches a channel with ``kernel.attach_analog_in(name, adc.read)`` and
``kernel.attach_analog_out(name, dac.write)``; encoders call ``on_edge(count, direction, stamp_ns)`` at the
ISR tick that sees an edge (see :mod:`netsim.io.encoder`).

ADC pipeline: plant output at the request instant -> + Gaussian noise -> saturation -> quantization
(``step * round(v / step)``). DAC pipeline: value -> saturation -> resolution (``res * round(v / res)``)
-> :meth:`~netsim.plant.Plant.set_input` (held until the next write).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from netsim.io.encoder import Encoder, encoder_step
from netsim.errors import ConfigError

__all__ = ["ADC", "DAC", "saturation_limits", "quantize"]


def saturation_limits(name: str, saturation: Any) -> tuple[float, float] | None:
    """``(low, high)`` from ``None``, a bound ``b`` (meaning ``[-b, b]``) or a pair; ConfigError otherwise."""
    if saturation is None:
        return None
    if isinstance(saturation, (int, float)) and not isinstance(saturation, bool):
        lo, hi = -abs(float(saturation)), abs(float(saturation))
    else:
        try:
            lo, hi = (float(v) for v in saturation)
        except (TypeError, ValueError):
            raise ConfigError(f"{name}: saturation must be a bound or a [low, high] pair, got {saturation!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi)) or lo >= hi:
        raise ConfigError(f"{name}: saturation needs finite low < high, got {saturation!r}")
    return lo, hi


def _positive_or_none(name: str, what: str, value: Any) -> float | None:
    if value is None:
        return None
    v = float(value)
    if not (v > 0 and math.isfinite(v)):
        raise ConfigError(f"{name}: {what} must be positive (or null), got {value!r}")
    return v


def quantize(value: float, step: float | None) -> float:
    """``value`` rounded to the nearest multiple of ``step`` (unchanged for ``step=None``)."""
    return value if step is None else step * round(value / step)


class ADC:
    """An analog input: samples a plant output at the instant of the request.

    Parameters
    ----------
    plant
        The plant.
    output
        Output index or name.
    noise_std
        Standard deviation of additive Gaussian noise.
    quant_step
        Quantization step (None: no quantization).
    saturation
        Input range: a bound or a ``(low, high)`` pair (None: unlimited).
    rng
        Noise stream; by default ``env.rng(f"io.{name}.noise")`` of the plant's environment.
    name
        Channel name (for the default noise stream and messages).
    """

    def __init__(
        self,
        plant: Any,
        output: int | str,
        *,
        noise_std: float = 0.0,
        quant_step: float | None = None,
        saturation: Any = None,
        rng: np.random.Generator | None = None,
        name: str | None = None,
    ) -> None:
        self.plant = plant
        self.output = plant.output_index(output)
        self.name = name or f"{plant.name}.{plant.output_names[self.output]}"
        std = float(noise_std)
        if not (std >= 0 and math.isfinite(std)):
            raise ConfigError(f"adc {self.name}: noise_std must be >= 0, got {noise_std!r}")
        self.noise_std = std
        self.quant_step = _positive_or_none(f"adc {self.name}", "quant_step", quant_step)
        self.limits = saturation_limits(f"adc {self.name}", saturation)
        self._rng = rng

    def read(self, t_ns: int) -> float:
        """The converted value of the output at ``t_ns``."""
        v = self.plant.output_value(self.output, t_ns)
        if self.noise_std > 0.0:
            if self._rng is None:
                if self.plant.env is None:
                    raise ConfigError(f"adc {self.name}: noise needs an rng or a plant bound to an environment")
                self._rng = self.plant.env.rng(f"io.{self.name}.noise")
            v += self.noise_std * float(self._rng.standard_normal())
        if self.limits is not None:
            v = min(max(v, self.limits[0]), self.limits[1])
        return v if self.quant_step is None else quantize(v, self.quant_step)


class DAC:
    """An analog output: holds the written value on a plant input (zero-order hold).

    Parameters
    ----------
    plant
        The plant.
    input
        Input index or name.
    saturation
        Output range: a bound or a ``(low, high)`` pair (None: unlimited).
    resolution
        Output step (None: exact).
    """

    def __init__(self, plant: Any, input: int | str, *, saturation: Any = None, resolution: float | None = None,
                 name: str | None = None) -> None:
        self.plant = plant
        self.input = plant.input_index(input)
        self.name = name or f"{plant.name}.{plant.input_names[self.input]}"
        self.limits = saturation_limits(f"dac {self.name}", saturation)
        self.resolution = _positive_or_none(f"dac {self.name}", "resolution", resolution)
        self.last = 0.0

    def convert(self, value: float) -> float:
        """What the converter puts out for ``value`` (saturated, then rounded to the resolution)."""
        v = float(value)
        if self.limits is not None and math.isfinite(v):
            v = min(max(v, self.limits[0]), self.limits[1])
        return v if self.resolution is None else quantize(v, self.resolution)

    def write(self, t_ns: int, value: float) -> None:
        """Advance the plant to ``t_ns`` and hold the converted ``value`` from then on."""
        # convert(value), inlined (a DAC write per control job)
        v = float(value)
        limits = self.limits
        if limits is not None and math.isfinite(v):
            if v < limits[0]:  # min(max(v, low), high) with low < high
                v = limits[0]
            elif v > limits[1]:
                v = limits[1]
        if self.resolution is not None:
            v = quantize(v, self.resolution)
        self.plant.set_input(self.input, v, t_ns)
        self.last = v
