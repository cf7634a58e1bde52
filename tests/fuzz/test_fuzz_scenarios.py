"""Malformed versions of the shipped scenarios: no traceback, no hang, a located message that says what to change,
and ``netsim run`` refuses exactly what ``netsim validate`` refuses (issue 14 B).

The cases come from :mod:`tests.fuzz.mutations` (delete a key, retype a value, duplicate a node or a task, extreme
numbers, unknown units, bad references, absurd names). The default run tries a few; ``-m slow`` tries thousands.
"""

from __future__ import annotations

import functools
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.fuzz.mutations import SCENARIOS, Mutation, case_file_name, evaluate, message_has_fix, message_has_path
from tests.fuzz.mutations import mutations as scenario_mutations

# hdd scenarios take seconds to validate (their controllers are designed at build): kept for the slow variant
FAST = [p for p in SCENARIOS if not p.name.startswith("hdd")]


@functools.cache
def _cases(path: Path) -> list[Mutation]:
    return scenario_mutations(path)


def _check(m: Mutation, workdir: Path) -> None:
    o = evaluate(m, workdir, seconds=30.0)
    what = f"{m.scenario}: {m.kind} at {m.path or '<top>'} ({m.detail})"
    assert o.traceback is None, f"{what}: traceback {o.traceback}"
    assert o.hang is None, f"{what}: {o.hang}"
    assert not o.leaked_warnings, f"{what}: python warnings reached the user: {o.leaked_warnings}"
    if m.must_refuse:
        assert o.validate_exit != 0, f"{what}: validate accepted it:\n{o.validate_out}"
        assert o.run_exit != 0, f"{what}: run accepted it:\n{o.run_out}"
    assert (o.run_validate_exit == 0) == (o.run_exit == 0), (
        f"{what}: validate exit {o.run_validate_exit} but run exit {o.run_exit}:\n{o.run_out[-2000:]}")
    for line in o.error_lines() if o.validate_exit else []:
        if m.path:
            assert message_has_path(line, case_file_name(m)), f"{what}: message without a path: {line[:300]}"
        assert message_has_fix(line), f"{what}: message without a fix: {line[:300]}"


def _case(paths: list[Path], data: st.DataObject) -> Mutation:
    """A case drawn by (scenario, index): hypothesis then shows two short values, not a whole scenario."""
    path = data.draw(st.sampled_from(paths), label="scenario")
    i = data.draw(st.integers(0, len(_cases(path)) - 1), label="case")
    return _cases(path)[i]


@settings(max_examples=6, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_malformed_shipped_scenarios_are_refused_cleanly(data, tmp_path_factory):
    _check(_case(FAST, data), tmp_path_factory.mktemp("fuzz"))


@pytest.mark.slow
@settings(max_examples=3000, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_malformed_shipped_scenarios_are_refused_cleanly_thousands(data, tmp_path_factory):
    _check(_case(SCENARIOS, data), tmp_path_factory.mktemp("fuzz"))


@pytest.mark.parametrize("kind", ["delete_required", "duplicate", "empty", "name"])
def test_each_structural_kind_is_refused(kind, tmp_path):
    """One case of each structural kind on the DC servo over CAN, always (the sampled test may miss them)."""
    (m, *_) = [c for c in _cases(SCENARIOS[[p.name for p in SCENARIOS].index("dc_servo_can.yaml")]) if c.kind == kind]
    _check(m, tmp_path)


def test_the_generator_makes_every_kind_of_edit():
    kinds = {m.kind for p in FAST for m in _cases(p)}
    assert kinds == {"delete_required", "delete_any", "retype", "extreme", "unit", "reference", "duplicate",
                     "empty", "name"}
