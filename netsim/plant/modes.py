"""Modes and guards of hybrid nonlinear plants (:class:`~netsim.plant.nonlinear.NonlinearPlant`), and the usual
three-mode stick-slip friction model (:func:`stick_slip_modes`). See :mod:`netsim.plant.nonlinear` for how the
plant switches modes at guard crossings; these names are also importable from there."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from netsim.errors import ConfigError

__all__ = ["Fn", "Mode", "Guard", "stick_slip_modes"]

#: A right-hand side, output, guard or selector signature: ``fn(t, x, u, params)`` (``t`` in seconds).
Fn = Callable[[float, np.ndarray, np.ndarray, Any], Any]


@dataclass(frozen=True)
class Guard:
    """A zero-crossing function ``fn(t, x, u, params)``; ``direction`` as in solve_ivp events
    (+1: only upward crossings, -1: only downward, 0: both)."""

    fn: Fn
    direction: float = 0.0


@dataclass(frozen=True)
class Mode:
    """One mode of a hybrid plant: its right-hand side (None: the plant's ``f``) and its guards."""

    f: Fn | None = None
    guards: tuple[Guard, ...] = field(default_factory=tuple)


def stick_slip_modes(
    f: Fn,
    *,
    velocity: int,
    applied_force: Fn,
    coulomb: float,
    static: float | None = None,
    mass: float = 1.0,
    v_eps: float = 1e-9,
) -> tuple[dict[str, Mode], Callable[..., tuple[str, np.ndarray]]]:
    """Modes and selector of Coulomb friction with stiction on state ``velocity``.

    Parameters
    ----------
    f
        Dynamics without friction.
    velocity
        Index of the velocity state.
    applied_force
        Net non-friction force ``F(t, x, u, params)`` on the mass (its effect is already in ``f``).
    coulomb, static
        Sliding and static friction forces (``static`` defaults to ``coulomb``).
    mass
        Mass that converts the friction force into acceleration.
    v_eps
        Speeds below this count as zero when a mode is chosen.

    Returns
    -------
    (modes, select_mode)
        Pass both to :class:`NonlinearPlant`. Modes: ``slip+`` (``v > 0``, friction ``-coulomb``),
        ``slip-`` and ``stick`` (``v`` held at exactly 0 while ``|F| <= static``).
    """
    fc = float(coulomb) / mass
    fs = float(coulomb if static is None else static)
    if fc < 0 or fs < 0:
        raise ConfigError("friction forces must be non-negative")

    def f_pos(t: float, x: np.ndarray, u: np.ndarray, p: Any) -> np.ndarray:
        dx = np.array(f(t, x, u, p), dtype=float)
        dx[velocity] -= fc
        return dx

    def f_neg(t: float, x: np.ndarray, u: np.ndarray, p: Any) -> np.ndarray:
        dx = np.array(f(t, x, u, p), dtype=float)
        dx[velocity] += fc
        return dx

    def f_stick(t: float, x: np.ndarray, u: np.ndarray, p: Any) -> np.ndarray:
        dx = np.array(f(t, x, u, p), dtype=float)
        dx[velocity] = 0.0
        return dx

    def speed(t: float, x: np.ndarray, u: np.ndarray, p: Any) -> float:
        return float(x[velocity])

    def breakaway(t: float, x: np.ndarray, u: np.ndarray, p: Any) -> float:
        return abs(float(applied_force(t, x, u, p))) - fs

    modes = {
        "slip+": Mode(f_pos, (Guard(speed, -1.0),)),
        "slip-": Mode(f_neg, (Guard(speed, +1.0),)),
        "stick": Mode(f_stick, (Guard(breakaway, +1.0),)),
    }

    def select(t: float, x: np.ndarray, u: np.ndarray, p: Any) -> tuple[str, np.ndarray]:
        v = float(x[velocity])
        if v > v_eps:
            return "slip+", x
        if v < -v_eps:
            return "slip-", x
        x = np.array(x, dtype=float)
        x[velocity] = 0.0
        force = float(applied_force(t, x, u, p))
        if abs(force) <= fs:
            return "stick", x
        return ("slip+" if force > 0 else "slip-"), x

    return modes, select
