"""Every bad input the issue lists gives a problem with its YAML path, its line and an exact message."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest
import yaml

from netsim.scenario import ScenarioError, check_scenario, load_scenario


def _errors(source, **kw):
    return [p for p in check_scenario(source, **kw) if p.is_error]


def _only(source) -> tuple[str, str]:
    problems = _errors(source)
    assert len(problems) == 1, [str(p) for p in problems]
    return problems[0].path, problems[0].message


def _write(tmp_path: Path, data, name: str = "s.yaml") -> Path:
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data, sort_keys=False) if not isinstance(data, str) else data)
    return path


def _line_of(path: Path, needle: str) -> int:
    """1-based line of the first line containing ``needle`` (computed independently of the loader)."""
    for i, line in enumerate(path.read_text().splitlines(), start=1):
        if needle in line:
            return i
    raise AssertionError(needle)


def test_the_base_scenario_is_valid(base):
    assert check_scenario(base()) == []


def test_unknown_key_lists_the_known_keys(base):
    raw = base()
    raw["output"] = {"dir": None, "colour": "red"}
    assert _only(raw) == ("output.colour", "unknown key 'colour' (known keys: dir, jobs, messages, plot, schedule)")


def test_misspelt_key_gets_a_did_you_mean(base):
    raw = base()
    task = raw["nodes"]["sensor"]["tasks"][0]
    task["perod"] = task.pop("period")
    problems = {p.path: p.message for p in _errors(raw)}
    assert problems["nodes.sensor.tasks[0].perod"] == "unknown key 'perod'; did you mean 'period'?"


def test_wrong_type_names_the_expected_type(base):
    raw = base()
    raw["seed"] = "abc"
    raw["nodes"]["sensor"]["tasks"][0]["priority"] = "high"
    problems = {p.path: p.message for p in _errors(raw)}
    assert problems == {
        "seed": "expected an integer, got 'abc'",
        "nodes.sensor.tasks[0].priority": "expected an integer, got 'high'",
    }


def test_negative_period_is_an_error(base):
    raw = base()
    raw["nodes"]["sensor"]["tasks"][0]["period"] = "-10 ms"
    assert _only(raw) == ("nodes.sensor.tasks[0].period", "time must not be negative, got '-10 ms'")


def test_zero_period_and_zero_duration_are_errors(base):
    raw = base()
    raw["nodes"]["sensor"]["tasks"][0]["period"] = "0 ms"
    raw["duration"] = 0
    problems = {p.path: p.message for p in _errors(raw)}
    assert problems == {
        "nodes.sensor.tasks[0].period": "duration must be positive, got '0 ms'",
        "duration": "duration must be positive, got 0",
    }


def test_unknown_unit_suggests_the_right_unit(tmp_path, base):
    raw = base()
    raw["nodes"]["controller"]["tasks"].append(
        {"name": "log", "program": "zzt_idle", "period": "100 usec", "priority": 3}
    )
    path = _write(tmp_path, raw)
    problems = _errors(path)
    assert [str(p) for p in problems] == [
        f"{path}:{_line_of(path, '100 usec')}: nodes.controller.tasks[1].period: unknown unit 'usec'; did you mean 'us'?"
    ]


def test_unknown_model_suggests_the_registered_one(base):
    raw = base()
    raw["plant"]["model"] = "zzt_plnt"
    assert _only(raw) == ("plant.model", "unknown plant 'zzt_plnt'; did you mean 'zzt_plant'?")


def test_unknown_program_is_reported_not_raised(base):
    raw = base()
    raw["nodes"]["controller"]["tasks"][0]["program"] = "zzt_idel"
    assert _only(raw) == ("nodes.controller.tasks[0].program", "unknown program 'zzt_idel'; did you mean 'zzt_idle'?")


def test_network_listing_a_node_that_does_not_exist(base):
    raw = base()
    raw["networks"]["bus"]["nodes"].append("ghost")
    assert _only(raw) == ("networks.bus.nodes[3]", "unknown node 'ghost' (known nodes: actuator, controller, sensor)")


def test_task_released_by_a_network_that_does_not_exist(base):
    raw = base()
    raw["nodes"]["controller"]["tasks"][0]["release"] = "on_message:ghost"
    assert _only(raw) == ("nodes.controller.tasks[0].release", "unknown network 'ghost' (known networks: bus)")


def test_task_released_by_a_network_its_node_is_not_on(base):
    raw = base()
    raw["networks"]["bus"]["nodes"] = ["sensor", "actuator"]
    raw["nodes"]["sensor"]["tasks"][0]["params"]["to"] = "actuator"
    assert _only(raw) == (
        "nodes.controller.tasks[0].release",
        "node 'controller' is not attached to network 'bus' (its nodes: sensor, actuator); "
        "add 'controller' to networks.bus.nodes",
    )


def test_message_to_a_node_not_on_the_network(base):
    raw = base()
    raw["nodes"]["lonely"] = {"policy": "edf"}
    raw["nodes"]["sensor"]["tasks"][0]["params"]["to"] = "lonely"
    assert _only(raw) == (
        "nodes.sensor.tasks[0].params.to",
        "node 'lonely' is not on network 'bus' (its nodes: sensor, controller, actuator); "
        "add it to networks.bus.nodes or send to one of those",
    )


def test_message_to_a_node_that_does_not_exist(base):
    raw = base()
    raw["nodes"]["sensor"]["tasks"][0]["params"]["to"] = "controler"
    assert _only(raw) == ("nodes.sensor.tasks[0].params.to", "unknown node 'controler'; did you mean 'controller'?")


def test_empty_file(tmp_path):
    path = _write(tmp_path, "# nothing here\n")
    problems = check_scenario(path)
    assert [(p.file, p.line, p.path, p.message) for p in problems] == [
        (str(path), 1, "", "the file is empty; a scenario needs at least 'name' and 'duration'")
    ]


def test_yaml_syntax_error_has_its_line(tmp_path):
    text = textwrap.dedent(
        """\
        name: broken
        duration: 1 s
        nodes:
          a: {policy: fp
          b: {}
        """
    )
    path = _write(tmp_path, text)
    problems = check_scenario(path)
    assert len(problems) == 1
    assert problems[0].message.startswith("YAML syntax error: ")
    # the flow mapping opened on line 4 is never closed; the parser notices on line 5
    assert problems[0].line == 5
    assert str(problems[0]).startswith(f"{path}:5: YAML syntax error")


def test_duplicate_key_is_a_yaml_error_with_its_line(tmp_path):
    path = _write(tmp_path, "name: a\nduration: 1 s\nname: b\n")
    problems = check_scenario(path)
    assert len(problems) == 1 and problems[0].line == 3
    assert "duplicate key" in problems[0].message


def test_file_that_does_not_exist(tmp_path):
    missing = tmp_path / "nope.yaml"
    assert [str(p) for p in check_scenario(missing)] == [f"{missing}: file not found: {missing}"]
    with pytest.raises(ScenarioError):
        load_scenario(missing)


def test_top_level_that_is_not_a_mapping(tmp_path):
    path = _write(tmp_path, "- a\n- b\n")
    assert [p.message for p in check_scenario(path)] == [
        "the top level must be a mapping (name: ..., duration: ...), got a list"
    ]


def test_missing_required_keys():
    assert {(p.path, p.message) for p in _errors({"nodes": {}})} == {
        ("name", "missing required key 'name'; add 'name: ...' there"),
        ("duration", "missing required key 'duration'; add 'duration: ...' there"),
        ("nodes", "'nodes' is empty; a scenario needs at least one node with a task or a handler "
                  "(add one, e.g. 'nodes: {cpu: {tasks: [...]}}')"),
    }


def test_every_problem_is_reported_at_once_with_its_line(tmp_path, base):
    raw = base()
    raw["seed"] = "abc"  # schema
    raw["nodes"]["sensor"]["tasks"][0]["period"] = "10 msec"  # unit
    raw["nodes"]["sensor"]["tasks"][0]["params"]["bits"] = -1  # plugin params
    raw["networks"]["bus"]["nodes"].append("ghost")  # cross reference
    raw["plant"]["model"] = "zzt_plnt"  # registry
    path = _write(tmp_path, raw)
    problems = _errors(path)
    got = {p.path: p.line for p in problems}
    assert got == {
        "seed": _line_of(path, "seed: abc"),
        "plant.model": _line_of(path, "zzt_plnt"),
        "nodes.sensor.tasks[0].params.bits": _line_of(path, "bits: -1"),
        "nodes.sensor.tasks[0].period": _line_of(path, "10 msec"),
        "networks.bus.nodes[3]": _line_of(path, "- ghost"),
    }
    assert [p.line for p in problems] == sorted(p.line for p in problems)


def test_plugin_parameter_errors_carry_the_full_path(base):
    raw = base()
    raw["nodes"]["sensor"]["tasks"][0]["params"]["bits"] = -1
    raw["nodes"]["sensor"]["tasks"][0]["params"]["bitz"] = 8
    raw["networks"]["bus"]["bitrate"] = "80 kbps/s"
    problems = {p.path: p.message for p in _errors(raw)}
    assert problems["nodes.sensor.tasks[0].params.bits"] == "input should be greater than 0, got -1"
    assert problems["nodes.sensor.tasks[0].params.bitz"] == "unknown key 'bitz'; did you mean 'bits'?"
    assert problems["networks.bus.bitrate"].startswith("cannot read '80 kbps/s' as a bit rate")
    assert len(problems) == 3


def test_load_scenario_raises_with_every_problem(base):
    raw = base()
    raw["seed"] = -1
    raw["nodes"]["sensor"]["tasks"][0]["period"] = "10 usec"
    with pytest.raises(ScenarioError) as info:
        load_scenario(raw)
    assert [p.path for p in info.value.problems] == ["seed", "nodes.sensor.tasks[0].period"]
    assert "scenario has 2 problems" in str(info.value)


def test_a_receiving_playout_actuator_without_network_is_refused_at_validate():
    """Found by the fuzz figures: validate said valid, run failed at build ('needs `network`')."""
    path = Path(__file__).resolve().parents[2] / "scenarios" / "hdd_case3.yaml"
    problems = [p for p in check_scenario(path, {"nodes.actuator.handlers[0].params.network": None}) if p.is_error]
    assert [(p.path, p.message) for p in problems] == [
        ("nodes.actuator.handlers[0].params", "mode 'receive' needs 'network': add the network its packets arrive on")]


def test_a_network_named_inside_a_list_of_program_parameters_is_checked():
    """state_feedback's measurements: [{network: ...}]: a ghost network was accepted by validate and run (found by
    the fuzz figures); nested parameters follow the same naming conventions as top-level ones."""
    path = Path(__file__).resolve().parents[2] / "scenarios" / "unicycle_ekf.yaml"
    at = "nodes.ekf.tasks[0].params.measurements[1].network"
    problems = [p for p in check_scenario(path, {at: "ghost_ref"}) if p.is_error]
    assert [(p.path, p.message.split(" (")[0]) for p in problems] == [(at, "unknown network 'ghost_ref'")]


# --------------------------------------------------------------- found by the fuzz figures in unicycle_lqr.yaml
UNICYCLE_LQR = Path(__file__).resolve().parents[2] / "scenarios" / "unicycle_lqr.yaml"


def test_negative_lqr_weights_are_refused_at_validate():
    """Before: validate said valid and run ended in slycot's SlycotArithmeticError traceback."""
    at = "nodes.ekf.tasks[0].params.lqr_Q[0]"
    assert [(p.path, p.message) for p in _errors(UNICYCLE_LQR, overrides={at: -1.0})] == [
        (at, "input should be greater than or equal to 0, got -1.0")]


def test_a_metric_reading_a_signal_record_left_out_is_a_message_not_a_traceback(tmp_path):
    """Before: KeyError: "['theta'] not in index" from the unicycle metric, as a traceback; now the metric declares
    the signals it reads and the run is refused while loading, before it runs."""
    from netsim.errors import ConfigError
    from netsim.runner import run

    record = [r for r in yaml.safe_load(UNICYCLE_LQR.read_text())["record"] if r != "theta"]
    with pytest.raises(ConfigError, match=r"metric 'unicycle' reads the signals theta, which 'record:' leaves out"):
        run(UNICYCLE_LQR, overrides={"record": record, "duration": "30 ms"}, out=tmp_path / "run")


def test_a_program_whose_design_raises_an_arithmetic_error_is_a_build_error():
    """slycot raises SlycotArithmeticError (an ArithmeticError, not a ValueError): build names the program."""
    from netsim.errors import BuildError
    from netsim.registry import register
    from netsim.runner import run

    @register("program", "zzt_arithmetic_design", "test program whose design fails")
    class _Failing:
        def __init__(self, ctx, params):
            raise ArithmeticError("The computed dimension of the solution does not\nequal N")

    raw = {"name": "design", "duration": "10 ms", "nodes": {"cpu": {"tasks": [
        {"name": "t", "program": "zzt_arithmetic_design", "period": "1 ms", "priority": 1}]}}}
    with pytest.raises(BuildError, match="cannot build program 'zzt_arithmetic_design': The computed dimension of "
                                         "the solution does not equal N"):
        run(raw, write=False)
