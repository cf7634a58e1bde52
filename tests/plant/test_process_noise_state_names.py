"""A process_noise entry naming a state (or input) the plant does not have is refused at that name's YAML path,
listing the plant's names, by validate and by run alike (fuzz figures: double_integrator_mpc with a
``plant.states`` entry renamed while a noise entry still names the old state)."""

from __future__ import annotations

import copy
from pathlib import Path

import pytest
import yaml

import netsim
from netsim.scenario.loader import check_scenario
from netsim.scenario.problems import ScenarioError
from tests.fuzz.mutations import message_has_fix

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "double_integrator_mpc.yaml"


def _renamed(noise) -> dict:
    raw = yaml.safe_load(SCENARIO.read_text())
    raw["plant"]["states"] = ["p", "speed"]  # 'v' renamed: the noise below still names it
    raw["plant"]["process_noise"] = copy.deepcopy(noise)
    raw["duration"] = "100 ms"
    return raw


CASES = [
    ({"states": ["v"], "sigma": 0.1, "sample": "10 ms"}, "plant.process_noise.states[0]"),
    ([{"inputs": ["u"], "sigma": 0.1, "sample": "10 ms"}, {"states": ["p", "v"], "sigma": [0.1, 0.1],
                                                          "sample": "10 ms"}], "plant.process_noise[1].states[1]"),
]


@pytest.mark.parametrize("noise, path", CASES)
def test_validate_refuses_an_unknown_state_name_at_its_path_listing_the_known_ones(noise, path):
    errs = [(p.path, p.message) for p in check_scenario(_renamed(noise)) if p.severity == "error"]
    assert [p for p, _ in errs] == [path], errs
    assert "no state 'v'" in errs[0][1] and "known: p, speed" in errs[0][1] and message_has_fix(errs[0][1])


@pytest.mark.parametrize("noise, path", CASES)
def test_run_refuses_an_unknown_state_name_at_the_same_path(noise, path):
    with pytest.raises(ScenarioError) as info:
        netsim.run(_renamed(noise))
    assert path in str(info.value) and "known: p, speed" in str(info.value)


def test_an_unknown_input_name_is_refused_the_same_way():
    errs = [(p.path, p.message) for p in check_scenario(_renamed({"inputs": ["force"], "sigma": 0.1,
                                                                  "sample": "10 ms"})) if p.severity == "error"]
    assert [p for p, _ in errs] == ["plant.process_noise.inputs[0]"], errs
    assert "known: u" in errs[0][1]
