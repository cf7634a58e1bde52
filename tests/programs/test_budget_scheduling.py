"""The budget_scheduler program (netsim.programs.budget_scheduling): a CBS's budget set at run time from YAML,
checked against budgets worked out by hand."""

from __future__ import annotations

import copy
from typing import Any

import netsim
from netsim.build.builder import build
from netsim.scenario import load_scenario

SCENARIO: dict[str, Any] = {
    "name": "budget_scheduler_check",
    "duration": "0.1 s",
    "nodes": {
        "cpu": {
            "policy": "edf",
            "servers": [{"name": "cbs", "type": "cbs", "budget": "1 ms", "period": "4 ms"}],
            "tasks": [
                # demand 2 ms per 4 ms in a soft CBS of 1 ms per 4 ms
                {"name": "greedy", "program": "idle", "period": "4 ms", "execution": "2 ms", "server": "cbs"},
                # a short deadline: under EDF it runs first at each release (0, 20, 40 ms), in zero time
                {"name": "tuner", "program": "budget_scheduler", "period": "20 ms", "deadline": "1 ms",
                 "params": {"server": "cbs", "margin": 0.2, "step": 0.5}},
            ],
        },
    },
}


def test_the_budget_follows_what_the_served_task_needs():
    sim = build(load_scenario(copy.deepcopy(SCENARIO)))
    sim.run(21_000_000)
    srv = sim.kernels["cpu"].servers["cbs"]
    # t = 20 ms: greedy is alone on the CPU and a soft CBS lets it run on with a postponed deadline, so it got its
    # 2 ms of every 4 ms: used = 10 ms in 20 ms, bandwidth 0.5; the budget ran out (1 ms < 2 ms per job), so
    # 0.5 * (1 + step 0.5) = 0.75 of the 4 ms period: Qs = 3 ms.
    assert sim.programs["cpu.tuner"].budgets == [(20_000_000, 3_000_000)]
    assert (srv.budget, srv.period) == (3_000_000, 4_000_000)


def test_a_run_records_the_budget_it_sets():
    result = netsim.run(copy.deepcopy(SCENARIO))
    assert result.status == "ok"
    budget = result.signal("budget_ms")
    assert float(budget.iloc[0]) == 3.0


def _problems(raw: dict[str, Any]) -> list[tuple[str, str]]:
    from netsim.scenario.loader import check_scenario

    return [(p.path, p.message) for p in check_scenario(raw) if p.severity == "error"]


def test_validate_refuses_a_server_the_node_does_not_have_at_its_yaml_path():
    # before: the name was looked up at the tuner's first job only, so validate passed and the run failed
    raw = copy.deepcopy(SCENARIO)
    raw["nodes"]["cpu"]["tasks"][1]["params"]["server"] = "cbz"
    errs = _problems(raw)
    assert len(errs) == 1
    path, message = errs[0]
    assert path == "nodes.cpu.tasks[1].params.server"
    assert "no server 'cbz'" in message and "(cbs)" in message


def test_validate_refuses_a_tbs_named_as_the_budget_schedulers_server():
    raw = copy.deepcopy(SCENARIO)
    raw["nodes"]["cpu"]["servers"].append({"name": "tb", "type": "tbs", "utilization": 0.1})
    raw["nodes"]["cpu"]["tasks"][1]["params"]["server"] = "tb"
    assert _problems(raw) == [("nodes.cpu.tasks[1].params.server",
                               "server 'tb' is a tbs, not a cbs; name a cbs of nodes.cpu.servers (cbs)")]


def test_validate_passes_the_shipped_form():
    assert _problems(copy.deepcopy(SCENARIO)) == []
