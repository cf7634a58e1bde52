"""The slides' designs for the pendulum and the analytic hold-still noise of each estimator.

Everything here is computed from :mod:`models.pendulum.model` (no number is typed in besides the study's
choices, which are named constants):

* :data:`POLES` -- the slides' observer poles ``0.55 +- 0.20j, 0.72, 0.82``;
* :func:`designs` -- observability rank, the Luenberger gains (printed/predictor: ``place(Ad', C', poles)``;
  current: ``place(Ad', (C Ad)', poles)``), the steady-state Kalman gain exactly as the slides compute it
  (``Pi = solve_discrete_are(Ad', C', Qn, Rn)``, ``K = Pi C' (C Pi C' + Rn)^-1``), the LQR gain;
* :func:`hold_still_std` -- the stationary std of the velocity estimates when the pendulum is held still and
  only the sensor noise drives the estimator, from a discrete Lyapunov equation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from models.pendulum.model import SENSOR_STD, TS, Linear, PendulumParams, discretise, observability_rank, process_noise_cov

__all__ = ["POLES", "Q_LQR", "R_LQR", "FD_CUTOFF_HZ", "MPC_HORIZON", "Designs", "designs", "estimator_dynamics",
           "hold_still_std", "ESTIMATORS"]

#: The slides' observer poles.
POLES = (0.55 + 0.20j, 0.55 - 0.20j, 0.72, 0.82)
#: LQR/MPC weights (angles in rad, voltage in V): theta and alpha weighted, velocities free.
Q_LQR = (5.0, 0.0, 20.0, 0.0)
R_LQR = 1.0
#: Cut-off of the low-pass filter on the finite-difference velocities (Hz): a time constant of 8 ms, the
#: speed of the fastest observer pole (0.55 at 5 ms).
FD_CUTOFF_HZ = 20.0
#: MPC horizon (samples of TS).
MPC_HORIZON = 20
#: The estimators of the study, as the state_feedback program's ``estimator`` entries.
ESTIMATORS: dict[str, dict[str, Any]] = {
    "fd_raw": {"type": "pendulum_fd"},
    "fd_lowpass": {"type": "pendulum_fd", "cutoff_hz": FD_CUTOFF_HZ},
    "luenberger": {"type": "luenberger", "form": "current", "poles": [str(p) for p in POLES]},
    "kalman": {"type": "steady_state_kalman"},  # Q and R filled by designs()
}


@dataclass(frozen=True)
class Designs:
    """The study's discrete model and designs (see the module docstring)."""

    lin: Linear
    rank: int
    L_pred: np.ndarray
    L_cur: np.ndarray
    Qn: np.ndarray
    Rn: np.ndarray
    Pi: np.ndarray
    K_kal: np.ndarray
    K_lqr: np.ndarray


def designs(p: PendulumParams | None = None, h: float = TS) -> Designs:
    """Compute every design of the study at period ``h``."""
    from scipy.linalg import solve_discrete_are
    from scipy.signal import place_poles

    from netsim.control.lqr import dlqr_gain

    p = PendulumParams() if p is None else p
    lin = discretise(p, h)
    Ad, Bd, C = lin.Ad, lin.Bd, lin.C
    L_pred = place_poles(Ad.T, C.T, np.array(POLES)).gain_matrix.T  # the slides' code
    L_cur = place_poles(Ad.T, (C @ Ad).T, np.array(POLES)).gain_matrix.T
    Qn = process_noise_cov(lin, p.disturbance_std, p.disturbance_hold)
    Rn = np.eye(2) * SENSOR_STD**2
    Pi = solve_discrete_are(Ad.T, C.T, Qn, Rn)  # the slides' code
    K_kal = Pi @ C.T @ np.linalg.inv(C @ Pi @ C.T + Rn)
    K_lqr, _ = dlqr_gain(Ad, Bd, np.diag(Q_LQR), R_LQR)
    return Designs(lin=lin, rank=observability_rank(Ad, C), L_pred=L_pred, L_cur=L_cur, Qn=Qn, Rn=Rn, Pi=Pi,
                   K_kal=K_kal, K_lqr=np.asarray(K_lqr))


def kalman_entry(d: Designs) -> dict[str, Any]:
    """The ``steady_state_kalman`` estimator entry with Qn and Rn as lists (for a scenario override)."""
    return {"type": "steady_state_kalman", "Q": d.Qn.tolist(), "R": d.Rn.tolist()}


def estimator_dynamics(name: str, d: Designs, cutoff_hz: float = FD_CUTOFF_HZ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(F, G, H)`` of an estimator held still with ``u = 0``: ``s[k] = F s[k-1] + G v[k]``, velocities ``H s[k]``.

    ``v[k]`` is the measurement noise of ``y[k] = [theta, alpha]``. Names: ``fd_raw``, ``fd_lowpass``,
    ``luenberger`` (current form), ``luenberger_predictor``, ``luenberger_printed``, ``kalman``.
    """
    Ad, C = d.lin.Ad, d.lin.C
    H = np.zeros((2, 4))
    H[0, 1] = H[1, 3] = 1.0
    if name in ("luenberger", "kalman"):
        L = d.L_cur if name == "luenberger" else d.K_kal
        return (np.eye(4) - L @ C) @ Ad, L, H
    if name == "luenberger_printed":
        return Ad - d.L_pred @ C, d.L_pred, H
    if name == "luenberger_predictor":
        # x_hat[k] = (A - L C) x_hat[k-1] + L v[k-1]: state s[k] = [x_hat[k], v[k]]
        F = np.zeros((6, 6))
        F[:4, :4] = Ad - d.L_pred @ C
        F[:4, 4:] = d.L_pred
        G = np.zeros((6, 2))
        G[4:, :] = np.eye(2)
        return F, G, np.hstack([H, np.zeros((2, 2))])
    if name in ("fd_raw", "fd_lowpass"):
        h = d.lin.h
        a = 0.0 if name == "fd_raw" else math.exp(-h * 2.0 * math.pi * cutoff_hz)
        # per angle: s = [v_f, p]: v_f[k] = a v_f[k-1] + (1 - a) (v[k] - p[k-1]) / h, p[k] = v[k]
        F1 = np.array([[a, -(1.0 - a) / h], [0.0, 0.0]])
        G1 = np.array([[(1.0 - a) / h], [1.0]])
        F, G = np.kron(np.eye(2), F1), np.kron(np.eye(2), G1)
        H = np.kron(np.eye(2), np.array([[1.0, 0.0]]))
        return F, G, H
    raise ValueError(f"unknown estimator {name!r}")


def hold_still_std(name: str, d: Designs, cutoff_hz: float = FD_CUTOFF_HZ) -> np.ndarray:
    """Stationary std of ``[theta_dot, alpha_dot]`` estimates, pendulum held still, only sensor noise ``Rn``.

    Solves ``P = F P F' + G Rn G'`` (discrete Lyapunov) for :func:`estimator_dynamics`; returns ``sqrt(diag(H P H'))``.
    """
    from scipy.linalg import solve_discrete_lyapunov

    F, G, H = estimator_dynamics(name, d, cutoff_hz)
    P = solve_discrete_lyapunov(F, G @ d.Rn @ G.T)
    return np.sqrt(np.diag(H @ P @ H.T))
