"""Honesty of reports/hdd/README.md: every number its prose quotes comes from the runs.

* the templates of :data:`netsim.models.hdd_report.TEXT` hold no number other than labels (a typed-in number
  fails here);
* the committed README's prose is the templates filled with the committed ``quoted.csv``, and its table
  is ``table.csv``;
* the quoted values and the table agree with fresh runs of the shipped cases (the variant runs and the
  GPI sweep in the slow test).
"""

import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from netsim.models import hdd_report as hr

REPORT = Path(__file__).resolve().parents[2] / "reports" / "hdd"


@pytest.fixture(scope="module")
def quoted():
    return pd.read_csv(REPORT / "quoted.csv", keep_default_na=False)


def _texts(quoted):
    return dict(zip(quoted["key"], quoted["text"].astype(str)))


def test_templates_hold_no_typed_in_numbers():
    for key, text in hr.TEXT.items():
        stripped = re.sub(r"\{[a-zA-Z0-9_]+\}", "", text)
        for pat in hr.LABEL_PATTERNS:
            stripped = re.sub(pat, "", stripped)
        assert not re.search(r"\d", stripped), f"TEXT[{key!r}] has a typed-in number: {stripped!r}"


def test_a_typed_in_number_is_caught():
    stripped = re.sub(r"\{[a-zA-Z0-9_]+\}", "", "ISE {c1_ISE} vs 3.75")
    for pat in hr.LABEL_PATTERNS:
        stripped = re.sub(pat, "", stripped)
    assert re.search(r"\d", stripped)


def test_readme_prose_is_the_templates_filled_with_quoted_values(quoted):
    readme = (REPORT / "README.md").read_text()
    texts = _texts(quoted)
    for key in hr.TEXT:
        if key in ("gpi", "gpi4") and "## GPI surface" not in readme:
            continue
        assert hr.render(key, texts) in readme, f"README text for {key!r} is not generated from quoted.csv"


def test_readme_table_is_table_csv():
    readme = (REPORT / "README.md").read_text()
    table = pd.read_csv(REPORT / "table.csv")
    for _, r in table.iterrows():
        assert f"| {int(r['case'])} | " in readme
        assert f"{hr._fmt(float(r['NE_ours']))} |" in readme or f"/ {hr._fmt(float(r['NE_ours']))} |" in readme
        assert r["reason"] in readme


def _check_rows_against_runs(quoted, rows):
    """Each quoted value whose source is ``<run>:<column>`` equals that column of the fresh run."""
    checked = 0
    for _, q in quoted.iterrows():
        src = str(q["source"])
        m = re.fullmatch(r"([a-z0-9_]+):([A-Za-z_]+)", src)
        if not m or m.group(1) not in rows:
            continue
        fresh = rows[m.group(1)][m.group(2)]
        assert float(q["value"]) == pytest.approx(fresh, rel=1e-9, abs=1e-12), f"{q['key']} ({src})"
        checked += 1
    return checked


def test_quoted_numbers_of_the_shipped_cases_match_fresh_runs(quoted):
    names = [f"case{n}" for n in range(1, 7)]
    results, rows, _sweeps = hr.collect(names, gpi=False)
    assert _check_rows_against_runs(quoted, rows) >= 40
    table = pd.read_csv(REPORT / "table.csv", keep_default_na=False)
    table = table[table["reading"] != "every_period"]  # Case 2's other reading: a variant run, not shipped
    for n in range(1, 7):
        t = table.set_index("case").loc[n]
        for col in ("Nsc", "Nca", "Uc", "Ua", "ISE", "ISEP", "NE", "GPI"):
            assert float(t[f"{col}_ours"]) == pytest.approx(rows[f"case{n}"][col], rel=1e-9, abs=1e-12)
        # overshoot: an independent computation from the recorded output
        y = results[f"case{n}"].signals["y"].to_numpy(float)
        assert float(t["OS_pct_ours"]) == pytest.approx(100 * (np.nanmax(y) - 1.0), rel=1e-9)


@pytest.mark.slow
def test_every_quoted_number_matches_fresh_runs(quoted):
    results, rows, sweeps = hr.collect(None, gpi=True)
    _check_rows_against_runs(quoted, rows)
    q = hr._quote(rows, *sweeps["gpi"], *sweeps["gpi4"])
    fresh = q.texts()
    for key, text in _texts(quoted).items():
        if re.fullmatch(r"gpi4?_(wall|workers|exec|res)", key):  # wall time, machine, resumed points
            continue
        assert fresh[key] == text, key
