"""The cart's 100 kHz encoder ISR: exact encoder + periodic load against the polling ISR (the faithful model)."""

from __future__ import annotations

import copy
from pathlib import Path

import pytest
import yaml

from netsim.analysis.rta import RTATask, response_times
from netsim.errors import BuildError, NetsimError
from netsim.timebase import MS, US

SCENARIO = Path(__file__).resolve().parents[3] / "scenarios" / "cart.yaml"
TICK, ISR_EXEC, CTRL_EXEC, PERIOD = 10 * US, 2 * US, 100 * US, 1 * MS  # from scenarios/cart.yaml


def _raw(mode: str, duration: str, isr_load: bool = True) -> dict:
    raw = yaml.safe_load(SCENARIO.read_text())
    raw["duration"] = duration
    raw["io"]["enc"]["mode"] = mode
    isr = raw["nodes"]["cart"]["handlers"][0]
    if mode == "polling":
        isr["trigger"] = {"timer": {"period": "10 us"}}
    else:
        isr["params"]["isr_load"] = isr_load
    return raw


def _simulate(raw: dict):
    from netsim.registry import load_plugins
    from netsim.scenario import build

    load_plugins()
    sim = build(copy.deepcopy(raw))
    sim.run()
    return sim


@pytest.fixture(scope="module")
def runs():
    # 0.2 s: 20 000 ISR ticks in polling mode (about a second of wall time), 200 control periods with edges
    return {name: _simulate(_raw(mode, "0.2 s", load)) for name, mode, load in
            (("polling", "polling", True), ("exact", "exact", True), ("edges_only", "exact", False))}


def _records(sim) -> list[tuple]:
    return [(r.task, r.job_id, r.release, r.start, r.finish, r.response, r.preemptions, r.cpu_time)
            for r in sim.kernels["cart"].job_records]


def _edges(sim) -> list[tuple[float, int]]:
    rec = sim.env.recorder
    return list(zip(rec.values["cart.count"], rec.times["cart.count"]))


def test_exact_encoder_with_isr_load_gives_the_polling_controller_jobs(runs):
    polling, exact = runs["polling"], runs["exact"]
    assert _records(exact) == _records(polling)
    # the (count, stamp) edge sequence the ISR stored, and what the controller computed from it
    edges = _edges(polling)
    assert len(edges) > 20
    assert _edges(exact) == edges
    rec_p, rec_e = polling.env.recorder, exact.env.recorder
    assert rec_e.values["cart.uV"] == rec_p.values["cart.uV"]
    assert rec_e.times["cart.uV"] == rec_p.times["cart.uV"]
    # the exact model ran the ISR only at the edge ticks
    k_e, k_p = exact.kernels["cart"], polling.kernels["cart"]
    assert k_e.handlers["isr"].invocations == len(edges) - 1  # minus the initial count, recorded at build
    assert k_p.handlers["isr"].invocations == 20_001  # every tick of [0, 0.2 s]


def test_isr_load_cpu_and_utilization_equal_the_polling_isr(runs):
    k_p, k_e = runs["polling"].kernels["cart"], runs["exact"].kernels["cart"]
    assert k_e.cpu_time == k_p.cpu_time
    # derived: 20 000 ticks before 0.2 s x 2 us for the ISR; 200 jobs x 100 us for the controller
    assert k_e.cpu_time == {"isr": 20_000 * ISR_EXEC, "control": 200 * CTRL_EXEC}
    # utilization = 2/10 + 100/1000 = 0.3, identical in both models (windows count as busy time)
    assert k_e.utilization() == pytest.approx(k_p.utilization(), abs=1e-12)
    assert k_e.utilization() == pytest.approx(ISR_EXEC / TICK + CTRL_EXEC / PERIOD, abs=1e-12)


def test_controller_response_includes_isr_interference_as_rta(runs):
    # Release on a tick (critical instant): RTA with the ISR as the top-priority task, w = 100 + ceil(w/10) * 2
    # -> 126 us. Without the load (edges only) the response is 100 us except at edge ticks.
    rta = response_times([RTATask("isr", ISR_EXEC, TICK, priority=0), RTATask("control", CTRL_EXEC, PERIOD, priority=1)])
    assert rta["control"] == 126 * US
    done = [r for r in runs["exact"].kernels["cart"].job_records if r.finish is not None]
    assert {r.response for r in done} == {rta["control"]}
    assert {r.start - r.release for r in done} == {ISR_EXEC}  # the ISR's window at the release tick
    old = [r.response for r in runs["edges_only"].kernels["cart"].job_records if r.finish is not None]
    assert min(old) == CTRL_EXEC and max(old) <= CTRL_EXEC + ISR_EXEC
    assert runs["edges_only"].kernels["cart"].utilization() < 0.11


def test_isr_load_needs_a_constant_execution_time():
    raw = _raw("exact", "0.01 s")
    raw["nodes"]["cart"]["handlers"][0]["execution"] = {"dist": "uniform", "low": "1 us", "high": "3 us"}
    with pytest.raises((BuildError, NetsimError), match="constant"):
        _simulate(raw)
