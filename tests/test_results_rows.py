"""The jobs and messages tables straight from the records (issue 19): the same DataFrame, CSV bytes and metrics
as the pandas path (jobs_table / messages_table, sorted, written by write_csv)."""

from __future__ import annotations

import math
import random
from pathlib import Path

import pandas as pd
import pytest

from netsim.kernel.records import JobRecord
from netsim.metrics.rows import network_metrics_rows as _network_metrics_rows
from netsim.metrics.rows import task_metrics_rows as _task_metrics_rows
from netsim.metrics.runtime import _network_metrics, _task_metrics
from netsim.network.records import MessageRecord
from netsim.results import jobs_table, messages_table, write_csv
from netsim.results.rows import Column, job_rows, message_rows


def _jobs(rng: random.Random, node: str, n: int) -> list[JobRecord]:
    out = []
    for k in range(n):
        release = rng.choice([0, 1_000_000_000, 2_000_000_000]) + rng.randrange(0, 3) * 500_000
        start = None if rng.random() < 0.1 else release + rng.randrange(0, 10**6)
        finish = None if start is None or rng.random() < 0.1 else start + rng.randrange(1, 10**7)
        killed = finish is not None and rng.random() < 0.1
        deadline = None if rng.random() < 0.3 else release + 5_000_000
        if killed:
            met = False
        elif finish is None:
            met = rng.choice([None, False])
        else:
            met = True if deadline is None else finish <= deadline
        out.append(JobRecord(task=rng.choice(["a", "b", "ctl"]), node=rng.choice([node, None]), job_id=k,
                             release=release, start=start, finish=finish,
                             response=None if finish is None or killed else finish - release, deadline=deadline,
                             deadline_met=met, preemptions=rng.randrange(0, 3), cpu_time=rng.randrange(0, 10**6),
                             killed=killed))
    return out


def _messages(rng: random.Random, net: str, n: int) -> list[MessageRecord]:
    out = []
    for k in range(n):
        sent = rng.randrange(0, 3 * 10**9)
        dropped = rng.random() < 0.2
        delivered = None if dropped or rng.random() < 0.1 else sent + rng.randrange(1, 10**7)
        for receiver in rng.choice([["c"], ["c", "a"], [None]]):
            out.append(MessageRecord(msg_id=rng.randrange(0, n // 2 + 1), network=net, sender="s", receiver=receiver,
                                     tag=rng.choice(["y", "u", ""]), bits=64, priority=rng.randrange(0, 4),
                                     sent_ns=sent, tx_start_ns=None if dropped else sent + 10,
                                     tx_end_ns=None if dropped else sent + 20, delivered_ns=delivered,
                                     dropped=dropped, drop_reason="lost" if dropped else "", delay_ns=None))
    return out


def _pandas_jobs(kernels: list[tuple[str, list[JobRecord]]]) -> pd.DataFrame:
    frame = pd.concat([jobs_table(recs, name) for name, recs in kernels], ignore_index=True)
    return frame.sort_values(["release_s", "node", "task", "job_id"], kind="stable").reset_index(drop=True)


def _pandas_messages(networks: list[list[MessageRecord]]) -> pd.DataFrame:
    frame = pd.concat([messages_table(recs) for recs in networks], ignore_index=True)
    return frame.sort_values(["msg_id", "network", "receiver"], kind="stable").reset_index(drop=True)


def _csv(rows, path: Path) -> bytes:
    chunks = rows.csv_chunks(chunk_rows=7)  # several chunks
    assert chunks is not None
    path.write_text("".join(chunks), encoding="utf-8")
    return path.read_bytes()


def _frame_csv(frame: pd.DataFrame, path: Path) -> bytes:
    write_csv(frame, path)
    return path.read_bytes()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_jobs_from_records_equal_the_pandas_table(tmp_path: Path, seed: int) -> None:
    rng = random.Random(seed)
    kernels = [("n2", _jobs(rng, "n2", 40)), ("n1", _jobs(rng, "n1", 35))]
    rows = job_rows(kernels)
    expected = _pandas_jobs(kernels)
    pd.testing.assert_frame_equal(rows.frame(), expected)
    assert _csv(rows, tmp_path / "a.csv") == _frame_csv(expected, tmp_path / "b.csv")
    assert _task_metrics_rows(rows) == pytest.approx(_task_metrics(expected, 3.0), rel=0, abs=0, nan_ok=True)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_messages_from_records_equal_the_pandas_table(tmp_path: Path, seed: int) -> None:
    rng = random.Random(seed)
    networks = [_messages(rng, "can", 50), _messages(rng, "eth", 30)]
    rows = message_rows(networks)
    expected = _pandas_messages(networks)
    pd.testing.assert_frame_equal(rows.frame(), expected)
    assert _csv(rows, tmp_path / "a.csv") == _frame_csv(expected, tmp_path / "b.csv")
    got, want = _network_metrics_rows(rows), _network_metrics(expected)
    assert list(got) == list(want)
    for key in want:  # bit-equal: the same sums in the same order
        assert got[key] == want[key] or (math.isnan(got[key]) and math.isnan(want[key])), key


def test_a_value_its_column_kind_does_not_expect_goes_through_pandas(tmp_path: Path) -> None:
    rng = random.Random(5)
    recs = _messages(rng, "can", 6)
    recs[2].tag = "a,b"  # needs quoting: written by pandas' csv writer
    assert message_rows([recs]).csv_chunks() is None
    recs[2].tag = "y"
    recs[3].priority = None  # None among whole numbers: pandas makes the column float
    assert message_rows([recs]).csv_chunks() is None
    recs[3].priority = 1
    assert message_rows([recs]).csv_chunks() is not None


def test_empty_tables_have_every_column(tmp_path: Path) -> None:
    rows = job_rows([("n", [])])
    assert len(rows) == 0
    assert list(rows.frame().columns) == list(jobs_table([]).columns)
    assert _csv(rows, tmp_path / "a.csv") == _frame_csv(jobs_table([]), tmp_path / "b.csv")
    assert _csv(message_rows([]), tmp_path / "c.csv") == _frame_csv(messages_table([]), tmp_path / "d.csv")


def test_an_extra_job_column_comes_before_outcome() -> None:
    recs = [{**{f: getattr(r, f) for f in ("task", "node", "job_id", "release", "start", "finish", "response",
                                           "deadline", "deadline_met", "preemptions", "cpu_time", "killed")},
             "late": None} for r in _jobs(random.Random(3), "n", 5)]
    recs[1]["late"] = 1_500_000_000
    rows = job_rows([("n", recs)], extra=(Column("arrival_s", "late", "time"),))
    assert rows.columns[-2:] == ["arrival_s", "outcome"]
    assert rows.frame()["arrival_s"].isna().sum() == 4
    assert 1.5 in list(rows.frame()["arrival_s"])


def test_run_writes_the_tables_from_the_records_and_builds_frames_when_read(tmp_path: Path) -> None:
    import netsim
    from netsim.results import Lazy

    root = Path(__file__).resolve().parents[1]
    res = netsim.run(root / "scenarios" / "dc_servo_can.yaml", out=tmp_path / "run")
    assert type(object.__getattribute__(res, "jobs")) is Lazy  # the metrics read a view: nothing built here
    assert type(object.__getattribute__(res, "messages")) is Lazy
    jobs, messages = res.jobs, res.messages  # built now
    assert (tmp_path / "run" / "jobs.csv").read_bytes() == _frame_csv(jobs, tmp_path / "j.csv")
    assert (tmp_path / "run" / "messages.csv").read_bytes() == _frame_csv(messages, tmp_path / "m.csv")
    assert res.metrics["net.can.messages"] == len(messages)
