"""Runtime metrics on hand-made tables: IAE/ISE of held signals, deadline misses, chain latency."""

import math

import numpy as np
import pandas as pd
import pytest

from netsim.kernel.records import deadline_verdict
from netsim.errors import ConfigError
from netsim.results import RunResult, jobs_table, messages_table, signals_table
from netsim.metrics.runtime import chain_latencies, control_error, generic_metrics, latency
from netsim.timebase import MS
from types import SimpleNamespace as NS


def test_control_error_integrates_held_values_exactly():
    # r = 1 held from 0; y = 0 on [0, 1 ms), 0.5 on [1 ms, 3 ms), 1 from 3 ms; run ends at 4 ms
    sig = signals_table({"r": [0], "y": [0, MS, 3 * MS, 4 * MS]}, {"r": [1.0], "y": [0.0, 0.5, 1.0, 1.0]})
    res = RunResult(signals=sig, meta={"t_end_s": 0.004})
    m = control_error(res, {"reference": "r", "output": "y"})
    # IAE = 1*1ms + 0.5*2ms = 2 ms; ISE = 1*1ms + 0.25*2ms = 1.5 ms
    assert m["y.IAE"] == pytest.approx(0.002)
    assert m["y.ISE"] == pytest.approx(0.0015)
    assert m["y.max_abs_error"] == 1.0
    with pytest.raises(ConfigError, match="not recorded"):
        control_error(res, {"reference": "r", "output": "nope"})


def _job(node, task, jid, rel, st, fin, dl, t_end=20 * MS):
    # deadline_met as the kernel records it at the end of a run that stopped at t_end (one rule for all tables)
    return NS(node=node, task=task, job_id=jid, release=rel, start=st, finish=fin, response=None if fin is None else fin - rel,
              deadline=dl, deadline_met=deadline_verdict(dl, fin, False, t_end), preemptions=0, cpu_time=0, killed=False)


def test_generic_task_metrics_count_misses_including_unfinished_overdue_jobs():
    jobs = jobs_table([
        _job("n", "a", 0, 0, 0, 2 * MS, 4 * MS),
        _job("n", "a", 1, 4 * MS, 4 * MS, 9 * MS, 8 * MS),   # late
        _job("n", "a", 2, 8 * MS, None, None, 12 * MS),       # unfinished, deadline passed by 20 ms
    ])
    res = RunResult(jobs=jobs)
    m = generic_metrics(res, None, 20 * MS)
    assert m["task.n.a.deadline_misses"] == 2
    assert m["task.n.a.max_response_s"] == pytest.approx(0.005)
    assert m["task.n.a.jobs"] == 3


def _msg(i, s, r, sent, deliv):
    return NS(msg_id=i, network="can", sender=s, receiver=r, tag="", bits=80, priority=0, sent_ns=sent,
              tx_start_ns=sent, tx_end_ns=deliv, delivered_ns=deliv, dropped=False, drop_reason="", delay_ns=deliv - sent)


def test_chain_latency_follows_messages_back_to_the_sampling_job():
    us = 1000
    jobs = jobs_table([
        _job("s", "sample", 0, 0, 0, 900 * us, 10 * MS),
        _job("c", "ctl", 0, 1500 * us, 1500 * us, 2000 * us, 10 * MS),
        _job("a", "act", 0, 3000 * us, 3000 * us, 3500 * us, 10 * MS),
        _job("s", "sample", 1, 10 * MS, 10 * MS, 10 * MS + 900 * us, 20 * MS),
    ])
    msgs = messages_table([_msg(0, "s", "c", 500 * us, 1500 * us), _msg(1, "c", "a", 2000 * us, 3000 * us)])
    lat = chain_latencies(jobs, msgs, ["s.sample", "c.ctl", "a.act"])
    # 0.5 + 1 + 0.5 + 1 + 0.5 ms
    assert lat == [pytest.approx(0.0035)]
    m = latency(RunResult(jobs=jobs, messages=msgs), {"chain": ["s.sample", "c.ctl", "a.act"]})
    assert m["latency.count"] == 1 and m["latency.max_s"] == pytest.approx(0.0035)
    assert generic_metrics(RunResult(jobs=jobs, messages=msgs), None, 20 * MS)["net.can.mean_delay_s"] == pytest.approx(0.001)


def test_chain_latency_is_exact_in_nanoseconds_away_from_time_zero():
    # the same chain as above shifted to t = 1 s: in float seconds 1.0035 - 1.0 = 0.0035000000000000586, in
    # integer ns it is 3_500_000 ns -> 0.0035 exactly (the float nearest to 3.5 ms, i.e. 3_500_000 / 1e9)
    us, t0 = 1000, 1_000_000_000
    jobs = jobs_table([
        _job("s", "sample", 0, t0, t0, t0 + 900 * us, t0 + 10 * MS),
        _job("c", "ctl", 0, t0 + 1500 * us, t0 + 1500 * us, t0 + 2000 * us, t0 + 10 * MS),
        _job("a", "act", 0, t0 + 3000 * us, t0 + 3000 * us, t0 + 3500 * us, t0 + 10 * MS),
    ])
    msgs = messages_table([_msg(0, "s", "c", t0 + 500 * us, t0 + 1500 * us),
                           _msg(1, "c", "a", t0 + 2000 * us, t0 + 3000 * us)])
    chain = ["s.sample", "c.ctl", "a.act"]
    assert chain_latencies(jobs, msgs, chain) == [0.0035]
    m = latency(RunResult(jobs=jobs, messages=msgs), {"chain": chain})
    assert m["latency.min_s"] == 0.0035 and m["latency.max_s"] == 0.0035 and m["latency.mean_s"] == 0.0035


def test_a_network_whose_own_metrics_fail_is_reported_not_hidden(caplog):
    import types

    import pandas as pd

    class Broken:
        def metrics(self, t_end_ns):
            raise ZeroDivisionError("division by zero")

    result = types.SimpleNamespace(
        signals=pd.DataFrame({"time_s": [0.0, 1.0]}),
        jobs=pd.DataFrame(columns=["node", "task", "cpu_time_s"]),
        messages=pd.DataFrame(columns=["network", "sender", "receiver", "sent_s", "delivered_s", "dropped"]),
    )
    sim = types.SimpleNamespace(kernels={}, networks={"bus": Broken()})
    with caplog.at_level("WARNING", logger="netsim"):
        out = generic_metrics(result, sim, 1_000_000_000)
    assert not any(k.startswith("net.bus.") and k.endswith("attempts") for k in out)
    assert "network 'bus'" in caplog.text and "ZeroDivisionError" in caplog.text
