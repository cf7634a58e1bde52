"""The case-study harness (netsim.casestudy): one formatter, quoted numbers, runs on one pool, a run cache keyed
by the scenario hash."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest

from netsim.casestudy import (Quotes, RunCache, code_fingerprint, digits_outside_labels, fill, fmt, log_progress,
                              md_table, run_all, scenario_key, splice)

ROOT = Path(__file__).resolve().parents[1]


def _square(x: int) -> int:
    return x * x


def _pid(_x: int) -> int:
    return os.getpid()


def test_fmt_gives_significant_digits_and_a_text_for_missing_values():
    # expected texts written out by hand from Python's :g format
    assert fmt(0.123456) == "0.123"
    assert fmt(123456.0, 2) == "1.2e+05"
    assert fmt(None) == "nan" and fmt(math.nan, missing="n/a") == "n/a"
    assert fmt(-0.0) == "0" and fmt(math.inf) == "inf"
    assert fmt(np.float64(2.0)) == "2"


def test_fmt_sci_uses_exponent_notation_outside_the_plain_range_only():
    assert fmt(1.234e-5, 3, sci=True) == "1.23e-05"
    assert fmt(2.5e7, 3, sci=True) == "2.50e+07"
    assert fmt(0.0123, 3, sci=True) == "0.0123"
    assert fmt(0.0123, 3) == "0.0123"


def test_quotes_format_each_value_once_and_fill_templates():
    q = Quotes()
    assert q.add("n", 464.4, "d", "paper") == "464"
    assert q.add("x", 0.012345, ".2g") == "0.012"
    assert q.add("y", 1 / 3) == "0.333"
    assert q.add("w", "rises", source="words") == "rises"
    assert q.fill("{n} runs, {x} / {y}: {w}") == "464 runs, 0.012 / 0.333: rises"
    df = q.frame()
    assert df.columns.tolist() == ["key", "value", "text", "source"]
    assert df.key.tolist() == ["n", "x", "y", "w"] and math.isnan(df.value.iloc[3]) and df.source.iloc[0] == "paper"
    with pytest.raises(KeyError):
        q.fill("{missing}")


def test_marked_quotes_give_the_text_and_the_template():
    q = Quotes()
    marked = "sd " + q.mark("s1.sd", 0.25, "0.25") + " m"
    assert Quotes.unmark(marked) == "sd 0.25 m"
    assert Quotes.template(marked) == "sd {s1.sd} m"
    assert fill(Quotes.template(marked), q.texts()) == "sd 0.25 m"
    assert q.frame(source=False).columns.tolist() == ["key", "value", "text"]


def test_digits_outside_labels_finds_a_number_written_into_a_template():
    labels = [r"eq \(\d+\)"]
    assert digits_outside_labels("as eq (22) says, {x} runs", labels) == []
    assert digits_outside_labels("as eq (22) says, 12 runs", labels) == ["12"]


def test_md_table_writes_a_header_a_rule_and_one_line_per_row():
    import pandas as pd

    df = pd.DataFrame({"a": [1.23456, 2.0], "b": ["x", "y"]})
    assert md_table(df) == ["| a | b |", "|---|---|", "| 1.23456 | x |", "| 2.0 | y |"]
    assert md_table(df, ["b"], cell=lambda v: v.upper()) == ["| b |", "|---|", "| X |", "| Y |"]


def test_splice_replaces_a_marked_section_or_puts_it_before_its_anchor():
    marks = ("<!-- s -->", "<!-- /s -->")
    new = [marks[0], "new", marks[1], ""]
    first = splice(["# T", "", "## Next", "end"], marks, new, "## Next")
    assert first == ["# T", "", marks[0], "new", marks[1], "", "## Next", "end"]
    again = splice(first, marks, [marks[0], "newer", marks[1], ""], "## Next")
    assert again == ["# T", "", marks[0], "newer", marks[1], "", "## Next", "end"]
    with pytest.raises(ValueError, match="## Gone"):
        splice(["# T"], marks, new, "## Gone")


def test_run_all_keeps_the_order_and_reports_progress():
    seen = []
    out = run_all(_square, list(range(7)), workers=2, progress=lambda d, n, w: seen.append((d, n, w)), what="sq")
    assert out == [0, 1, 4, 9, 16, 25, 36]
    assert seen[-1] == (7, 7, "sq") and [d for d, _, _ in seen] == list(range(1, 8))


def test_run_all_hands_each_result_over_as_it_comes():
    got = []
    run_all(_square, [3, 4], workers=1, each=lambda i, r: got.append((i, r)))
    assert got == [(0, 9), (1, 16)]


def test_run_all_with_one_worker_runs_in_this_process():
    assert run_all(_pid, [1, 2], workers=1) == [os.getpid()] * 2
    assert set(run_all(_pid, [1, 2, 3, 4], workers=2)) - {os.getpid()}  # a pool: other processes


def test_log_progress_logs_about_every_tenth_run(caplog):
    p = log_progress("netsim.progress.test", "study")
    with caplog.at_level("INFO", logger="netsim.progress.test"):
        for i in range(1, 21):
            p(i, 20, "grid")
    assert len(caplog.records) == 10 and "study: grid: 20/20 runs" in caplog.records[-1].getMessage()


def test_scenario_key_is_the_hash_the_sweep_gives_a_point():
    from netsim.sweep.points import point_hash

    import yaml

    path = ROOT / "scenarios" / "dc_servo_can.yaml"
    raw = yaml.safe_load(path.read_text())
    assert scenario_key(path, seed=3) == point_hash(raw, 3)
    assert scenario_key(path, {"duration": "0.5 s"}, 3) != scenario_key(path, seed=3)


def test_run_cache_keeps_rows_per_key_and_code(tmp_path):
    cache = RunCache(tmp_path, "c0de")
    assert cache.get("abc") is None
    cache.put("abc", {"x": np.float64(0.1), "n": np.int64(3), "s": "ok", "m": math.nan})
    again = RunCache(tmp_path, "c0de")
    row = again.get("abc")
    assert row["x"] == 0.1 and row["n"] == 3 and row["s"] == "ok" and math.isnan(row["m"]) and again.reused == 1
    assert RunCache(tmp_path, "other").get("abc") is None
    memory = RunCache(None, "c0de")
    assert memory.get("abc") is None
    memory.put("abc", {"x": 1.0})
    assert memory.get("abc") == {"x": 1.0} and memory.reused == 1  # in memory only
    assert RunCache(None, "c0de").get("abc") is None
    with pytest.raises(ValueError, match="cache key"):
        cache.put("../x", {})


def test_run_cache_floats_come_back_bit_for_bit(tmp_path):
    vals = [0.1 + 0.2, 1 / 3, 2.0 ** -1074, 1.7976931348623157e308, 0.9169120220000001]
    RunCache(tmp_path).put("k", {f"v{i}": v for i, v in enumerate(vals)})
    assert list(RunCache(tmp_path).get("k").values()) == vals


def test_code_fingerprint_changes_with_the_files_and_the_extra_text(tmp_path):
    a, b = tmp_path / "a.py", tmp_path / "b.py"
    a.write_text("x = 1\n")
    b.write_text("x = 2\n")
    assert code_fingerprint([a]) == code_fingerprint([a]) and len(code_fingerprint([a])) == 12
    assert code_fingerprint([a]) != code_fingerprint([b])
    assert code_fingerprint([a], "4.0") != code_fingerprint([a], "3.2")
