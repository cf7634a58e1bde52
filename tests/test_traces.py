"""Traces as a choice (issue 19): output: {jobs, messages: full|summary|off, schedule: on|off}."""

from __future__ import annotations

import math
import random
from pathlib import Path

import numpy as np
import pytest

import netsim
from netsim.errors import ConfigError
from netsim.results import RunResult
from netsim.results.traces import QuantileSketch

ROOT = Path(__file__).resolve().parents[1]
CAN = ROOT / "scenarios" / "dc_servo_can.yaml"
#: dc_servo_can without its latency metric (which reads the rows), 0.5 s, and interference share 0.3 so that the
#: CAN frames wait and the response times and delays vary.
BASE = {"duration": "0.5 s", "nodes.interference.tasks[0].params.share": 0.3,
        "metrics": [{"type": "control_error", "params": {"reference": "r", "output": "y"}}]}


def test_sketch_quantiles_within_the_relative_accuracy() -> None:
    rng = random.Random(3)
    values = [rng.lognormvariate(10.0, 2.0) for _ in range(20000)] + [0.0] * 100
    sketch = QuantileSketch(0.01)
    for v in values:
        sketch.add(v)
    ordered = sorted(values)
    for q in (0.0, 0.01, 0.5, 0.9, 0.99, 1.0):
        exact = ordered[round(q * (len(ordered) - 1))]  # the value of rank q (n - 1), the sketch's definition
        got = sketch.quantile(q)
        assert abs(got - exact) <= 0.01 * exact + 1e-12, (q, got, exact)
    assert sketch.count == len(values)
    # bounded memory: log-spaced buckets over ~17 decades of e^(10 +- 8 sigma) span at most a few thousand
    assert len(sketch._buckets) < 2000


def test_sketch_refuses_negative_values_and_is_nan_when_empty() -> None:
    sketch = QuantileSketch()
    assert math.isnan(sketch.quantile(0.5))
    with pytest.raises(ValueError, match=">= 0"):
        sketch.add(-1.0)


def test_summary_traces_give_the_row_statistics(tmp_path: Path) -> None:
    full = netsim.run(CAN, write=False, overrides=BASE)
    summ = netsim.run(CAN, out=tmp_path / "s", overrides={**BASE, "output.jobs": "summary",
                                                              "output.messages": "summary", "output.schedule": "off"})
    assert summ.jobs.empty and summ.messages.empty and summ.schedule.empty
    files = {p.name for p in (tmp_path / "s").iterdir()}
    assert {"jobs_summary.csv", "messages_summary.csv"} <= files and not {"jobs.csv", "messages.csv"} & files
    # counts, misses and maxima equal the row tables' exactly; the mean is the exact ns mean (rounded once)
    for (node, task), grp in full.jobs.groupby(["node", "task"]):
        row = summ.job_summary[(summ.job_summary.node == node) & (summ.job_summary.task == task)].iloc[0]
        assert row["jobs"] == len(grp)
        assert row["deadline_misses"] == full.metrics[f"task.{node}.{task}.deadline_misses"]
        resp = grp["response_s"].dropna().to_numpy()
        assert row["max_response_s"] == resp.max()
        assert row["mean_response_s"] == pytest.approx(resp.mean(), rel=1e-12)
        for q in (50, 95, 99):  # 1 % relative accuracy of the sketch against the exact rank q (n - 1)
            exact = np.sort(resp)[round(q / 100 * (len(resp) - 1))]
            assert abs(row[f"p{q}_response_s"] - exact) <= 0.01 * exact + 1e-15
    delays = full.messages["delay_s"].dropna().to_numpy()
    assert delays.std() > 0  # the interference makes the delays vary: the percentiles are a real check
    net = summ.message_summary.iloc[0]
    assert net["messages"] == len(full.messages) and net["max_delay_s"] == delays.max()
    exact = np.sort(delays)[round(0.95 * (len(delays) - 1))]
    assert abs(net["p95_delay_s"] - exact) <= 0.01 * exact
    for key in full.metrics.index:  # the same metric names, same values but for the mean's rounding
        assert summ.metrics[key] == pytest.approx(full.metrics[key], rel=1e-12, nan_ok=True), key
    back = RunResult.read(tmp_path / "s")
    assert back.traces["jobs"] == "summary" and back.job_summary["jobs"].tolist() == summ.job_summary["jobs"].tolist()


def test_off_keeps_nothing_and_rowwise_metrics_are_refused(tmp_path: Path) -> None:
    off = netsim.run(CAN, out=tmp_path / "o", overrides={**BASE, "output.jobs": "off", "output.messages": "off"})
    assert off.job_summary is None and off.jobs.empty
    assert not any(k.startswith("task.") for k in off.metrics.index)
    assert "cpu.sensor.utilization" in off.metrics.index  # from the kernel, not from the rows
    # et_control reads the messages row by row and cannot stream them (latency streams: tests/metrics)
    with pytest.raises(ConfigError, match=r"metrics\[\d+\] \(et_control\).*output.messages: full"):
        netsim.run(ROOT / "scenarios" / "hdd_case1.yaml", write=False, overrides={"output.messages": "summary"})


def test_default_output_leaves_the_resolved_scenario_unchanged() -> None:
    from netsim.scenario import load_scenario

    assert load_scenario(CAN).resolved_dict()["output"] == {"dir": None, "plot": False}
    changed = load_scenario(CAN, overrides={"output.schedule": False}).resolved_dict()["output"]
    assert changed == {"dir": None, "plot": False, "schedule": "off"}


def test_signals_table_holds_values_as_pandas_reindex_ffill_does() -> None:
    """The numpy signals table equals the pandas construction it replaced (an independent computation here)."""
    import pandas as pd

    from netsim.results import signals_table
    from netsim.timebase import S

    def by_pandas(times: dict, values: dict) -> pd.DataFrame:
        cols = {}
        for n in times:
            s = pd.Series(np.asarray(values[n], dtype=float), index=np.asarray(times[n], dtype=np.int64))
            s = s[~s.index.duplicated(keep="last")].sort_index(kind="stable")
            cols[n] = s
        union = np.unique(np.concatenate([c.index.to_numpy() for c in cols.values()]))
        frame = pd.DataFrame({n: c.reindex(union).ffill() for n, c in cols.items()})
        frame.insert(0, "time_s", union / S)
        return frame.reset_index(drop=True)

    rng = np.random.default_rng(1)
    for _ in range(200):  # unsorted and repeated instants, NaN samples (held over), signals starting late
        times, values = {}, {}
        for n in "abc":
            k = int(rng.integers(1, 30))
            t = rng.integers(0, 50, k)
            t = np.sort(t) if rng.random() < 0.5 else t
            v = rng.normal(size=k)
            v[rng.random(k) < 0.3] = np.nan
            times[n], values[n] = list(t), list(v)
        got = signals_table(times, values)
        assert got.equals(by_pandas(times, values)[list(got.columns)])


def test_a_result_with_a_lazy_table_pickles_and_copies_with_the_table_built() -> None:
    import copy
    import pickle

    result = netsim.run(CAN, write=False, overrides={**BASE, "duration": "0.05 s"})
    assert type(object.__getattribute__(result, "schedule")).__name__ == "Lazy"  # not built yet
    back = pickle.loads(pickle.dumps(result))
    assert back.schedule.equals(result.schedule) and len(back.schedule) > 0
    assert copy.deepcopy(result).signals.equals(result.signals)
