"""Release jitter and sporadic tasks in the analysis (issue 20): the RTA bound ``R = J + w`` from the nominal
release and the sporadic minimum inter-arrival, against the simulated worst case of the same task set."""

from __future__ import annotations

import pytest

import netsim
from netsim.analysis.rta import RTATask, edf_demand, edf_schedulable, response_times
from netsim.cli.analyze import analyze_run
from netsim.scenario import load_scenario

MS = 1_000_000


def test_jitter_of_a_higher_priority_task_lengthens_the_lower_bound_by_hand():
    # a: C = 2, T = 10, J = 4; b: C = 7, T = 30.  R_a = J + C = 6.
    # b: w = 7 + ceil((w + 4) / 10) * 2: 7 -> 11 -> 11 (without the jitter: 7 -> 9 -> 9).
    a, b = RTATask("a", 2 * MS, 10 * MS, jitter=4 * MS), RTATask("b", 7 * MS, 30 * MS)
    assert response_times([a, b]) == {"a": 6 * MS, "b": 11 * MS}
    assert response_times([RTATask("a", 2 * MS, 10 * MS), b]) == {"a": 2 * MS, "b": 9 * MS}


def test_edf_demand_counts_a_jittered_deadline_from_the_latest_arrival():
    # D = 5, J = 2: the first job is due 3 after its latest arrival, so dbf(3) = C
    t = RTATask("a", 1 * MS, 10 * MS, deadline=5 * MS, jitter=2 * MS)
    assert (edf_demand([t], 3 * MS - 1), edf_demand([t], 3 * MS)) == (0, 1 * MS)
    # two tasks of demand 3 each due at 3 (after the jitter) overflow; without jitter they are due at 5 and fit
    x = [RTATask("a", 3 * MS, 20 * MS, deadline=5 * MS, jitter=2 * MS),
         RTATask("b", 3 * MS, 20 * MS, deadline=5 * MS, jitter=2 * MS)]
    y = [RTATask("a", 3 * MS, 20 * MS, deadline=6 * MS), RTATask("b", 3 * MS, 20 * MS, deadline=6 * MS)]
    assert (edf_schedulable(x), edf_schedulable(y)) == (False, True)


def _scenario(b_task: dict, a_jitter: object = None, policy: str = "fp", duration: str = "3 s"):
    a = {"name": "a", "program": "idle", "priority": 1, "period": "10 ms", "execution": "2 ms"}
    if a_jitter is not None:
        a["release_jitter"] = a_jitter
    b = {"name": "b", "program": "idle", "priority": 2, "execution": "7 ms", **b_task}
    return load_scenario({"name": "rta_jitter", "duration": duration, "seed": 4,
                          "nodes": {"cpu": {"policy": policy, "tasks": [a, b]}}})


def _table(scenario):
    result = netsim.run(scenario)
    return analyze_run(scenario, result).set_index(["kind", "name"]), result


def test_the_jitter_bound_is_reached_by_the_simulated_worst_case():
    # a's jobs arrive 0 or 4 ms after their nominal release (each 1/2); b is released at 3 ms (+ 30 ms k). When
    # a's job at 30k arrives at 30k + 4 and the next at 30k + 10, b runs 3-4, 6-10, 12-14: R_b = 11 ms, the bound.
    sc = _scenario({"period": "30 ms", "offset": "3 ms"}, {"dist": "empirical", "values": ["0 ms", "4 ms"]})
    table, _ = _table(sc)
    a, b = table.loc[("task", "cpu.a")], table.loc[("task", "cpu.b")]
    assert (a["analysis"], b["analysis"]) == (pytest.approx(6.0), pytest.approx(11.0))
    assert (a["simulated"], b["simulated"]) == (pytest.approx(6.0), pytest.approx(11.0))
    assert a["verdict"] == b["verdict"] == "ok"
    assert "R = J + w from the nominal release (J = 4 ms" in a["note"]


def test_a_sporadic_task_enters_with_its_minimum_inter_arrival():
    sc = _scenario({"min_interarrival": "25 ms", "extra_interarrival": {"dist": "exponential", "mean": "5 ms"}})
    table, result = _table(sc)
    b = table.loc[("task", "cpu.b")]
    # w = 7 + ceil(w / 10) * 2: 7 -> 9 -> 9 (T_b plays no part in b's own bound; D = 25 ms by default)
    assert b["analysis"] == pytest.approx(9.0) and b["simulated"] <= 9.0 + 1e-9 and b["verdict"] == "ok"
    assert "sporadic: T = min_interarrival (25 ms)" in b["note"]
    rel = result.jobs[result.jobs.task == "b"].release_s.to_numpy()
    assert len(rel) > 50 and (rel[1:] - rel[:-1]).min() >= 0.025


def test_a_sporadic_task_loads_the_tasks_below_it_at_its_minimum_rate():
    # b (sporadic, priority 1 here) above c: c's bound counts b every 25 ms, and the run stays within it
    sc = load_scenario({"name": "rta_sporadic", "duration": "3 s", "seed": 2, "nodes": {"cpu": {"policy": "rm",
        "tasks": [{"name": "b", "program": "idle", "min_interarrival": "25 ms", "execution": "7 ms",
                   "extra_interarrival": {"dist": "uniform", "low": "0 ms", "high": "2 ms"}},
                  {"name": "c", "program": "idle", "period": "40 ms", "execution": "10 ms",
                   "release_jitter": {"dist": "uniform", "low": "0 ms", "high": "3 ms"}}]}}})
    table, _ = _table(sc)
    c = table.loc[("task", "cpu.c")]
    # w = 10 + ceil(w / 25) * 7: 17 -> 17; R = J + w = 3 + 17 = 20 ms (from c's nominal release)
    assert c["analysis"] == pytest.approx(20.0)
    assert c["simulated"] <= 20.0 + 1e-9 and c["verdict"] == "ok"


def test_an_unbounded_jitter_gets_no_bound():
    sc = _scenario({"period": "30 ms"}, {"dist": "exponential", "mean": "1 ms"}, duration="200 ms")
    table, _ = _table(sc)
    assert table.loc[("task", "cpu.a"), "analysis"] == "n/a"
    assert "release jitter unbounded" in table.loc[("task", "cpu.a"), "note"]
