"""A state_feedback task's design refusals carry their YAML path as data (issue 28, the build room).

Before, ``feedback_design._model`` recovered the path from the message text: a refusal without a path whose message
began with a parameter's name and a colon (``"measurements[0].outputs: ..."``) was moved to that parameter and the
lead cut off. A message that merely began with a parameter's name was then misplaced.
"""

from __future__ import annotations

from typing import Any

import pytest

from netsim.control import design_checks
from netsim.errors import ConfigError
from netsim.scenario import check_scenario

TASK = "nodes.c.tasks[0]"


def _scenario(**params: Any) -> dict[str, Any]:
    """A one-task state_feedback loop on the DC servo model 1000/(s(s+1)), given as its own discrete model."""
    base: dict[str, Any] = {
        "model": {"A": [[1, 0.01], [0, 0.99]], "B": [[0], [10]], "C": [[1, 0]]},
        "measurements": [{"channel": "y"}],
        "estimator": {"type": "kalman", "Q": [0, 0.01], "R": 1.0e-6},
        "law": {"type": "lqr", "Q": [1, 0], "R": 0.1},
        "output_channel": "u",
    }
    base.update(params)
    return {
        "name": "design_paths", "duration": "50 ms",
        "plant": {"type": "ss", "A": [[0, 1], [0, -1]], "B": [0, 1000], "C": [1, 0], "inputs": ["u"],
                  "outputs": ["y"]},
        "io": {"y": {"type": "adc", "output": 0}, "u": {"type": "dac", "input": "u"}},
        "nodes": {"c": {"tasks": [{"name": "control", "program": "state_feedback", "period": "10 ms",
                                   "priority": 1, "params": base}]}},
    }


def test_the_base_loop_is_valid() -> None:
    assert [str(p) for p in check_scenario(_scenario()) if p.is_error] == []


def test_a_refusal_without_a_path_stays_at_params_whatever_its_message_begins_with(monkeypatch: pytest.MonkeyPatch
                                                                                 ) -> None:
    # a matrix check that refuses with a message starting "law: ...": the old text parsing put it at params.law
    def refuse(name: str, value: Any, shape: Any = None) -> Any:
        raise ConfigError("law: this text is not a path")

    monkeypatch.setattr(design_checks, "as_matrix", refuse)
    (problem,) = [p for p in check_scenario(_scenario()) if p.is_error]
    assert (problem.path, problem.message) == (f"{TASK}.params", "law: this text is not a path")


def test_a_measured_output_the_model_lacks_is_refused_at_its_own_path() -> None:
    # the model has 1 output (C is 1x2): output 1 does not exist
    (problem,) = [p for p in check_scenario(_scenario(measurements=[{"channel": "y", "outputs": [1]}])) if p.is_error]
    assert (problem.path, problem.message) == (f"{TASK}.params.measurements[0].outputs",
                                               "output 1 does not exist (the model has 1 outputs)")
