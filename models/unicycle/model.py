"""The two-wheel-drive cart of seed 001 (a course report): kinematics, exact arcs, IR wall sensors, Jacobians.

Equations (numbers as in the report, ``/work/shared/seeds/001_*``):

* eq (1): ``v = r/2 (wL + wR)``, ``w = r/(2a) (wR - wL)``; eq (2) its inverse (:func:`wheels_to_body`,
  :func:`body_to_wheels`).
* eq (3): the unicycle ``x' = v cos(theta)``, ``y' = v sin(theta)``, ``theta' = w``. With ``(v, w)`` held, the
  motion is an arc, integrated exactly by :func:`arc` (the chord form
  ``dx = v dt sinc(w dt / 2) cos(theta + w dt / 2)``, exact for every ``w`` including 0).
* eq (4): signed distance of a point to the wall ``p x + q y = r_w``: ``(r_w - p x - q y) / sqrt(p^2 + q^2)``.
* eqs (5)-(6): sensor positions. The text puts the side sensor at ``beta`` along ``X'`` and ``gamma`` along
  ``-Y'``; rotating the body offset ``(beta, -gamma)`` gives ``x_s = x + beta cos + gamma sin``,
  ``y_s = y + beta sin - gamma cos``. The printed eq (6) (and eqs 9, 16, 17 built on it) has the opposite
  sign of ``gamma``, i.e. the sensor at ``+Y'``. :data:`SIDE_DERIVED` is the default; ``side="printed"``
  keeps the printed form. At ``theta = 0`` both give the same distance; their ``theta`` derivatives differ in
  sign (``-gamma`` against ``+gamma``).
* eq (10): forward Euler, eqs (12)-(13) its Jacobians, eqs (14)-(17) the measurement Jacobians.
* eq (24): the world-frame error rotated into the cart frame; eq (26) the linearised error model. Deriving the
  lateral error ``e2 = -sin(theta) ex + cos(theta) ey`` gives ``e2' = v_ref sin(e3) - w e1``, so the entry
  ``A_d[1, 2]`` is ``+Ts v_ref``; the report prints ``-Ts v_ref`` (kept as ``a_sign="printed"``).

Choices the report leaves open (also stated in the scenarios' comments): filter and control period
``TS = 10 ms``; wheel radius ``WHEEL_RADIUS = 0.0325 m``; half wheelbase ``HALF_WHEELBASE = 0.075 m`` (a small
2WD kit cart, consistent with the sensor offsets of 7-8 cm); walls ``y = 0`` (front sensor) and ``x = 0`` (side
sensor) as in the report's Figure 4. The trajectory is in :mod:`netsim.models.unicycle.trajectory`.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np

__all__ = [
    "ALPHA", "BETA", "GAMMA", "WALL_FRONT", "WALL_SIDE", "TS", "WHEEL_RADIUS", "HALF_WHEELBASE",
    "XI0_HAT", "P0", "Q_REPORT", "R_REPORT", "FRONT_OFFSET", "SIDE_DERIVED", "SIDE_PRINTED",
    "wheels_to_body", "body_to_wheels", "arc", "arc_floats", "euler_step", "jac_A", "jac_B", "rotation",
    "sensor_position", "wall_distance", "measure", "measure_jacobian", "side_offset",
]

#: Front sensor offset along X' [m] (report section 1.2).
ALPHA = 0.075
#: Side sensor offset along X' [m].
BETA = 0.065
#: Side sensor offset along -Y' [m].
GAMMA = 0.078
#: Wall seen by the front sensor, ``(p, q, r)`` of ``p x + q y = r``: ``y = 0`` (eq 8).
WALL_FRONT = (0.0, 1.0, 0.0)
#: Wall seen by the side sensor: ``x = 0`` (eq 9).
WALL_SIDE = (1.0, 0.0, 0.0)
#: Filter and control period [s] (our choice; the report gives none).
TS = 0.01
#: Wheel radius r [m] (our choice).
WHEEL_RADIUS = 0.0325
#: Half wheelbase a [m] (our choice).
HALF_WHEELBASE = 0.075
#: Initial estimate, eq (20) [m, m, rad].
XI0_HAT = np.array([-0.30, -0.20, 0.0])
#: Initial covariance, eq (21).
P0 = np.diag([1e-3, 1e-3, 7.6e-3])
#: Process noise covariance per step, eq (22).
Q_REPORT = np.diag([8e-9, 9e-8, 9e-7])
#: Measurement noise variances (front, side), eq (23) [m^2].
R_REPORT = np.array([0.0198, 0.09])

#: Body-frame offset ``(along X', along Y')`` of the front sensor.
FRONT_OFFSET = (ALPHA, 0.0)
#: Side sensor offset as the text states it (``gamma`` along ``-Y'``).
SIDE_DERIVED = (BETA, -GAMMA)
#: Side sensor offset as the printed eq (6) has it (``gamma`` along ``+Y'``).
SIDE_PRINTED = (BETA, GAMMA)

Side = Literal["derived", "printed"]


def side_offset(side: Side = "derived") -> tuple[float, float]:
    """Body-frame offset of the side sensor: ``"derived"`` (text, -Y') or ``"printed"`` (eq 6, +Y')."""
    if side == "derived":
        return SIDE_DERIVED
    if side == "printed":
        return SIDE_PRINTED
    raise ValueError(f"side must be 'derived' or 'printed', got {side!r}")


def wheels_to_body(w_left: float, w_right: float, r: float = WHEEL_RADIUS,
                   a: float = HALF_WHEELBASE) -> tuple[float, float]:
    """Eq (1): forward velocity ``v`` [m/s] and turn rate ``w`` [rad/s] from the wheel speeds [rad/s]."""
    return 0.5 * r * (w_left + w_right), 0.5 * r / a * (w_right - w_left)


def body_to_wheels(v: float, w: float, r: float = WHEEL_RADIUS, a: float = HALF_WHEELBASE) -> tuple[float, float]:
    """Eq (2): wheel speeds ``(w_left, w_right)`` [rad/s] for ``(v, w)``."""
    return (v - a * w) / r, (v + a * w) / r


def arc_floats(x: float, y: float, th: float, v: float, w: float, dt: float) -> tuple[float, float, float]:
    """:func:`arc` on floats: the pose ``(x, y, theta)`` after ``dt`` seconds with ``(v, w)`` held."""
    half = 0.5 * w * dt
    s = v * dt * (math.sin(half) / half if half != 0.0 else 1.0)
    mid = th + half
    return x + s * math.cos(mid), y + s * math.sin(mid), th + w * dt


def arc(xi: np.ndarray, v: float, w: float, dt: float) -> np.ndarray:
    """Exact solution of eq (3) after ``dt`` seconds with ``(v, w)`` held (a straight line when ``w = 0``)."""
    return np.array(arc_floats(float(xi[0]), float(xi[1]), float(xi[2]), v, w, dt))


def euler_step(xi: np.ndarray, u: np.ndarray, ts: float = TS) -> np.ndarray:
    """Eq (10) without noise: ``xi + Ts f(xi, u)`` with ``u = (v, w)``."""
    v, w = float(u[0]), float(u[1])
    th = float(xi[2])
    return np.array([xi[0] + ts * v * math.cos(th), xi[1] + ts * v * math.sin(th), th + ts * w])


def jac_A(xi: np.ndarray, u: np.ndarray, ts: float = TS) -> np.ndarray:
    """Eq (12): Jacobian of eq (10) with respect to the state."""
    v, th = float(u[0]), float(xi[2])
    return np.array([[1.0, 0.0, -ts * v * math.sin(th)], [0.0, 1.0, ts * v * math.cos(th)], [0.0, 0.0, 1.0]])


def jac_B(xi: np.ndarray, ts: float = TS) -> np.ndarray:
    """Eq (13): Jacobian of eq (10) with respect to the input ``(v, w)``."""
    th = float(xi[2])
    return np.array([[ts * math.cos(th), 0.0], [ts * math.sin(th), 0.0], [0.0, ts]])


def rotation(theta: float) -> np.ndarray:
    """Eq (24): world-frame pose error to the cart frame."""
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])


def sensor_position(xi: np.ndarray, offset: tuple[float, float]) -> np.ndarray:
    """Eqs (5)-(6): world position of a sensor at body offset ``(along X', along Y')``."""
    c, s = math.cos(float(xi[2])), math.sin(float(xi[2]))
    ox, oy = offset
    return np.array([xi[0] + ox * c - oy * s, xi[1] + ox * s + oy * c])


def wall_distance(point: np.ndarray, wall: tuple[float, float, float]) -> float:
    """Eq (4): signed distance ``(r - p x - q y) / sqrt(p^2 + q^2)`` of ``point`` to the wall ``(p, q, r)``."""
    p, q, r = wall
    return (r - p * float(point[0]) - q * float(point[1])) / math.hypot(p, q)


def measure(xi: np.ndarray, offset: tuple[float, float], wall: tuple[float, float, float]) -> float:
    """Eqs (7)-(9): noiseless reading of a sensor at ``offset`` facing ``wall``."""
    return wall_distance(sensor_position(xi, offset), wall)


def measure_jacobian(xi: np.ndarray, offset: tuple[float, float], wall: tuple[float, float, float]) -> np.ndarray:
    """Eqs (14)-(16): one row ``[-p/n, -q/n, -(p dx/dtheta + q dy/dtheta)/n]`` of the measurement Jacobian."""
    p, q, _ = wall
    n = math.hypot(p, q)
    c, s = math.cos(float(xi[2])), math.sin(float(xi[2]))
    ox, oy = offset
    dx, dy = -ox * s - oy * c, ox * c - oy * s
    return np.array([[-p / n, -q / n, -(p * dx + q * dy) / n]])
