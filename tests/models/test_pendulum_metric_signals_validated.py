"""validate refuses a pendulum scenario whose run would not record what the ``pendulum`` metric reads.

Found by tests/fuzz: with a ``record:`` entry (theta, alpha or u) or ``plant.record_grid`` deleted, pendulum_hold_still,
pendulum_network and pendulum_lqr_rk4 passed ``netsim validate`` and then the metric failed after the run on a
column that was never recorded. The metric now declares ``reads_signals``; the plant outputs theta and alpha are
recorded only on the record grid (the measurements' ``outputs: [theta]`` read them, they record nothing).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from netsim.scenario import check_scenario

ROOT = Path(__file__).resolve().parents[2]
FILES = ["pendulum_hold_still.yaml", "pendulum_network.yaml", "pendulum_lqr_rk4.yaml"]


def _errors(file: str, overrides: dict) -> list[tuple[str, str]]:
    return [(p.path, p.message) for p in check_scenario(ROOT / "scenarios" / file, overrides) if p.is_error]


@pytest.mark.parametrize("file", FILES)
@pytest.mark.parametrize("left_out", ["theta", "alpha", "u"])
def test_a_record_list_without_a_signal_the_metric_reads_is_refused(file, left_out):
    kept = [n for n in ("theta", "alpha", "u", "x_hat") if n != left_out]
    assert _errors(file, {"record": kept}) == [(
        "metrics[0].type", f"metric 'pendulum' reads the signals {left_out}, which 'record:' leaves out "
                           f"(record: [{', '.join(sorted(kept))}]); add them to 'record:'")]


def test_the_estimate_is_optional_for_the_metric():
    assert _errors("pendulum_hold_still.yaml", {"record": ["theta", "alpha", "u"]}) == []


@pytest.mark.parametrize("file", FILES)
def test_no_record_grid_is_refused_for_each_angle_the_metric_reads(file):
    errors = _errors(file, {"plant.record_grid": None})
    assert [(path, message.split(",")[0]) for path, message in errors] == [
        ("metrics[0].type", "metric 'pendulum' reads the plant output 'theta'"),
        ("metrics[0].type", "metric 'pendulum' reads the plant output 'alpha'")]
    assert all("add e.g. 'record_grid:" in message for _, message in errors)
