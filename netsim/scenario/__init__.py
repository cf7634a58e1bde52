"""Scenario files: schema, loading with complete validation, dotted paths, resolved dumps and hashes.

Examples
--------
>>> from netsim.scenario import load_scenario, check_scenario
>>> sc = load_scenario("scenarios/dc_servo_can.yaml")              # doctest: +SKIP
>>> for p in check_scenario("broken.yaml"): print(p)              # doctest: +SKIP
broken.yaml:12: nodes.controller.tasks[1].period: unknown unit 'usec'; did you mean 'us'?

The runtime side (turning a scenario into kernels, networks and a plant) is in
:mod:`netsim.build.builder`, imported only when :func:`build` is called.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from netsim.scenario.loader import check_scenario, dump_resolved, load_scenario, resolved_dict, scenario_hash
from netsim.scenario.paths import format_path, get_path, parse_override, parse_path, set_path
from netsim.scenario.problems import Problem, ScenarioError
from netsim.scenario.schema import Scenario

if TYPE_CHECKING:
    from netsim.build.builder import Simulation

__all__ = [
    "build",
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


def build(source: Any, *, allow_plugins: bool | None = None) -> "Simulation":
    """A runnable simulation of ``source``: a :class:`Scenario`, a scenario file, or a dict.

    A path or dict is loaded and validated first (:func:`load_scenario`); in a dict, ``plant`` may be a
    python-control ``StateSpace``, ``TransferFunction`` or ``NonlinearIOSystem`` (or ``{system: <it>, x0: ...}``,
    see :func:`netsim.plant.described.resolve_plant_object`).

    Parameters
    ----------
    source
        What to build.
    allow_plugins
        Whether the plugin files a scenario's ``plugins:`` names may run (default: the user's settings).

    Raises
    ------
    ScenarioError
        When ``source`` does not validate (every problem with its path).
    BuildError
        When a valid description cannot be turned into runtime objects.
    """
    from netsim.build import builder

    if not isinstance(source, Scenario):
        from netsim.plant.described import resolve_plant_object

        source = load_scenario(resolve_plant_object(source), allow_plugins=allow_plugins)
    return builder.build(source)

