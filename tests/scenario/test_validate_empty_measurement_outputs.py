"""A state_feedback measurement source with ``outputs: []`` is refused at its path by validate.

Found by tests/fuzz: pendulum_lqr_rk4 with ``measurements[1].outputs[0]`` deleted passed ``netsim validate`` and
failed only during the run ("measurement source 1 sent 1 values, it measures 0 outputs").
"""

from __future__ import annotations

from pathlib import Path

from netsim.scenario import check_scenario

ROOT = Path(__file__).resolve().parents[2]
AT = "nodes.rip.tasks[0].params.measurements[1].outputs"


def test_a_measurement_source_measuring_no_output_is_refused_at_its_outputs():
    problems = check_scenario(ROOT / "scenarios" / "pendulum_lqr_rk4.yaml", {AT: []})
    assert [(p.path, p.message) for p in problems if p.is_error] == [(AT, "'outputs' is empty; give at least 1 entry")]


def test_a_measurement_source_naming_its_output_stays_valid():
    problems = check_scenario(ROOT / "scenarios" / "pendulum_lqr_rk4.yaml", {AT: ["alpha"]})
    assert [p for p in problems if p.is_error] == []
