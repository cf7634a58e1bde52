"""The pendulum study's measures as a registered metric (``metrics: [{type: pendulum}]``), for runs and sweeps.

Computed from the recorded signals ``theta``, ``alpha`` (the plant's true angles on its record grid), ``u`` (the
applied voltage) and, when recorded, ``x_hat[1]``, ``x_hat[3]`` (the velocity estimates), over the control
samples ``t_k = k period``:

``pendulum.u_std``
    std of ``u`` for ``t >= settle`` (the chatter once balanced);
``pendulum.saturated_share``
    share of samples with ``|u| >= u_limit``;
``pendulum.rms_theta``, ``pendulum.rms_alpha``, ``pendulum.rms_alpha_after_settle``
    RMS of the true angles (whole run; ``alpha`` also from ``settle`` on);
``pendulum.lqg_cost_per_step``, ``pendulum.lqg_cost_after_settle``
    mean of ``q_theta theta^2 + q_alpha alpha^2 + r u^2`` (the LQR's weights: they weight the angles only, so
    the true angles give the cost exactly);
``pendulum.stable``
    1 when ``|alpha| < stable_alpha`` over the last second, else 0;
``pendulum.theta_dot_est_std``, ``pendulum.alpha_dot_est_std``
    std of the velocity estimates from ``settle`` on (in a hold-still run: the estimator's noise);
``pendulum.est_converged_s``
    how long the estimator takes to catch up: the time after which both angle estimates ``x_hat[0]``,
    ``x_hat[2]`` (the estimate made from each sample, the last one recorded before the next sample) stay within
    ``est_tol`` of the true angles (0 when they always are; the run's length when they never settle).

The metric also judges the run (:mod:`netsim.results.verdict`, ``pendulum_metric.verdict``): a pendulum whose ``|alpha|``
reaches :data:`FALLEN_ALPHA` (pi/2, below the horizontal) has fallen, and the run's status is ``unstable at t = ...
s`` from the first such sample, bounded as its states may be (``verdict.metrics: false`` turns it off).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pandas as pd
from pydantic import Field

from netsim.registry import register
from netsim.units import StrictModel

__all__ = ["PendulumMetricParams", "pendulum_measures", "pendulum_metric", "fallen_at", "FALLEN_ALPHA"]


class PendulumMetricParams(StrictModel):
    """Parameters of the ``pendulum`` metric (defaults: the study's choices)."""

    period: float = Field(0.005, gt=0, description="control period (s)")
    settle: float = Field(1.0, ge=0, description="start of the 'balanced' part of the run (s)")
    u_limit: float = Field(3.0, gt=0, description="actuator limit (V)")
    stable_alpha: float = Field(0.05, gt=0, description="|alpha| bound over the last second for 'stable' (rad)")
    q_theta: float = Field(5.0, ge=0, description="LQR weight on theta")
    q_alpha: float = Field(20.0, ge=0, description="LQR weight on alpha")
    r: float = Field(1.0, gt=0, description="LQR weight on u")
    est_tol: float = Field(0.005, gt=0, description="angle-estimate error bound for est_converged_s (rad): "
                           "about 5.6 encoder-noise stds, so the noise alone does not cross it")


def _at(s: pd.DataFrame, col: str, t: np.ndarray) -> np.ndarray:
    """Held value of ``col`` at the times ``t`` (the last value recorded at or before each)."""
    series = s[col].dropna()
    idx = np.searchsorted(series.index.to_numpy(float), t + 1e-12, side="right") - 1
    vals = series.to_numpy(float)
    return np.where(idx >= 0, vals[np.clip(idx, 0, None)], np.nan)


def pendulum_measures(signals: pd.DataFrame, ok: bool, p: PendulumMetricParams | None = None) -> dict[str, float]:
    """The measures of the module docstring from a signals table (``time_s`` column or index)."""
    p = PendulumMetricParams() if p is None else p
    s = signals.set_index("time_s") if "time_s" in signals.columns else signals
    s = s.sort_index()
    t_end = float(s.index.max())
    h = p.period
    tk = np.arange(0.0, t_end - h + 1e-9, h)
    theta, alpha = _at(s, "theta", tk), _at(s, "alpha", tk)
    u = np.nan_to_num(_at(s, "u", tk + h - 1e-9), nan=0.0)  # the input applied over each sample
    late = tk >= p.settle
    cost = p.q_theta * theta**2 + p.q_alpha * alpha**2 + p.r * u**2
    last = tk >= t_end - 1.0
    finite = bool(np.all(np.isfinite(alpha)))
    max_last = float(np.max(np.abs(alpha[last]))) if finite else float("inf")
    out = {
        "u_std": _std(u[late]),
        "saturated_share": float(np.mean(np.abs(u) >= p.u_limit - 1e-9)),
        "rms_theta": float(np.sqrt(np.mean(theta**2))),
        "rms_alpha": float(np.sqrt(np.mean(alpha**2))),
        "rms_alpha_after_settle": float(np.sqrt(_mean(alpha[late] ** 2))),
        "lqg_cost_per_step": float(np.mean(cost)),
        "lqg_cost_after_settle": _mean(cost[late]),
        "max_alpha_last_s": max_last,
        "stable": float(ok and finite and max_last < p.stable_alpha),
    }
    for i, name in ((1, "theta_dot_est_std"), (3, "alpha_dot_est_std")):
        col = f"x_hat[{i}]"
        if col in s.columns:
            out[name] = _std(_at(s, col, tk)[late])
    if "x_hat[0]" in s.columns and "x_hat[2]" in s.columns:
        err = np.maximum(np.abs(_at(s, "x_hat[0]", tk + h - 1e-9) - theta), np.abs(_at(s, "x_hat[2]", tk + h - 1e-9) - alpha))
        out["est_converged_s"] = _converged(tk, err, p.est_tol, h)
    return out


def _mean(x: np.ndarray) -> float:
    """The mean, NaN for a run that ends before ``settle`` (no samples; numpy would warn)."""
    return float(np.mean(x)) if len(x) else float("nan")


def _std(x: np.ndarray) -> float:
    """The standard deviation, NaN for a run that ends before ``settle`` (no samples; numpy would warn)."""
    return float(np.std(x)) if len(x) else float("nan")


def _converged(tk: np.ndarray, err: np.ndarray, tol: float, h: float) -> float:
    """The time after which ``err`` (NaN counts as outside) stays below ``tol``: one period after the last
    sample outside, 0 when none is."""
    outside = np.flatnonzero(~(err < tol))
    if outside.size == 0:
        return 0.0
    return float(tk[outside[-1]] + h)


@register("metric", "pendulum", "pendulum study: u chatter, saturation, RMS angles, LQG cost, stability, estimate noise")
def pendulum_metric(result: Any, params: Any, baseline: Any = None) -> dict[str, float]:
    """``pendulum.<measure>`` for a run (see the module docstring)."""
    from netsim.metrics.runtime import validate_params

    p = validate_params(PendulumMetricParams, params, "pendulum")
    ok = str(getattr(result, "status", "ok")).startswith("ok")
    return {f"pendulum.{k}": v for k, v in pendulum_measures(result.signals, ok, p).items()}


#: ``|alpha|`` (rad) at which the pendulum has fallen: below the horizontal, gravity pulls it away from upright
#: and no balancing law about the upright position brings it back.
FALLEN_ALPHA = math.pi / 2


def fallen_at(signals: pd.DataFrame, bound: float = FALLEN_ALPHA) -> tuple[float, float] | None:
    """``(t_s, alpha)`` of the first recorded sample with ``|alpha| >= bound``, or None (no ``alpha`` column, or the
    pendulum stayed up)."""
    if "alpha" not in signals.columns:
        return None
    alpha = signals["alpha"].to_numpy(float)
    t = signals["time_s"].to_numpy(float) if "time_s" in signals.columns else signals.index.to_numpy(float)
    down = np.abs(alpha) >= bound  # NaN (not yet sampled) compares False
    if not down.any():
        return None
    k = int(np.argmax(down))
    return float(t[k]), float(alpha[k])


def pendulum_verdict(result: Any, params: Any) -> tuple[float, str] | None:
    """The metric's verdict on a run: ``(t_s, text)`` when the pendulum fell (``|alpha| >= pi/2``), else None."""
    hit = fallen_at(result.signals)
    if hit is None:
        return None
    t, alpha = hit
    return t, (f"the pendulum fell: |alpha| reached {abs(alpha):.3g} rad at t = {t:.9g} s, past pi/2 (below the "
               f"horizontal; the pendulum metric's verdict, verdict.metrics: false turns it off)")


pendulum_metric.Params = PendulumMetricParams  # type: ignore[attr-defined]
#: The columns the measures need (``x_hat[i]`` are optional): validate refuses a run that would not record them.
pendulum_metric.reads_signals = ("theta", "alpha", "u")  # type: ignore[attr-defined]
pendulum_metric.verdict = pendulum_verdict  # type: ignore[attr-defined]
