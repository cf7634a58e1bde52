"""Baseline velocity estimators users compare model-based estimators against.

:class:`FiniteDifferenceVelocity` turns a position measurement into the state estimate ``[p, v]``:

* raw: ``v[k] = (p[k] - p[j]) / (t[k] - t[j])`` with ``j`` the previous sample that had a measurement;
* low-pass filtered: ``v_f[k] = a v_f[j] + (1 - a) v[k]`` with ``a = exp(-(t[k] - t[j]) / tau)``,
  ``tau = 1 / (2 pi f_c)`` (the exact discretisation of the first-order filter ``tau dv_f/dt = v - v_f`` for a
  velocity held over the interval).

The times are the sample grid ``k h`` unless the measurement carries its own time ``t`` (seconds), which then
takes care of jitter. No model is used: the estimate between measurements is held.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from netsim.errors import ConfigError, SimulationError

__all__ = ["FiniteDifferenceVelocity"]


class FiniteDifferenceVelocity:
    """Position and finite-difference velocity, raw or low-pass filtered (see the module docstring).

    Parameters
    ----------
    h
        Sampling period in seconds.
    cutoff_hz
        Cut-off frequency of the first-order low-pass filter on the velocity; ``None`` for the raw difference.
    """

    def __init__(self, h: float, *, cutoff_hz: float | None = None) -> None:
        if not (isinstance(h, (int, float)) and h > 0 and math.isfinite(h)):
            raise ConfigError(f"h must be a positive sampling period in seconds, got {h!r}")
        if cutoff_hz is not None and not (cutoff_hz > 0 and math.isfinite(cutoff_hz)):
            raise ConfigError(
                f"cutoff_hz must be a positive frequency (or null for the raw difference), got {cutoff_hz!r}"
            )
        self.h = float(h)
        self.tau = None if cutoff_hz is None else 1.0 / (2.0 * math.pi * float(cutoff_hz))
        self.reset()

    def reset(self) -> None:
        """Forget the previous sample."""
        self.k = 0
        self.x = np.zeros(2)
        self._last: tuple[float, float] | None = None  # (time, position) of the previous measurement
        self._seen = False

    @property
    def x_hat(self) -> np.ndarray:
        """``[position, velocity]`` at the current sample."""
        return self.x

    def correct(self, y: Any, t: float | None = None) -> bool:
        """Use a position measurement of the current sample (taken at ``t`` seconds when given)."""
        if self._seen:
            return False
        p = float(np.asarray(y, dtype=float).reshape(-1)[0])
        t = self.k * self.h if t is None else float(t)
        v = self.x[1]
        if self._last is not None:
            dt = t - self._last[0]
            if not dt > 0:
                raise SimulationError(
                    f"finite-difference velocity: sample times must increase ({self._last[0]} then {t})"
                )
            raw = (p - self._last[1]) / dt
            v = raw if self.tau is None else math.exp(-dt / self.tau) * v + (1.0 - math.exp(-dt / self.tau)) * raw
        self._last = (t, p)
        self.x = np.array([p, v])
        self._seen = True
        return True

    def predict(self, u: Any = None) -> None:
        """Next sample (the estimate is held; ``u`` is not used)."""
        self.k += 1
        self._seen = False
