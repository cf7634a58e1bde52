"""The pendulum loop's expected cost under an input-output delay, from :mod:`netsim.analysis.lqg` (Jitterbug-style).

The loop of ``scenarios/pendulum_network.yaml`` linearised: the continuous plant (the upright linearisation of
:mod:`netsim.models.pendulum.model`), sampled every ``TS``; the estimator of the study (:func:`netsim.models.pendulum.design.
_estimator_ss`) and the LQR as one discrete controller; the input reaches the plant ``delay_s`` after the
sample and is held. Noise: the white input-voltage disturbance as process noise of intensity ``std^2 hold``
through ``B`` (the simulated disturbance is that noise held over ``hold = 1 ms``, short against the loop's
time constants), the encoder noise as measurement noise ``SENSOR_STD^2 I``. Cost: the LQR's weights
``Q = diag(5, 0, 20, 0)``, ``R = 1``.

:func:`netsim.analysis.lqg.lqg_cost` needs every output to reach the plant before the next sample, so a delay
of ``D`` whole periods plus a fraction ``f`` is modelled as a delay line of ``D`` samples inside the controller
(its output is ``u[k - D]``) and a delay ``f`` inside the period.

* :func:`controller_matrices` -- ``(Ac, Bc, Cc, Dc)`` of the estimator + LQR (+ delay line);
* :func:`analytic_cost` -- the stationary cost per second ``J`` (the time average of ``x' Q x + u' R u``),
  the expected cost at the sampling instants (what the ``pendulum`` metric's ``lqg_cost_after_settle``
  estimates) and the spectral radius of the loop;
* :func:`lqg_delay_margin` -- the largest delay with a mean-square stable loop (bisection on the spectral
  radius), an exact counterpart of the phase-margin estimate :func:`netsim.models.pendulum.design.delay_margin`;
* :func:`law_delay_margin` -- the delay margin of the LQR law fed the true state: the limit of any estimator
  told the delay with an exact model (issue 26 section 5), since the loop's eigenvalues are then those of the law
  on the delayed plant and those of the estimation error (separation).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from netsim.models.pendulum.design import Q_LQR, R_LQR, Designs, _estimator_ss
from netsim.models.pendulum.model import DISTURBANCE_HOLD, DISTURBANCE_STD, SENSOR_STD

__all__ = ["controller_matrices", "sampled_loop", "analytic_cost", "lqg_delay_margin", "law_spectral_radius",
           "law_delay_margin"]


def controller_matrices(name: str, d: Designs, delay_samples: int = 0) -> tuple[np.ndarray, ...]:
    """``(Ac, Bc, Cc, Dc)`` of estimator ``name`` + LQR, its output delayed by ``delay_samples`` periods.

    Controller state ``xc[k] = [s[k-1], u[k-1], ..., u[k-L]]`` with ``L = max(delay_samples, 1)`` (``s`` the
    estimator's state, ``u`` the computed inputs): ``s[k] = Fe s[k-1] + Be u[k-1] + Ge y[k]``, ``x_hat[k] = He
    s[k] + Je y[k]``, ``u[k] = -K x_hat[k]``; the output is ``u[k]`` (no delay) or ``u[k - delay_samples]``.
    """
    if delay_samples < 0:
        raise ValueError(f"delay_samples must be >= 0, got {delay_samples}")
    Fe, Ge, Be, He, Je = _estimator_ss(name, d)
    K = d.K_lqr
    ne, p = Fe.shape[0], Ge.shape[1]
    line = max(int(delay_samples), 1)
    nc = ne + line
    S = np.zeros((ne, nc))  # s[k] = S xc[k] + Ge y[k]
    S[:, :ne], S[:, ne:ne + 1] = Fe, Be
    U = -K @ He @ S  # u[k] = U xc[k] + Uy y[k]
    Uy = -K @ (He @ Ge + Je)
    Ac = np.zeros((nc, nc))
    Bc = np.zeros((nc, p))
    Ac[:ne], Bc[:ne] = S, Ge
    Ac[ne:ne + 1], Bc[ne:ne + 1] = U, Uy
    for i in range(1, line):  # shift the line: u[k-i] moves one place down
        Ac[ne + i, ne + i - 1] = 1.0
    if delay_samples == 0:
        return Ac, Bc, U, Uy
    Cc = np.zeros((1, nc))
    Cc[0, ne + line - 1] = 1.0
    return Ac, Bc, Cc, np.zeros((1, p))


def sampled_loop(name: str, d: Designs, delay_s: float) -> tuple[Any, float]:
    """The :class:`netsim.analysis.lqg.SampledLoop` of estimator ``name`` with a total delay ``delay_s``, and the
    part of the delay inside one period (the rest is the controller's delay line)."""
    from netsim.analysis.lqg import SampledLoop

    h = d.lin.h
    steps = int(math.floor(delay_s / h + 1e-9))
    frac = max(delay_s - steps * h, 0.0)
    Ac, Bc, Cc, Dc = controller_matrices(name, d, steps)
    B = d.lin.B
    loop = SampledLoop(A=d.lin.A, B=B, C=d.lin.C, Ac=Ac, Bc=Bc, Cc=Cc, Dc=Dc, period_s=h,
                       Q1=np.diag(Q_LQR), Q2=[[R_LQR]], R1=B @ B.T * DISTURBANCE_STD**2 * DISTURBANCE_HOLD,
                       R2=np.eye(2) * SENSOR_STD**2)
    return loop, frac


def analytic_cost(name: str, d: Designs, delay_s: float) -> dict[str, float]:
    """Stationary cost of the loop with estimator ``name`` and total input-output delay ``delay_s``.

    Returns ``J`` (per second: the time average of ``x' Q x + u' R u``), ``per_sample`` (the expected
    ``x' Q x + u' R u`` at the sampling instants, the applied input held there) and ``spectral_radius``
    (of the second-moment recursion; ``J`` is ``inf`` when it is 1 or more).
    """
    from netsim.analysis.lqg import lqg_cost

    loop, frac = sampled_loop(name, d, delay_s)
    res = lqg_cost(loop, delay=frac)
    if res.covariance is None:
        return {"J": math.inf, "per_sample": math.inf, "spectral_radius": res.spectral_radius}
    P = res.covariance  # E[z z'], z = [x; xc; u held], at the sampling instants
    n, nc = loop.n, loop.nc
    per_sample = float(np.trace(loop.Q1 @ P[:n, :n]) + R_LQR * P[n + nc, n + nc])
    return {"J": res.cost, "per_sample": per_sample, "spectral_radius": res.spectral_radius}


def lqg_delay_margin(name: str, d: Designs, max_delay_s: float = 0.08, step_s: float = 0.0005,
                     tol_s: float = 1e-6) -> float:
    """The smallest delay (s) at which the loop stops being mean-square stable (its cost becomes infinite).

    Scans ``0, step_s, ...`` up to ``max_delay_s`` for the first unstable delay, then bisects to ``tol_s``.
    Returns ``inf`` when the loop is stable over the whole range.
    """
    def unstable(tau: float) -> bool:
        return analytic_cost(name, d, tau)["spectral_radius"] >= 1.0

    prev = 0.0
    for tau in np.arange(step_s, max_delay_s + 1e-12, step_s):
        if unstable(float(tau)):
            lo, hi = prev, float(tau)
            while hi - lo > tol_s:
                mid = 0.5 * (lo + hi)
                lo, hi = (lo, mid) if unstable(mid) else (mid, hi)
            return 0.5 * (lo + hi)
        prev = float(tau)
    return math.inf


def law_spectral_radius(d: Designs, delay_s: float) -> float:
    """Spectral radius of ``x[k+1] = Phi x[k] + Gamma1 u[k-D-1] + Gamma0 u[k-D]``, ``u[k] = -K x[k]``, for a delay
    ``D h + f`` (Astrom & Wittenmark's augmented state ``[x; u[k-D-1] ... u[k-1]]``; ``Gamma0, Gamma1``: the ZOH
    split of the period at ``f``, :func:`netsim.control.interface.zoh_split`)."""
    from netsim.control.interface import zoh_split

    h = d.lin.h
    D = int(math.floor(delay_s / h + 1e-9))
    f = max(delay_s - D * h, 0.0)
    Phi, G0, G1 = zoh_split(d.lin.A, d.lin.B, h, f)
    K = d.K_lqr
    n = Phi.shape[0]
    N = n + D + 1  # z = [x; u[k-D-1], ..., u[k-1]]
    F = np.zeros((N, N))
    F[:n, :n] = Phi
    F[:n, n:n + 1] = G1
    if D == 0:  # u[k-D] = u[k] = -K x[k]
        F[:n, :n] += -G0 @ K
        F[n, :n] = -K  # the next u[k-1] is u[k]
    else:
        F[:n, n + 1:n + 2] = G0
        for i in range(D):  # shift the line
            F[n + i, n + i + 1] = 1.0
        F[n + D, :n] = -K  # the newest entry becomes u[k]
    return float(np.max(np.abs(np.linalg.eigvals(F))))


def law_delay_margin(d: Designs, max_delay_s: float = 0.1, step_s: float = 0.0005, tol_s: float = 1e-6) -> float:
    """The smallest total delay (s) at which the LQR law fed the true state loses stability (:func:`law_spectral_
    radius` reaches 1): scan by ``step_s``, then bisect to ``tol_s``; ``inf`` when stable up to ``max_delay_s``."""
    prev = 0.0
    for tau in np.arange(step_s, max_delay_s + 1e-12, step_s):
        if law_spectral_radius(d, float(tau)) >= 1.0:
            lo, hi = prev, float(tau)
            while hi - lo > tol_s:
                mid = 0.5 * (lo + hi)
                lo, hi = (lo, mid) if law_spectral_radius(d, mid) >= 1.0 else (mid, hi)
            return 0.5 * (lo + hi)
        prev = float(tau)
    return math.inf
