"""Closed-form motion of the cart over one interval with a constant command and a held friction level.

Model (paper section II-B): ``p' = v``, ``v' = u + u_bias - v/Td`` with ``u = Ku uV``; ``1/Td = 0`` by
default (the paper's approximation), ``Td = 0.23 s`` optional. Here ``u_bias`` is the Coulomb friction
``-F sign(v)`` with the level ``F`` held over the interval; at rest the cart stays while ``|u| <= Fs``
(breakaway level). The motion is at most two analytic segments: until the velocity reaches zero (when
friction decelerates it), then either stuck or moving off in the direction of ``u``.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["segment", "stop_time", "propagate", "propagate1"]


def segment(p0: float, v0: float, a: float, tau: np.ndarray, td: float | None) -> tuple[np.ndarray, np.ndarray]:
    """Position and velocity after ``tau`` (s, array) under constant acceleration ``a`` (and ``-v/Td``)."""
    if td is None:
        return p0 + v0 * tau + 0.5 * a * tau * tau, v0 + a * tau
    vinf = a * td
    e = np.exp(-tau / td)
    return p0 + vinf * tau + (v0 - vinf) * td * (1.0 - e), vinf + (v0 - vinf) * e


def stop_time(v0: float, a: float, td: float | None) -> float:
    """Time at which the velocity reaches zero from ``v0`` under ``a`` (inf if it never does)."""
    if v0 == 0.0 or a == 0.0 or (a > 0.0) == (v0 > 0.0):
        return math.inf
    if td is None:
        return -v0 / a
    vinf = a * td
    return -td * math.log(vinf / (vinf - v0))


def propagate(
    p0: float, v0: float, u: float, f: float, fs: float, tau: np.ndarray, td: float | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """State at the times ``tau`` (sorted, >= 0, s) from ``(p0, v0)`` under command ``u`` and friction ``f``.

    Parameters
    ----------
    p0, v0
        Initial position (m) and velocity (m/s).
    u
        Acceleration command ``Ku uV`` (m/s^2).
    f, fs
        Coulomb level and breakaway level (m/s^2), held over the interval.
    tau
        Times after the start (s).
    td
        Velocity time constant (s) or ``None`` for the pure double integrator.
    """
    tau = np.asarray(tau, dtype=float)
    if v0 == 0.0:
        if abs(u) <= fs:
            return np.full_like(tau, p0), np.zeros_like(tau)
        return segment(p0, 0.0, u - math.copysign(f, u), tau, td)
    a = u - math.copysign(f, v0)
    ts = stop_time(v0, a, td)
    if ts >= (tau[-1] if tau.size else 0.0):
        return segment(p0, v0, a, tau, td)
    p1, _ = segment(p0, v0, a, np.array([ts]), td)
    p_stop = float(p1[0])
    before = tau < ts
    p = np.empty_like(tau)
    v = np.empty_like(tau)
    p[before], v[before] = segment(p0, v0, a, tau[before], td)
    after = ~before
    if abs(u) <= fs:
        p[after], v[after] = p_stop, 0.0
    else:
        p[after], v[after] = segment(p_stop, 0.0, u - math.copysign(f, u), tau[after] - ts, td)
    return p, v


def propagate1(p0: float, v0: float, u: float, f: float, fs: float, tau: float,
               td: float | None = None) -> tuple[float, float]:
    """:func:`propagate` at one time ``tau`` (s), in plain floats (no numpy round trip).

    Without ``Td`` the arithmetic is the same sequence of IEEE operations as :func:`propagate`, so the result
    is bit-identical to ``propagate(..., np.array([tau]))``; with ``Td`` it calls :func:`propagate` (whose
    ``np.exp`` may differ from ``math.exp`` in the last bit).
    """
    if td is not None:
        p, v = propagate(p0, v0, u, f, fs, np.array([tau]), td)
        return float(p[0]), float(v[0])
    if v0 == 0.0:
        if abs(u) <= fs:
            return p0, 0.0
        a = u - math.copysign(f, u)
        return p0 + 0.0 * tau + 0.5 * a * tau * tau, 0.0 + a * tau
    a = u - math.copysign(f, v0)
    ts = stop_time(v0, a, td)
    if ts >= tau:
        return p0 + v0 * tau + 0.5 * a * tau * tau, v0 + a * tau
    p_stop = p0 + v0 * ts + 0.5 * a * ts * ts
    if abs(u) <= fs:
        return p_stop, 0.0
    a2 = u - math.copysign(f, u)
    dt = tau - ts
    return p_stop + 0.0 * dt + 0.5 * a2 * dt * dt, 0.0 + a2 * dt
