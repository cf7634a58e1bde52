"""Non-uniform multi-rate estimator (NUMRE), eqs (9)-(15) of Cuenca et al.

The model is the augmented plant + disturbance system of eq (3)/(4)::

    x_{k+1} = A x_k + B u_k + Bw w_k,   y_k = C x_k + v_k,   d_k = Cbar x_k

Measurements arrive at non-uniform instants; the multiplicity ``N = k - k_ls`` (eq 9) is the number of
fast periods since the previous received sample. On arrival the prior ``x(k|k-N)`` is corrected with
the gain ``K(N)`` (eq 11); between arrivals the state is predicted open loop (eq 14) and ``y_hat``,
``d_hat`` follow from eq (15).

``K(N)`` (eqs 12-13): the recursion of eq (12) for a fixed ``N`` is the Kalman filter of the lifted
system ``(A^N, C)`` with process noise covariance ``We(N)``; its steady state depends on ``N`` only, so
it is computed once per ``N`` (discrete Riccati equation) and cached. ``We(N)`` is computed for *white*
``w`` as ``sum_c A^(N-1-c) Bw W Bw' A^(N-1-c)'`` (``we_form="white"``, the covariance of the sum in
eq 13 when the ``w_{k+c}`` are independent); the printed formula ``(sum A^.. Bw) W (sum A^.. Bw)'``
holds only if ``w`` is constant over the N periods and is available as ``we_form="held"``.

``h >= N_max`` (the text after eq 14): :meth:`Numre.check_horizon` reports multiplicities above ``h``;
the cascade in :mod:`netsim.control.cascade` keeps predicting with the held last action in that case
and counts the violations.
"""

from __future__ import annotations

import logging
from typing import Literal

import numpy as np

from netsim.control.kalman import kalman_gain, steady_state_prior
from netsim.errors import ConfigError

__all__ = ["Numre", "lifted_noise_cov"]

log = logging.getLogger(__name__)


def lifted_noise_cov(A: np.ndarray, Bw: np.ndarray, W: np.ndarray, N: int,
                     form: Literal["white", "held"] = "white") -> np.ndarray:
    """``We(N)`` of eq (13): covariance of ``sum_{c<N} A^(N-1-c) Bw w_{k+c}``."""
    n = A.shape[0]
    if form == "white":
        Q = Bw @ W @ Bw.T
        We = np.zeros((n, n))
        P = np.eye(n)
        for _ in range(N):  # sum_{j=0}^{N-1} A^j Q A^j'
            We += P @ Q @ P.T
            P = A @ P
        return We
    if form == "held":
        S = np.zeros_like(Bw)
        P = np.eye(n)
        for _ in range(N):
            S += P @ Bw
            P = A @ P
        return S @ W @ S.T
    raise ConfigError(f"NUMRE: we_form must be 'white' or 'held', got {form!r}")


class Numre:
    """The NUMRE filter: cached ``K(N)``, correction (eq 11) and cascade prediction (eq 14).

    Parameters
    ----------
    A, B, C, Cbar, Bw
        Augmented model matrices of eq (3) (``Cbar`` may be ``None`` when no disturbance is modelled).
    W, V
        Covariances of ``w`` and ``v``.
    h
        Prediction horizon (number of future steps, eq 14).
    """

    def __init__(self, A, B, C, Bw, W, V, *, Cbar=None, h: int = 1,
                 we_form: Literal["white", "held"] = "white") -> None:
        self.A = np.atleast_2d(np.asarray(A, float))
        n = self.A.shape[0]
        self.B = np.asarray(B, float).reshape(n, -1)
        self.C = np.atleast_2d(np.asarray(C, float))
        self.Bw = np.asarray(Bw, float).reshape(n, -1)
        self.W = np.atleast_2d(np.asarray(W, float))
        self.V = np.atleast_2d(np.asarray(V, float))
        self.Cbar = None if Cbar is None else np.atleast_2d(np.asarray(Cbar, float))
        if int(h) != h or h < 0:
            raise ConfigError(f"NUMRE: horizon h must be an integer >= 0, got {h!r}")
        if np.any(np.linalg.eigvalsh(0.5 * (self.V + self.V.T)) <= 0):
            raise ConfigError("NUMRE: the measurement noise covariance V must be positive definite")
        self.h = int(h)
        self.we_form = we_form
        self._gains: dict[int, np.ndarray] = {}
        self._priors: dict[int, np.ndarray] = {}
        self._b = self.B[:, 0].copy()
        self.n = n
        self._c0 = self.C[0]
        self._cbar0 = None if self.Cbar is None else self.Cbar[0]
        self._fused = self._fused_matrix()

    def _fused_matrix(self) -> np.ndarray | None:
        """``[A; C0; Cbar0]`` stacked, if one product with it gives the same bits as the separate ones.

        The cascade needs ``A x``, ``C0 x`` and ``Cbar0 x`` of the same state at each step; one
        matrix-vector product serves all three. The rows are the same dot products, but BLAS may order the
        sums of a matrix-vector product differently from those of a vector dot product, so the fused form is
        used only if it reproduces the separate products bit for bit on a set of probe vectors (it does with
        the OpenBLAS kernels numpy ships; otherwise :meth:`step_outputs` falls back to separate products).
        """
        rows = [self.A, self.C[:1]] + ([] if self.Cbar is None else [self.Cbar[:1]])
        M = np.ascontiguousarray(np.vstack(rows))
        n = self.n
        for i in range(48):  # deterministic probes over many magnitudes and sign patterns
            x = np.sin(np.arange(1, n + 1) * (0.7 + 0.37 * i)) * 10.0 ** ((i % 13) - 6)
            z = M @ x
            if not np.array_equal(z[:n], self.A @ x) or float(z[n]) != float(self._c0 @ x):
                return None
            if self._cbar0 is not None and float(z[n + 1]) != float(self._cbar0 @ x):
                return None
        return M

    # --- gains ---------------------------------------------------------------------------------
    def prior_cov(self, N: int) -> np.ndarray:
        """Steady-state prior covariance of the N-lifted filter (fixed point of eq 12)."""
        if N < 1:
            raise ConfigError(f"NUMRE: multiplicity N must be >= 1, got {N}")
        if N not in self._priors:
            AN = np.linalg.matrix_power(self.A, N)
            We = lifted_noise_cov(self.A, self.Bw, self.W, N, self.we_form)
            self._priors[N] = steady_state_prior(AN, self.C, We, self.V)
        return self._priors[N]

    def gain(self, N: int) -> np.ndarray:
        """``K(N)`` of eq (12), cached per ``N``."""
        K = self._gains.get(N)
        if K is None:
            K = kalman_gain(self.prior_cov(N), self.C, self.V)
            self._gains[N] = K
        return K

    def precompute(self, N_max: int) -> None:
        """Compute and cache ``K(1) .. K(N_max)`` (build time)."""
        for N in range(1, N_max + 1):
            self.gain(N)

    # --- filter --------------------------------------------------------------------------------
    def correct(self, x_prior: np.ndarray, y, N: int) -> np.ndarray:
        """Eq (11): ``x(k|k) = x(k|k-N) + K(N) (y_k - C x(k|k-N))``."""
        K = self.gain(N)
        innov = np.atleast_1d(np.asarray(y, float)) - self.C @ x_prior
        return x_prior + K @ innov

    def predict_step(self, x: np.ndarray, u: float) -> np.ndarray:
        """One step of eq (14): ``A x + B u`` (scalar input)."""
        return self.A @ x + self._b * u

    def outputs(self, x: np.ndarray) -> tuple[float, float]:
        """Eq (15): ``(y_hat, d_hat)`` of a state (``d_hat = 0`` without a disturbance model)."""
        y = float(self._c0 @ x)
        d = 0.0 if self._cbar0 is None else float(self._cbar0 @ x)
        return y, d

    def step_outputs(self, x: np.ndarray) -> tuple[np.ndarray, float, float]:
        """``(A x, y_hat, d_hat)`` of a state: :meth:`outputs` plus the free part of :meth:`predict_step`.

        ``predict_step(x, u) == step_outputs(x)[0] + B u`` bit for bit (one matrix product when possible).
        """
        M = self._fused
        if M is not None:
            z = M @ x
            n = self.n
            return z[:n], float(z[n]), (0.0 if self._cbar0 is None else float(z[n + 1]))
        y, d = self.outputs(x)
        return self.A @ x, y, d

    def predict(self, x: np.ndarray, u_seq) -> np.ndarray:
        """Eq (14) for ``l = 0..len(u_seq)``: rows ``x(k+l|k)``."""
        us = np.ravel(np.asarray(u_seq, float))
        out = np.empty((us.size + 1, self.n))
        out[0] = x
        for i, u in enumerate(us):
            out[i + 1] = self.A @ out[i] + self._b * u
        return out

    def check_horizon(self, N: int) -> bool:
        """True if ``h >= N`` (the requirement after eq 14); logs a warning otherwise."""
        if N > self.h:
            log.warning("NUMRE: multiplicity N=%d exceeds the prediction horizon h=%d (need h >= N_max)", N, self.h)
            return False
        return True
