"""The ``latency`` metric with the jobs/messages tables not kept (issue 31 fault 6): streamed while the run goes
(netsim.metrics.chain), in bounded memory, with the numbers the whole tables give.

Before, a run with ``output.jobs`` or ``output.messages`` at ``summary`` refused the latency metric ("reads the
jobs table row by row ... set output.jobs: full"). The reference numbers are the full-mode metric: the walk over
the whole tables, whose values tests/test_runtime_metrics.py checks against hand-computed chains.
"""

from __future__ import annotations

import copy
import logging
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest
import yaml

import netsim
import netsim.metrics.chain as chain_module
from netsim.metrics.chain import ChainLatencyStream

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "dc_servo_can.yaml"


def _raw(after_send: str | None = None) -> dict[str, Any]:
    """dc_servo_can for 4 s with interference share 0.6: the CAN frames wait, the latencies vary (3.5 to 28 ms)."""
    raw = yaml.safe_load(SCENARIO.read_text())
    raw["duration"] = "4 s"
    raw["nodes"]["interference"]["tasks"][0]["params"]["share"] = 0.6
    if after_send is not None:
        raw["nodes"]["sensor"]["tasks"][0]["params"]["after_send"] = after_send
    return raw


def _latency(raw: dict[str, Any], jobs: str, messages: str) -> dict[str, float]:
    raw = copy.deepcopy(raw)
    raw["output"] = {"jobs": jobs, "messages": messages}
    result = netsim.run(raw, write=False)
    return {k: float(v) for k, v in result.metrics.items() if k.startswith("latency.")}


@pytest.fixture(scope="module")
def full() -> dict[str, float]:
    values = _latency(_raw(), "full", "full")
    assert values["latency.count"] == 400 and values["latency.max_s"] > 2 * values["latency.min_s"]  # they vary
    return values


@pytest.mark.parametrize(("jobs", "messages"), [("summary", "summary"), ("full", "summary"), ("summary", "full"),
                                                ("off", "off")])
def test_latency_streamed_equals_the_full_tables(full, jobs, messages) -> None:
    assert _latency(_raw(), jobs, messages) == full


def test_small_windows_and_batches_give_the_same_numbers(full, monkeypatch) -> None:
    """Batches of 3 jobs against windows of 8 records: the windows are trimmed hundreds of times."""
    monkeypatch.setattr(chain_module, "BATCH", 3)
    monkeypatch.setattr(chain_module, "KEEP", 8)
    assert _latency(_raw(), "summary", "summary") == full


def test_a_sender_job_still_running_defers_the_chain(monkeypatch) -> None:
    """The sensor works 7 ms after sending: the actuator's job ends while the sensor job that sent the sample still
    runs. Resolved at once (a batch of one), the walk would miss that job (count 108 instead of 400 before the
    deferral was written); deferred, it matches the whole tables."""
    raw = _raw(after_send="7 ms")
    want = _latency(raw, "full", "full")
    monkeypatch.setattr(chain_module, "BATCH", 1)
    assert _latency(raw, "summary", "summary") == want
    assert want["latency.count"] == 400


# ---------------------------------------------------------------------------------------- synthetic records
MS = 1_000_000


def _job(node: str, task: str, job_id: int, release: int, start: int | None, finish: int | None) -> Any:
    return SimpleNamespace(node=node, task=task, job_id=job_id, release=release, start=start, finish=finish)


def _message(sender: str, receiver: str, sent: int, delivered: int) -> Any:
    return SimpleNamespace(sender=sender, receiver=receiver, sent_ns=sent, delivered_ns=delivered, dropped=False)


def _feed_loop(stream: ChainLatencyStream, periods: int) -> int:
    """A 1 ms loop, in the order a run makes the records: sensor job k runs 0.1 ms and sends at its end
    (delivered 0.2 ms later), the controller (on message) 0.2 ms and sends (delivered 0.1 ms later), the actuator
    0.1 ms: every latency is 0.7 ms by construction. Returns the largest number of records the stream held."""
    held = 0
    for k in range(periods):
        t = k * MS
        stream.job(_job("sensor", "sample", k, t, t, t + MS // 10))
        stream.message(_message("sensor", "controller", t + MS // 10, t + 3 * MS // 10))
        stream.job(_job("controller", "control", k, t + 3 * MS // 10, t + 3 * MS // 10, t + 5 * MS // 10))
        stream.message(_message("controller", "actuator", t + 5 * MS // 10, t + 6 * MS // 10))
        stream.job(_job("actuator", "actuate", k, t + 6 * MS // 10, t + 6 * MS // 10, t + 7 * MS // 10))
        held = max(held, sum(len(w.items) for w in (*stream._jobs, *stream._msgs)) + len(stream._pending))
    return held


def test_the_stream_holds_a_bounded_number_of_records(monkeypatch) -> None:
    monkeypatch.setattr(chain_module, "BATCH", 50)
    monkeypatch.setattr(chain_module, "KEEP", 100)
    stream = ChainLatencyStream([("sensor", "sample"), ("controller", "control"), ("actuator", "actuate")], "lat")
    held = _feed_loop(stream, 5000)
    # two job windows and two message windows of at most KEEP + BATCH each, and fewer than BATCH pending jobs
    assert held <= 4 * (100 + 50) + 50
    got = stream.metrics()
    assert got == {"lat.mean_s": 0.0007, "lat.max_s": 0.0007, "lat.min_s": 0.0007, "lat.count": 5000.0}


def test_a_chain_reaching_back_past_the_window_is_reported_not_guessed(monkeypatch, caplog) -> None:
    """One sample sent at t = 0 and never again: every later actuator job walks back to sensor job 0. Once that job
    has left the window (KEEP = 4 sensor jobs), its chains are counted as beyond the window, with a warning, and
    left out of the statistics; the ones resolved before are counted (0.5 ms + k ms each)."""
    monkeypatch.setattr(chain_module, "BATCH", 2)
    monkeypatch.setattr(chain_module, "KEEP", 4)
    stream = ChainLatencyStream([("sensor", "sample"), ("actuator", "actuate")], "lat")
    stream.message(_message("sensor", "actuator", MS // 10, 2 * MS // 10))
    for k in range(20):
        t = k * MS
        stream.job(_job("sensor", "sample", k, t, t, t + MS // 10))
        stream.job(_job("actuator", "actuate", k, t + 3 * MS // 10, t + 3 * MS // 10, t + 5 * MS // 10))
    with caplog.at_level(logging.WARNING, logger="netsim.metrics.chain"):
        got = stream.metrics()
    assert got["lat.count"] + got["lat.beyond_window"] == 20
    assert got["lat.beyond_window"] > 0 and "reach back past" in caplog.text
    n = int(got["lat.count"])  # the first n actuator jobs, k = 0 .. n-1: latency k ms + 0.5 ms from sensor job 0
    assert got["lat.min_s"] == 0.0005 and got["lat.max_s"] == pytest.approx((n - 1) * 1e-3 + 0.0005, abs=1e-15)


def test_a_sender_that_stopped_does_not_keep_jobs_pending(monkeypatch) -> None:
    """The sensor sends once, at the end of its only job, and never runs again (a node out of battery); the
    actuator keeps running on that sample. With the kernels saying no sensor job runs, every actuator job is
    resolved in its batch (without them, each would wait for a sensor job that never ends: pending would grow
    with the run)."""
    monkeypatch.setattr(chain_module, "BATCH", 10)
    stream = ChainLatencyStream([("sensor", "sample"), ("actuator", "actuate")], "lat")
    stream.active = lambda node, task: None
    stream.job(_job("sensor", "sample", 0, 0, 0, MS // 10))
    stream.message(_message("sensor", "actuator", MS // 10, 2 * MS // 10))
    for k in range(1000):
        t = k * MS + 3 * MS // 10
        stream.job(_job("actuator", "actuate", k, t, t, t + MS // 10))
        assert len(stream._pending) < 10
    got = stream.metrics()
    assert got["lat.count"] == 1000 and got["lat.min_s"] == 0.0004  # actuator job 0 ends at 0.4 ms
