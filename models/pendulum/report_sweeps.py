"""The pendulum report's sweeps: the shipped sweep files run by :func:`netsim.sweep.run.run_sweep`, and their tables.

The report runs ``scenarios/pendulum_{kalman,poles,delay}_sweep.yaml`` exactly as ``netsim sweep`` does
(same seeds, same points; output in ``reports/pendulum/runs/<sweep>/``, resumed when run again) and reads
their ``summary.csv``:

* :func:`tuning_table` -- the slides' "try Qn, Rn" and "try several pole sets": per setting the analytic
  error radius (and its time constant) and held-still velocity noise, beside the simulated convergence time
  of the estimates, chatter and costs (mean over the seeds);
* :func:`delay_cost_table` -- per estimator and delay: the simulated stationary cost with its 95 % Monte-Carlo
  interval over the seeds, beside the expected cost from :mod:`netsim.models.pendulum.analysis`;
* :func:`noise_delay_margins` -- per estimator the largest delay with every seed stable and the first with a
  failing one;
* :func:`delay_aware_table` -- the Luenberger observer and the Kalman filter told the delay
  (``scenarios/pendulum_delay_aware_sweep.yaml``: the state_feedback task's ``input_delay``, issue 26 section 5)
  beside the same estimators unaware of it (the rows of ``delay_cost.csv``): per delay the runs that stayed
  balanced and the stationary cost; :func:`delay_aware_margins` gives each row's delay bracket.
"""

from __future__ import annotations

import logging
import math
import sys
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from netsim.casestudy import sweep
from netsim.shipped import folder as shipped_scenarios

__all__ = ["SWEEPS", "run_sweeps", "point_values", "estimator_name", "tuning_table", "delay_cost_table",
           "noise_delay_margins", "equal_ratio_gain_difference", "NETWORK_BASE_DELAY_MS", "CI_LEVEL",
           "DELAY_AWARE_SWEEP", "run_delay_aware", "delay_aware_table", "delay_aware_margins"]

log = logging.getLogger("netsim.progress.pendulum")

_SCEN = shipped_scenarios()
SWEEPS = ("pendulum_kalman_sweep", "pendulum_poles_sweep", "pendulum_delay_sweep")
#: The sweep of the estimators told the delay (run on its own by ``netsim report pendulum_delay_aware``).
DELAY_AWARE_SWEEP = "pendulum_delay_aware_sweep"
#: Sample-to-actuation delay of pendulum_network.yaml without the act link: 0.5 ms offset + 0.5 ms execution
#: + 0.1 ms actuator (read from the scenario in tests/models/test_pendulum_report.py).
NETWORK_BASE_DELAY_MS = 1.1
#: Confidence level of the Monte-Carlo intervals (Student t over the seeds).
CI_LEVEL = 0.95


def run_sweeps(out: Path, workers: int | None = None) -> dict[str, Any]:
    """Run (or resume) each shipped sweep into ``out/runs/<sweep>``; returns ``summary.csv`` as a DataFrame by name.

    The tables count a diverged or unstable run as a run that did not stay balanced (``stable`` 0); a run that
    gave no result (``error``, ``interrupted``, ``pending``) stops the report (:func:`netsim.casestudy.sweep`)."""
    summaries = {}
    for name in SWEEPS:
        log.info("pendulum: sweep %s (scenarios/%s.yaml) ...", name, name)
        res = sweep(_SCEN / f"{name}.yaml", out / "runs" / name, workers=workers, progress=sys.stderr.isatty())
        log.info("pendulum: %s", res.describe().splitlines()[0])
        summaries[name] = res.summary
    return summaries


def point_values(name: str) -> list[dict[str, Any]]:
    """The factor values of each run of sweep ``name``, by ``summary.csv`` index (as Python values)."""
    from netsim.sweep.spec import load_sweep

    return [p.values for p in load_sweep(_SCEN / f"{name}.yaml").points]


def estimator_name(entry: dict[str, Any], estimators: Mapping[str, dict[str, Any]]) -> str:
    """The study's name of an estimator entry: its key in ``estimators`` (``netsim.models.pendulum.report.ESTIMATORS``)."""
    for key, value in estimators.items():
        if value == entry:
            return key
    raise ValueError(f"estimator entry {entry!r} is none of the study's ({', '.join(estimators)})")


def _with_values(summary: Any, name: str) -> Any:
    s = summary.copy()
    vals = point_values(name)
    s["values"] = [vals[int(i)] for i in s["index"]]
    return s


def _kalman_gain(d: Any, scale_Q: float, scale_R: float) -> np.ndarray:
    from netsim.control import KalmanFilter

    return KalmanFilter(d.lin.Ad, d.lin.Bd, d.lin.C, d.Qn * scale_Q, d.Rn * scale_R, steady_state=True).K_ss


def _error_stats(d: Any, L: np.ndarray) -> dict[str, float]:
    """Error radius, its time constant (ms) and the held-still alpha_dot noise (Lyapunov) of ``(I - L C) A``."""
    from scipy.linalg import solve_discrete_lyapunov

    F = (np.eye(4) - L @ d.lin.C) @ d.lin.Ad
    P = solve_discrete_lyapunov(F, L @ d.Rn @ L.T)
    rho = float(np.max(np.abs(np.linalg.eigvals(F))))
    return {"error_radius": rho, "error_tau_ms": -1e3 * d.lin.h / math.log(rho),
            "alpha_dot_noise_lyap": float(np.sqrt(P[3, 3]))}


def tuning_table(summaries: dict[str, Any]) -> Any:
    """One row per Qn/Rn scaling and per pole set: analytic error dynamics and noise, simulated means over seeds."""
    import pandas as pd

    from netsim.models.pendulum.design import designs
    from netsim.control.luenberger import observer_gain

    d = designs()
    rows = []
    for name in ("pendulum_kalman_sweep", "pendulum_poles_sweep"):
        s = _with_values(summaries[name], name)
        keys = [str(v) for v in s["values"]]
        for key in dict.fromkeys(keys):
            g = s[[k == key for k in keys]]
            v = g["values"].iloc[0]
            if name == "pendulum_kalman_sweep":
                sq, sr = float(v["scale_Q"]), float(v["scale_R"])
                L = _kalman_gain(d, sq, sr)
                r: dict[str, Any] = {"sweep": "kalman", "setting": f"Qn x {sq:g}, Rn x {sr:g}", "scale_Q": sq,
                                     "scale_R": sr, "qr_ratio": sq / sr}
            else:
                poles = [complex(str(p)) for p in v["poles"]]
                L = observer_gain(d.lin.Ad, d.lin.C, poles, "current")
                slowest = max(abs(p) for p in poles)
                r = {"sweep": "poles", "setting": f"poles up to {slowest:g}", "scale_Q": math.nan,
                     "scale_R": math.nan, "qr_ratio": math.nan}
            r.update(_error_stats(d, L))
            ok = g["status"] == "ok"
            r["seed_count"] = int(len(g))
            r["stable_share"] = float((g["pendulum.stable"].where(ok, 0.0)).mean())
            for col, src in (("est_converged_s", "pendulum.est_converged_s"), ("u_std", "pendulum.u_std"),
                             ("rms_alpha", "pendulum.rms_alpha"), ("lqg_cost_per_step", "pendulum.lqg_cost_per_step"),
                             ("lqg_cost_after_1s", "pendulum.lqg_cost_after_settle")):
                r[col] = float(g.loc[ok, src].mean()) if ok.any() else math.nan
            r["est_converged_s_max"] = float(g.loc[ok, "pendulum.est_converged_s"].max()) if ok.any() else math.nan
            rows.append(r)
    return pd.DataFrame(rows)


def equal_ratio_gain_difference(table: Any) -> float:
    """Largest difference between Kalman gains of grid points with the same Qn/Rn ratio (should be rounding)."""
    from netsim.models.pendulum.design import designs

    d = designs()
    k = table[table.sweep == "kalman"]
    worst = 0.0
    for _, g in k.groupby("qr_ratio"):
        gains = [_kalman_gain(d, a, b) for a, b in zip(g.scale_Q, g.scale_R)]
        for G in gains[1:]:
            worst = max(worst, float(np.max(np.abs(G - gains[0]))))
    return worst


def _delay_ms(text: Any) -> float:
    value, unit = str(text).split()
    if unit != "ms":
        raise ValueError(f"expected a delay in ms, got {text!r}")
    return float(value)


def delay_cost_table(summaries: dict[str, Any], estimators: Mapping[str, dict[str, Any]]) -> Any:
    """Per estimator and act delay: simulated stationary cost (mean, 95 % interval over the seeds) beside the
    expected cost of :func:`netsim.models.pendulum.analysis.analytic_cost` at the same total delay (``estimators``: the
    study's estimator entries by name, to name the sweep's)."""
    import pandas as pd
    from scipy import stats

    from netsim.models.pendulum.analysis import analytic_cost
    from netsim.models.pendulum.design import designs

    d = designs()
    name = "pendulum_delay_sweep"
    s = _with_values(summaries[name], name)
    s["estimator"] = [estimator_name(v["estimator"], estimators) for v in s["values"]]
    s["act_delay_ms"] = [_delay_ms(v["act_delay"]) for v in s["values"]]
    rows = []
    for (e, dl), g in s.groupby(["estimator", "act_delay_ms"], sort=False):
        total = dl + NETWORK_BASE_DELAY_MS
        ana = analytic_cost(e, d, total * 1e-3)
        ok = g["status"] == "ok"
        stable = g["pendulum.stable"].where(ok, 0.0).astype(float)
        cost = g["pendulum.lqg_cost_after_settle"].astype(float)
        n = len(g)
        r = {"estimator": e, "act_delay_ms": dl, "total_delay_ms": total, "seed_count": n,
             "stable_share": float(stable.mean()), "analytic_cost": ana["per_sample"], "analytic_J": ana["J"],
             "spectral_radius": ana["spectral_radius"]}
        if stable.min() > 0.5:
            m, sd = float(cost.mean()), float(cost.std(ddof=1))
            half = float(stats.t.ppf(0.5 + CI_LEVEL / 2, n - 1)) * sd / math.sqrt(n)
            r.update({"sim_cost": m, "sim_ci_low": m - half, "sim_ci_high": m + half,
                      "analytic_inside_ci": float(m - half <= ana["per_sample"] <= m + half),
                      "rel_diff": m / ana["per_sample"] - 1.0 if math.isfinite(ana["per_sample"]) else math.nan})
        else:
            r.update({"sim_cost": math.nan, "sim_ci_low": math.nan, "sim_ci_high": math.nan,
                      "analytic_inside_ci": math.nan, "rel_diff": math.nan})
        rows.append(r)
    return pd.DataFrame(rows)


def noise_delay_margins(cost: Any) -> dict[str, tuple[float, float]]:
    """Per estimator: (largest total delay with every seed stable below the first failure, first failing one)."""
    out = {}
    for e, g in cost.groupby("estimator", sort=False):
        g = g.sort_values("total_delay_ms")
        fails = g[g.stable_share < 1.0]
        first = float(fails.total_delay_ms.iloc[0]) if len(fails) else math.nan
        ok = g[(g.stable_share >= 1.0) & ((g.total_delay_ms < first) if len(fails) else True)]
        out[str(e)] = (float(ok.total_delay_ms.max()) if len(ok) else math.nan, first)
    return out


def run_delay_aware(out: Path, workers: int | None = None) -> Any:
    """Run (or resume) :data:`DELAY_AWARE_SWEEP` into ``out/runs/<sweep>``; returns its ``summary.csv``."""
    log.info("pendulum: sweep %s ...", DELAY_AWARE_SWEEP)
    return sweep(_SCEN / f"{DELAY_AWARE_SWEEP}.yaml", out / "runs" / DELAY_AWARE_SWEEP, workers=workers,
                 progress=sys.stderr.isatty()).summary


def delay_aware_table(summary: Any, estimators: Mapping[str, dict[str, Any]], unaware: Any) -> Any:
    """One row per estimator, estimation (``unaware``: ``delay_cost.csv``'s rows; ``input_delay``: told the delay)
    and act delay: the runs, how many stayed balanced (``pendulum.stable``), and the mean stationary cost
    (``pendulum.lqg_cost_after_settle``) when every run did."""
    import pandas as pd

    s = _with_values(summary, DELAY_AWARE_SWEEP)
    s["estimator"] = [estimator_name(v["estimator"], estimators) for v in s["values"]]
    s["act_delay_ms"] = [_delay_ms(v["act_delay"]) for v in s["values"]]
    s["input_delay_ms"] = [_delay_ms(v["input_delay"]) for v in s["values"]]
    rows = []
    names = list(dict.fromkeys(s["estimator"]))
    for e in names:
        u = unaware[unaware.estimator == e]
        for _, r in u.iterrows():
            n = int(r.seed_count)
            rows.append({"estimator": e, "estimation": "unaware", "act_delay_ms": float(r.act_delay_ms),
                         "total_delay_ms": float(r.total_delay_ms), "input_delay_ms": math.nan, "seed_count": n,
                         "stable_runs": int(round(float(r.stable_share) * n)), "stable_share": float(r.stable_share),
                         "sim_cost": float(r.sim_cost)})
        for (dl, di), g in s[s.estimator == e].groupby(["act_delay_ms", "input_delay_ms"], sort=True):
            ok = g["status"] == "ok"
            stable = g["pendulum.stable"].where(ok, 0.0).astype(float)
            all_stable = bool(stable.min() > 0.5)
            rows.append({"estimator": e, "estimation": "input_delay", "act_delay_ms": float(dl),
                         "total_delay_ms": float(dl) + NETWORK_BASE_DELAY_MS, "input_delay_ms": float(di),
                         "seed_count": int(len(g)), "stable_runs": int((stable > 0.5).sum()),
                         "stable_share": float(stable.mean()),
                         "sim_cost": float(g["pendulum.lqg_cost_after_settle"].astype(float).mean()) if all_stable
                         else math.nan})
    return pd.DataFrame(rows)


def delay_aware_margins(table: Any) -> Any:
    """Per estimator and estimation: the largest total delay with every run balanced below the first delay with a
    fallen run, that first delay (NaN: none in the sweep) and how many runs stayed balanced there, and the
    largest delay run."""
    import pandas as pd

    rows = []
    for (e, how), g in table.groupby(["estimator", "estimation"], sort=False):
        g = g.sort_values("total_delay_ms")
        fails = g[g.stable_runs < g.seed_count]
        first = float(fails.total_delay_ms.iloc[0]) if len(fails) else math.nan
        ok = g[(g.stable_runs == g.seed_count) & ((g.total_delay_ms < first) if len(fails) else True)]
        rows.append({"estimator": e, "estimation": how,
                     "stable_up_to_ms": float(ok.total_delay_ms.max()) if len(ok) else math.nan,
                     "fails_at_ms": first,
                     "stable_runs_at_fail": int(fails.stable_runs.iloc[0]) if len(fails) else -1,
                     "seed_count": int(g.seed_count.max()), "largest_delay_ms": float(g.total_delay_ms.max())})
    return pd.DataFrame(rows)
