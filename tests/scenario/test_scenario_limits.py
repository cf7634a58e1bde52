"""Limits of a scenario: absurd times and numbers, long and empty names, empty lists, duplicates, run size."""

from __future__ import annotations

import math

import pytest
import yaml

from netsim.scenario import check_scenario
from netsim.scenario.limits import EVENTS_WARN, NAME_MAX, expected_events
from netsim.timebase import MAX_TIME, S, TimeParseError, parse_time
from netsim.units import NUMBER_LIMIT


def _errors(raw):
    return {p.path: p.message for p in check_scenario(raw) if p.is_error}


def _warnings(raw):
    return {p.path: p.message for p in check_scenario(raw) if not p.is_error}


@pytest.mark.parametrize("text", ["3e10 s", "1e300 s", "1e20 ns", "99999999999999999999 s", "1e999999999 s",
                                  "1000000000.000000001 s", "-2e9 s"])
def test_times_beyond_the_limit_are_refused_with_the_limit(text):
    with pytest.raises(TimeParseError, match=r"beyond netsim's limit of 1e9 s .*write a shorter time"):
        parse_time(text, allow_negative=True)


def test_the_time_limit_itself_is_accepted():
    # MAX_TIME is 10**18 ns = 1e9 s exactly (documented in netsim.timebase)
    assert MAX_TIME == 10**18
    assert parse_time("1e9 s") == 10**18 and parse_time("1000000000 s") == MAX_TIME


def test_absurd_duration_and_period_are_refused_at_their_paths(base):
    raw = base()
    raw["duration"] = "1e300 s"
    raw["nodes"]["sensor"]["tasks"][0]["period"] = "1e20 ns"
    errors = _errors(raw)
    assert "beyond netsim's limit" in errors["duration"]
    assert "beyond netsim's limit" in errors["nodes.sensor.tasks[0].period"]


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf, 1e308, 10**30])
def test_non_finite_and_huge_numbers_are_refused_everywhere(base, bad):
    """Typed fields (signal value), untyped plugin parameters (plant gain) and list items (x0)."""
    raw = base()
    raw["plant"]["params"]["gain"] = bad
    raw["plant"]["x0"] = [0.0, bad]
    raw["signals"]["r"]["value"] = bad
    errors = _errors(raw)
    for path in ("plant.params.gain", "plant.x0[1]", "signals.r.value"):
        assert path in errors, (path, errors)
    assert f"{NUMBER_LIMIT:g}" in errors["plant.params.gain"]  # the message gives the valid range


def test_nan_written_as_text_is_refused_by_float_fields(base):
    """YAML reads a plain ``nan`` as the text 'nan'; pydantic would turn it into a float NaN."""
    raw = base()
    raw["signals"]["r"]["value"] = "nan"
    assert "signals.r.value" in _errors(raw)


def test_numbers_at_the_limit_are_fine(base):
    raw = base()
    raw["plant"]["params"]["gain"] = NUMBER_LIMIT
    assert _errors(raw) == {}


def test_a_huge_seed_is_an_identifier_not_a_quantity(base):
    raw = base()
    raw["seed"] = 2**80
    assert "seed" not in _errors(raw)


def test_a_million_character_name_is_refused_at_validate_with_a_short_message(base):
    raw = base()
    long = "n" * 10**6
    raw["nodes"][long] = raw["nodes"].pop("actuator")
    raw["name"] = "s" * 10**6
    problems = [p for p in check_scenario(raw) if p.is_error]
    by_path = {p.path: p.message for p in problems}
    assert f"at most {NAME_MAX} characters" in by_path["nodes"] and "1000000 characters" in by_path["nodes"]
    assert f"at most {NAME_MAX} characters" in by_path["name"]  # the schema's limit (MAX_NAME_LENGTH)
    # nothing echoes the name whole (the old "known nodes" list did)
    assert max(len(str(p)) for p in problems) < 1000


def test_a_name_of_the_limit_is_fine(base):
    raw = base()
    raw["nodes"]["sensor"]["tasks"][0]["name"] = "t" * NAME_MAX
    assert _errors(raw) == {}
    raw["nodes"]["sensor"]["tasks"][0]["name"] = "t" * (NAME_MAX + 1)
    assert list(_errors(raw)) == ["nodes.sensor.tasks[0].name"]


def test_empty_nodes_is_refused(base):
    raw = base()
    raw["nodes"] = {}
    raw["networks"] = {}
    raw["io"] = {}
    raw["metrics"] = []
    assert "is empty" in _errors(raw)["nodes"]


def test_empty_task_list_without_handlers_is_refused_and_an_idle_node_warns(base):
    raw = base()
    raw["nodes"]["sensor"]["tasks"] = []
    assert "empty 'tasks' list" in _errors(raw)["nodes.sensor.tasks"]
    raw = base()
    raw["nodes"]["idle"] = {"policy": "fp"}
    assert _errors(raw) == {}
    assert "runs no task and no handler" in _warnings(raw)["nodes.idle"]


def test_duplicate_task_names_name_the_first_definition_with_its_line(tmp_path, base):
    raw = base()
    raw["nodes"]["sensor"]["tasks"].append(dict(raw["nodes"]["sensor"]["tasks"][0]))
    path = tmp_path / "dup.yaml"
    with open(path, "w") as fh:
        yaml.safe_dump(raw, fh)  # keys sorted: each task starts with its execution
    lines = path.read_text().splitlines()
    first = next(i for i, ln in enumerate(lines, 1) if ln.strip() == "- execution: 0.5 ms")  # tasks[0] starts here
    (dup,) = [p for p in check_scenario(path) if p.is_error]
    assert dup.path == "nodes.sensor.tasks[1].name"
    assert f"first defined at nodes.sensor.tasks[0], line {first}" in dup.message


def test_duplicate_node_keys_are_refused_with_their_line(tmp_path):
    path = tmp_path / "dupnode.yaml"
    path.write_text("name: d\nduration: 1 s\nnodes:\n  a: {tasks: []}\n  a: {tasks: []}\n")
    (p,) = check_scenario(path)
    assert p.line == 5 and "duplicate key" in p.message
    assert p.path == "nodes.a"  # the second key (before: no path, the reader places refusals by line only)


def test_a_refusal_the_reader_places_by_line_gets_the_path_of_that_line(tmp_path):
    from netsim.scenario.messages import path_at_line

    path = tmp_path / "tag.yaml"
    path.write_text("name: t\nduration: 1 s\nnodes:\n  a:\n    tasks:\n      - !!python/object:os.system x\n")
    (p,) = check_scenario(path)
    assert (p.path, p.line) == ("nodes.a.tasks[0]", 6) and "is not allowed" in p.message
    assert path_at_line(str(path), 4) == "nodes.a" and path_at_line(str(path), 99) == ""


def test_duplicate_task_names_name_the_first_definition(base):
    raw = base()
    raw["nodes"]["sensor"]["tasks"].append(dict(raw["nodes"]["sensor"]["tasks"][0]))
    assert _errors(raw) == {"nodes.sensor.tasks[1].name": "duplicate name 'sample' on node 'sensor': first defined at "
                            "nodes.sensor.tasks[0]; task and handler names must be unique per node: rename one"}


def test_check_raw_gives_the_line_of_the_first_definition_when_it_can(base):
    from netsim.scenario.validate import check_raw

    raw = base()
    raw["nodes"]["sensor"]["tasks"].append(dict(raw["nodes"]["sensor"]["tasks"][0]))
    lines = {"nodes.sensor.tasks[0]": 17}
    problems, _ = check_raw(raw, lines.get)
    assert [p.message for p in problems if p.path == "nodes.sensor.tasks[1].name"] == [
        "duplicate name 'sample' on node 'sensor': first defined at nodes.sensor.tasks[0], line 17; task and "
        "handler names must be unique per node: rename one"]


def test_expected_event_count_warns_with_the_estimate(base, monkeypatch):
    monkeypatch.setenv("NETSIM_MEMORY_BUDGET", "0")  # no memory budget: 1e8 job rows kept would be refused (issue 31)
    raw = base()
    raw["duration"] = "1000 s"
    raw["nodes"]["sensor"]["tasks"][0]["period"] = "10 us"
    total, parts = expected_events(raw)
    # 1000 s / 10 us = 1e8 jobs of the sampler (the only periodic item of the base scenario)
    assert total == pytest.approx(1000 * S / 10_000) and total > EVENTS_WARN
    assert parts[0][0] == "nodes.sensor.tasks[0].period"
    warning = _warnings(raw)["duration"]
    assert "1e+08 events" in warning and "shorten 'duration'" in warning
    assert _errors(raw) == {}


def test_the_base_scenario_does_not_warn_about_its_size(base):
    assert "duration" not in _warnings(base())


def _write_with_long_integer(tmp_path, base, where):
    """``base()`` as a YAML file with a 5000-digit integer (more than Python reads from text) at ``where``."""
    raw = base()
    node = raw
    for part in where[:-1]:
        node = node[part]
    node[where[-1]] = "LONG_INTEGER"
    path = tmp_path / "long.yaml"
    with open(path, "w") as fh:
        yaml.safe_dump(raw, fh)
    text = path.read_text()
    path.write_text(text.replace("LONG_INTEGER", "9" * 5000))
    line = next(i for i, ln in enumerate(text.splitlines(), 1) if "LONG_INTEGER" in ln)
    return path, line


@pytest.mark.parametrize("where", [("plant", "params", "gain"), ("io", "y", "output"),
                                  ("networks", "bus", "min_frame_bits")])
def test_an_integer_with_more_digits_than_python_reads_is_refused_at_its_path_and_line(tmp_path, base, where):
    """Before: the file's name only ('YAML value cannot be read (ValueError: Exceeds the limit (4300 digits)'),
    and a traceback from the io check once the integer was read. One message: the other checks' views of the same
    unusable value are dropped (Problem.supersedes)."""
    path, line = _write_with_long_integer(tmp_path, base, where)
    (p,) = check_scenario(path)
    assert p.path == ".".join(where) and p.line == line
    assert "over 4000 digits" in p.message and "write a smaller value" in p.message
    assert len(str(p)) < 300


def test_a_seed_with_5000_digits_is_refused_at_its_path(tmp_path, base):
    path, line = _write_with_long_integer(tmp_path, base, ("seed",))
    (p,) = check_scenario(path)
    assert (p.path, p.line) == ("seed", line) and "between 0 and 2^128 - 1" in p.message


def test_a_seed_is_below_2_to_the_128(base):
    raw = base()
    raw["seed"] = 2**128 - 1  # the largest seed (limits.SEED_LIMIT - 1)
    assert _errors(raw) == {}
    raw["seed"] = 2**128
    assert "between 0 and 2^128 - 1" in _errors(raw)["seed"]


def test_a_refused_number_is_the_only_message_at_its_path(base):
    """NaN in a typed field: the limit's message, not also the schema's view of the same value."""
    raw = base()
    raw["signals"]["r"]["value"] = math.nan
    problems = [p for p in check_scenario(raw) if p.path == "signals.r.value"]
    assert [p.message.split(";")[0] for p in problems] == ["NaN is not a usable number"]


def test_a_container_s_complaint_about_the_same_non_finite_number_is_dropped():
    """``plant.A: A contains NaN or infinite entries`` (the ss plant's own check, no fix) beside the limit's message
    at ``plant.A[1][0]``: only the precise one stays; another problem of the container stays too."""
    from netsim.scenario.problems import Problem, sort_problems

    problems = [Problem("plant.A", "A contains NaN or infinite entries"), Problem("plant.A", "A must be square"),
                Problem("plant.A[1][0]", "infinity is not a usable number; write a finite number", supersedes=True),
                Problem("plant.AB", "AB contains NaN")]  # not inside plant.A
    assert [p.path + ": " + p.message for p in sort_problems(problems)] == [
        "plant.A: A must be square", "plant.A[1][0]: infinity is not a usable number; write a finite number",
        "plant.AB: AB contains NaN"]


def test_a_multi_line_library_message_becomes_one_line():
    from netsim.scenario.problems import Problem

    p = Problem("nodes.c.tasks[0].params.law.Q", "Q: no stabilising solution (\nThe computed dimension\n  of the "
                "solution does not match); make Q weight every unstable mode")
    assert "\n" not in str(p) and "( The computed dimension of the solution" in p.message


@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_a_non_finite_radio_position_is_refused(bad):
    """Issue 14 B: NaN radio positions ran to 'ok' with every message delivered (NaN distances compare False)."""
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "scenarios" / "dc_servo_zigbee.yaml"
    problems = [p for p in check_scenario(path, {"networks.bus.positions.sensor": [bad, 0]}) if p.is_error]
    assert [p.path for p in problems] == ["networks.bus.positions.sensor[0]"]
    assert "write a finite number" in problems[0].message


def test_a_task_without_period_and_release_is_refused_as_nothing_releases_it(base):
    """Deleting the period of a task that had no 'release:' left an aperiodic task no netsim program ever releases
    (issue 14 B: a deleted required key that validate accepted without a word; a warning until issue 31)."""
    raw = base()
    del raw["nodes"]["sensor"]["tasks"][0]["period"]
    assert "add e.g. 'period: 10 ms'" in _errors(raw)["nodes.sensor.tasks[0]"]
    raw["nodes"]["sensor"]["tasks"][0]["release"] = "aperiodic"  # said on purpose: accepted
    assert "nodes.sensor.tasks[0]" not in _errors(raw) and "nodes.sensor.tasks[0]" not in _warnings(raw)


def test_a_5000_digit_integer_from_python_gets_the_same_message_as_from_a_file(base):
    """Before: ValueError (int to text beyond 4300 digits) from the io check's message, as a traceback."""
    raw = base()
    raw["io"]["y"]["output"] = 10**5000
    raw["seed"] = -(10**5000)
    errors = _errors(raw)
    assert "over 4000 digits" in errors["io.y.output"] and "write a smaller value" in errors["io.y.output"]
    assert "seed" in errors


def test_a_sporadic_task_counts_one_job_per_min_interarrival(base):
    raw = base()
    raw["duration"] = "1000 s"
    task = raw["nodes"]["sensor"]["tasks"][0]
    del task["period"]
    task["release"] = "sporadic"
    task["min_interarrival"] = "10 us"
    total, parts = expected_events(raw)
    # at most 1000 s / 10 us = 1e8 jobs: the sporadic task's bound, as a 10 us period would give
    assert total == pytest.approx(1000 * S / 10_000)
    assert parts[0][0] == "nodes.sensor.tasks[0].min_interarrival"
