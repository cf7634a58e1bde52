"""The build room: a validated :class:`~netsim.scenario.schema.Scenario` turned into runtime objects.

- :mod:`netsim.build.builder`: :func:`~netsim.build.builder.build`, the one build (signals, plant, io channels,
  kernels with their programs, networks, energy meters, recording) and the :class:`~netsim.build.builder.Simulation`
  it returns;
- :mod:`netsim.build.wiring`: the kernels and networks of a scenario (steps 5 and 6 of the build);
- :mod:`netsim.build.dry_run`: ``netsim validate``'s build check, which is the same
  :func:`~netsim.build.builder.build` on a dry-run environment (:class:`~netsim.build.builder.DryRunEnv`), run
  once, its first error a :class:`~netsim.scenario.problems.Problem` at the YAML path the error carries; a run makes
  no dry run: it builds once and checks that build the same way (:func:`~netsim.build.dry_run.built_problems`).

The room sits beside :mod:`netsim.scenario` (the loader runs the dry run lazily, the builder reads the validated
scenario); it never loads a file, so loading stays one-way. Nothing here is imported by ``import netsim`` or by
the command line's start-up: the builder imports numpy, the kernel and the programs only when a build starts.
"""

from __future__ import annotations

__all__: list[str] = []
