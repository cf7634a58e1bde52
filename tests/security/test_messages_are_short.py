"""A message names what it refuses but never echoes a huge key or value (issue 14 A: "never echoes a file")."""

from __future__ import annotations

import pytest

from netsim.scenario import check_scenario

BIG = "k" * 1_000_000

PUT = {
    "unknown_top_level_key": lambda raw: raw.update({BIG: 1}),
    "plant_model": lambda raw: raw["plant"].update(model=BIG),
    "plant_parameter_key": lambda raw: raw["plant"]["params"].update({BIG: 1}),
    "task_period": lambda raw: raw["nodes"]["computer"]["tasks"][0].update(period=BIG + " ms"),
    "record_entry": lambda raw: raw.update(record=[BIG]),
}


@pytest.mark.parametrize("case", sorted(PUT))
def test_a_million_character_key_or_value_is_not_echoed(scenario, case):
    raw = scenario()
    PUT[case](raw)
    problems = [p for p in check_scenario(raw) if p.is_error]
    assert problems
    assert all(len(p.describe()) < 400 for p in problems), [len(p.describe()) for p in problems]


def test_a_yaml_error_naming_a_huge_alias_is_not_echoed(tmp_path):
    """A parser's message may quote the alias name; before, the 300 kB name came back whole."""
    path = tmp_path / "alias.yaml"
    path.write_text("name: *" + "q" * 300_000 + "\nduration: 1 s\n")
    (problem,) = check_scenario(path)
    assert problem.is_error and problem.line == 1
    assert len(problem.describe()) < 400


def test_every_problem_is_short_whoever_makes_it():
    from netsim.scenario.problems import LONG_TOKEN, Problem

    p = Problem("a." + "k" * 10**6, "unknown key '" + "k" * 10**6 + "'; did you mean 'kp'?")
    assert len(p.describe()) < 400 and p.message.endswith(" did you mean 'kp'?")
    short = "x" * LONG_TOKEN  # a token of the limit is kept whole
    assert Problem("", short).message == short
