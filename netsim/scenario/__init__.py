"""Scenario files: schema, loading with complete validation, dotted paths, resolved dumps and hashes.

Examples
--------
>>> from netsim.scenario import load_scenario, check_scenario
>>> sc = load_scenario("scenarios/dc_servo_can.yaml")              # doctest: +SKIP
>>> for p in check_scenario("broken.yaml"): print(p)              # doctest: +SKIP
broken.yaml:12: nodes.controller.tasks[1].period: unknown unit 'usec'; did you mean 'us'?

The runtime side (turning a scenario into kernels, networks and a plant) is in
:mod:`netsim.scenario.builder`, which is not imported here.
"""

from __future__ import annotations

from netsim.scenario.loader import check_scenario, dump_resolved, load_scenario, resolved_dict, scenario_hash
from netsim.scenario.paths import format_path, get_path, parse_override, parse_path, set_path
from netsim.scenario.problems import Problem, ScenarioError
from netsim.scenario.schema import Scenario

__all__ = [
    "load_scenario",
    "check_scenario",
    "Scenario",
    "ScenarioError",
    "Problem",
    "scenario_hash",
    "dump_resolved",
    "resolved_dict",
    "get_path",
    "set_path",
    "parse_path",
    "format_path",
    "parse_override",
]
