"""The pendulum report's sweep tables count a diverged or unstable run as not balanced; a run without a result
(error, interrupted, pending) stops the report instead of being counted as a fall."""

from __future__ import annotations

import pandas as pd
import pytest

from netsim.models.pendulum.report_sweeps import with_results
from netsim.errors import NetsimError


def test_unstable_and_diverged_runs_are_results() -> None:
    s = pd.DataFrame({"index": [0, 1, 2], "status": ["ok", "unstable at t = 2 s", "diverged at t = 1 s"]})
    assert with_results(s, "pendulum_delay_sweep") is s


@pytest.mark.parametrize("status", ["error", "interrupted at t = 1 s", "pending"])
def test_a_run_without_a_result_is_reported_as_an_error(status: str) -> None:
    s = pd.DataFrame({"index": [0, 1], "status": ["ok", status], "error": ["", "ValueError: bad"]})
    with pytest.raises(NetsimError, match=r"pendulum_delay_sweep: 1 of 2 runs gave no result \(run 1: "):
        with_results(s, "pendulum_delay_sweep")
