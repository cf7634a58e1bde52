"""netsim.analysis.from_scenario: the one mapping of a scenario's tasks to the analysis' RTATask."""

from __future__ import annotations

from netsim.analysis.from_scenario import ISR_PRIORITY, message_period, node_tasks, response_bounds, wcet_ns
from netsim.analysis.rta import RTATask
from netsim.scenario import load_scenario
from netsim.timebase import MS, US


def _scenario():
    return load_scenario({"name": "map", "duration": "1 s", "nodes": {"cpu": {
        "policy": "fp", "context_switch": "10 us",
        "tasks": [
            {"name": "ctl", "program": "idle", "period": "10 ms", "priority": 1,
             "execution": {"dist": "uniform", "low": "1 ms", "high": "2 ms"},
             "release_jitter": {"dist": "uniform", "low": "0 ms", "high": "0.5 ms"}},
            {"name": "spo", "program": "idle", "min_interarrival": "20 ms", "priority": 2, "execution": "3 ms"},
            {"name": "bg", "program": "idle", "release": "aperiodic", "priority": 3, "execution": "1 ms"},
        ],
        "handlers": [{"name": "isr", "program": "idle", "latency": "5 us", "execution": "20 us",
                      "trigger": {"timer": {"period": "1 ms"}}}],
    }}})


def test_tasks_map_to_rta_tasks_at_their_largest_execution_and_jitter():
    node = _scenario().nodes["cpu"]
    mapped = node_tasks(node, {}, lambda name: 50 * MS if name == "bg" else None)
    by_name = {it.name: it for it in mapped.items}
    # C = upper end of the execution + two context switches; J = upper end of the jitter (module notes)
    assert by_name["ctl"] == RTATask("ctl", 2 * MS + 20 * US, 10 * MS, deadline=10 * MS, priority=1.0,
                                     jitter=500 * US)
    assert by_name["spo"] == RTATask("spo", 3 * MS + 20 * US, 20 * MS, deadline=20 * MS, priority=2.0)
    assert by_name["bg"].period == 50 * MS  # released by program code: the run's shortest gap
    assert by_name["isr"] == RTATask("isr", 25 * US, 1 * MS, priority=ISR_PRIORITY)  # latency + execution
    assert mapped.skipped == [] and mapped.how == "FP RTA"


def test_an_unbounded_execution_time_gets_no_bound():
    sc = _scenario()
    assert wcet_ns(sc.nodes["cpu"].tasks[0]) == 2 * MS  # uniform: its high end
    normal = type(sc.nodes["cpu"].tasks[0]).model_validate({
        "name": "n", "program": "idle", "period": "10 ms",
        "execution": {"dist": "normal", "mean": "1 ms", "std": "0.1 ms"}})
    assert wcet_ns(normal) is None


def test_response_bounds_and_message_periods():
    items = [RTATask("a", 1 * MS, 4 * MS, priority=1), RTATask("b", 2 * MS, 8 * MS, priority=2)]
    # preemptive FP: R_a = 1 ms, R_b = 2 + ceil(R_b / 4) * 1 = 3 ms. Non-preemptive (Davis et al. 2007, the CAN
    # recurrence): a is blocked by b's whole 2 ms, R_a = 2 + 1 = 3 ms; b queues behind one job of a, w_b = 1 ms,
    # R_b = 1 + 2 = 3 ms
    assert response_bounds("fp", items) == {"a": 1 * MS, "b": 3 * MS}
    assert response_bounds("np_fp", items) == {"a": 3 * MS, "b": 3 * MS}
    node = _scenario().nodes["cpu"]
    assert message_period(node, "can", 1, {}, "cpu") == (None, 0, "event-driven: T = shortest gap in the run")
