"""The two ``set_period`` rules (issue 26 section 7): ``next_release`` (TrueTime 1.5, the default) moves the
release already scheduled to one new period after the last release; ``keep_armed`` (TrueTime 2.0's
``ttSetPeriod``) keeps it. Release times below are worked out by hand in the comments."""

from __future__ import annotations

import pytest

import netsim
from netsim.env import SimEnv
from netsim.errors import SimulationError
from netsim.kernel import Kernel
from netsim.kernel.task import TaskSpec
from netsim.timebase import MS


def _body(job):
    yield job.execute(MS)


def _releases(rule: str | None, new_ms: int, *, call_rule: str | None = None) -> list[int]:
    env = SimEnv(seed=0)
    k = Kernel(env, "n", policy="fp")
    fields = {} if rule is None else {"set_period": rule}
    k.add_task(TaskSpec("a", period=10 * MS, priority=1, **fields), _body)
    env.run(12 * MS)  # a released at 0 and 10 ms; the release at 20 ms is armed
    k.set_period("a", new_ms * MS, call_rule)
    env.run(80 * MS)
    return sorted(r.release // MS for r in k.job_records if r.task == "a")


@pytest.mark.parametrize(("rule", "new_ms", "expected"), [
    # shorter period 4 ms set at 12 ms: next_release -> 10 + 4 = 14, then every 4 ms
    ("next_release", 4, [0, 10, 14, 18, 22, 26, 30, 34, 38, 42, 46, 50, 54, 58, 62, 66, 70, 74, 78]),
    # keep_armed -> the armed 20 ms stays, then 24, 28, ... every 4 ms
    ("keep_armed", 4, [0, 10, 20, 24, 28, 32, 36, 40, 44, 48, 52, 56, 60, 64, 68, 72, 76, 80]),
    # longer period 25 ms: next_release -> 10 + 25 = 35, 60; keep_armed -> 20, 45, 70
    ("next_release", 25, [0, 10, 35, 60]),
    ("keep_armed", 25, [0, 10, 20, 45, 70]),
    # no rule given: the default is next_release (the behaviour before the option existed)
    (None, 25, [0, 10, 35, 60]),
])
def test_set_period_rule_decides_what_happens_to_the_armed_release(rule, new_ms, expected):
    assert _releases(rule, new_ms) == expected


def test_the_calls_rule_overrides_the_tasks():
    # the task says next_release, the call keep_armed: 20 (armed), 45, 70 as above
    assert _releases("next_release", 25, call_rule="keep_armed") == [0, 10, 20, 45, 70]
    with pytest.raises(SimulationError, match="rule must be one of next_release, keep_armed"):
        _releases(None, 25, call_rule="soon")


def test_an_unknown_rule_is_refused_when_the_task_is_added():
    k = Kernel(SimEnv(seed=0), "n", policy="fp")
    with pytest.raises(Exception, match="set_period"):
        k.add_task(TaskSpec("a", period=10 * MS, priority=1, set_period="later"), _body)


def _pid1_releases_ms(rule: str | None) -> list[float]:
    overrides = {"duration": "120 ms"}
    if rule is not None:
        overrides["nodes.cpu.tasks[1].set_period"] = rule
    jobs = netsim.run("scenarios/feedback_scheduling.yaml", write=False, overrides=overrides).jobs
    return [round(v * 1e3, 6) for v in jobs[jobs.task == "pid1"]["release_s"].sort_values()]


def test_the_yaml_field_reaches_the_feedback_schedulers_period_changes():
    # pid1 (period 6 ms) is released at 0, 6, ..., 48 ms and its release at 54 ms is armed when the scheduler
    # (released at 50 ms) sets its new period p. keep_armed: 54 stays, then 54 + p. next_release: 48 + p.
    armed = _pid1_releases_ms("keep_armed")
    moved = _pid1_releases_ms(None)
    assert armed[:9] == moved[:9] == [6.0 * i for i in range(9)]
    p = armed[10] - armed[9]
    assert p != 6.0  # the scheduler did change the period (else this test shows nothing)
    assert armed[9] == 54.0
    assert moved[9] == pytest.approx(max(50.0, 48.0 + p), abs=1e-6)


def test_the_default_rule_leaves_the_resolved_scenario_as_it_was():
    from netsim.scenario.loader import load_scenario, resolved_dict

    task = resolved_dict(load_scenario("scenarios/feedback_scheduling.yaml"))["nodes"]["cpu"]["tasks"][1]
    assert "set_period" not in task  # dumped (and hashed) as before the field existed
    task = resolved_dict(load_scenario("scenarios/feedback_scheduling.yaml",
                                       {"nodes.cpu.tasks[1].set_period": "keep_armed"}))["nodes"]["cpu"]["tasks"][1]
    assert task["set_period"] == "keep_armed"
