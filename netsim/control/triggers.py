"""Sensor-side sampling triggers (section 3.1.2 of Cuenca et al.) and their baselines.

Every trigger is a plain numeric object evaluated once per fast period ``k``::

    send = trig.should_send(k, y, r)     # decides and, if it sends, remembers y as the last sent value

``check`` decides without changing state and ``commit`` records a transmission, so triggers can be
combined (:class:`AnyOf`: send when any member fires; every member then records the send, e.g. the
safety timer of eq (7) restarts when the PET condition sent).

Norm convention for the mixed triggered mechanism (MTM) eq (6)/(22): the printed ``||.||2`` is read as
the *squared* Euclidean norm (``e'e > sigma y'y + delta``), the quadratic form of the MTM literature the
paper cites; ``norm="2"`` gives the plain 2-norm reading. The first evaluation always sends (there is no
``y_bar`` yet).
"""

from __future__ import annotations

import abc

from typing import Literal, Protocol, runtime_checkable

import numpy as np

from netsim.errors import ConfigError

__all__ = [
    "SensorTrigger",
    "TimeTriggered",
    "MixedTrigger",
    "MaxIntervalTrigger",
    "ReferenceChangeTrigger",
    "SendOnDelta",
    "AnyOf",
    "mtm_fires",
]

Norm = Literal["squared", "2"]


def _sq(v) -> float:
    a = np.asarray(v, dtype=float)
    return float(np.dot(a.ravel(), a.ravel()))


def mtm_fires(last, current, sigma: float, delta: float, norm: Norm = "squared") -> bool:
    """Mixed triggered mechanism ``||last - current|| > sigma ||current|| + delta`` (eqs 6 and 22)."""
    d = np.asarray(last, float) - np.asarray(current, float)
    if norm == "squared":
        return _sq(d) > sigma * _sq(current) + delta
    return float(np.sqrt(_sq(d))) > sigma * float(np.sqrt(_sq(current))) + delta


def _nonneg(name: str, value: float) -> float:
    if value is None or not np.isfinite(value) or value < 0:
        raise ConfigError(f"trigger threshold {name} must be a finite number >= 0, got {value!r}")
    return float(value)


@runtime_checkable
class SensorTrigger(Protocol):
    """What the sensor handler program needs from a trigger."""

    def check(self, k: int, y, r: float | None = None) -> bool: ...

    def commit(self, k: int, y) -> None: ...

    def should_send(self, k: int, y, r: float | None = None) -> bool: ...

    def reset(self) -> None: ...


class _Base(abc.ABC):
    def __init__(self) -> None:
        self.last_y: np.ndarray | None = None
        self.last_k: int | None = None

    def reset(self) -> None:
        self.last_y = None
        self.last_k = None

    def commit(self, k: int, y) -> None:
        self.last_y = np.array(y, dtype=float, copy=True)
        self.last_k = int(k)

    @abc.abstractmethod
    def check(self, k: int, y, r: float | None = None) -> bool:
        """True when the sample ``y`` of period ``k`` is to be sent (each trigger's own condition)."""

    def should_send(self, k: int, y, r: float | None = None) -> bool:
        """Decide for sample ``y`` at instant ``k``; remember ``y`` when it is sent."""
        fire = self.check(k, y, r)
        if fire:
            self.commit(k, y)
        return fire


class TimeTriggered(_Base):
    """Time-triggered sampling: send at every ``every``-th period (``every=1``: every sample)."""

    def __init__(self, every: int = 1) -> None:
        super().__init__()
        if int(every) != every or every < 1:
            raise ConfigError(f"time-triggered sampling needs an integer every >= 1, got {every!r}")
        self.every = int(every)

    def check(self, k: int, y, r: float | None = None) -> bool:
        return k % self.every == 0


class MixedTrigger(_Base):
    """PET condition eq (6): send when ``||y_bar - y_k|| > sigma_s ||y_k|| + delta_s``."""

    def __init__(self, sigma: float, delta: float, norm: Norm = "squared") -> None:
        super().__init__()
        self.sigma = _nonneg("sigma_s", sigma)
        self.delta = _nonneg("delta_s", delta)
        if norm not in ("squared", "2"):
            raise ConfigError(f"trigger norm must be 'squared' or '2', got {norm!r}")
        self.norm: Norm = norm

    def check(self, k: int, y, r: float | None = None) -> bool:
        if self.last_y is None:
            return True
        return mtm_fires(self.last_y, y, self.sigma, self.delta, self.norm)


class MaxIntervalTrigger(_Base):
    """TT safety condition eq (7): send when ``k - k_lm == k_max`` (``k_lm``: last send)."""

    def __init__(self, k_max: int) -> None:
        super().__init__()
        if int(k_max) != k_max or k_max < 1:
            raise ConfigError(f"k_max must be an integer >= 1 (periods), got {k_max!r}")
        self.k_max = int(k_max)

    def check(self, k: int, y, r: float | None = None) -> bool:
        if self.last_k is None:
            return True
        return k - self.last_k >= self.k_max


class ReferenceChangeTrigger(_Base):
    """Eq (8): send when ``k - k_lr == k_max``, ``k_lr`` the last instant the reference changed.

    The reference is observed through the ``r`` argument of :meth:`check` (the sensor knows the
    predefined reference). ``k_max = 0`` sends at the change itself.
    """

    def __init__(self, k_max: int = 0) -> None:
        super().__init__()
        if int(k_max) != k_max or k_max < 0:
            raise ConfigError(f"k_max must be an integer >= 0 (periods), got {k_max!r}")
        self.k_max = int(k_max)
        self._r_prev: float | None = None
        self._k_lr: int | None = None

    def reset(self) -> None:
        super().reset()
        self._r_prev = None
        self._k_lr = None

    def check(self, k: int, y, r: float | None = None) -> bool:
        if r is not None:
            if self._r_prev is not None and r != self._r_prev:
                self._k_lr = k
            self._r_prev = r
        return self._k_lr is not None and k - self._k_lr == self.k_max


class SendOnDelta(_Base):
    """Send-on-delta: send when ``||y - y_bar|| > delta`` (plain norm)."""

    def __init__(self, delta: float) -> None:
        super().__init__()
        self.delta = _nonneg("delta", delta)

    def check(self, k: int, y, r: float | None = None) -> bool:
        if self.last_y is None:
            return True
        return float(np.sqrt(_sq(np.asarray(y, float) - self.last_y))) > self.delta


class AnyOf(_Base):
    """Send when any member fires (e.g. PET eq (6) OR safety eq (7)); all members record the send."""

    def __init__(self, members: list) -> None:
        super().__init__()
        if not members:
            raise ConfigError("a combined trigger needs at least one member")
        self.members = list(members)

    def reset(self) -> None:
        super().reset()
        for t in self.members:
            t.reset()

    def check(self, k: int, y, r: float | None = None) -> bool:
        fired = False
        for t in self.members:  # evaluate all: stateful members (reference change) must see every k
            fired = t.check(k, y, r) or fired
        return fired

    def commit(self, k: int, y) -> None:
        super().commit(k, y)
        for t in self.members:
            t.commit(k, y)
