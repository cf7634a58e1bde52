"""BusyMeter: the intervals spread over the bins in batches give the bins an interval-by-interval count gives."""

from __future__ import annotations

import random

import pytest

from netsim.network.stats import BusyMeter


def _by_hand(intervals: list[tuple[int, int]], bin_ns: int) -> dict[int, int]:
    """Busy ns per bin, each interval cut at the bin edges one by one (independent of BusyMeter)."""
    out: dict[int, int] = {}
    for s, t in intervals:
        for k in range(s // bin_ns, (t - 1) // bin_ns + 1):
            lo, hi = max(s, k * bin_ns), min(t, (k + 1) * bin_ns)
            out[k] = out.get(k, 0) + hi - lo
    return out


@pytest.mark.parametrize("fold", [1, 7, 1024])
def test_bins_and_series_do_not_depend_on_the_batch_size(monkeypatch: pytest.MonkeyPatch, fold: int) -> None:
    monkeypatch.setattr(BusyMeter, "FOLD", fold)
    rng = random.Random(3)
    meter, t, intervals = BusyMeter(1000), 0, []
    for _ in range(600):
        s = t + rng.randrange(0, 3000)
        e = s + rng.randrange(1, 2500)  # some intervals span several bins
        meter.start(s)
        meter.stop(e)
        intervals.append((s, e))
        t = e
    expected = _by_hand(intervals, 1000)
    assert meter.bins == expected
    assert meter.busy(t) == sum(e - s for s, e in intervals)
    series = meter.series(t + 2500)
    assert len(series) == -(-(t + 2500) // 1000)
    assert series[:-3] == [expected.get(k, 0) / 1000 for k in range(len(series) - 3)]
    assert series[-1] == 0.0  # past the last interval


def test_held_intervals_stay_below_the_batch_size() -> None:
    meter = BusyMeter(10_000)
    for k in range(5 * BusyMeter.FOLD):
        meter.add(2 * k, 2 * k + 1)
    assert len(meter._intervals) < BusyMeter.FOLD
    assert meter.busy(10 * BusyMeter.FOLD) == 5 * BusyMeter.FOLD
