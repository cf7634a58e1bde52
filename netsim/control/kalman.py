"""Discrete Kalman filter helpers (steady state by the discrete Riccati equation, and one step).

Plain numpy/scipy: the steady-state prior covariance solves the filter DARE
``M = A M A' + W - A M C' (C M C' + V)^-1 C M A'`` with :func:`scipy.linalg.solve_discrete_are`
(the dual of the LQR equation), and the gain used for a correction from a prior is
``K = M C' (C M C' + V)^-1``.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from netsim.errors import ConfigError

__all__ = ["steady_state_prior", "kalman_gain", "riccati_step"]


def steady_state_prior(A: np.ndarray, C: np.ndarray, W: np.ndarray, V: np.ndarray) -> np.ndarray:
    """Steady-state prior covariance of the filter for ``x+ = A x + w``, ``y = C x + v``.

    Raises
    ------
    ConfigError
        If the Riccati equation has no stabilizing solution (``(A, C)`` not detectable or the noise
        does not excite an unstable mode).
    """
    A = np.atleast_2d(A)
    C = np.atleast_2d(C)
    try:
        M = sla.solve_discrete_are(A.T, C.T, np.atleast_2d(W), np.atleast_2d(V))
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise ConfigError(
            f"Kalman filter: the discrete Riccati equation has no stabilizing solution ({exc}); check that "
            "the model is detectable from the measurement and that V is positive definite"
        ) from exc
    return 0.5 * (M + M.T)


def kalman_gain(M: np.ndarray, C: np.ndarray, V: np.ndarray) -> np.ndarray:
    """Correction gain ``K = M C' (C M C' + V)^-1`` from a prior covariance ``M``."""
    C = np.atleast_2d(C)
    S = C @ M @ C.T + np.atleast_2d(V)
    return np.linalg.solve(S.T, (M @ C.T).T).T


def riccati_step(M: np.ndarray, A: np.ndarray, C: np.ndarray, W: np.ndarray, V: np.ndarray) -> np.ndarray:
    """One step of the prior-covariance recursion (eq 12 of Cuenca et al. with ``A`` = ``A^N``)."""
    C = np.atleast_2d(C)
    S = C @ M @ C.T + np.atleast_2d(V)
    AM = A @ M
    return AM @ A.T + W - AM @ C.T @ np.linalg.solve(S, C @ M @ A.T)
