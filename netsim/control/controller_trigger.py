"""Controller-side event-triggered condition, eq (22) of Cuenca et al.

Evaluated only when a measurement has been processed: the newly computed current action ``u_k`` is
compared with ``u_bar``, the *first* value of the last packet that was sent (eq 21)::

    send  <=>  ||u_bar - u_k|| > sigma_c ||u_k|| + delta_c

The first evaluation always sends. The norm reading is the one of
:func:`netsim.control.triggers.mtm_fires` (squared by default).
"""

from __future__ import annotations

import numpy as np

from netsim.control.triggers import Norm, mtm_fires
from netsim.errors import ConfigError

__all__ = ["ControllerTrigger"]


class ControllerTrigger:
    """Eq (22) with thresholds ``sigma_c``, ``delta_c``; ``enabled=False`` sends every time (TTS)."""

    def __init__(self, sigma: float = 0.0, delta: float = 0.0, norm: Norm = "squared", enabled: bool = True) -> None:
        for name, v in (("sigma_c", sigma), ("delta_c", delta)):
            if v is None or not np.isfinite(v) or v < 0:
                raise ConfigError(f"controller trigger threshold {name} must be a finite number >= 0, got {v!r}")
        if norm not in ("squared", "2"):
            raise ConfigError(f"controller trigger norm must be 'squared' or '2', got {norm!r}")
        self.sigma = float(sigma)
        self.delta = float(delta)
        self.norm: Norm = norm
        self.enabled = bool(enabled)
        self.u_bar: np.ndarray | None = None

    def reset(self) -> None:
        self.u_bar = None

    def check(self, u) -> bool:
        if not self.enabled or self.u_bar is None:
            return True
        return mtm_fires(self.u_bar, u, self.sigma, self.delta, self.norm)

    def commit(self, u) -> None:
        self.u_bar = np.array(u, dtype=float, copy=True)

    def should_send(self, u) -> bool:
        """Decide for the current action ``u``; remember it as ``u_bar`` when sent (eq 21)."""
        fire = self.check(u)
        if fire:
            self.commit(u)
        return fire
