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
from netsim.scenario.problems import WARNING, Problem

if TYPE_CHECKING:
    from netsim.build.simulation import Simulation
    from netsim.scenario.schema import Scenario

__all__ = ["build_problems", "built_problems"]

log = logging.getLogger(__name__)


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
