"""The slides' designs for the pendulum and the analytic hold-still noise of each estimator.

Everything here is computed from :mod:`netsim.models.pendulum.model` (no number is typed in besides the study's
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

from netsim.models.pendulum.model import SENSOR_STD, TS, Linear, PendulumParams, discretise, observability_rank, process_noise_cov

__all__ = ["POLES", "Q_LQR", "R_LQR", "FD_CUTOFF_HZ", "MPC_HORIZON", "Designs", "designs", "estimator_dynamics",
           "hold_still_std", "ESTIMATORS", "kalman_entry", "linear_motion", "motion_errors",
           "loop_gain", "delay_margin", "delay_spectral_radius"]

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


def linear_motion(d: Designs, n: int = 400, tilt: float = 0.05, amp: float = 0.5, freq: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    """A noise-free trajectory of the discrete linear model in motion: LQR from ``alpha = tilt`` plus a sine
    input of ``amp`` V at ``freq`` Hz; returns the states ``x[k]`` and inputs ``u[k]``."""
    lin = d.lin
    x = np.array([0.0, 0.0, tilt, 0.0])
    xs, us = [], []
    for k in range(n):
        u = float(-(d.K_lqr @ x)[0] + amp * math.sin(2 * math.pi * freq * k * lin.h))
        xs.append(x.copy())
        us.append(u)
        x = lin.Ad @ x + lin.Bd[:, 0] * u
    return np.array(xs), np.array(us)


def motion_errors(d: Designs, skip: int = 200) -> dict[str, np.ndarray]:
    """RMS estimation error of ``[theta, theta_dot, alpha, alpha_dot]`` per Luenberger form on
    :func:`linear_motion`, noise-free, after ``skip`` samples (the initial error has then decayed)."""
    from netsim.models.pendulum.estimators import PrintedLuenberger
    from netsim.control import LuenbergerObserver

    lin = d.lin
    xs, us = linear_motion(d)
    out = {}
    for name, obj in (("current", LuenbergerObserver(lin.Ad, lin.Bd, lin.C, POLES, form="current")),
                      ("predictor", LuenbergerObserver(lin.Ad, lin.Bd, lin.C, POLES, form="predictor")),
                      ("printed", PrintedLuenberger(lin.Ad, lin.Bd, lin.C, POLES))):
        est = []
        for x, u in zip(xs, us):
            obj.correct(lin.C @ x)
            est.append(np.array(obj.x_hat))
            obj.predict([u])
        e = xs - np.array(est)
        out[name] = np.sqrt(np.mean(e[skip:] ** 2, axis=0))
    out["motion_rms"] = np.sqrt(np.mean(xs[skip:] ** 2, axis=0))
    return out


def _estimator_fr(name: str, d: Designs, z: complex, cutoff_hz: float = FD_CUTOFF_HZ) -> tuple[np.ndarray, np.ndarray]:
    """``(E_y, E_u)`` with ``X_hat(z) = E_y Y(z) + E_u U(z)`` for the estimator ``name`` at ``z``."""
    A, B, C = d.lin.Ad, d.lin.Bd, d.lin.C
    I = np.eye(4)
    zi = 1.0 / z
    if name in ("luenberger", "kalman"):
        L = d.L_cur if name == "luenberger" else d.K_kal
        F = (I - L @ C) @ A
        Minv = np.linalg.inv(I - zi * F)
        return Minv @ L, Minv @ (zi * (I - L @ C) @ B)
    if name == "luenberger_printed":
        Minv = np.linalg.inv(I - zi * (A - d.L_pred @ C))
        return Minv @ d.L_pred, Minv @ (zi * B)
    if name in ("fd_raw", "fd_lowpass"):
        h = d.lin.h
        a = 0.0 if name == "fd_raw" else math.exp(-h * 2.0 * math.pi * cutoff_hz)
        D = (1.0 - a) / h * (1.0 - zi) / (1.0 - a * zi)
        Ey = np.array([[1, 0], [D, 0], [0, 1], [0, D]], dtype=complex)
        return Ey, np.zeros((4, 1), dtype=complex)
    raise ValueError(f"unknown estimator {name!r}")


def loop_gain(name: str, d: Designs, w: float) -> complex:
    """Loop gain at the plant input, ``L = (1 + K E_u)^-1 K E_y P`` (``u = -K x_hat``), at ``w`` rad/s."""
    z = complex(math.cos(w * d.lin.h), math.sin(w * d.lin.h))
    P = d.lin.C @ np.linalg.solve(z * np.eye(4) - d.lin.Ad, d.lin.Bd)
    Ey, Eu = _estimator_fr(name, d, z)
    K = d.K_lqr
    return complex((np.linalg.inv(np.eye(1) + K @ Eu) @ K @ Ey @ P)[0, 0])


def delay_margin(name: str, d: Designs, n: int = 20000) -> dict[str, float]:
    """Delay margin of the LQR loop with estimator ``name`` predicted from the linear model.

    At each gain crossover ``|L(e^{j w h})| = 1`` (found on a log grid of ``n`` frequencies up to Nyquist, then
    refined by bisection) the phase margin ``pm`` is ``angle(L) + pi`` (mod ``2 pi``); an extra input delay
    ``tau`` adds the phase lag ``w tau``, so the loop is lost at ``tau = min pm / w``. Returns the crossover
    frequency ``wc`` (rad/s), ``pm_deg`` and ``margin_s`` of the binding crossover.
    """
    h = d.lin.h
    ws = np.logspace(-2, math.log10(math.pi / h * 0.9999), n)
    mag = np.array([abs(loop_gain(name, d, w)) for w in ws]) - 1.0
    best = {"wc": math.nan, "pm_deg": math.nan, "margin_s": math.inf}
    for i in np.where(np.sign(mag[:-1]) != np.sign(mag[1:]))[0]:
        lo, hi = ws[i], ws[i + 1]
        for _ in range(60):
            mid = math.sqrt(lo * hi)
            if np.sign(abs(loop_gain(name, d, mid)) - 1.0) == np.sign(mag[i]):
                lo = mid
            else:
                hi = mid
        wc = math.sqrt(lo * hi)
        pm = (math.atan2(loop_gain(name, d, wc).imag, loop_gain(name, d, wc).real) + math.pi) % (2 * math.pi)
        if pm / wc < best["margin_s"]:
            best = {"wc": wc, "pm_deg": math.degrees(pm), "margin_s": pm / wc}
    return best


def _estimator_ss(name: str, d: Designs, cutoff_hz: float = FD_CUTOFF_HZ) -> tuple[np.ndarray, ...]:
    """The estimator as ``s[k] = Fe s[k-1] + Ge y[k] + Be u[k-1]``, ``x_hat[k] = He s[k] + Je y[k]``."""
    A, B, C = d.lin.Ad, d.lin.Bd, d.lin.C
    I = np.eye(4)
    if name in ("luenberger", "kalman"):
        L = d.L_cur if name == "luenberger" else d.K_kal
        return (I - L @ C) @ A, L, (I - L @ C) @ B, I, np.zeros((4, 2))
    if name == "luenberger_printed":
        return A - d.L_pred @ C, d.L_pred, B, I, np.zeros((4, 2))
    if name in ("fd_raw", "fd_lowpass"):
        h = d.lin.h
        a = 0.0 if name == "fd_raw" else math.exp(-h * 2.0 * math.pi * cutoff_hz)
        F1 = np.array([[a, -(1.0 - a) / h], [0.0, 0.0]])  # per angle: [v_f, previous position]
        G1 = np.array([[(1.0 - a) / h], [1.0]])
        He = np.zeros((4, 4))
        He[1, 0] = He[3, 2] = 1.0
        Je = np.array([[1.0, 0.0], [0.0, 0.0], [0.0, 1.0], [0.0, 0.0]])
        return np.kron(np.eye(2), F1), np.kron(np.eye(2), G1), np.zeros((4, 1)), He, Je
    raise ValueError(f"unknown estimator {name!r}")


def delay_spectral_radius(name: str, d: Designs, steps: int) -> float:
    """Spectral radius of the linear discrete loop (estimator ``name`` + LQR) when the input reaches the plant
    ``steps`` whole samples late (``u_applied[k] = u[k - steps]``): below 1 the loop is stable.

    An exact check of :func:`delay_margin` at whole-sample delays (no frequency-response approximation).
    """
    A, B, C, K = d.lin.Ad, d.lin.Bd, d.lin.C, d.K_lqr
    Fe, Ge, Be, He, Je = _estimator_ss(name, d)
    ne = Fe.shape[0]
    D = max(int(steps), 1)
    n = 4 + ne + D  # z[k] = [x[k], s[k-1], u[k-1], ..., u[k-D]]
    S = np.zeros((ne, n))
    S[:, :4], S[:, 4:4 + ne], S[:, 4 + ne:5 + ne] = Ge @ C, Fe, Be
    U = -K @ He @ S
    U[:, :4] += -(K @ Je @ C)
    UA = U if steps == 0 else np.eye(n)[4 + ne + steps - 1:4 + ne + steps]
    M = np.zeros((n, n))
    M[:4, :4] = A
    M[:4] += B @ UA
    M[4:4 + ne] = S
    M[4 + ne:5 + ne] = U
    for i in range(1, D):
        M[4 + ne + i, 4 + ne + i - 1] = 1.0
    return float(np.max(np.abs(np.linalg.eigvals(M))))
