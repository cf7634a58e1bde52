"""The study's EKF (eqs 10-17) on plain floats: the same filter as the toolbox's ``ExtendedKalmanFilter``.

:func:`~netsim.models.unicycle.design.make_ekf` builds the toolbox's :class:`~netsim.control.ExtendedKalmanFilter`
with this study's model functions (3x3 numpy matrices, checks of every model call). A run of the netsim
scenario calls the filter some 3000 times, and the Monte-Carlo studies a million times; with 3 states the numpy
call overhead is most of the cost. :class:`CartEkf` does the same arithmetic on floats:

* the state ``x`` is a tuple ``(x, y, theta)``, the covariance ``P`` a tuple of its six distinct entries
  ``(p00, p01, p02, p11, p12, p22)`` (immutable: a history of priors needs no copies);
* prediction, eq (10) with ``F`` of eq (12) at the prior estimate: ``x <- f(x, u)``, ``P <- F P F' + Q``
  written out for ``F = [[1, 0, a], [0, 1, b], [0, 0, 1]]``;
* correction with one scalar reading (each IR sensor gives one): ``S = H P H' + R``, ``K = P H' / S``,
  ``x <- x + K (z - h(x))``, ``P <- P - (P H')(P H')' / S``, which equals the toolbox's Joseph form for the
  optimal gain (a test compares the two filters to 1e-12 along a run).

``Q`` must be diagonal (the report's eq 22 is).
"""

from __future__ import annotations

import math
from typing import Any, Literal

import numpy as np

from netsim.models.unicycle.model import FRONT_OFFSET, P0, Q_REPORT, R_REPORT, TS, WALL_FRONT, WALL_SIDE, XI0_HAT, side_offset

__all__ = ["CartEkf", "Sensor", "sym_to_matrix", "matrix_to_sym"]

Sym = tuple[float, float, float, float, float, float]
Vec = tuple[float, float, float]


def matrix_to_sym(P: Any) -> Sym:
    """The six distinct entries ``(p00, p01, p02, p11, p12, p22)`` of a symmetric 3x3 matrix."""
    M = np.asarray(P, dtype=float).reshape(3, 3)
    return (float(M[0, 0]), float(M[0, 1]), float(M[0, 2]), float(M[1, 1]), float(M[1, 2]), float(M[2, 2]))


def sym_to_matrix(p: Sym) -> np.ndarray:
    """The 3x3 matrix of the six entries of :func:`matrix_to_sym`."""
    return np.array([[p[0], p[1], p[2]], [p[1], p[3], p[4]], [p[2], p[4], p[5]]])


class Sensor:
    """An IR sensor of eqs (4)-(9), (14)-(17): body offset ``(ox, oy)``, wall ``p x + q y = r``, variance ``R``."""

    __slots__ = ("ox", "oy", "p", "q", "r", "n", "R", "hx", "hy")

    def __init__(self, offset: tuple[float, float], wall: tuple[float, float, float], R: float) -> None:
        self.ox, self.oy = float(offset[0]), float(offset[1])
        self.p, self.q, self.r = (float(v) for v in wall)
        self.n = math.hypot(self.p, self.q)
        self.R = float(R)
        self.hx, self.hy = -self.p / self.n, -self.q / self.n

    def h(self, x: float, y: float, th: float) -> float:
        """Eqs (7)-(9): the noiseless reading at the pose (the same float operations as ``model.measure``)."""
        c, s = math.cos(th), math.sin(th)
        return (self.r - self.p * (x + self.ox * c - self.oy * s) - self.q * (y + self.ox * s + self.oy * c)) / self.n

    def h_theta(self, th: float) -> float:
        """Eqs (14)-(17): the reading's derivative with respect to ``theta`` (those to ``x``, ``y`` are constant)."""
        c, s = math.cos(th), math.sin(th)
        return -(self.p * (-self.ox * s - self.oy * c) + self.q * (self.ox * c - self.oy * s)) / self.n


class CartEkf:
    """The EKF of the study on floats (module docstring); sources ``front`` and ``side``.

    Parameters
    ----------
    Q
        Process noise covariance per step (3x3, diagonal) or its diagonal.
    R
        Variances of the front and side readings [m^2].
    x0, P0_
        Initial estimate and covariance (3x3 symmetric).
    ts
        Filter period [s].
    side
        ``"derived"`` or ``"printed"`` side sensor offset (:func:`~netsim.models.unicycle.model.side_offset`).
    """

    def __init__(self, Q: Any = Q_REPORT, R: Any = R_REPORT, x0: Any = XI0_HAT, P0_: Any = P0, ts: float = TS,
                 side: Literal["derived", "printed"] = "derived") -> None:
        Qm = np.asarray(Q, dtype=float)
        if Qm.ndim == 1:
            Qm = np.diag(Qm)
        if Qm.shape != (3, 3) or np.any(Qm != np.diag(np.diag(Qm))):
            raise ValueError("CartEkf: Q must be a diagonal 3x3 matrix (or its 3 diagonal entries)")
        self.q = (float(Qm[0, 0]), float(Qm[1, 1]), float(Qm[2, 2]))
        Rv = np.asarray(R, dtype=float).reshape(-1)
        if Rv.shape != (2,) or np.any(Rv <= 0):
            raise ValueError("CartEkf: R must hold the two positive variances (front, side)")
        self.sensors = {"front": Sensor(FRONT_OFFSET, WALL_FRONT, Rv[0]),
                        "side": Sensor(side_offset(side), WALL_SIDE, Rv[1])}
        self.ts = float(ts)
        x0v = np.asarray(x0, dtype=float).reshape(3)
        self.x0: Vec = (float(x0v[0]), float(x0v[1]), float(x0v[2]))
        self.P0: Sym = matrix_to_sym(P0_)
        self.x: Vec = self.x0
        self.P: Sym = self.P0
        self.k = 0

    def reset(self, x: Vec | None = None, P: Sym | None = None) -> None:
        """Back to ``(x, P)`` (tuples as stored in ``x`` and ``P``), or to the initial estimate."""
        self.x = self.x0 if x is None else x
        self.P = self.P0 if P is None else P

    def predict(self, v: float, w: float) -> None:
        """Eqs (10), (12): ``x <- x + Ts f(x, u)``, ``P <- F P F' + Q`` with ``F`` at the prior estimate."""
        x, y, th = self.x
        tv = self.ts * v
        c, s = math.cos(th), math.sin(th)
        a, b = -tv * s, tv * c
        p00, p01, p02, p11, p12, p22 = self.P
        r02 = p02 + a * p22
        r12 = p12 + b * p22
        q0, q1, q2 = self.q
        self.P = (p00 + a * p02 + a * r02 + q0, p01 + a * p12 + b * r02, r02,
                  p11 + b * p12 + b * r12 + q1, r12, p22 + q2)
        self.x = (x + tv * c, y + tv * s, th + self.ts * w)
        self.k += 1

    def correct(self, z: float, source: str) -> None:
        """Fuse one reading ``z`` of ``source`` (``"front"`` or ``"side"``) taken at the current sample."""
        sen = self.sensors[source]
        x, y, th = self.x
        hx, hy, ht = sen.hx, sen.hy, sen.h_theta(th)
        p00, p01, p02, p11, p12, p22 = self.P
        g0 = p00 * hx + p01 * hy + p02 * ht  # P H'
        g1 = p01 * hx + p11 * hy + p12 * ht
        g2 = p02 * hx + p12 * hy + p22 * ht
        S = hx * g0 + hy * g1 + ht * g2 + sen.R
        e = (z - sen.h(x, y, th)) / S
        self.x = (x + g0 * e, y + g1 * e, th + g2 * e)
        self.P = (p00 - g0 * g0 / S, p01 - g0 * g1 / S, p02 - g0 * g2 / S,
                  p11 - g1 * g1 / S, p12 - g1 * g2 / S, p22 - g2 * g2 / S)

    def predicted(self, source: str) -> tuple[float, float]:
        """The predicted reading of ``source`` and its standard deviation ``sqrt(H P H' + R)``."""
        sen = self.sensors[source]
        x, y, th = self.x
        hx, hy, ht = sen.hx, sen.hy, sen.h_theta(th)
        p00, p01, p02, p11, p12, p22 = self.P
        hph = (hx * (p00 * hx + p01 * hy + p02 * ht) + hy * (p01 * hx + p11 * hy + p12 * ht)
               + ht * (p02 * hx + p12 * hy + p22 * ht))
        return sen.h(x, y, th), math.sqrt(hph + sen.R)

    def det(self) -> float:
        """``det P``."""
        p00, p01, p02, p11, p12, p22 = self.P
        return p00 * (p11 * p22 - p12 * p12) - p01 * (p01 * p22 - p12 * p02) + p02 * (p01 * p12 - p11 * p02)

    def covariance(self) -> np.ndarray:
        """``P`` as a 3x3 array."""
        return sym_to_matrix(self.P)
