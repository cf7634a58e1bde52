"""The pendulum study's report (registered as kind ``report``, name ``pendulum``): ``netsim report pendulum``.

Runs the shipped scenarios (``scenarios/pendulum_*.yaml``) through :func:`netsim.runner.run`, in parallel
processes, and writes ``reports/pendulum/``:

* ``table.csv`` -- one row per estimator x controller with the stable columns ``estimator, controller,
  seed_count, theta_dot_noise, alpha_dot_noise, u_std, saturated_share, rms_theta, rms_alpha,
  lqg_cost_per_step, stable_share`` (then the spread over the seeds: ``*_min``, ``*_max``);
* ``hold_still.csv`` (simulated and Lyapunov velocity noise), ``forms.csv`` (the Luenberger forms noise-free in
  motion), ``delay.csv`` (delay sweep against the predicted margin), ``loss.csv``, ``mpc_timing.csv``,
  ``quantised.csv``, ``runs.csv`` (every run), ``quoted.csv`` (every number the prose quotes);
* ``README.md`` -- each claim of the slides, what we got and why it differs. Every number in its prose is a
  ``{placeholder}`` of :data:`TEXT` (``models/pendulum/report.md``) filled from ``quoted.csv`` (``tests/models/test_pendulum_report.py``).

Definitions (over the control samples ``t_k = k Ts``; true angles from the plant's record grid):

* ``u_std``: std of the applied voltage for ``t >= 1 s`` (the chatter once balanced);
* ``saturated_share``: share of samples with ``|u| >= 3 V`` (the actuator limit);
* ``rms_theta``, ``rms_alpha``: RMS of the true angles over the run;
* ``lqg_cost_per_step``: mean of ``x' Q x + u' R u`` with the LQR's weights (they weight only the angles, so
  the true angles give the cost exactly);
* ``stable``: the run did not diverge and ``|alpha| < 0.05 rad`` over its last second;
* ``theta_dot_noise``, ``alpha_dot_noise``: std of the velocity estimates in the hold-still run of the
  estimator (the same for both controllers: the estimator alone makes it).

Why this module is long: it runs every case of the study, builds the tables from them and computes every value
a placeholder of the README names (:func:`quote`); the words and layout are data, in ``models/pendulum/report.md``.
"""

from __future__ import annotations

import logging
import math
import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from netsim.casestudy import Quotes, Templates, fmt as _fmt, log_progress, md_table, run_all as _run_pool, splice
from netsim.lazy_import import lazy_module
from netsim.registry import register
from netsim.shipped import folder as shipped_scenarios

if TYPE_CHECKING:
    import pandas as pd
else:
    pd = lazy_module("pandas")  # imported at first use: `netsim list` and `netsim docs` import this module too

__all__ = ["pendulum_report", "render_readme", "run_case", "closed_loop_cases", "TEXT", "render", "LABEL_PATTERNS", "ESTIMATORS"]

log = logging.getLogger("netsim.progress.pendulum")

_ROOT = Path(__file__).resolve().parents[2]
SCEN = shipped_scenarios()
RIP = "nodes.rip.tasks[0].params"
NET = "nodes.controller.tasks[0].params"
SEEDS = (1, 2, 3)
U_LIMIT = 3.0
STABLE_ALPHA = 0.05
CHATTER_FROM_S = 1.0
#: Initial tilt of the closed-loop scenarios (plant.x0[2]; read from the scenario in the tests).
TILT = 0.2
#: Hold-still runs: 20 s (3800 samples after the first second: about 2 % Monte-Carlo error on a std).
HOLD_STILL_DURATION = "20 s"
#: Samples after which the MPC-vs-LQR comparison starts (the transient: 0.2 s).
TRANSIENT_SAMPLES = 40
#: Estimator entries of the state_feedback program, by the study's names.
ESTIMATORS: dict[str, dict[str, Any]] = {
    "fd_raw": {"type": "pendulum_fd"},
    "fd_lowpass": {"type": "pendulum_fd", "cutoff_hz": 20.0},
    "luenberger": {"type": "luenberger", "form": "current", "poles": ["0.55+0.2j", "0.55-0.2j", 0.72, 0.82]},
    "luenberger_printed": {"type": "luenberger_printed", "poles": ["0.55+0.2j", "0.55-0.2j", 0.72, 0.82]},
    "kalman": {"type": "pendulum_kalman"},
}
DELAYS_MS = (0.0, 10.0, 20.0, 25.0, 30.0, 35.0, 40.0, 50.0)
DELAY_ESTIMATORS = ("fd_raw", "fd_lowpass", "luenberger", "kalman")
LOSSES: dict[str, dict[str, Any]] = {
    "bernoulli_0.2": {"model": "bernoulli", "p": 0.2},
    "bernoulli_0.5": {"model": "bernoulli", "p": 0.5},
    "gilbert_elliott": {"model": "gilbert_elliott", "p_good_to_bad": 0.05, "p_bad_to_good": 0.25},
}
LOSS_ESTIMATORS = ("fd_lowpass", "luenberger", "kalman")
MPC_TIMINGS: dict[str, dict[str, Any]] = {
    "h20_0.1ms": {"horizon": 20, "per_iteration": "0.1 ms"},
    "h20_1ms": {"horizon": 20, "per_iteration": "1 ms"},
    "h20_3ms": {"horizon": 20, "per_iteration": "3 ms"},
    "h5_3ms": {"horizon": 5, "per_iteration": "3 ms"},
}
#: Estimators drawn in closed_loop_lqr.png (their LQR runs of seed 1 keep their signals).
FIGURE_ESTIMATORS = ("fd_raw", "luenberger", "kalman")
#: Sample-to-actuation delay of the single-node scenarios (the control task's execution time, ms).
TASK_DELAY_MS = 0.5


# ------------------------------------------------------------------------------------------------ one run
def run_case(case: dict[str, Any]) -> dict[str, Any]:
    """Run one case (``scenario``, ``seed``, ``overrides``) and return ``case`` with its measures."""
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    from netsim.runner import run

    res = run(str(SCEN / case["scenario"]), write=False, seed=case["seed"], overrides=case.get("overrides", {}))
    row = {k: v for k, v in case.items() if k not in ("overrides", "keep_signals")}
    row["status"] = str(res.status).split(" ")[0]
    row.update(_measures(res, case))
    if case.get("keep_signals"):
        row["_signals"] = res.to_pandas().ffill()[["alpha", "u"]]
    return row


def _measures(res: Any, case: dict[str, Any]) -> dict[str, float]:
    from netsim.models.pendulum.metrics import pendulum_measures

    ok = str(res.status).startswith("ok")
    pm = pendulum_measures(res.signals, ok)
    if case["kind"] == "hold_still":
        return {"theta_dot_noise": pm["theta_dot_est_std"], "alpha_dot_noise": pm["alpha_dot_est_std"]}
    out: dict[str, float] = {k: pm[k] for k in ("u_std", "saturated_share", "rms_theta", "rms_alpha",
                                                "lqg_cost_per_step", "max_alpha_last_s", "stable")}
    out["est_converged_s"] = pm.get("est_converged_s", math.nan)
    out["rms_alpha_after_1s"] = pm["rms_alpha_after_settle"]
    out["lqg_cost_after_1s"] = pm["lqg_cost_after_settle"]
    out["alpha_dot_est_std"] = pm.get("alpha_dot_est_std", math.nan)
    m = res.metrics
    for key in ("deadline_misses", "max_response_s"):
        for node in ("rip", "controller"):
            name = f"task.{node}.control.{key}"
            if name in m:
                out[key] = float(m[name])
    for node in ("rip", "controller"):
        for key in ("prediction_only", "mpc_solver_iterations", "mpc_fallbacks"):
            name = f"control.{node}.control.{key}"
            if name in m:
                out[key] = float(m[name])
    if case["kind"] == "mpc_vs_lqr":
        s = res.to_pandas().sort_index().ffill()
        ts = 0.005
        tk = np.arange(0.0, float(s.index.max()) - ts + 1e-9, ts)
        at = s.reindex(s.index.union(tk)).ffill().loc[tk]
        u = s["u"].reindex(s.index.union(tk + ts - 1e-9)).ffill().loc[tk + ts - 1e-9].to_numpy(float)
        out.update(_mpc_vs_lqr(at, np.nan_to_num(u, nan=0.0)))
    return out


def _mpc_vs_lqr(at: pd.DataFrame, u: np.ndarray) -> dict[str, float]:
    """At every sample of an MPC run: the LQR's input for the same estimate, and where the two agree."""
    from netsim.models.pendulum.design import designs

    K = designs().K_lqr
    xh = at[[f"x_hat[{i}]" for i in range(4)]].to_numpy(float)
    u_lqr = -(xh @ K.T)[:, 0]
    inside = np.abs(u_lqr) < U_LIMIT - 1e-6
    diff = np.abs(u - u_lqr)
    active = np.abs(u) >= U_LIMIT - 1e-9
    return {"max_abs_u": float(np.max(np.abs(u))),
            "max_diff_lqr_unsat": float(np.max(diff[inside & ~active & (np.arange(len(u)) > TRANSIENT_SAMPLES)])),
            "active_steps": float(np.sum(active)),
            "lqr_would_exceed": float(np.sum(~inside))}


# ------------------------------------------------------------------------------------------------ the cases
def hold_still_cases() -> list[dict[str, Any]]:
    """One hold-still run per estimator (seed 1), longer than the shipped scenario's 10 s."""
    return [{"kind": "hold_still", "scenario": "pendulum_hold_still.yaml", "estimator": e, "seed": 1,
             "overrides": {f"{RIP}.estimator": ESTIMATORS[e], "duration": HOLD_STILL_DURATION}} for e in ESTIMATORS]


def closed_loop_cases(seeds: tuple[int, ...] = SEEDS) -> list[dict[str, Any]]:
    """Each estimator x {LQR, MPC} from the 0.2 rad tilt, one run per seed."""
    out = []
    for e in ESTIMATORS:
        for ctrl, scen in (("lqr", "pendulum_lqr.yaml"), ("mpc", "pendulum_mpc.yaml")):
            for seed in seeds:
                out.append({"kind": "mpc_vs_lqr" if ctrl == "mpc" else "closed_loop", "scenario": scen,
                            "estimator": e, "controller": ctrl, "seed": seed,
                            "overrides": {f"{RIP}.estimator": ESTIMATORS[e]},
                            "keep_signals": ctrl == "lqr" and seed == 1 and e in FIGURE_ESTIMATORS})
    return out


def timing_cases() -> list[dict[str, Any]]:
    """Delay sweep from the tilt, measurement loss, MPC solve time and quantisation (seed 1)."""
    out = []
    for e in DELAY_ESTIMATORS:
        for dl in DELAYS_MS:
            out.append({"kind": "delay", "scenario": "pendulum_network.yaml", "estimator": e, "seed": 1,
                        "act_delay_ms": dl, "overrides": {f"{NET}.estimator": ESTIMATORS[e],
                                                          "networks.act.delay.value": f"{dl} ms"}})
    for e in LOSS_ESTIMATORS:
        for label, loss in LOSSES.items():
            out.append({"kind": "loss", "scenario": "pendulum_network.yaml", "estimator": e, "seed": 1,
                        "loss": label, "overrides": {f"{NET}.estimator": ESTIMATORS[e], "networks.sense.loss": loss}})
    for label, t in MPC_TIMINGS.items():
        out.append({"kind": "mpc_timing", "scenario": "pendulum_mpc.yaml", "estimator": "luenberger", "seed": 1,
                    "timing": label, "overrides": {f"{RIP}.estimator": ESTIMATORS["luenberger"],
                                                   f"{RIP}.law.horizon": t["horizon"],
                                                   f"{RIP}.solve_time.per_iteration": t["per_iteration"]}})
    for e in ("fd_lowpass", "luenberger", "kalman"):
        # its reference (Gaussian noise, same seed) is the closed-loop LQR run of seed 1
        out.append({"kind": "quantised", "scenario": "pendulum_quantised.yaml", "estimator": e, "seed": 1,
                    "overrides": {f"{RIP}.estimator": ESTIMATORS[e]}})
    return out


def run_all(cases: list[dict[str, Any]], workers: int | None = None) -> pd.DataFrame:
    """Run the cases on one process pool (``workers``: default one per CPU) and return one row per run."""
    rows = _run_pool(run_case, cases, workers=workers or os.cpu_count() or 1,
                     progress=log_progress(log, "pendulum"), what="single runs")
    return pd.DataFrame(rows)


# ------------------------------------------------------------------------------------------------ tables
#: The columns of tuning.csv and delay_cost.csv shown in the README.
TUNING_COLUMNS = ["setting", "error_radius", "error_tau_ms", "alpha_dot_noise_lyap", "est_converged_s", "u_std",
                  "lqg_cost_per_step", "lqg_cost_after_1s", "stable_share"]
DELAY_COST_COLUMNS = ["estimator", "total_delay_ms", "stable_share", "sim_cost", "sim_ci_low", "sim_ci_high",
                      "analytic_cost", "rel_diff"]
TABLE_COLUMNS = ["estimator", "controller", "seed_count", "theta_dot_noise", "alpha_dot_noise", "u_std",
                 "saturated_share", "rms_theta", "rms_alpha", "lqg_cost_per_step", "stable_share"]


def make_table(runs: pd.DataFrame) -> pd.DataFrame:
    """The stable table: mean over the seeds (``*_min``, ``*_max``: the spread) per estimator x controller, and
    ``lqg_cost_analytic``: the stationary expected cost of the linear LQR loop with this estimator and the
    task's 0.5 ms delay (:func:`netsim.models.pendulum.analysis.analytic_cost`; LQR rows only)."""
    from netsim.models.pendulum.analysis import analytic_cost
    from netsim.models.pendulum.design import designs

    d = designs()
    hs = runs[runs.kind == "hold_still"].set_index("estimator")
    cl = runs[runs.kind.isin(["closed_loop", "mpc_vs_lqr"])]
    rows = []
    for (e, c), g in cl.groupby(["estimator", "controller"], sort=False):
        e = str(e)  # an estimator name
        r: dict[str, Any] = {"estimator": e, "controller": c, "seed_count": len(g),
                             "theta_dot_noise": float(hs.theta_dot_noise[e]),
                             "alpha_dot_noise": float(hs.alpha_dot_noise[e])}
        for col in ("u_std", "saturated_share", "rms_theta", "rms_alpha", "lqg_cost_per_step", "lqg_cost_after_1s"):
            r[col] = float(g[col].mean())
        r["stable_share"] = float(g["stable"].mean())
        for col in ("u_std", "rms_alpha", "lqg_cost_per_step", "lqg_cost_after_1s"):
            r[f"{col}_min"], r[f"{col}_max"] = float(g[col].min()), float(g[col].max())
        r["lqg_cost_analytic"] = (analytic_cost(e, d, TASK_DELAY_MS * 1e-3)["per_sample"] if c == "lqr"
                                  else math.nan)
        rows.append(r)
    df = pd.DataFrame(rows)
    return df[TABLE_COLUMNS + [c for c in df.columns if c not in TABLE_COLUMNS]]


def hold_still_table(runs: pd.DataFrame) -> pd.DataFrame:
    """Simulated hold-still noise beside the Lyapunov value."""
    from netsim.models.pendulum.design import designs, hold_still_std

    d = designs()
    hs = runs[runs.kind == "hold_still"]
    rows = []
    for _, r in hs.iterrows():
        ana = hold_still_std(r["estimator"], d)
        rows.append({"estimator": r["estimator"], "theta_dot_sim": r["theta_dot_noise"], "theta_dot_lyap": ana[0],
                     "alpha_dot_sim": r["alpha_dot_noise"], "alpha_dot_lyap": ana[1]})
    return pd.DataFrame(rows)


def delay_table(runs: pd.DataFrame, noise_margins: dict[str, tuple[float, float]]) -> pd.DataFrame:
    """Per estimator: the predicted delay margins (phase margin over crossover; the delay at which the expected
    cost of :mod:`netsim.models.pendulum.analysis` becomes infinite; the exact discrete loop at whole samples) beside
    the simulated ones (from upright over the seeds of ``pendulum_delay_sweep``: ``noise_*``; from the tilt,
    seed 1: ``stable_up_to_ms``, ``fails_at_ms``). Delays are total sample-to-actuation delays."""
    from netsim.models.pendulum.analysis import lqg_delay_margin
    from netsim.models.pendulum.design import delay_margin, delay_spectral_radius, designs
    from netsim.models.pendulum.report_sweeps import NETWORK_BASE_DELAY_MS

    d = designs()

    def bracket(g: pd.DataFrame) -> tuple[float, float]:
        g = g.sort_values("act_delay_ms")
        fails = g[g.stable < 0.5]
        first_fail = float(fails.act_delay_ms.iloc[0]) if len(fails) else math.nan
        ok = g[(g.stable > 0.5) & ((g.act_delay_ms < first_fail) if len(fails) else True)]
        last_ok = float(ok.act_delay_ms.max()) if len(ok) else math.nan
        return last_ok + NETWORK_BASE_DELAY_MS, first_fail + NETWORK_BASE_DELAY_MS

    rows = []
    for e, g in runs[runs.kind == "delay"].groupby("estimator", sort=False):
        e = str(e)  # an estimator name
        ok, fail = bracket(g)
        pred = delay_margin(e, d)
        steps = 0
        while steps < 40 and delay_spectral_radius(e, d, steps + 1) < 1.0:
            steps += 1
        n_ok, n_fail = noise_margins.get(str(e), (math.nan, math.nan))
        rows.append({"estimator": e, "predicted_margin_ms": 1e3 * pred["margin_s"], "crossover_rad_s": pred["wc"],
                     "phase_margin_deg": pred["pm_deg"], "lqg_margin_ms": 1e3 * lqg_delay_margin(e, d),
                     "linear_stable_up_to_ms": 1e3 * steps * d.lin.h, "noise_stable_up_to_ms": n_ok,
                     "noise_fails_at_ms": n_fail, "stable_up_to_ms": ok, "fails_at_ms": fail})
    return pd.DataFrame(rows)


# ------------------------------------------------------------------------------------------------ prose
#: The report's templates (``models/pendulum/report.md``): the README's layout (``readme*``, ``delay_cost_figure``)
#: and the prose (:data:`TEXT`), whose numbers are all ``{placeholder}``s filled from the quoted values; the only
#: digits allowed in the prose are labels matching :data:`LABEL_PATTERNS`.
TEMPLATES = Templates(Path(__file__).with_suffix(".md"))
TEXT: dict[str, str] = {k: v for k, v in TEMPLATES.items()
                        if not k.startswith(("readme", "delay_cost_figure", "da_fails", "da_holds", "dn_"))}
#: The delay-aware section's first and last lines (``netsim report pendulum_delay_aware`` splices between them).
DELAY_AWARE_MARK = (TEMPLATES["readme_delay_aware"].split("\n")[0], TEMPLATES["readme_delay_aware"].split("\n")[-1])
LABEL_PATTERNS = (r"QUBE-Servo \d", r"qube2_rotpen_param", r"y\[k\]", r"x\[k-1\]", r"x\[k\]", r"u\[k-1\]",
                  r"e\[k-1\]", r"e\[k\]", r"\^-1", r"x\[k\|k-1\]")


def render(key: str, values: dict[str, str]) -> str:
    """The template ``key`` filled with the quoted texts (a missing one is an error naming it)."""
    return TEMPLATES.fill(key, values)


def fmt(x: float, digits: int = 3) -> str:
    """A number with ``digits`` significant digits (exponent notation outside 1e-3 to 1e5)."""
    return _fmt(x, digits, sci=True)


def _quoter() -> tuple[Quotes, Callable[..., None]]:
    """A :class:`~netsim.casestudy.Quotes` and its ``add(key, value, source, text=None)`` (values as floats)."""
    q = Quotes(sci=True)

    def add(key: str, value: float, source: str, text: str | None = None) -> None:
        q.add(key, float(value), source=source, text=text)

    return q, add


def quote(runs: pd.DataFrame, table: pd.DataFrame, hs: pd.DataFrame, dl: pd.DataFrame,
          sw: pd.DataFrame, dc: pd.DataFrame) -> pd.DataFrame:
    """Every number the prose quotes: ``key, value, text, source``."""
    from netsim.models.pendulum.design import POLES, designs, motion_errors
    from netsim.models.pendulum.model import TS
    from netsim.control import KalmanFilter, LuenbergerObserver

    d = designs()
    q, add = _quoter()

    ev = np.linalg.eigvals(d.lin.A)
    add("unstable_pole", float(np.max(ev.real)), "model: eig(A)")
    add("ts_ms", TS * 1e3, "model: TS")
    add("rank", d.rank, "design: observability matrix")
    add("n_states", 4, "model: state dimension")
    add("poles", 0, "design: POLES", ", ".join(f"{p.real:g}{p.imag:+g}j" if p.imag else f"{p.real:g}" for p in POLES))
    errs = []
    for form in ("predictor", "current"):
        obs = LuenbergerObserver(d.lin.Ad, d.lin.Bd, d.lin.C, POLES, form=form)
        got = np.linalg.eigvals(obs.error_matrix)
        errs.append(max(min(abs(g - p) for g in got) for p in POLES))
    add("pole_err", max(errs), "design: eig of the error matrices", f"{max(errs):.1e}")
    me = motion_errors(d)
    add("motion_rms_ad", me["motion_rms"][3], "design.motion_errors")
    add("cur_err_ad", me["current"][3], "design.motion_errors", f"{me['current'][3]:.1e}")
    add("pred_err_ad", me["predictor"][3], "design.motion_errors", f"{me['predictor'][3]:.1e}")
    add("printed_err_ad", me["printed"][3], "design.motion_errors")
    add("printed_err_td", me["printed"][1], "design.motion_errors")
    kf = KalmanFilter(d.lin.Ad, d.lin.Bd, d.lin.C, d.Qn, d.Rn, steady_state=True)
    kd = float(np.max(np.abs(kf.K_ss - d.K_kal)))
    add("kal_diff", kd, "design vs KalmanFilter", f"{kd:.1e}")
    add("kal_rho", float(np.max(np.abs(np.linalg.eigvals((np.eye(4) - d.K_kal @ d.lin.C) @ d.lin.Ad)))),
        "design: eig((I - K C) A)")
    dev = np.max(np.abs(np.concatenate([hs.theta_dot_sim / hs.theta_dot_lyap - 1, hs.alpha_dot_sim / hs.alpha_dot_lyap - 1])))
    add("hs_max_dev", 100 * dev, "hold_still.csv", f"{100 * dev:.2g}")
    h = hs.set_index("estimator")
    for key, e in (("hs_fd_raw", "fd_raw"), ("hs_fd_lp", "fd_lowpass"), ("hs_lu", "luenberger"), ("hs_kal", "kalman")):
        add(key, h.loc[e, "alpha_dot_sim"], f"hold_still:{e}")
    cl = runs[runs.kind.isin(["closed_loop", "mpc_vs_lqr"])]
    add("tilt", TILT, "scenario: plant.x0")
    add("stable_runs", cl.stable.sum(), "runs.csv", str(int(cl.stable.sum())))
    add("all_runs", len(cl), "runs.csv", str(len(cl)))
    t = table.set_index(["estimator", "controller"])
    for key, e in (("chat_fd_raw", "fd_raw"), ("chat_fd_lp", "fd_lowpass"), ("chat_lu", "luenberger"),
                   ("chat_kal", "kalman")):
        add(key, t.loc[(e, "lqr"), "u_std"], f"table:{e}/lqr")
    add("n_seeds", len(SEEDS), "report: SEEDS", str(len(SEEDS)))
    lqr_t = table[table.controller == "lqr"].set_index("estimator")
    for tail, col in (("", "lqg_cost_per_step"), ("1", "lqg_cost_after_1s")):  # whole run; after the first second
        add(f"best_lqg{tail}", 0.0, f"table: argmin {col} (lqr)", str(lqr_t[col].idxmin()))
        add(f"best_lqg{tail}_val", lqr_t[col].min(), "table")
        for tag, e in (("kal", "kalman"), ("lu", "luenberger"), ("fd", "fd_raw")):
            add(f"{tag}_lqg{tail}", lqr_t.loc[e, col], f"table:{e}/lqr")
    lq, best1 = lqr_t["lqg_cost_per_step"], str(lqr_t["lqg_cost_after_1s"].idxmin())
    mv = runs[runs.kind == "mpc_vs_lqr"]
    add("mpc_max_u", mv.max_abs_u.max(), "runs: mpc")
    k1 = mv[(mv.estimator == "kalman") & (mv.seed == 1)].iloc[0]
    add("mpc_active", k1.active_steps, "runs: mpc kalman seed 1", str(int(k1.active_steps)))
    add("lqr_exceed", k1.lqr_would_exceed, "runs: mpc kalman seed 1", str(int(k1.lqr_would_exceed)))
    add("mpc_lqr_diff", k1.max_diff_lqr_unsat, "runs: mpc kalman seed 1", f"{k1.max_diff_lqr_unsat:.1e}")
    dt = dl.set_index("estimator")
    for tag, e in (("lu", "luenberger"), ("kal", "kalman"), ("fd", "fd_raw"), ("lp", "fd_lowpass")):
        add(f"dl_{tag}_ok", dt.loc[e, "stable_up_to_ms"], f"delay:{e}")
        add(f"dl_{tag}_fail", dt.loc[e, "fails_at_ms"], f"delay:{e}")
        add(f"dl_{tag}_pred", dt.loc[e, "predicted_margin_ms"], f"delay:{e}")
        add(f"dq_{tag}", dt.loc[e, "lqg_margin_ms"], f"delay:{e} (analysis.lqg_delay_margin)")
        add(f"dlx_{tag}", dt.loc[e, "linear_stable_up_to_ms"], f"delay:{e} (design.delay_spectral_radius)")
        add(f"dn_{tag}_ok", dt.loc[e, "noise_stable_up_to_ms"], f"delay:{e} (pendulum_delay_sweep)")
        add(f"dn_{tag}_fail", dt.loc[e, "noise_fails_at_ms"], f"delay:{e} (pendulum_delay_sweep)")
    inside = (dl.noise_stable_up_to_ms <= dl.lqg_margin_ms) & (dl.lqg_margin_ms < dl.noise_fails_at_ms)
    add("dn_bracket", float(inside.sum()), "delay: noise_stable_up_to_ms <= lqg_margin_ms < noise_fails_at_ms",
        render("dn_all_in_bracket" if inside.all() else "dn_some_in_bracket",
               {"inside": str(int(inside.sum())), "estimators": str(len(dl))}))
    from netsim.models.pendulum.report_sweeps import CI_LEVEL

    add("ci_pct", 100 * CI_LEVEL, "report_sweeps: CI_LEVEL", f"{100 * CI_LEVEL:g}")
    pm_diff = float(np.max(np.abs(dl.lqg_margin_ms - dl.predicted_margin_ms)))
    add("dq_pm_diff", pm_diff, "delay: max |lqg_margin_ms - predicted_margin_ms|", f"{pm_diff:.1g}")
    add("dsw_seeds", dc.seed_count.max(), "delay_cost: seed_count", str(int(dc.seed_count.max())))
    dmin = dc.total_delay_ms.min()
    add("dc_min_delay", dmin, "delay_cost: smallest total delay")
    d0c = dc[dc.total_delay_ms == dmin].set_index("estimator")
    for tag, e in (("lu", "luenberger"), ("kal", "kalman"), ("fd", "fd_raw"), ("lp", "fd_lowpass")):
        for key, col in (("sim", "sim_cost"), ("lo", "sim_ci_low"), ("hi", "sim_ci_high"), ("ana", "analytic_cost")):
            add(f"dc_{tag}_{key}", d0c.loc[e, col], f"delay_cost:{e} {dmin} ms")
        last = dc[(dc.estimator == e) & (dc.stable_share >= 1.0)].sort_values("total_delay_ms").iloc[-1]
        add(f"dc_{tag}_last", last.total_delay_ms, f"delay_cost:{e} largest delay with every seed stable")
        add(f"dc_{tag}_last_sim", last.sim_cost, f"delay_cost:{e} {last.total_delay_ms} ms")
        add(f"dc_{tag}_last_ana", last.analytic_cost, f"delay_cost:{e} {last.total_delay_ms} ms")
    pts = dc[dc.stable_share >= 1.0]
    add("dc_points", len(pts), "delay_cost: points with every seed stable", str(len(pts)))
    add("dc_inside", pts.analytic_inside_ci.sum(), "delay_cost: analytic_inside_ci", str(int(pts.analytic_inside_ci.sum())))
    worst = pts.iloc[pts.rel_diff.abs().argmax()]  # by position: pandas-stubs type idxmax() as Hashable
    add("dc_max_rel", 100 * abs(worst.rel_diff), "delay_cost: max |rel_diff|", f"{100 * abs(worst.rel_diff):.2g}")
    add("dc_max_rel_where", 0.0, "delay_cost: argmax |rel_diff|", f"{worst.estimator} at {fmt(worst.total_delay_ms)} ms")
    # the orderings the study rests on, with their measured margins
    hsi = hs.set_index("estimator")
    add("ord_noise_lp_lu", hsi.alpha_dot_sim["fd_lowpass"] / hsi.alpha_dot_sim["luenberger"], "hold_still")
    add("ord_noise_lu_kal", hsi.alpha_dot_sim["luenberger"] / hsi.alpha_dot_sim["kalman"], "hold_still")
    add("ord_chat_lp_lu", t.u_std_min[("fd_lowpass", "lqr")] / t.u_std_max[("luenberger", "lqr")],
        "table: u_std_min / u_std_max")
    add("ord_chat_lu_kal", t.u_std_min[("luenberger", "lqr")] / t.u_std_max[("kalman", "lqr")],
        "table: u_std_min / u_std_max")
    add("ord_kal_whole", lq["kalman"] / lq.min(), "table: lqg_cost_per_step kalman / lowest")
    others = lqr_t.drop(index=best1)
    add("ord_lqg1_margin", others.lqg_cost_after_1s_min.min() / lqr_t.loc[best1, "lqg_cost_after_1s_max"],
        "table: lqg_cost_after_1s_min (next) / lqg_cost_after_1s_max (lowest)")
    ana = lqr_t["lqg_cost_analytic"].sort_values()
    add("best_ana", 0.0, "table: argmin lqg_cost_analytic (lqr)", str(ana.index[0]))
    add("best_ana_val", ana.iloc[0], "table")
    add("ord_ana_margin", ana.iloc[1] / ana.iloc[0], "table: second lowest / lowest lqg_cost_analytic")
    for tag, e in (("kal", "kalman"), ("lu", "luenberger"), ("fd", "fd_raw")):
        add(f"{tag}_ana", lqr_t.loc[e, "lqg_cost_analytic"], f"table:{e}/lqr lqg_cost_analytic")
    st0 = d0c.sort_values("sim_cost")
    add("best_stat", 0.0, f"delay_cost: argmin sim_cost at {dmin} ms", str(st0.index[0]))
    add("ord_stat_margin", st0.sim_ci_low.iloc[1] / st0.sim_ci_high.iloc[0], "delay_cost: next ci_low / lowest ci_high")
    cl_lqr1 = runs[(runs.kind == "closed_loop") & (runs.seed == 1)].set_index("estimator")
    for tag, e in (("kal", "kalman"), ("lu", "luenberger")):
        add(f"{tag}_conv", cl_lqr1.loc[e, "est_converged_s"], f"runs: closed_loop {e} lqr seed 1")
    from netsim.models.pendulum.metrics import PendulumMetricParams

    add("est_tol", PendulumMetricParams().est_tol, "metrics: PendulumMetricParams.est_tol")
    ls = runs[runs.kind == "loss"].set_index(["estimator", "loss"])
    d0 = runs[(runs.kind == "delay") & (runs.act_delay_ms == 0)].set_index("estimator")
    for tag, e in (("kal", "kalman"), ("lu", "luenberger"), ("fd", "fd_lowpass")):
        add(f"loss_{tag}_b5", ls.loc[(e, "bernoulli_0.5"), "rms_alpha_after_1s"], f"loss:{e}")
        add(f"loss_{tag}_0", d0.loc[e, "rms_alpha_after_1s"], f"delay:{e} 0 ms")
        add(f"loss_{tag}_ge", ls.loc[(e, "gilbert_elliott"), "rms_alpha_after_1s"], f"loss:{e}")
    ge = LOSSES["gilbert_elliott"]
    add("ge_burst", 1.0 / ge["p_bad_to_good"], "report: LOSSES (1 / p_bad_to_good)")
    add("ge_loss", 100 * ge["p_good_to_bad"] / (ge["p_good_to_bad"] + ge["p_bad_to_good"]),
        "report: LOSSES (stationary share of the bad state)")
    mt = runs[runs.kind == "mpc_timing"].set_index("timing")
    add("mpt_fast", _ms(MPC_TIMINGS["h20_0.1ms"]["per_iteration"]), "report: MPC_TIMINGS")
    add("mpt_fast_resp", 1e3 * mt.max_response_s["h20_0.1ms"], "mpc_timing")
    add("mpt_slow", _ms(MPC_TIMINGS["h20_3ms"]["per_iteration"]), "report: MPC_TIMINGS")
    add("mpt_slow_resp", 1e3 * mt.max_response_s["h20_3ms"], "mpc_timing")
    add("mpt_slow_miss", mt.loc["h20_3ms", "deadline_misses"], "mpc_timing", str(int(mt.deadline_misses["h20_3ms"])))
    add("mpt_short_h", MPC_TIMINGS["h5_3ms"]["horizon"], "report: MPC_TIMINGS", str(MPC_TIMINGS["h5_3ms"]["horizon"]))
    add("mpt_short_resp", 1e3 * mt.max_response_s["h5_3ms"], "mpc_timing")
    add("mpt_short_miss", mt.loc["h5_3ms", "deadline_misses"], "mpc_timing", str(int(mt.deadline_misses["h5_3ms"])))
    for key, lab in (("mpt_fast_rms", "h20_0.1ms"), ("mpt_slow_rms", "h20_3ms"), ("mpt_short_rms", "h5_3ms")):
        add(key, mt.loc[lab, "rms_alpha_after_1s"], f"mpc_timing:{lab}")
    from netsim.models.pendulum.report_sweeps import equal_ratio_gain_difference

    k = sw[sw.sweep == "kalman"]
    add("sw_seeds", sw.seed_count.max(), "tuning: seed_count", str(int(sw.seed_count.max())))
    for key, val, src in (("sw_q_lo", k.scale_Q.min(), "scale_Q"), ("sw_q_hi", k.scale_Q.max(), "scale_Q"),
                          ("sw_r_lo", k.scale_R.min(), "scale_R"), ("sw_r_hi", k.scale_R.max(), "scale_R"),
                          ("sw_ratio_lo", k.qr_ratio.min(), "qr_ratio"), ("sw_ratio_hi", k.qr_ratio.max(), "qr_ratio")):
        add(key, val, f"tuning: {src} (pendulum_kalman_sweep.yaml)", f"{val:g}")
    gd = equal_ratio_gain_difference(sw)
    add("sw_gain_diff", gd, "tuning: largest gain difference at equal Qn/Rn", f"{gd:.1e}")
    mid = float(k.qr_ratio.iloc[int(np.argmin(np.abs(np.log(k.qr_ratio.to_numpy(float)))))])  # the study's: 1
    for tag, ratio in (("rlo", k.qr_ratio.min()), ("rmid", mid), ("rhi", k.qr_ratio.max())):
        g = k[k.qr_ratio == ratio]
        for key, col in (("noise", "alpha_dot_noise_lyap"), ("u", "u_std"), ("conv", "est_converged_s"),
                         ("rho", "error_radius"), ("tau", "error_tau_ms"), ("cost", "lqg_cost_per_step"),
                         ("cost1", "lqg_cost_after_1s")):
            add(f"sw_{tag}_{key}", g[col].mean(), f"tuning: Qn/Rn = {ratio:g}, mean over its grid points")
    add("sw_best_cost", 0.0, "tuning: argmin lqg_cost_per_step", str(k.setting.iloc[k.lqg_cost_per_step.argmin()]))
    add("sw_best_cost1", 0.0, "tuning: argmin lqg_cost_after_1s", str(k.setting.iloc[k.lqg_cost_after_1s.argmin()]))
    ps = sw[sw.sweep == "poles"]
    for tag, row in (("pf", ps.iloc[ps.error_radius.argmin()]), ("ps", ps.iloc[ps.error_radius.argmax()])):
        for key, col in (("noise", "alpha_dot_noise_lyap"), ("u", "u_std"), ("conv", "est_converged_s"),
                         ("rho", "error_radius"), ("cost", "lqg_cost_per_step"), ("cost1", "lqg_cost_after_1s")):
            add(f"sw_{tag}_{key}", row[col], f"tuning: {row.setting}")
    qz = runs[runs.kind == "quantised"].set_index("estimator")
    qr = runs[(runs.kind == "closed_loop") & (runs.seed == 1)].set_index("estimator")  # same seed, Gaussian noise
    for tag, e in (("kal", "kalman"), ("lu", "luenberger"), ("fd", "fd_lowpass")):
        add(f"q_{tag}", qz.loc[e, "u_std"], f"quantised:{e}")
        add(f"q_{tag}_ref", qr.loc[e, "u_std"], f"closed_loop:{e} lqr seed 1")
    return q.frame()


def _ms(text: str) -> float:
    """``"3 ms"`` -> 3.0."""
    value, unit = text.split()
    if unit != "ms":
        raise ValueError(f"expected a time in ms, got {text!r}")
    return float(value)


def _md_table(df: pd.DataFrame) -> list[str]:
    return md_table(df, cell=lambda v: fmt(v) if isinstance(v, float) else str(v))


def write_readme(out: Path, quoted: pd.DataFrame, tables: dict[str, pd.DataFrame]) -> None:
    """``README.md`` from the templates and the tables."""
    texts = dict(zip(quoted["key"], quoted["text"].astype(str)))
    blocks = {"hold_still_table": tables["hold_still"], "closed_loop_table": tables["table"][TABLE_COLUMNS],
              "tuning_table": tables["tuning"][TUNING_COLUMNS], "delay_table": tables["delay"],
              "delay_cost_table": tables["delay_cost"][DELAY_COST_COLUMNS]}
    texts.update({k: "\n".join(_md_table(v)) for k, v in blocks.items()})
    texts.update({k: render(k, texts) for k in TEXT if k != "delay_aware"})
    texts["closed_loop_figure"] = ("![alpha and u under LQR, seed 1](closed_loop_lqr.png)\n\n"
                                   if (out / "closed_loop_lqr.png").exists() else "")
    texts["delay_cost_figure"] = render("delay_cost_figure", texts) + "\n\n" if (out / "delay_cost.png").exists() else ""
    texts["delay_aware_section"] = ("\n".join(delay_aware_lines(texts, tables["delay_aware"],
                                                               tables["delay_aware_margins"])) + "\n"
                                    if "delay_aware" in tables else "")
    (out / "README.md").write_text(render("readme", texts) + "\n")


def quote_delay_aware(da: pd.DataFrame, margins: pd.DataFrame, dc: pd.DataFrame) -> pd.DataFrame:
    """The numbers of the delay-aware paragraph (keys ``da_*``), from ``delay_aware.csv``, its margins and
    ``delay_cost.csv`` (the raw FD row)."""
    from netsim.models.pendulum.report_sweeps import noise_delay_margins

    q, add = _quoter()

    m = margins.set_index(["estimator", "estimation"])
    for tag, e in (("kal", "kalman"), ("lu", "luenberger")):
        for how, name in (("unaware", "unaware"), ("input_delay", "aware")):
            r = cast("pd.Series", m.loc[(e, how)])  # one row: (estimator, estimation) is unique
            src = f"delay_aware_margins:{e} {how}"
            add(f"da_{tag}_{name}_ok", r.stable_up_to_ms, src)
            if math.isfinite(r.fails_at_ms):
                phrase = render("da_fails", {"ok": fmt(r.stable_up_to_ms), "fail": fmt(r.fails_at_ms),
                                             "balanced": str(int(r.stable_runs_at_fail)), "runs": str(int(r.seed_count))})
                add(f"da_{tag}_{name}_fail", r.fails_at_ms, src)
            else:
                phrase = render("da_holds", {"largest": fmt(r.largest_delay_ms)})
            add(f"da_{tag}_{name}", 0.0, src, phrase)
    add("da_seeds", da[da.estimation == "input_delay"].seed_count.max(), "delay_aware: seed_count")
    add("da_fd_ok", noise_delay_margins(dc)["fd_raw"][0], "delay_cost: fd_raw (noise_delay_margins)")
    from netsim.models.pendulum.analysis import law_delay_margin
    from netsim.models.pendulum.design import designs

    add("da_law", 1e3 * law_delay_margin(designs()), "analysis.law_delay_margin (LQR fed the true state)")
    k = da[(da.estimator == "kalman")]
    both = sorted(set(k[(k.estimation == "unaware") & k.sim_cost.notna()].total_delay_ms)
                  & set(k[(k.estimation == "input_delay") & k.sim_cost.notna()].total_delay_ms))
    at = both[-1]
    add("da_cost_delay", at, "delay_aware: largest delay with every Kalman run balanced in both rows")
    for how, name in (("unaware", "unaware"), ("input_delay", "aware")):
        add(f"da_kal_cost_{name}", float(k[(k.estimation == how) & (k.total_delay_ms == at)].sim_cost.iloc[0]),
            f"delay_aware:kalman {how} {at} ms")
    return q.frame()


DELAY_AWARE_COLUMNS = ["estimator", "estimation", "total_delay_ms", "seed_count", "stable_runs", "sim_cost"]


def delay_aware_lines(texts: dict[str, str], da: pd.DataFrame, margins: pd.DataFrame) -> list[str]:
    """The README section of the delay-aware estimators, between :data:`DELAY_AWARE_MARK`."""
    blocks = {"delay_aware": render("delay_aware", texts), "delay_aware_margins_table": "\n".join(_md_table(margins)),
              "delay_aware_table": "\n".join(_md_table(da[DELAY_AWARE_COLUMNS]))}
    return render("readme_delay_aware", {**texts, **blocks}).split("\n") + [""]


@register("report", "pendulum_delay_aware",
          "pendulum: only the delay-aware estimators (input_delay) beside delay_cost.csv; splices its README section")
def pendulum_delay_aware_report(out_dir: Path | None = None, plots: bool = True, *,
                                workers: int | None = None) -> dict[str, pd.DataFrame]:
    """Run (or resume) ``pendulum_delay_aware_sweep`` and write ``delay_aware.csv``, ``delay_aware_margins.csv``,
    the ``da_*`` rows of ``quoted.csv`` and the README's delay-aware section, next to the full report's
    ``delay_cost.csv`` (which gives the unaware rows). The rest of the report is left as it is."""
    from netsim.models.pendulum.report_sweeps import delay_aware_margins, delay_aware_table, run_delay_aware

    out = Path(out_dir) if out_dir is not None else Path("reports") / "pendulum"
    dc = pd.read_csv(out / "delay_cost.csv")
    da = delay_aware_table(run_delay_aware(out, workers), ESTIMATORS, dc)
    margins = delay_aware_margins(da)
    da.to_csv(out / "delay_aware.csv", index=False)
    margins.to_csv(out / "delay_aware_margins.csv", index=False)
    qd = quote_delay_aware(da, margins, dc)
    quoted = pd.read_csv(out / "quoted.csv", keep_default_na=False)
    quoted = pd.concat([quoted[~quoted.key.astype(str).str.startswith("da_")], qd], ignore_index=True)
    quoted.to_csv(out / "quoted.csv", index=False)
    texts = dict(zip(qd["key"], qd["text"].astype(str)))
    section = delay_aware_lines(texts, da, margins)
    readme = (out / "README.md").read_text().split("\n")
    readme = splice(readme, DELAY_AWARE_MARK, section, "### Loss, solve time, quantisation")
    (out / "README.md").write_text("\n".join(readme))
    return {"delay_aware": da, "delay_aware_margins": margins, "quoted": qd}


def render_readme(out: Path) -> pd.DataFrame:
    """Quote the numbers again from the CSV tables of ``out`` and rewrite ``quoted.csv`` and ``README.md``
    (no run: for a change of the prose). Returns the quoted values."""
    names = ("table", "hold_still", "delay", "delay_cost", "runs", "tuning")
    tables = {n: pd.read_csv(out / f"{n}.csv") for n in names}
    quoted = quote(tables["runs"], tables["table"], tables["hold_still"], tables["delay"], tables["tuning"],
                   tables["delay_cost"])
    if (out / "delay_aware.csv").exists():
        tables["delay_aware"] = pd.read_csv(out / "delay_aware.csv")
        tables["delay_aware_margins"] = pd.read_csv(out / "delay_aware_margins.csv")
        quoted = pd.concat([quoted, quote_delay_aware(tables["delay_aware"], tables["delay_aware_margins"],
                                                      tables["delay_cost"])], ignore_index=True)
    quoted.to_csv(out / "quoted.csv", index=False)
    write_readme(out, quoted, tables)
    return quoted


@register("report", "pendulum", "rotary inverted pendulum (seed 002): FD vs Luenberger vs Kalman under LQR and MPC")
def pendulum_report(out_dir: Path | None = None, plots: bool = True, *, workers: int | None = None,
                    seeds: tuple[int, ...] = SEEDS) -> dict[str, pd.DataFrame]:
    """Run the study and write ``reports/pendulum`` (or ``out_dir``); returns the tables by name."""
    from netsim.models.pendulum.figures import closed_loop_figure, delay_figure

    out = Path(out_dir) if out_dir is not None else Path("reports") / "pendulum"
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    from netsim.models.pendulum.report_sweeps import delay_cost_table, noise_delay_margins, run_sweeps, tuning_table

    summaries = run_sweeps(out, workers)
    cases = hold_still_cases() + closed_loop_cases(seeds) + timing_cases()
    log.info("pendulum: %d single runs (hold still, closed loop, delay from the tilt, loss, MPC timing, "
             "quantisation) ...", len(cases))
    runs = run_all(cases, workers)
    signals = {}
    if "_signals" in runs.columns:
        for _, r in runs[runs["_signals"].notna()].iterrows():
            signals[r["estimator"]] = r["_signals"]
        runs = runs.drop(columns="_signals")
    runs.to_csv(out / "runs.csv", index=False)  # kept even if a later step fails: render_readme redoes the rest
    if plots:
        closed_loop_figure(out, {e: signals[e] for e in FIGURE_ESTIMATORS if e in signals})
    log.info("pendulum: analysis (designs, delay margins, expected costs) ...")
    table = make_table(runs)
    hs = hold_still_table(runs)
    dc = delay_cost_table(summaries, ESTIMATORS)
    dl = delay_table(runs, noise_delay_margins(dc))
    from netsim.models.pendulum.report_sweeps import delay_aware_margins, delay_aware_table, run_delay_aware

    da = delay_aware_table(run_delay_aware(out, workers), ESTIMATORS, dc)
    da_margins = delay_aware_margins(da)
    from netsim.models.pendulum.design import designs, motion_errors

    me = motion_errors(designs())
    forms = pd.DataFrame([{"form": k, "theta_err": v[0], "theta_dot_err": v[1], "alpha_err": v[2],
                           "alpha_dot_err": v[3]} for k, v in me.items()])
    sw = tuning_table(summaries)
    quoted = quote(runs, table, hs, dl, sw, dc)
    quoted = pd.concat([quoted, quote_delay_aware(da, da_margins, dc)], ignore_index=True)
    tables = {"table": table, "hold_still": hs, "delay": dl, "delay_cost": dc, "forms": forms, "runs": runs,
              "delay_aware": da, "delay_aware_margins": da_margins,
              "quoted": quoted, "tuning": sw, "loss": runs[runs.kind == "loss"],
              "mpc_timing": runs[runs.kind == "mpc_timing"], "quantised": runs[runs.kind == "quantised"]}
    table.to_csv(out / "table.csv", index=False)
    for name in ("hold_still", "delay", "delay_cost", "forms", "runs", "quoted", "loss", "mpc_timing", "quantised",
                 "tuning", "delay_aware", "delay_aware_margins"):
        tables[name].to_csv(out / f"{name}.csv", index=False)
    stale = out / "sweeps.csv"  # before the sweeps ran through netsim sweep: tuning.csv
    if stale.exists():
        stale.unlink()
    if plots:
        delay_figure(out, dc)
    write_readme(out, quoted, tables)
    log.info("pendulum: report written to %s (%.0f s)", out, time.perf_counter() - t0)
    return tables
