"""Malformed input to the issue-20 features (mobility paths, a feedback scheduler's tasks, output channels, sync
declarations): ``netsim validate`` refuses it at its YAML path with a fix, never crashes, and refuses what
``netsim run`` refuses (issue 14's standard). Each case was found by fuzzing the scenarios wireless_battery,
feedback_scheduling and sync_servo (h14f)."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import pytest

from netsim.errors import NetsimError
from netsim.network.mobility import Motion, Track
from netsim.scenario import check_scenario, load_scenario
from netsim.scenario.loader import read_yaml
from netsim.timebase import S

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"


def _raw(name: str) -> dict[str, Any]:
    raw, _ = read_yaml(SCENARIOS / name)
    return copy.deepcopy(raw)


def _errors(raw: dict[str, Any]) -> dict[str, str]:
    return {p.path: p.message for p in check_scenario(raw) if p.severity == "error"}


# ------------------------------------------------------------------------------------------------- mobility
MOBILE = "networks.bus.mobility.sensor.path"


def _with_path(path: Any) -> dict[str, Any]:
    raw = _raw("wireless_battery.yaml")
    raw["networks"]["bus"]["mobility"]["sensor"]["path"] = path
    return raw


def test_two_waypoints_at_the_same_time_are_refused() -> None:
    """'1 s' and '1000 ms' are one instant: one waypoint silently replaced the other before."""
    errors = _errors(_with_path({"1 s": [0, 0], "1000 ms": [5, 0], "8 s": [-350, 0]}))
    assert MOBILE in errors and "same time" in errors[MOBILE] and "remove one" in errors[MOBILE]


@pytest.mark.parametrize(("path", "words"), [
    ({"-1 s": [0, 0]}, "negative"),              # was "invalid name '-1 s'" (a time key read as a name)
    ({"1e30 s": [0, 0]}, "beyond"),
    ({"8 s": [1]}, "expected [x, y]"),           # was at 'path.8 s[1]', a path no line can be found for
    ({"8 s": [1, "abc"]}, "expected [x, y]"),
    ({"8 s": "here"}, "expected [x, y]"),
])
def test_a_bad_waypoint_is_named_at_the_path_key(path: dict[str, Any], words: str) -> None:
    errors = _errors(_with_path(path))
    assert list(errors) == [MOBILE], errors
    assert "waypoint" in errors[MOBILE] and words in errors[MOBILE]


def test_a_good_path_reads_as_before() -> None:
    """Waypoints out of order are sorted; the track interpolates between them (10 m in 1 s: 5 m at 0.5 s)."""
    motion = Motion.model_validate({"path": {"2 s": [10, 0], "1 s": [0, 10]}})
    assert list(motion.path) == [1 * S, 2 * S]
    assert Track((0.0, 0.0), motion).at(S + S // 2) == (5.0, 5.0)


# ---------------------------------------------------------------------------------------- feedback scheduler
def test_a_scheduler_listing_itself_is_refused_by_validate() -> None:
    """run refused it ('is the scheduler itself') after validate had said valid."""
    raw = _raw("feedback_scheduling.yaml")
    raw["nodes"]["cpu"]["tasks"][0]["params"]["tasks"] = ["scheduler"]
    errors = _errors(raw)
    at = "nodes.cpu.tasks[0].params.tasks[0]"
    assert at in errors and "remove it" in errors[at]
    with pytest.raises(NetsimError):  # loading refuses it as validate does
        load_scenario(raw)


def test_a_task_name_that_is_a_mapping_does_not_crash_validate() -> None:
    """A mapping as a task's name made the scheduler's task check raise TypeError (unhashable dict)."""
    raw = _raw("feedback_scheduling.yaml")
    raw["nodes"]["cpu"]["tasks"][1]["name"] = {"a": 1}
    errors = _errors(raw)
    assert "nodes.cpu.tasks[1].name" in errors


@pytest.mark.parametrize(("edit", "at", "fix"), [
    (lambda t: t[0]["params"].update(tasks=["pid1", "pid1"]), "nodes.cpu.tasks[0].params", "remove the repeats"),
    (lambda t: t[1].pop("period"), "nodes.cpu.tasks[0].params.tasks[0]", "give it a period"),
])
def test_the_tasks_messages_say_what_to_change(edit: Any, at: str, fix: str) -> None:
    raw = _raw("feedback_scheduling.yaml")
    edit(raw["nodes"]["cpu"]["tasks"])
    errors = _errors(raw)
    assert at in errors and fix in errors[at]


# ------------------------------------------------------------------------------------------ output channels
def test_an_output_channel_that_is_not_a_dac_is_refused_by_validate() -> None:
    """mailbox_controller writing to the adc 'y': validate said valid and run failed ('no analog output')."""
    raw = _raw("sync_servo.yaml")
    raw["nodes"]["computer"]["tasks"][0]["params"]["output_channel"] = "y"
    errors = _errors(raw)
    at = "nodes.computer.tasks[0].params.output_channel"
    assert at in errors and "dac" in errors[at] and "use one of the dac channels (u)" in errors[at]


# ---------------------------------------------------------------------------------------- sync declarations
@pytest.mark.parametrize(("edit", "at", "fix"), [
    (lambda s: s.update(semaphores={"s": {"count": 2, "maximum": 1}}), "nodes.computer.sync.semaphores.s",
     "raise 'maximum' or lower 'count'"),
    (lambda s: s["monitors"].update(other={"protocol": "ceiling"}), "nodes.computer.sync.monitors.other.users",
     "add it to the parameters"),
])
def test_the_sync_messages_say_what_to_change(edit: Any, at: str, fix: str) -> None:
    raw = _raw("sync_servo.yaml")
    edit(raw["nodes"]["computer"]["sync"])
    errors = _errors(raw)
    assert at in errors and fix in errors[at]


# ------------------------------------------------------------------------------------- arrival distributions
JITTER = "nodes.computer.tasks[0].release_jitter"


@pytest.mark.parametrize(("value", "at", "words"), [
    ("-1 ms", f"{JITTER}.value", "must not be negative"),              # was at '.constant.value'
    ({"dist": "uniform", "low": "0 ms"}, f"{JITTER}.high", "add 'high: ...'"),  # was '.uniform.high'
    ({"dist": "constant", "value": "1 ms", "x": 1}, f"{JITTER}.x", "known keys: dist, value"),  # no hint before
    ({"value": "1 ms"}, JITTER, "missing required key 'dist'"),        # was "unable to extract tag"
    ({"dist": "gauss"}, f"{JITTER}.dist", "unknown distribution 'gauss'"),
    ([1], JITTER, "expected a time such as '1 ms'"),
])
def test_a_bad_time_distribution_is_named_at_its_yaml_path(value: Any, at: str, words: str) -> None:
    raw = _raw("sync_servo.yaml")
    raw["nodes"]["computer"]["tasks"][0]["release_jitter"] = value
    errors = _errors(raw)
    assert at in errors and words in errors[at], errors


def test_the_distribution_tags_use_the_schema_s_tag_mark() -> None:
    """schema_task cannot import schema (which imports it); the mark messages strip must be the same one."""
    from netsim.scenario import schema, schema_task

    assert schema_task._TAG == schema.TAG_MARK
