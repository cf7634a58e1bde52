"""Every run of a sweep counts in the 2WD cart report: an unstable or diverged run is a lost loop, a run without a
result stops the report with its error (before, ``_sweep`` kept only ``ok`` runs, so lost loops vanished)."""

from __future__ import annotations

import math

import pandas as pd
import pytest

from netsim.models.unicycle.readme_net import LOST_E3, lost_runs, stability_limits
from netsim.models.unicycle.report import counted_runs
from netsim.errors import NetsimError


def _summary() -> pd.DataFrame:
    # three delays, three runs each; at 200 ms two runs end 'unstable' (the verdict stopped nothing: metrics
    # present, heading error still under a quarter turn) and at 300 ms one diverged (no metrics after the stop)
    rows = []
    for ms, statuses, e3 in ((0, ["ok"] * 3, [0.1, 0.1, 0.1]),
                             (200, ["ok", "unstable at t = 4.2 s", "unstable at t = 3.9 s"], [0.2, 1.0, 1.2]),
                             (300, ["ok", "ok", "diverged at t = 1.5 s"], [0.3, 0.3, math.nan])):
        for i, (st, e) in enumerate(zip(statuses, e3)):
            rows.append({"index": len(rows), "replicate": i, "status": st, "_ms": float(ms),
                         "unicycle.track_max_e3": e, "unicycle.track_rms_e1": 0.01 * (1 + ms / 100)})
    return pd.DataFrame(rows)


def test_unstable_and_diverged_runs_are_kept_and_count_as_lost_loops() -> None:
    d = counted_runs(_summary(), "constructed")
    assert len(d) == 9  # no run dropped
    assert d["_failed"].tolist() == [False] * 4 + [True, True] + [False, False, True]
    lost = lost_runs(d)
    assert lost.sum() == 3 and not (d["unicycle.track_max_e3"] > LOST_E3).any()  # e3 alone sees none of them
    # 2 of 3 runs lost at 200 ms: more than half, so the loop is lost from 200 ms (the ok-only filter saw 0 of 1)
    lim = stability_limits(d)
    assert lim["lost_ms"] == 200.0


def test_a_run_without_a_result_stops_the_report_with_its_error() -> None:
    s = _summary()
    s.loc[4, "status"] = "error"
    s["error"] = ""
    s.loc[4, "error"] = "SimulationError: integrator failed"
    with pytest.raises(NetsimError, match=r"sweep constructed: 1 of 9 runs gave no result \(run 4: error: "
                                          r"SimulationError: integrator failed\)"):
        counted_runs(s, "constructed")
