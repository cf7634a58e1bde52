"""Servers (nodes.<n>.servers, tasks[].server) and time-triggered tables (nodes.<n>.timetable) in YAML, issue 30:
each bad input is one problem at its YAML path, and netsim validate refuses what run refuses."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import pytest

from netsim.build.builder import build
from netsim.runner import simulate
from netsim.scenario import check_scenario, load_scenario
from netsim.scenario.loader import read_yaml

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"


def _raw(name: str) -> dict[str, Any]:
    raw, _ = read_yaml(SCENARIOS / f"{name}.yaml")
    return copy.deepcopy(raw)


def _errors(raw: dict[str, Any]) -> dict[str, str]:
    return {p.path: p.message for p in check_scenario(raw) if p.severity == "error"}


def test_the_shipped_scenarios_are_valid_and_build_their_server_and_table() -> None:
    assert _errors(_raw("three_servos_cbs")) == {}
    assert _errors(_raw("dc_servo_timetable")) == {}
    cpu = build(load_scenario(SCENARIOS / "three_servos_cbs.yaml")).kernels["cpu"]
    srv = cpu.servers["cbs"]
    assert (srv.budget, srv.period, srv.hard, [t.name for t in srv.tasks]) == (1_000_000, 4_000_000, False, ["pid3"])
    ecu = build(load_scenario(SCENARIOS / "dc_servo_timetable.yaml")).kernels["ecu"]
    assert [(s.start, s.task, s.length) for s in ecu.timetable.slots] == [
        (0, "pid", 2_000_000), (4_000_000, "diag", 2_000_000)]


def test_the_cbs_scenario_keeps_the_other_loops_on_time() -> None:
    # the scenario's header: pid1 and pid2 (U = 0.733) with the server's 0.25 fit in 1, so under EDF they never
    # miss, whatever pid3 does; pid3 (2 ms per 4 ms, 1 ms of budget) misses
    sc = load_scenario(SCENARIOS / "three_servos_cbs.yaml", {"duration": "0.5 s"})
    result, _, failure = simulate(sc)
    assert failure is None
    jobs = result.jobs
    done = jobs[jobs.finish_s.notna()]
    for task in ("pid1", "pid2"):
        assert done[done.task == task].deadline_met.all()
    assert not done[done.task == "pid3"].deadline_met.all()


def _set(raw: dict[str, Any], node: str, **fields: Any) -> dict[str, Any]:
    raw["nodes"][node].update(fields)
    return raw


@pytest.mark.parametrize("change, path, words", [
    # a server on a node whose policy is not EDF
    (lambda r: _set(r, "cpu", policy="dm"), "nodes.cpu.servers[0]", "needs policy 'edf'"),
    # a task naming an unknown server
    (lambda r: r["nodes"]["cpu"]["tasks"][2].update(server="cbz"), "nodes.cpu.tasks[2].server",
     "unknown server 'cbz'; did you mean 'cbs'"),
    # a bandwidth above 1
    (lambda r: r["nodes"]["cpu"]["servers"][0].update(budget="5 ms"), "nodes.cpu.servers[0]", "exceeds 1"),
    # a negative budget
    (lambda r: r["nodes"]["cpu"]["servers"][0].update(budget="-1 ms"), "nodes.cpu.servers[0].budget", "negative"),
    # a TBS above the CPU
    (lambda r: r["nodes"]["cpu"]["servers"].__setitem__(0, {"name": "cbs", "type": "tbs", "utilization": 1.5}),
     "nodes.cpu.servers[0]", "exceeds 1"),
    # two servers over the CPU together
    (lambda r: r["nodes"]["cpu"]["servers"].append({"name": "more", "type": "cbs", "budget": "4 ms",
                                                   "period": "4 ms"}),
     "nodes.cpu.servers[1]", "above the CPU"),
])
def test_a_bad_server_is_one_problem_at_its_path(change: Any, path: str, words: str) -> None:
    raw = _raw("three_servos_cbs")
    change(raw)
    errors = _errors(raw)
    assert list(errors) == [path], errors
    assert words in errors[path]


def _slot(raw: dict[str, Any], i: int, **fields: Any) -> dict[str, Any]:
    raw["nodes"]["ecu"]["timetable"]["slots"][i].update(fields)
    return raw


@pytest.mark.parametrize("change, path, words", [
    (lambda r: _slot(r, 1, start="9 ms"), "nodes.ecu.timetable.slots[1].length", "after the cycle's end"),
    (lambda r: _slot(r, 1, start="1 ms"), "nodes.ecu.timetable.slots[1].start", "overlaps the slot of 'pid'"),
    # (diag released by program code, so that only the slot's typo is at fault)
    (lambda r: _slot(r, 1, task="diagg") and r["nodes"]["ecu"]["tasks"][1].update(release="aperiodic"),
     "nodes.ecu.timetable.slots[1].task", "did you mean 'diag'"),
    (lambda r: r["nodes"]["ecu"]["tasks"][0].update(wcet="3 ms"), "nodes.ecu.timetable.slots[0].length",
     "shorter than the task's wcet"),
    (lambda r: r["nodes"]["ecu"].pop("timetable") and r["nodes"]["ecu"]["tasks"][0].update(release="aperiodic")
     or r["nodes"]["ecu"]["tasks"][1].update(release="aperiodic"), "nodes.ecu.timetable", "needs a schedule table"),
    (lambda r: _set(r, "ecu", policy="edf"), "nodes.ecu.timetable", "needs policy 'tt'"),
])
def test_a_table_that_does_not_fit_is_one_problem_at_its_path(change: Any, path: str, words: str) -> None:
    raw = _raw("dc_servo_timetable")
    change(raw)
    errors = _errors(raw)
    assert list(errors) == [path], errors
    assert words in errors[path]


def test_a_scenario_without_servers_resolves_as_before() -> None:
    data = load_scenario(SCENARIOS / "three_servos_edf.yaml").resolved_dict()
    node = data["nodes"]["cpu"]
    assert "servers" not in node and "timetable" not in node
    assert all("server" not in task for task in node["tasks"])
    served = load_scenario(SCENARIOS / "three_servos_cbs.yaml").resolved_dict()["nodes"]["cpu"]
    assert served["servers"][0]["name"] == "cbs" and served["tasks"][2]["server"] == "cbs"
