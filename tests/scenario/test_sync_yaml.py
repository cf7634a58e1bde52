"""Mailboxes, semaphores, events and monitors declared per node in YAML (nodes.<n>.sync), issue 20."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from netsim.kernel.node_sync import MailboxName
from netsim.registry import register
from netsim.runner import simulate
from netsim.scenario import check_scenario, load_scenario
from netsim.build.builder import build
from netsim.scenario.loader import read_yaml

from netsim.units import StrictModel

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "sync_servo.yaml"


def _raw() -> dict[str, Any]:
    raw, _ = read_yaml(SCENARIO)
    return raw


def _errors(raw: dict[str, Any]) -> dict[str, str]:
    return {p.path: p.message for p in check_scenario(raw) if p.severity == "error"}


def _worst(protocol: str) -> dict[str, int]:
    sc = load_scenario(SCENARIO, {"nodes.computer.sync.monitors.state.protocol": protocol, "duration": "0.2 s"})
    result, _, failure = simulate(sc)
    assert failure is None
    jobs = result.jobs
    return {t: round(jobs[jobs.task == t].response_s.max() * 1e9) for t in ("controller", "logger")}


def test_the_objects_are_created_on_the_kernel() -> None:
    sim = build(load_scenario(SCENARIO))
    sync = sim.kernels["computer"].sync
    assert sync.mailbox("samples").capacity == 1
    mon = sync.monitor("state")
    assert mon.protocol == "inherit" and set(mon.users) == {"controller", "logger"}  # the tasks naming it


def test_inheritance_bounds_the_controller_response() -> None:
    """The scenario's comment: 3.5 ms with inheritance (B = the logger's 2 ms left + 1 ms of its own + 0.5 ms
    waiting for the sample), 7.5 ms without (the background task's 4 ms more), 3.5 ms with the ceiling."""
    assert _worst("inherit")["controller"] == 3_500_000
    assert _worst("none")["controller"] == 7_500_000
    assert _worst("ceiling")["controller"] == 3_500_000


def test_validate_checks_every_name_a_program_uses() -> None:
    raw = _raw()
    raw["nodes"]["computer"]["tasks"][0]["params"]["mailbox"] = "sample"
    raw["nodes"]["computer"]["tasks"][3]["params"]["monitor"] = "stat"
    errors = _errors(raw)
    assert errors["nodes.computer.tasks[0].params.mailbox"] == (
        "node 'computer' has no mailbox 'sample' (its mailboxes: samples); did you mean 'samples'?; declare it "
        "under nodes.computer.sync.mailboxes")
    assert "no monitor 'stat' (its monitors: state); did you mean 'state'?" in errors[
        "nodes.computer.tasks[3].params.monitor"]
    raw = _raw()
    raw["nodes"]["computer"]["tasks"][2]["params"]["wait_event"] = "go"
    assert _errors(raw) == {"nodes.computer.tasks[2].params.wait_event": (
        "node 'computer' has no event 'go' (it declares no events); declare it under nodes.computer.sync.events")}
    raw["nodes"]["computer"]["sync"]["events"] = {"go": None}  # a name with nothing after it: the defaults
    assert _errors(raw) == {}


def test_the_sync_section_is_validated_with_paths() -> None:
    raw = _raw()
    raw["nodes"]["computer"]["sync"]["semaphores"] = {"s": {"count": 2, "maximum": 1}}
    raw["nodes"]["computer"]["sync"]["mailboxes"]["samples"]["capacity"] = 0
    errors = _errors(raw)
    assert any(p.startswith("nodes.computer.sync.semaphores.s") and "below the initial count" in m
               for p, m in errors.items()), errors
    assert any(p.startswith("nodes.computer.sync.mailboxes.samples.capacity") for p in errors), errors
    raw = _raw()
    raw["nodes"]["computer"]["sync"]["monitors"]["state"] = {"protocol": "pcp"}
    assert any(p.startswith("nodes.computer.sync.monitors.state.protocol") for p in _errors(raw))


def test_a_handler_cannot_use_a_monitor() -> None:
    raw = _raw()
    raw["nodes"]["computer"]["handlers"] = [{"name": "isr", "program": "critical_section",
                                             "params": {"monitor": "state", "inside": "1 us"},
                                             "trigger": {"timer": {"period": "10 ms"}}}]
    assert _errors(raw) == {"nodes.computer.handlers[0].params.monitor": (
        "monitor 'state': an interrupt handler cannot wait for a monitor (the kernel refuses its enter); use it "
        "from a task")}


def test_a_ceiling_needs_a_static_policy_and_known_users() -> None:
    raw = _raw()
    raw["nodes"]["computer"]["policy"] = "edf"
    raw["nodes"]["computer"]["sync"]["monitors"]["state"]["protocol"] = "ceiling"
    for t in raw["nodes"]["computer"]["tasks"]:
        t.pop("priority")
    errors = _errors(raw)
    assert "needs a static-priority policy" in errors["nodes.computer.sync.monitors.state.protocol"]
    raw = _raw()
    raw["nodes"]["computer"]["sync"]["monitors"]["state"]["users"] = ["loger"]
    assert _errors(raw) == {"nodes.computer.sync.monitors.state.users": (
        "monitor 'state': user 'loger' is not a task of this node; did you mean 'logger'?")}


def test_nodes_without_sync_dump_as_before() -> None:
    from netsim.scenario.loader import resolved_dict

    sc = load_scenario(SCENARIO.with_name("dc_servo_ideal.yaml"))
    assert "sync" not in resolved_dict(sc)["nodes"]["computer"]
    assert "sync" in resolved_dict(load_scenario(SCENARIO))["nodes"]["computer"]


@register("program", "zzt_sync_plugin_consumer", "test: a plugin program that fetches from a named mailbox")
class _PluginConsumer:
    class Params(StrictModel):
        inbox: MailboxName | None = None
        more: list[MailboxName] = []

    def __init__(self, ctx: Any, params: Any) -> None:
        self.mb = ctx.kernel.sync.mailbox(params.inbox)

    def __call__(self, job: Any) -> Any:
        item = yield job.try_fetch(self.mb)
        job.shared.setdefault("got", []).append(item)


def test_plugin_programs_name_sync_objects_too() -> None:
    raw = _raw()
    raw["nodes"]["computer"]["tasks"].append({"name": "plug", "program": "zzt_sync_plugin_consumer",
                                              "params": {"inbox": "samples", "more": ["samples", "extra"]},
                                              "period": "10 ms", "priority": 5})
    assert _errors(raw) == {"nodes.computer.tasks[4].params.more[1]": (
        "node 'computer' has no mailbox 'extra' (its mailboxes: samples); declare it under "
        "nodes.computer.sync.mailboxes")}
    raw["nodes"]["computer"]["tasks"][-1]["params"]["more"] = []
    sc = load_scenario(raw)
    assert sc.nodes["computer"].tasks[-1].validated_params().inbox == "samples"
    sim = build(sc)
    assert sim.kernels["computer"].sync.mailbox("samples") is sim.programs["computer.plug"].mb



def test_events_and_semaphores_from_yaml_at_run_time() -> None:
    """waiter (prio 1, released at 0) waits for 'go'; notifier (prio 2, at 2 ms) executes 0.5 ms and notifies at
    2.5 ms; the waiter then executes 1 ms: finish 3.5 ms. 'slot' (count 1) guards 2 ms of a and b (prio 3, 4; b
    released first at 4 ms, a at 5 ms): a waits for b's give at 6 ms (b runs 4-6 inside), runs 6-8: response 3 ms."""
    raw = _raw()
    node = raw["nodes"]["computer"]
    node["sync"] = {"events": {"go": None}, "semaphores": {"slot": {"count": 1, "maximum": 1}}}
    node["tasks"] = [
        {"name": "waiter", "program": "critical_section", "period": "20 ms", "priority": 1,
         "params": {"wait_event": "go", "before": "1 ms"}},
        {"name": "notifier", "program": "critical_section", "period": "20 ms", "offset": "2 ms", "priority": 2,
         "params": {"notify_event": "go", "before": "0.5 ms"}},
        {"name": "a", "program": "critical_section", "period": "20 ms", "offset": "5 ms", "priority": 3,
         "params": {"semaphore": "slot", "inside": "2 ms"}},
        {"name": "b", "program": "critical_section", "period": "20 ms", "offset": "4 ms", "priority": 4,
         "params": {"semaphore": "slot", "inside": "2 ms"}}]
    raw["metrics"] = []
    result, _, failure = simulate(load_scenario(raw, {"duration": "0.1 s"}))
    assert failure is None
    jobs = result.jobs
    worst = {t: round(jobs[jobs.task == t].response_s.max() * 1e9) for t in ("waiter", "a", "b")}
    assert worst == {"waiter": 3_500_000, "a": 3_000_000, "b": 2_000_000}


def test_the_editor_schema_accepts_an_empty_entry_and_flags_a_typo() -> None:
    """`netsim schema`: `go:` (null, the defaults) is accepted as the loader accepts it; a misspelt key is not."""
    from netsim.cli.docs import json_schema
    from tests.cli.test_docs_and_schema import _problems  # the suite's minimal JSON Schema checker

    schema = json_schema()
    raw = _raw()
    raw["nodes"]["computer"]["sync"]["events"] = {"go": None}
    assert _problems(raw, schema, schema) == []
    raw["nodes"]["computer"]["sync"]["mailboxes"]["samples"]["capacty"] = 1
    assert _problems(raw, schema, schema) == [".nodes.computer.sync.mailboxes.samples.capacty: not allowed"]
