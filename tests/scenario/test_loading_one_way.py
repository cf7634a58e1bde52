"""Scenario loading goes one way (issue 15 B): text -> raw tree -> overrides and seed -> one validation -> a frozen
Scenario; positions are parsed only for a problem to report; one YAML library, read as YAML 1.2's core schema."""

from __future__ import annotations

import ast
import math
from pathlib import Path

import pytest

from netsim.scenario import check_scenario, load_scenario
from netsim.scenario import safe_yaml
from netsim.scenario.safe_yaml import YamlRefused, dump_text, load_text
from netsim.scenario.schema import Scenario

ROOT = Path(__file__).resolve().parents[2]
SERVO = ROOT / "scenarios" / "dc_servo_ideal.yaml"


@pytest.fixture
def count_validations(monkeypatch):
    """Counts ``Scenario.model_validate`` calls (the schema validation of one raw tree)."""
    calls: list[int] = []
    original = Scenario.model_validate.__func__  # type: ignore[attr-defined]

    def counting(cls, *args, **kwargs):
        if cls is Scenario:
            calls.append(1)
        return original(cls, *args, **kwargs)

    monkeypatch.setattr(Scenario, "model_validate", classmethod(counting))
    return calls


# ------------------------------------------------------------------------------------------ one validation
def test_run_with_seed_and_overrides_validates_the_schema_once(count_validations):
    from netsim.runner import run

    result = run(SERVO, write=False, seed=3, overrides={"duration": "20 ms"})
    assert result.meta["seed"] == 3 and result.meta["t_end_s"] == pytest.approx(0.02)
    assert len(count_validations) == 1  # before: 1 in run(), 3 for a scenario with a baseline, 5 with --seed


def test_cli_run_with_seed_and_set_validates_the_schema_once(count_validations, tmp_path):
    from netsim.cli import main

    code = main(["run", str(SERVO), "--out", str(tmp_path / "run"), "--seed", "4", "--set", "duration=20 ms", "-q"])
    assert code == 0
    assert len(count_validations) == 1
    assert '"seed": 4' in (tmp_path / "run" / "meta.json").read_text()


def test_a_baseline_is_validated_once_with_its_scenario_and_run_as_loaded(count_validations):
    from netsim.runner import clear_baseline_cache, run

    raw = safe_yaml.load_file(SERVO)[0]
    raw["duration"] = "20 ms"
    raw["baseline"] = {"overrides": {"nodes.computer.tasks[0].execution": "0.5 ms"}}
    sc = load_scenario(raw)
    assert len(count_validations) == 2  # the scenario and its baseline, once each
    base = sc.baseline_scenario()
    assert base is sc.baseline_scenario() and base.baseline is None
    assert base.nodes["computer"].tasks[0].execution == 500_000  # 0.5 ms in ns: the override applied
    clear_baseline_cache()
    result = run(sc, write=False)
    assert result.meta["baseline"] == {"status": "ok"}
    assert len(count_validations) == 2  # run() validated nothing again


def test_validate_refuses_a_baseline_that_run_would_refuse(base):
    raw = base()
    raw["baseline"] = {"overrides": {"nodes.sensor.tasks[0].params.channel": "nope"}}
    errors = [p for p in check_scenario(raw) if p.is_error]
    assert [p.path for p in errors] == ["baseline.overrides"]
    assert errors[0].message.startswith("override gives nodes.sensor.tasks[0].params.channel: unknown io channel "
                                        "'nope'")


def test_a_scenario_built_without_the_loader_says_how_to_get_its_baseline(base):
    from netsim.scenario import ScenarioError

    raw = base()
    raw["baseline"] = {"overrides": {"seed": 2}}
    with pytest.raises(ScenarioError, match="load_scenario"):
        Scenario.model_validate(raw).baseline_scenario()
    assert load_scenario(raw).baseline_scenario().seed == 2


# ------------------------------------------------------------------------------------------ the schema is data
def test_the_schema_imports_no_loader_or_checker():
    """Not even inside a function: the schema is data, the layers above it use it (no import circle)."""
    tree = ast.parse((ROOT / "netsim" / "scenario" / "schema.py").read_text())
    imported = {node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom) and node.module}
    imported |= {alias.name for node in ast.walk(tree) if isinstance(node, ast.Import) for alias in node.names}
    above = {f"netsim.scenario.{m}" for m in ("loader", "validate", "messages", "limits", "safe_yaml")}
    above |= {f"netsim.build.{m}" for m in ("builder", "wiring", "dry_run")}
    assert not any(name == "netsim.build" or name.startswith("netsim.build.") for name in imported)
    assert imported & above == set()


# ------------------------------------------------------------------------------------------ positions on demand
def test_positions_are_parsed_only_when_a_problem_needs_a_line(monkeypatch, tmp_path):
    calls: list[int] = []
    original = safe_yaml.line_table

    def counting(text):
        calls.append(1)
        return original(text)

    monkeypatch.setattr(safe_yaml, "line_table", counting)
    assert load_scenario(SERVO).name == "dc_servo_ideal"
    assert calls == []
    bad = tmp_path / "bad.yaml"
    text = SERVO.read_text().replace("period: 6 ms", "period: 6 msec")
    bad.write_text(text)
    (problem,) = check_scenario(bad)
    line = next(i for i, ln in enumerate(text.splitlines(), 1) if "period: 6 msec" in ln)
    assert (problem.path, problem.line) == ("nodes.computer.tasks[0].period", line)
    assert calls == [1]


def test_line_table_gives_keys_their_line_and_items_the_line_of_their_value():
    text = "a: 1\nb:\n  - x\n  -\n    c: 2\n  - {d: 3}\nx-m: &m {p: 1}\nn:\n  <<: *m\n  q: 2\n"
    lines = safe_yaml.line_table(text)
    assert lines[("a",)] == 1 and lines[("b", 0)] == 3
    assert lines[("b", 1)] == 5 and lines[("b", 1, "c")] == 5  # the mapping of an empty '-' line starts below
    assert lines[("b", 2, "d")] == 6 and lines[("n", "q")] == 10
    assert ("n", "p") not in lines  # merged in by '<<': its nearest ancestor ('n', line 8) places it


# ------------------------------------------------------------------------------------------ YAML 1.2 scalars
# YAML 1.2.2, section 10.3.2 (core schema tag resolution), as scenario files have always been read
@pytest.mark.parametrize("text,value", [
    ("true", True), ("False", False), ("TRUE", True), ("yes", "yes"), ("on", "on"), ("n", "n"),
    ("null", None), ("~", None), ("", None), ("Null", None),
    ("010", 10), ("0o10", 8), ("0x1F", 31), ("-0x10", -16), ("0b101", 5), ("1_000", 1000), ("+1", 1),
    ("1e-5", 1e-5), ("1E5", 1e5), ("1.5e3", 1500.0), (".5", 0.5), ("5.", 5.0), ("-.inf", -math.inf),
    (".Inf", math.inf), ("1:30", "1:30"), ("nan", "nan"), ("inf", "inf"), ("1 ms", "1 ms"), ("0x", "0x"),
])
def test_plain_scalars_are_read_as_yaml_1_2s_core_schema(text, value):
    got = load_text(f"v: {text}\n")["v"]
    assert got == value and type(got) is type(value)


def test_nan_is_read_from_dot_nan_only():
    assert math.isnan(load_text("v: .nan\n")["v"])
    assert load_text("v: NaN\n")["v"] == "NaN"


# ------------------------------------------------------------------------------------------ keys and merges
def test_duplicate_keys_are_refused_with_both_lines():
    with pytest.raises(YamlRefused) as info:
        load_text("name: a\nduration: 1 s\nname: b\n")
    assert info.value.line == 3 and "duplicate key 'name' (first on line 1)" in info.value.message
    with pytest.raises(YamlRefused, match="duplicate key '<<'"):
        load_text("x-a: &a {p: 1}\nx-b: &b {p: 2}\nn:\n  <<: *a\n  <<: *b\n")


def test_merge_keys_written_keys_win_and_the_first_merged_mapping_wins():
    data = load_text("x-d: &d {p: 1, q: 2}\nx-e: &e {r: 1, p: 5}\nn: {a: 1, <<: [*d, *e], q: 7}\n")
    assert data["n"] == {"a": 1, "q": 7, "p": 1, "r": 1} and list(data["n"]) == ["a", "q", "p", "r"]


def test_a_merged_mapping_keeps_its_own_keys_when_it_is_merged_before_it_is_built():
    # PyYAML's own SafeLoader gives n.p == 1 here: it flattens the mapping &b in place, merged keys first
    text = "x-a: &a {p: 1, q: 3}\ntop:\n  x: &b {<<: *a, p: 2}\nn: {<<: *b, z: 1}\n"
    data = load_text(text)
    assert data["top"]["x"] == {"p": 2, "q": 3}
    assert data["n"] == {"z": 1, "p": 2, "q": 3}


def test_an_integer_python_cannot_read_is_a_placeholder_the_limits_refuse():
    from netsim.scenario.limits import long_integer_placeholder

    assert load_text("v: -" + "9" * 5000 + "\n")["v"] == long_integer_placeholder(True)  # the limits' placeholder
    assert load_text("v: " + "9" * 5000 + "\n")["v"] == long_integer_placeholder(False)


def test_dump_text_quotes_what_either_yaml_version_reads_as_a_number():
    data = {"a": "1e5", "b": "yes", "c": "0o7", "d": 1e-5, "e": [1, "x", None, True], "f": "1 ms", "g": "é"}
    text = dump_text(data)
    assert "a: '1e5'" in text and "c: '0o7'" in text and "f: 1 ms" in text
    assert load_text(text) == data


def test_set_values_are_read_like_scenario_files():
    from netsim.scenario import parse_override

    assert parse_override("plant.params.gain=1e3") == ("plant.params.gain", 1000.0)
    assert parse_override("seed=010") == ("seed", 10)
    from netsim.errors import ConfigError

    with pytest.raises(ConfigError, match="is not allowed"):
        parse_override("description=!!python/object/apply:os.system [ls]")
