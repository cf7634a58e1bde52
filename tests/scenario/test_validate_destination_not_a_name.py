"""A sender's ``to`` given as a mapping or list is refused at its YAML path with the fix (a node name or 'all').

Found by tests/fuzz: dc_servo_flexray with ``nodes.interference.tasks[0].params.to`` a mapping crashed
``netsim validate`` with "TypeError: unhashable type: 'dict'" (the interference check hashed the raw value).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from netsim.scenario import check_scenario

ROOT = Path(__file__).resolve().parents[2]


def _errors(overrides: dict) -> list[tuple[str, str]]:
    return [(p.path, p.message) for p in check_scenario(ROOT / "scenarios" / "dc_servo_flexray.yaml", overrides)
            if p.is_error]


@pytest.mark.parametrize(("path", "value", "kind"), [
    ("nodes.interference.tasks[0].params.to", {"a": 1}, "a mapping"),
    ("nodes.interference.tasks[0].params.to", ["actuator"], "a list"),
    ("nodes.controller.tasks[0].params.to", {"node": "actuator"}, "a mapping"),
])
def test_a_destination_that_is_not_a_name_is_refused_in_one_line_at_its_path(path, value, kind):
    assert _errors({path: value}) == [
        (path, f"'to' is {kind}; write one node's name (e.g. 'to: actuator') or 'to: all'")]
