"""Results: the wide signals table, the job/message tables, and the run folder files."""

import math
from types import SimpleNamespace

import numpy as np
import pandas as pd

from netsim.results import MESSAGE_COLUMNS, RunResult, jobs_table, messages_table, signals_table
from netsim.timebase import MS


def test_signals_table_is_union_of_instants_forward_filled():
    times = {"y": [0, 2 * MS, 4 * MS], "u": [1 * MS, 4 * MS, 4 * MS]}
    values = {"y": [0.0, 1.0, 2.0], "u": [5.0, 6.0, 7.0]}
    frame = signals_table(times, values, order=["y", "u"])
    assert list(frame.columns) == ["time_s", "y", "u"]
    assert frame["time_s"].tolist() == [0.0, 0.001, 0.002, 0.004]
    assert frame["y"].tolist() == [0.0, 0.0, 1.0, 2.0]
    # u: empty before its first sample, then held; the last of two samples at one instant wins
    assert math.isnan(frame["u"][0])
    assert frame["u"].tolist()[1:] == [5.0, 5.0, 7.0]


def test_signals_table_orders_unlisted_columns_by_name():
    frame = signals_table({"b": [0], "a": [0], "x[1]": [0], "x[0]": [0]}, {"b": [1], "a": [2], "x[1]": [3], "x[0]": [4]}, order=["x"])
    assert list(frame.columns) == ["time_s", "x[0]", "x[1]", "a", "b"]


def test_job_and_message_tables_convert_ns_to_seconds():
    job = SimpleNamespace(task="t", node="n", job_id=3, release=1 * MS, start=2 * MS, finish=None, response=None,
                          deadline=5 * MS, deadline_met=None, preemptions=0, cpu_time=MS // 2, killed=False)
    jt = jobs_table([job])
    assert jt.loc[0, "start_s"] == 0.002 and math.isnan(jt.loc[0, "finish_s"])
    msg = SimpleNamespace(msg_id=7, network="can", sender="a", receiver="b", tag="y", bits=80, priority=1,
                          sent_ns=MS, tx_start_ns=MS, tx_end_ns=2 * MS, delivered_ns=2 * MS, dropped=False,
                          drop_reason="", delay_ns=None)
    mt = messages_table([msg])
    assert list(mt.columns) == MESSAGE_COLUMNS
    assert mt.loc[0, "delay_s"] == 0.001


def _result():
    sig = signals_table({"y": [0, MS, 3 * MS]}, {"y": [0.1, 1.0 / 3.0, np.pi]})
    return RunResult(signals=sig, metrics=pd.Series({"b": 2.0, "a": 1.0 / 7.0}), meta={"seed": 1, "status": "ok"},
                     scenario={"name": "x", "duration": "1 s"})


def test_to_csv_writes_every_run_folder_file_with_fixed_float_format(tmp_path):
    out = _result().to_csv(tmp_path / "run")
    for name in ["scenario.yaml", "signals.csv", "jobs.csv", "messages.csv", "metrics.csv", "meta.json"]:
        assert (out / name).exists(), name
    text = (out / "signals.csv").read_text()
    assert text.splitlines()[0] == "time_s,y"
    assert "3.141592653589793" in text  # repr: the shortest text that reads back as the same float
    assert (out / "metrics.csv").read_text().splitlines()[0] == "metric,value"


def test_writing_twice_is_byte_identical_and_reads_back(tmp_path):
    a = _result().to_csv(tmp_path / "a")
    b = _result().to_csv(tmp_path / "b")
    for name in ["signals.csv", "jobs.csv", "messages.csv", "metrics.csv"]:
        assert (a / name).read_bytes() == (b / name).read_bytes()
    back = RunResult.read(a)
    assert back.metrics["b"] == 2.0
    assert back.signals["y"].tolist()[2] == np.pi  # exactly (issue 21: %.12g moved it by 2e-12)
