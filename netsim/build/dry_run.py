"""``netsim validate``'s build check: the run's own build, on a dry-run environment, once.

:func:`build_problems` calls :func:`netsim.build.builder.build` with ``dry_run=True`` -- the same function a run
calls, in the same order: signals, plant (``x0``, ``process_noise``, disturbances), io channels, the kernels with
their tasks, handlers, triggers and programs (a ``state_feedback`` task designs its model, estimator and law, so
a weight that is not positive definite, an unstabilisable pair or an MPC whose initial state is infeasible is
refused), the networks, the receive bindings and the energy meters -- on a
:class:`~netsim.build.builder.DryRunEnv` that is never run. Then each kernel's reference check
(``Kernel.validate``, which a run makes when it starts) runs. The first error becomes a
:class:`~netsim.scenario.problems.Problem` at the YAML path the error carries (:func:`netsim.build.wiring.checked_call`
places a kernel's error at the field it names); no message text is read to find a path.

What a dry run leaves out (issue 14: validating must not run code a scenario brings along): plugins that do not
come from netsim's own modules (:func:`netsim.registry.is_builtin`) -- a program of a user's plugin gets a
placeholder body (its ``Params`` are checked by :mod:`netsim.scenario.validate`), a user's plant or signal leaves
out the plant, io channels and programs, a user's network the networks, a user's policy the kernels. Cost: about a
millisecond per node plus what the plant and the programs cost to make (the HDD plant's first design in a process
imports python-control, about 1.3 s, then ``netsim.models.hdd`` caches it). A design a dry run makes stays on
the task's parameters for the run to take (:func:`netsim.programs.feedback_design.claim_design`), so a validated
scenario that is then run designs once.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING

from netsim.errors import ConfigError
from netsim.scenario.problems import ERROR, WARNING, Problem, ScenarioError, sort_problems

if TYPE_CHECKING:
    from netsim.build.simulation import Simulation
    from netsim.scenario.loader import LineIndex
    from netsim.scenario.schema import Scenario

__all__ = ["build_problems", "built_problems", "RunCheck", "override_gives"]

log = logging.getLogger(__name__)
#: The warnings a run's build check logs are loading's: they go out under the loader's name, as they did.
_LOADER_LOG = logging.getLogger("netsim.scenario.loader")


def build_problems(scenario: Scenario) -> list[Problem]:
    """The problem the run's build would raise for ``scenario`` (a valid Scenario), as a list of at most one
    error; else the build's warnings (an unstable nominal loop, issue 26).

    Returns
    -------
    list[Problem]
        Empty when everything builds and every kernel's references resolve.
    """
    from netsim.build.builder import build

    try:
        sim = build(scenario, dry_run=True)
    except ConfigError as exc:
        return [Problem(exc.path or "", exc.message)]
    return built_problems(sim)


def built_problems(sim: Simulation) -> list[Problem]:
    """What :func:`build_problems` checks on a simulation that is built already: each kernel's references (at most
    one error), else the warnings of an unstable nominal loop.

    A run that builds its scenario once (:func:`netsim.runner.run`, issue 28) checks its own build with this.
    """
    for name, kernel in sim.kernels.items():
        try:
            kernel.validate()
        except ConfigError as exc:
            return [Problem(exc.path or f"nodes.{name}", exc.message)]
    if sim.plant is None:
        return []
    from netsim.programs.design_summary import nominal_warnings_at  # issue 26 s4: unstable nominal loops

    return [Problem(at, text, severity=WARNING) for at, text in nominal_warnings_at(sim.scenario, sim.plant)]


def override_gives(p: Problem) -> Problem:
    """A problem of the baseline scenario as the scenario's own error at ``baseline.overrides``."""
    return Problem("baseline.overrides", f"override gives {p.path}: {p.message}" if p.path
                   else f"override gives: {p.message}")


class RunCheck:
    """What loading for a run (``load_scenario(..., for_run=True)``) leaves to the run's one build (issue 28).

    Loading for a run validates everything but the build; :func:`netsim.runner.run` then builds the scenario (and
    its baseline) once, checks that build (:func:`built_problems`) and hands its problems here, which turns them
    into what loading with its dry run gives: the same error (file, line, YAML path, message, the warnings found so
    far beside it) and the same warnings logged in the same order (under the loader's logger name).
    """

    def __init__(self, problems: list[Problem], index: LineIndex, file: str | None,
                 base_warnings: list[Problem]) -> None:
        self._problems = problems  # the scenario's (warnings only), with paths and no lines
        self._index = index
        self._file = file
        self._base_warnings = base_warnings  # the baseline's validation warnings, not yet compared

    def _located(self, problems: list[Problem]) -> list[Problem]:
        from netsim.scenario.messages import shorten_problem

        located = [shorten_problem(p.located(self._index.line_of(p.path), self._file)) for p in problems]
        return sort_problems(located)

    def refused(self, found: list[Problem]) -> ScenarioError | None:
        """The error loading gives for the scenario's build problems ``found`` (None: it built)."""
        if not any(p.severity == ERROR for p in found):
            return None
        return ScenarioError(self._located([*self._problems, *found]))

    def refused_baseline(self, found: list[Problem], base_found: list[Problem]) -> ScenarioError | None:
        """The error loading gives when the baseline's build has problems ``base_found`` (None: it built)."""
        errors = [override_gives(p) for p in base_found if p.severity == ERROR]
        if not errors:
            return None
        return ScenarioError(self._located([*self._problems, *found, *errors]))

    def warnings(self, found: list[Problem], base_found: list[Problem]) -> list[Problem]:
        """Every warning loading would log, in its order: the scenario's (with the build's ``found``), located and
        sorted, then the baseline's (with its build's ``base_found``) that the scenario has not said already."""
        said = {(p.path, p.message) for p in [*self._problems, *found]}
        base = [p for p in [*self._base_warnings, *base_found] if p.severity != ERROR]
        return [*self._located([*self._problems, *found]), *[p for p in base if (p.path, p.message) not in said]]

    def log_warnings(self, found: list[Problem], base_found: list[Problem]) -> None:
        """Log :meth:`warnings` as :func:`load_scenario` logs a scenario's warnings."""
        for p in self.warnings(found, base_found):
            _LOADER_LOG.warning("%s", p.describe(tag=False))
