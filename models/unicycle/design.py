"""Trajectory, EKF and cart-frame LQR of the 2WD cart study (our choices where the report gives none).

Trajectory (:data:`PHASES`, 10 s; the report describes it only as a straight part, a 90 degree turn with
both sensors off, then a part with the front sensor only): from the report's initial pose eq (20),
``(-0.30, -0.20, 0)``:

=========  ========  ============  =============  ==================
phase      duration  v [m/s]       w [rad/s]      sensors
=========  ========  ============  =============  ==================
straight   4 s       0.03          0              front and side
turn       2 s       0.02          pi/4 (90 deg)  none (blackout)
front      4 s       0.015         0              front only
=========  ========  ============  =============  ==================

It ends at about ``(-0.155, -0.115, pi/2)``, 4 cm short of the front wall ``y = 0`` (front sensor at 0.075 m).

LQR weights (the report's section 4.3 gives none; Bryson's rule): ``Q_lqr = diag(1/0.01^2, 1/0.01^2,
1/0.1^2)`` (1 cm longitudinal and lateral error, 0.1 rad heading error), ``R_lqr = diag(1/0.05^2, 1/1^2)``
(5 cm/s and 1 rad/s of command). The error model of eq (26) splits into the longitudinal error driven by ``v``
and the (lateral, heading) pair driven by ``w``; :func:`lqr_gain` solves the two Riccati equations apart
(python-control's ``dlqr``) and assembles ``K`` with the zeros of eq (27) exactly zero (a test checks it
against ``dlqr`` of the whole 3-state model).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal, Sequence

import numpy as np

from netsim.models.unicycle.model import (
    FRONT_OFFSET, P0, Q_REPORT, R_REPORT, TS, WALL_FRONT, WALL_SIDE, XI0_HAT, arc, euler_step, jac_A,
    measure, measure_jacobian, side_offset,
)
from netsim.control import ExtendedKalmanFilter, MeasurementSource

__all__ = ["Phase", "PHASES", "Trajectory", "error_model", "lqr_gain", "LQR_Q", "LQR_R", "make_ekf",
           "cart_frame_error", "TrackingLaw"]


@dataclass(frozen=True)
class Phase:
    """A piece of the trajectory with constant ``(v, w)`` and the sensors that are on.

    ``front``/``side`` schedule the sensors of the standalone studies (:mod:`netsim.models.unicycle.studies`); in a
    netsim scenario the sensors' own ``on`` windows do (``unicycle_ekf``'s phases carry no flags).
    """

    duration: float
    v: float
    w: float
    front: bool = True
    side: bool = True
    name: str = ""


#: The default 10 s trajectory (module docstring).
PHASES: tuple[Phase, ...] = (
    Phase(4.0, 0.03, 0.0, True, True, "straight"),
    Phase(2.0, 0.02, math.pi / 4, False, False, "turn"),
    Phase(4.0, 0.015, 0.0, True, False, "front"),
)

#: LQR state weight (module docstring).
LQR_Q = np.diag([1 / 0.01**2, 1 / 0.01**2, 1 / 0.1**2])
#: LQR input weight.
LQR_R = np.diag([1 / 0.05**2, 1.0])


class Trajectory:
    """Reference poses and inputs along piecewise-constant phases, sampled every ``ts`` seconds (exact arcs)."""

    def __init__(self, phases: Sequence[Phase] = PHASES, start: Any = XI0_HAT, ts: float = TS) -> None:
        if not phases:
            raise ValueError("the trajectory needs at least one phase")
        self.phases = tuple(phases)
        self.ts = float(ts)
        self.ends = np.cumsum([p.duration for p in self.phases])
        self.duration = float(self.ends[-1])
        self.start = np.asarray(start, dtype=float).reshape(3)
        self.n = int(round(self.duration / self.ts))
        self.poses = np.empty((self.n + 1, 3))
        self.inputs = np.empty((self.n + 1, 2))
        xi = self.start.copy()
        for k in range(self.n + 1):
            ph = self.phase(k * self.ts)
            self.poses[k] = xi
            self.inputs[k] = (ph.v, ph.w)
            xi = arc(xi, ph.v, ph.w, self.ts)

    def phase_index(self, t: float) -> int:
        """Index of the phase at time ``t`` [s] (the last one after the end)."""
        i = int(np.searchsorted(self.ends, t + 1e-9 * self.ts, side="right"))
        return min(i, len(self.phases) - 1)

    def phase(self, t: float) -> Phase:
        """The phase at time ``t`` [s]."""
        return self.phases[self.phase_index(t)]

    def at(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Reference pose and input ``(v, w)`` at sample ``k`` (held after the end)."""
        k = min(max(int(k), 0), self.n)
        return self.poses[k], self.inputs[k]


def error_model(v_ref: float, ts: float = TS, a_sign: Literal["derived", "printed"] = "derived"
                ) -> tuple[np.ndarray, np.ndarray]:
    """Eq (26): ``(A_d, B_d)`` of the cart-frame error; ``a_sign="printed"`` uses the report's ``-Ts v_ref``."""
    sgn = 1.0 if a_sign == "derived" else -1.0
    if a_sign not in ("derived", "printed"):
        raise ValueError(f"a_sign must be 'derived' or 'printed', got {a_sign!r}")
    A = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, sgn * ts * v_ref], [0.0, 0.0, 1.0]])
    B = np.array([[-ts, 0.0], [0.0, 0.0], [0.0, -ts]])
    return A, B


def lqr_gain(v_ref: float, Q: Any = LQR_Q, R: Any = LQR_R, ts: float = TS,
             a_sign: Literal["derived", "printed"] = "derived") -> np.ndarray:
    """Eq (27): ``K`` (2 x 3) with ``u = -K e'``, from ``dlqr`` of the two decoupled subsystems of eq (26).

    ``Q`` and ``R`` must be diagonal (the decoupling needs it). Raises ``ValueError`` otherwise, or when
    ``v_ref = 0`` (the lateral error is then not controllable).
    """
    import control

    Q = np.asarray(Q, dtype=float)
    R = np.asarray(R, dtype=float)
    if Q.ndim == 1:
        Q = np.diag(Q)
    if R.ndim == 1:
        R = np.diag(R)
    if np.any(Q != np.diag(np.diag(Q))) or np.any(R != np.diag(np.diag(R))):
        raise ValueError("lqr_gain: Q and R must be diagonal for the structure of eq (27)")
    if v_ref == 0.0:
        raise ValueError("lqr_gain: v_ref = 0 leaves the lateral error uncontrollable; give v_ref != 0")
    A, B = error_model(v_ref, ts, a_sign)
    k1, _, _ = control.dlqr(A[:1, :1], B[:1, :1], Q[:1, :1], R[:1, :1])
    k2, _, _ = control.dlqr(A[1:, 1:], B[1:, 1:], Q[1:, 1:], R[1:, 1:])
    K = np.zeros((2, 3))
    K[0, 0] = float(np.asarray(k1)[0, 0])
    K[1, 1:] = np.asarray(k2)[0]
    return K


def cart_frame_error(ref: np.ndarray, xi_hat: np.ndarray) -> np.ndarray:
    """Eq (24): ``R(theta_hat) (xi_ref - xi_hat)``, the heading error wrapped to ``(-pi, pi]``."""
    e = np.asarray(ref, dtype=float) - np.asarray(xi_hat, dtype=float)
    e[2] = math.atan2(math.sin(e[2]), math.cos(e[2]))
    c, s = math.cos(float(xi_hat[2])), math.sin(float(xi_hat[2]))
    return np.array([c * e[0] + s * e[1], -s * e[0] + c * e[1], e[2]])


Law = Literal["feedforward", "lqr", "lqr_ff"]


class TrackingLaw:
    """``(v, w)`` along a :class:`Trajectory`: feed-forward only, LQR on the cart-frame error, or both.

    ``lqr``: ``u = -K(v_ref) e'`` (no feed-forward, the report's section 4.3); ``lqr_ff``: ``u = u_ref - K e'``;
    ``feedforward``: ``u = u_ref`` (the report's open-loop EKF experiments). ``K`` is designed once per
    distinct ``v_ref`` of the trajectory (:func:`lqr_gain`).
    """

    def __init__(self, traj: Trajectory, law: Law = "feedforward", Q: Any = LQR_Q, R: Any = LQR_R,
                 a_sign: Literal["derived", "printed"] = "derived") -> None:
        if law not in ("feedforward", "lqr", "lqr_ff"):
            raise ValueError(f"law must be feedforward, lqr or lqr_ff, got {law!r}")
        self.traj, self.law = traj, law
        self.gains: dict[float, np.ndarray] = {}
        if law != "feedforward":
            for ph in traj.phases:
                if ph.v not in self.gains:
                    self.gains[ph.v] = lqr_gain(ph.v, Q, R, traj.ts, a_sign)
        # plain floats for the per-sample step: reference poses, inputs, and per sample the gain's entries
        # (k11, k22, k23) of eq (27) (the others are zero by construction)
        self._poses: list[list[float]] = traj.poses.tolist()
        self._inputs: list[tuple[float, float]] = [(float(a), float(b)) for a, b in traj.inputs.tolist()]
        self._k = {v: (float(K[0, 0]), float(K[1, 1]), float(K[1, 2])) for v, K in self.gains.items()}

    def ref_at(self, k: int) -> list[float]:
        """Reference pose at sample ``k`` as floats (held after the end)."""
        return self._poses[min(max(k, 0), self.traj.n)]

    def step(self, k: int, xi_hat: Any) -> tuple[float, float]:
        """Command ``(v, w)`` at sample ``k`` for the estimate ``xi_hat``."""
        k = min(max(int(k), 0), self.traj.n)
        u_ref = self._inputs[k]
        if self.law == "feedforward":
            return u_ref
        rx, ry, rt = self._poses[k]
        x, y, th = float(xi_hat[0]), float(xi_hat[1]), float(xi_hat[2])
        ex, ey, et = rx - x, ry - y, rt - th
        et = math.atan2(math.sin(et), math.cos(et))
        c, s = math.cos(th), math.sin(th)
        e1, e2 = c * ex + s * ey, -s * ex + c * ey
        k11, k22, k23 = self._k[u_ref[0]]
        v, w = -(k11 * e1), -(k22 * e2 + k23 * et)
        return (v + u_ref[0], w + u_ref[1]) if self.law == "lqr_ff" else (v, w)


def make_ekf(Q: Any = Q_REPORT, R: Any = R_REPORT, x0: Any = XI0_HAT, P0_: Any = P0, ts: float = TS,
             side: Literal["derived", "printed"] = "derived") -> ExtendedKalmanFilter:
    """The EKF of eqs (10)-(17): sources ``front`` (wall ``y = 0``) and ``side`` (wall ``x = 0``).

    ``R`` holds the two variances (front, side). ``side="printed"`` uses the report's eq (6)/(17) offset.
    """
    R = np.asarray(R, dtype=float).reshape(-1)
    off_s = side_offset(side)

    def f(x: np.ndarray, u: np.ndarray) -> np.ndarray:
        return euler_step(x, u, ts)

    def F(x: np.ndarray, u: np.ndarray) -> np.ndarray:
        return jac_A(x, u, ts)

    sources = {
        "front": MeasurementSource(lambda x: [measure(x, FRONT_OFFSET, WALL_FRONT)], R[0],
                                   lambda x: measure_jacobian(x, FRONT_OFFSET, WALL_FRONT)),
        "side": MeasurementSource(lambda x: [measure(x, off_s, WALL_SIDE)], R[1],
                                  lambda x: measure_jacobian(x, off_s, WALL_SIDE)),
    }
    return ExtendedKalmanFilter(f, sources, Q, x0, P0=P0_, n_inputs=2, F=F)
