"""Both readings of HDD Case 2 in the report's headline table, and the reason for the default in one place.

Issue 26 section 8: the `every_period` reading reproduces the paper's Case 2 table, the default `arrival`
follows the paper's text. The headline table shows a row for each; the argument for the default is written
once (the "Case 2 between measurements" section), the rest points to it.
"""

import re
from pathlib import Path

import pandas as pd
import pytest

from netsim.models import hdd_report as hr

REPORT = Path(__file__).resolve().parents[2] / "reports" / "hdd"
#: Section 5.2 of Cuenca et al.: Nsc, Nca, Uc, Ua, ISEP, NE of Case 2.
PAPER_CASE2 = {"Nsc": 250, "Nca": 78, "Uc": 0.54, "Ua": 0.16, "ISEP": 0.54, "NE": 0.14}


def _placeholder_texts() -> dict[str, str]:
    """Every placeholder of the templates filled with a marker (the table's numbers do not come from it)."""
    names = set(re.findall(r"\{([a-zA-Z0-9_]+)\}", "".join(hr.TEXT.values())))
    return {n: "<x>" for n in names}


def _row(base: float) -> dict[str, float]:
    cols = ["Nsc", "Nca", "Uc", "Ua", "Cc_pct", "ISE", "ISEP", "NE", "GPI", "OS_pct", "N_max",
            "played_past_packet", "u_gap_max"]
    return {c: base + i for i, c in enumerate(cols)}


def test_headline_table_has_a_row_for_each_case2_reading():
    rows = {f"case{n}": _row(100.0 * n) for n in range(1, 7)}
    rows["case2_every"] = _row(7000.0)
    table = hr._table(rows, _placeholder_texts())
    two = table[table["case"] == 2].set_index("reading")
    assert sorted(two.index) == ["arrival (default)", "every_period"]
    # ours from the run of each reading, the paper's from section 5.2 on both rows
    assert two.loc["every_period", "Nsc_ours"] == 7000.0
    assert two.loc["arrival (default)", "Nsc_ours"] == 200.0
    for reading in two.index:
        for col, val in PAPER_CASE2.items():
            assert two.loc[reading, f"{col}_paper"] == pytest.approx(val)
    # the other cases keep one row each, without a reading label
    assert table["case"].tolist() == [1, 2, 2, 3, 4, 5, 6]
    assert (table.loc[table["case"] != 2, "reading"] == "").all()


def test_off_text_gives_the_relative_difference_from_the_paper():
    paper = pd.Series(PAPER_CASE2)
    # (364 - 250) / 250 = +45.6 %, (120 - 78) / 78 = +53.8 %; (241 - 250) / 250 = -3.6 %, (0.129 - 0.14) / 0.14 = -7.9 %
    assert hr.off_text({"Nsc": 364, "Nca": 120, "ISEP": 1.58, "NE": 0.424}, paper) == \
        "Nsc +46 %, Nca +54 %, ISEP +193 %, NE +203 %"
    assert hr.off_text({"Nsc": 241, "Nca": 75, "ISEP": 0.48, "NE": 0.129}, paper) == \
        "Nsc -3.6 %, Nca -3.8 %, ISEP -11 %, NE -7.9 %"


def _headline_rows(readme: str) -> list[list[str]]:
    lines = readme.splitlines()
    i = next(k for k, ln in enumerate(lines) if ln.startswith("| case | reading |"))
    out = []
    for ln in lines[i + 2:]:
        if not ln.startswith("|"):
            break
        out.append([c.strip() for c in ln.strip().strip("|").split("|")])
    return out


def test_committed_headline_table_shows_both_case2_readings_from_their_runs():
    readme = (REPORT / "README.md").read_text()
    readings = pd.read_csv(REPORT / "readings.csv").set_index("run")
    rows = {(r[0], r[1]): r for r in _headline_rows(readme)}
    for run, label in (("case2", "arrival (default)"), ("case2_every", "every_period")):
        r = rows[("2", label)]
        # columns: case, reading, Nsc, Nca, Uc, Ua, Cc_pct, ISE, ISEP, NE (paper / ours)
        assert r[2] == f"250 / {hr._fmt(float(readings.loc[run, 'Nsc']))}"
        assert r[3] == f"78 / {hr._fmt(float(readings.loc[run, 'Nca']))}"
        assert r[9] == f"0.14 / {hr._fmt(float(readings.loc[run, 'NE']))}"
    table = pd.read_csv(REPORT / "table.csv", keep_default_na=False)
    assert sorted(table.loc[table["case"] == 2, "reading"]) == ["arrival (default)", "every_period"]


def test_committed_report_states_the_reason_for_the_default_once():
    readme = (REPORT / "README.md").read_text()
    # the argument (the paper's text on when the controller works) appears once, in the Case 2 section
    assert readme.count("not needed to work at any synchronous time") == 1
    section = readme.split("### Case 2 between measurements", 1)[1].split("###", 1)[0]
    assert "not needed to work at any synchronous time" in section
    # the headline rows point to it instead of repeating it
    assert readme.count('see "Case 2 between measurements" below') == 1
    assert readme.count("support the first reading, the table the second") == 0
