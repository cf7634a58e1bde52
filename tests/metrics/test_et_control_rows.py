"""et_control reads a run's messages from the records' columns: no pandas messages table is built (issue 29)."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from netsim.metrics.et import count_messages
from netsim.results.rows import Rows
from netsim.runner import clear_baseline_cache, run

CASE1 = Path(__file__).resolve().parents[2] / "scenarios" / "hdd_case1.yaml"


def test_hdd_case1_metrics_build_no_messages_dataframe(monkeypatch):
    built: list[int] = []
    frame = Rows.frame

    def counting(self):
        built.append(len(self))
        return frame(self)

    monkeypatch.setattr(Rows, "frame", counting)
    clear_baseline_cache()
    res = run(CASE1, write=False)
    assert built == []
    # time-triggered: one sensor and one actuator message in each of the 9.28 ms / 20 us = 464 periods
    assert (float(res.metrics["et.Nsc"]), float(res.metrics["et.Nca"])) == (464.0, 464.0)
    assert float(res.metrics["et.u_gap_max"]) == 1.0  # a packet in every period: each covers its own period


@pytest.mark.parametrize("as_rows", [False, True])
def test_count_messages_reads_a_dataframe_and_the_records_columns_alike(as_rows):
    table = pd.DataFrame({"tag": ["y", "u", "y", "y"], "sent_s": [0.0, 1e-5, 2e-5, 4e-5],
                          "dropped": [False, False, True, False]})
    if as_rows:
        from netsim.results.rows import MESSAGE_FIELDS

        kinds = {c.name: c for c in MESSAGE_FIELDS}
        table = Rows([(kinds["tag"], ["y", "u", "y", "y"]), (kinds["sent_s"], [0, 10_000, 20_000, 40_000]),
                      (kinds["dropped"], [False, False, True, False])])
    # by hand from the four rows: three 'y', two of them sent before 30 us, two 'y' delivered
    assert count_messages(table, "y") == 3
    assert count_messages(table, "y", before_s=3e-5) == 2
    assert count_messages(table, "y", delivered=True) == 2
    assert count_messages(table, "u", delivered=True, before_s=1e-5) == 0
