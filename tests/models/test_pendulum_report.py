"""Honesty of reports/pendulum/README.md: every number its prose quotes comes from the runs.

* the templates of :data:`models.pendulum.report.TEXT` hold no number besides labels (a typed-in number fails);
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
from models.pendulum import report as rp

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
    from models.pendulum.design import designs, motion_errors

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
