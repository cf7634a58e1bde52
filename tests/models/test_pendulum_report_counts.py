"""The case-study sweeps count a diverged or unstable run as a result (the pendulum's tables: not balanced); a run
without a result (error, interrupted, pending) stops the report instead of being counted as a fall
(:func:`netsim.casestudy.sweep`, which the pendulum, unicycle and HDD reports run their sweeps through)."""

from __future__ import annotations

from types import SimpleNamespace

import pandas as pd
import pytest

import netsim.sweep.run
from netsim.casestudy import sweep
from netsim.errors import NetsimError


def _fake_sweep(monkeypatch: pytest.MonkeyPatch, summary: pd.DataFrame) -> None:
    monkeypatch.setattr(netsim.sweep.run, "run_sweep", lambda path, **kw: SimpleNamespace(summary=summary))


def test_unstable_and_diverged_runs_are_results(monkeypatch: pytest.MonkeyPatch) -> None:
    s = pd.DataFrame({"index": [0, 1, 2], "status": ["ok", "unstable at t = 2 s", "diverged at t = 1 s"]})
    _fake_sweep(monkeypatch, s)
    assert sweep("scenarios/pendulum_delay_sweep.yaml", "unused").summary is s


@pytest.mark.parametrize("status", ["error", "interrupted at t = 1 s", "pending"])
def test_a_run_without_a_result_is_reported_as_an_error(monkeypatch: pytest.MonkeyPatch, status: str) -> None:
    s = pd.DataFrame({"index": [0, 1], "status": ["ok", status], "error": ["", "ValueError: bad"]})
    _fake_sweep(monkeypatch, s)
    with pytest.raises(NetsimError, match=r"pendulum_delay_sweep: 1 of 2 runs gave no result \(run 1: "):
        sweep("scenarios/pendulum_delay_sweep.yaml", "unused")
    assert sweep("scenarios/pendulum_delay_sweep.yaml", "unused", complete=False).summary is s  # the HDD surface
