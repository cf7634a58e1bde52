"""The ``pendulum`` metric on hand-made signals (expected values computed by hand in each test)."""

import math
import warnings

import numpy as np
import pandas as pd
import pytest

import netsim  # noqa: F401
from netsim.models.pendulum.metrics import PendulumMetricParams, pendulum_measures


def _signals(n=600, h=0.005):
    t = np.arange(n) * h
    u = np.where(t < 0.05, 3.0, 0.1 * np.sin(2 * np.pi * 5 * t))  # 10 samples at the limit, then a sine
    return pd.DataFrame({"time_s": t, "theta": np.full(n, 0.1), "alpha": np.where(t < 1.0, 0.02, 0.0), "u": u,
                         "x_hat[1]": np.where(np.arange(n) % 2 == 0, 1.0, -1.0), "x_hat[3]": np.zeros(n)})


def test_measures_of_hand_made_signals():
    s = _signals()
    m = pendulum_measures(s, ok=True)
    n_samples = len(np.arange(0.0, s.time_s.max() - 0.005 + 1e-9, 0.005))  # 599 samples
    assert m["saturated_share"] == pytest.approx(10 / n_samples)
    assert m["rms_theta"] == pytest.approx(0.1)
    assert m["rms_alpha"] == pytest.approx(0.02 * math.sqrt(200 / n_samples))  # 200 samples before 1 s
    assert m["rms_alpha_after_settle"] == 0.0
    # after 1 s u is a 5 Hz sine of amplitude 0.1 sampled at 200 Hz over whole periods: std 0.1 / sqrt(2)
    assert m["u_std"] == pytest.approx(0.1 / math.sqrt(2), rel=2e-2)
    # +-1 alternating over the 399 samples from 1 s on (200 of +1, 199 of -1): mean 1/399
    assert m["theta_dot_est_std"] == pytest.approx(math.sqrt(1 - (1 / 399) ** 2), rel=1e-12)
    assert m["stable"] == 1.0
    u = s.u.to_numpy()[:n_samples]  # the value held over each sample (recorded at its start)
    th = np.full(n_samples, 0.1)
    al = np.where(np.arange(n_samples) * 0.005 < 1.0, 0.02, 0.0)
    assert m["lqg_cost_per_step"] == pytest.approx(np.mean(5 * th**2 + 20 * al**2 + u**2), rel=1e-12)


def test_a_fallen_pendulum_is_not_stable():
    s = _signals()
    s.loc[s.time_s > 2.0, "alpha"] = math.pi
    assert pendulum_measures(s, ok=True)["stable"] == 0.0
    assert pendulum_measures(_signals(), ok=False)["stable"] == 0.0
    tight = PendulumMetricParams(stable_alpha=1e-3)
    s2 = _signals()
    s2.loc[s2.time_s > 2.0, "alpha"] = 0.01
    assert pendulum_measures(s2, ok=True)["stable"] == 1.0
    assert pendulum_measures(s2, ok=True, p=tight)["stable"] == 0.0


def test_estimate_convergence_time():
    # the alpha estimate is 0.01 rad off (above est_tol = 0.005) until 0.3 s, exact afterwards: the last sample
    # outside is t = 0.295 s, so the estimates have converged one period later, at 0.3 s
    s = _signals()
    t = s["time_s"].to_numpy()
    s["x_hat[0]"] = s["theta"]
    s["x_hat[2]"] = s["alpha"] + np.where(t < 0.3, 0.01, 0.0)
    assert pendulum_measures(s, ok=True)["est_converged_s"] == pytest.approx(0.3)
    s["x_hat[2]"] = s["alpha"] + 0.004  # always inside the bound
    assert pendulum_measures(s, ok=True)["est_converged_s"] == 0.0
    s["x_hat[0]"] = s["theta"] + np.where(t > 2.0, 0.02, 0.0)  # leaves the bound for good: the run's end
    assert pendulum_measures(s, ok=True)["est_converged_s"] == pytest.approx(t[-2] + 0.005)


def test_a_run_shorter_than_settle_gives_nan_after_settle_and_no_numpy_warning():
    s = _signals()
    short = s[s["time_s"] <= 0.03].copy()  # 30 ms: nothing from settle = 1 s on
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        m = pendulum_measures(short, ok=True)
    assert all(math.isnan(m[k]) for k in ("u_std", "rms_alpha_after_settle", "lqg_cost_after_settle"))
    assert math.isfinite(m["rms_alpha"])  # the whole-run measures still have samples
