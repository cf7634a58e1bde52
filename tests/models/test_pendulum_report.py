"""Honesty of reports/pendulum/README.md: every number its prose quotes comes from the runs.

* the templates of :data:`netsim.models.pendulum.report.TEXT` hold no number besides labels (a typed-in number fails);
* the committed README's prose is the templates filled with the committed ``quoted.csv``, its closed-loop table
  is ``table.csv``, and ``table.csv`` has the issue's stable columns;
* quoted values agree with fresh computations: the analytic ones (designs) and two fresh closed-loop runs
  (rows of ``runs.csv``, compared to 1e-9).
"""

import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

import netsim  # noqa: F401 - pins BLAS before numpy work
from netsim.models.pendulum import report as rp

ROOT = Path(__file__).resolve().parents[2]
REPORT = ROOT / "reports" / "pendulum"


@pytest.fixture(scope="module")
def quoted():
    return pd.read_csv(REPORT / "quoted.csv", keep_default_na=False)


def _texts(quoted):
    return dict(zip(quoted["key"], quoted["text"].astype(str)))


def _strip(text):
    s = re.sub(r"\{[a-zA-Z0-9_]+\}", "", text)
    for pat in rp.LABEL_PATTERNS:
        s = re.sub(pat, "", s)
    return s


def test_templates_hold_no_typed_in_numbers():
    for key, text in rp.TEXT.items():
        assert not re.search(r"\d", _strip(text)), f"TEXT[{key!r}] has a typed-in number: {_strip(text)!r}"


def test_a_typed_in_number_is_caught():
    assert re.search(r"\d", _strip("u std {chat_kal} V against 0.02"))


def test_readme_prose_is_the_templates_filled_with_quoted_values(quoted):
    readme = (REPORT / "README.md").read_text()
    texts = _texts(quoted)
    for key in rp.TEXT:
        assert rp.render(key, texts) in readme, f"README text for {key!r} is not generated from quoted.csv"


def test_table_has_the_stable_columns_and_is_in_the_readme():
    table = pd.read_csv(REPORT / "table.csv")
    assert list(table.columns[: len(rp.TABLE_COLUMNS)]) == rp.TABLE_COLUMNS
    readme = (REPORT / "README.md").read_text()
    for _, r in table.iterrows():
        cells = [r["estimator"], r["controller"], str(int(r["seed_count"])), rp.fmt(float(r["u_std"])),
                 rp.fmt(float(r["lqg_cost_per_step"]))]
        assert f"| {r['estimator']} | {r['controller']} | " in readme
        for c in cells:
            assert c in readme


def test_quoted_tilt_is_the_scenarios():
    for name in ("pendulum_lqr", "pendulum_mpc", "pendulum_network", "pendulum_quantised"):
        x0 = yaml.safe_load((ROOT / "scenarios" / f"{name}.yaml").read_text())["plant"]["x0"]
        assert x0[2] == rp.TILT


def test_analytic_quotes_match_a_fresh_computation(quoted):
    from netsim.models.pendulum.design import designs, motion_errors

    d = designs()
    q = quoted.set_index("key")["value"].astype(float)
    me = motion_errors(d)
    assert q["printed_err_ad"] == pytest.approx(me["printed"][3], rel=1e-9)
    assert q["motion_rms_ad"] == pytest.approx(me["motion_rms"][3], rel=1e-9)
    assert q["unstable_pole"] == pytest.approx(np.max(np.linalg.eigvals(d.lin.A).real), rel=1e-9)
    assert q["rank"] == 4


def test_runs_csv_rows_match_fresh_runs():
    runs = pd.read_csv(REPORT / "runs.csv")
    cases = [c for c in rp.closed_loop_cases((1,)) if c["controller"] == "lqr" and c["estimator"] in ("kalman", "fd_raw")]
    assert len(cases) == 2
    for case in cases:
        fresh = rp.run_case(case)
        row = runs[(runs.kind == case["kind"]) & (runs.estimator == case["estimator"]) & (runs.seed == 1)
                   & (runs.controller == "lqr")].iloc[0]
        for col in ("u_std", "saturated_share", "rms_theta", "rms_alpha", "lqg_cost_per_step"):
            assert float(row[col]) == pytest.approx(fresh[col], rel=1e-9, abs=1e-12), (case["estimator"], col)


# ------------------------------------------------------------------------------------------------ sweeps, delay
def test_the_tuning_rows_are_the_sweep_files_runs():
    # the report's Qn/Rn numbers are those of `netsim sweep scenarios/pendulum_kalman_sweep.yaml`: the three
    # replicates of one grid point, run here with the seeds the sweep file gives them, have the mean u_std and
    # convergence time of tuning.csv
    from netsim.runner import run
    from netsim.sweep.spec import load_sweep

    sweep = load_sweep(ROOT / "scenarios" / "pendulum_kalman_sweep.yaml")
    points = [p for p in sweep.points if p.values["scale_Q"] == 100 and p.values["scale_R"] == 1]
    assert len(points) == sweep.spec.replicates == 3
    res = [run(sweep.point_raw(p), write=False, seed=p.seed).metrics for p in points]
    tuning = pd.read_csv(REPORT / "tuning.csv")
    row = tuning[(tuning.sweep == "kalman") & (tuning.scale_Q == 100) & (tuning.scale_R == 1)].iloc[0]
    assert row.u_std == pytest.approx(np.mean([float(m["pendulum.u_std"]) for m in res]), rel=1e-9)
    assert row.est_converged_s == pytest.approx(np.mean([float(m["pendulum.est_converged_s"]) for m in res]), rel=1e-9)


def test_report_delays_are_the_scenarios():
    from netsim.models.pendulum.report_sweeps import NETWORK_BASE_DELAY_MS
    from netsim.scenario import load_scenario

    net = load_scenario(ROOT / "scenarios" / "pendulum_network.yaml")
    ctrl = net.nodes["controller"].tasks[0]
    act = net.nodes["actuator"].tasks[0]
    # sample at t_k, controller released offset later, runs its execution time, actuator its own
    assert NETWORK_BASE_DELAY_MS == pytest.approx(1e-6 * (ctrl.offset + ctrl.execution + act.execution))  # times in ns
    lqr = load_scenario(ROOT / "scenarios" / "pendulum_lqr.yaml").nodes["rip"].tasks[0]
    assert rp.TASK_DELAY_MS == pytest.approx(1e-6 * lqr.execution)


def test_delay_sweep_points_are_the_study_estimators():
    from netsim.models.pendulum.report_sweeps import estimator_name, point_values

    names = {estimator_name(v["estimator"], rp.ESTIMATORS) for v in point_values("pendulum_delay_sweep")}
    assert names == set(rp.DELAY_ESTIMATORS)


def test_delay_cost_and_margins_are_consistent():
    dc = pd.read_csv(REPORT / "delay_cost.csv")
    dl = pd.read_csv(REPORT / "delay.csv").set_index("estimator")
    for e, g in dc.groupby("estimator"):
        # the analysis says infinite exactly beyond its own margin
        assert np.all(np.isfinite(g.analytic_cost) == (g.total_delay_ms < dl.loc[e, "lqg_margin_ms"])), e
        ok = g[g.sim_cost.notna()]
        assert np.all(ok.sim_ci_low <= ok.sim_cost) and np.all(ok.sim_cost <= ok.sim_ci_high)
    # the two predictions of the margin are independent computations of the same quantity (one crossover)
    assert np.allclose(dl.lqg_margin_ms, dl.predicted_margin_ms, atol=0.01)


# ------------------------------------------------------------------------------------------------ orderings
def test_observers_give_smoother_velocities_than_finite_differences():
    # held still (20 s per estimator): each step of the ordering with its measured factor
    hs = pd.read_csv(REPORT / "hold_still.csv").set_index("estimator")["alpha_dot_sim"]
    order = ["fd_raw", "fd_lowpass", "luenberger", "kalman"]
    ratios = [hs[a] / hs[b] for a, b in zip(order, order[1:])]
    assert min(ratios) > 2.0, dict(zip(order[1:], ratios))


def test_observers_give_less_chatter_than_finite_differences_on_every_seed():
    t = pd.read_csv(REPORT / "table.csv")
    t = t[t.controller == "lqr"].set_index("estimator")
    order = ["fd_raw", "fd_lowpass", "luenberger", "kalman"]
    margins = [t.loc[a, "u_std_min"] / t.loc[b, "u_std_max"] for a, b in zip(order, order[1:])]
    assert min(margins) > 1.5, dict(zip(order[1:], margins))


def test_kalman_has_the_lowest_stationary_cost_and_not_the_lowest_whole_run_cost():
    t = pd.read_csv(REPORT / "table.csv")
    t = t[t.controller == "lqr"].set_index("estimator")
    assert t.lqg_cost_analytic.idxmin() == "kalman"
    assert t.lqg_cost_after_1s_max["kalman"] < t.drop(index="kalman").lqg_cost_after_1s_min.min()
    dc = pd.read_csv(REPORT / "delay_cost.csv")
    first = dc[dc.total_delay_ms == dc.total_delay_ms.min()].set_index("estimator")
    assert first.sim_ci_high["kalman"] < first.drop(index="kalman").sim_ci_low.min()
    # over the whole run from the tilt the slow Kalman filter is not the lowest (the README says so)
    assert t.lqg_cost_per_step.idxmin() != "kalman"
