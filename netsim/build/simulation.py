"""What a build returns: the :class:`Simulation` (desmod's run and collect steps) and the environments it runs on.

:func:`netsim.build.builder.build` creates every runtime object on a :class:`SeedWatchEnv` (a run) or a
:class:`DryRunEnv` (``netsim validate``'s dry run, never run) and returns them as a :class:`Simulation`;
:meth:`Simulation.run` runs the event loop and :meth:`Simulation.finish` the end-of-run finalizers.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

from netsim.env import SimEnv, run_events

if TYPE_CHECKING:
    from netsim.scenario.schema import Scenario

__all__ = ["Simulation", "SeedWatchEnv", "DryRunEnv", "ProgressFn", "PROGRESS_SLICES"]

log = logging.getLogger(__name__)

#: A progress callback ``fn(t_ns, t_end_ns)`` of :meth:`Simulation.run`.
ProgressFn = Callable[[int, int], None]

#: Number of progress reports per run (one per 1 % of simulated time).
PROGRESS_SLICES = 100


@dataclass
class Simulation:
    """Everything :func:`build` created, ready to run.

    Attributes
    ----------
    scenario, env, plant
        The scenario, the environment and the plant (None when the scenario has none).
    signals : dict[str, Callable[[int], float]]
    channels : dict[str, Any]
        ``io`` channel objects by name (ADC, DAC, Encoder).
    kernels : dict[str, Kernel]
    networks : dict[str, Network]
    duration : int
        Simulated time in ns.
    """

    scenario: Scenario
    env: SimEnv
    plant: Any = None
    signals: dict[str, Callable[[int], float]] = field(default_factory=dict)
    channels: dict[str, Any] = field(default_factory=dict)
    kernels: dict[str, Any] = field(default_factory=dict)
    networks: dict[str, Any] = field(default_factory=dict)
    programs: dict[str, Any] = field(default_factory=dict)
    duration: int = 0
    energy: dict[str, Any] = field(default_factory=dict)  # node -> EnergyMeter (nodes with an energy model)
    finished_at: int | None = None

    def run(self, until: int | None = None, progress: ProgressFn | None = None) -> int:
        """Run to ``until`` ns (default: the scenario duration); returns the time reached.

        Parameters
        ----------
        until
            End time in ns (events at ``until`` are processed).
        progress
            Optional ``progress(t_ns, t_end_ns)``, called at the start, after every 1 % of simulated time and
            at the end. The event loop then runs in 100 slices ``(k-1) t_end/100 < t <= k t_end/100``: the
            same events in the same order as one pass (no extra event is scheduled), so results are identical
            with and without it; with ``None`` the loop is not sliced at all.

        Exceptions from the model (e.g. :class:`~netsim.errors.DivergenceError`) propagate; the finalizers
        (plant flush, open schedule intervals) are then run at the current time by :meth:`finish`, so the
        tables hold everything up to the failure.
        """
        if isinstance(self.env, DryRunEnv):
            raise RuntimeError("a dry run's simulation is never run; build the scenario without dry_run to run it")
        t_end = self.duration if until is None else int(until)
        try:
            if progress is None:
                run_events(self.env.sim, t_end)
            else:
                _run_sliced(self.env, t_end, progress)
        except BaseException:
            self.finish(self.env.now)
            raise
        self.finish(t_end)
        return t_end

    def used_seed(self) -> bool:
        """True if the run so far depended on the scenario seed (read it, or drew from a random stream).

        False means the same scenario gives the same results with any seed (results caches use this).
        """
        used = getattr(self.env, "used_seed", None)
        return True if used is None else bool(used())

    def finish(self, t_ns: int) -> None:
        """Run the env's end-of-run finalizers at ``t_ns`` after an aborted run (each at most once)."""
        if self.finished_at is not None:
            return
        self.finished_at = int(t_ns)
        for fn in list(getattr(self.env, "_finalizers", [])):
            try:
                fn(int(t_ns))
            except Exception:  # noqa: BLE001 - collecting after a failure must not raise again
                log.debug("finalizer failed after an aborted run", exc_info=True)


def _run_sliced(env: SimEnv, t_end: int, progress: ProgressFn, slices: int = PROGRESS_SLICES) -> None:
    """:func:`netsim.env.run_events` to ``t_end`` in ``slices`` steps of simulated time, reporting after each."""
    start = int(env.now)
    progress(start, t_end)
    span = max(t_end - start, 0)
    for k in range(1, slices + 1):
        t = start + span * k // slices  # integer ns; the last slice ends exactly at t_end
        run_events(env.sim, t)
        progress(t, t_end)


class SeedWatchEnv(SimEnv):
    """A :class:`SimEnv` that notes whether the run used its seed (for :meth:`Simulation.used_seed`).

    The seed counts as used when code read ``env.seed`` itself (instead of asking for a named stream) or when
    any named stream produced a number. A run that used neither gives the same results for every seed.
    """

    def __init__(self, seed: int = 0, record: set[str] | None = None) -> None:
        self.seed_read = False
        self._initial: dict[str, Any] = {}
        self._in_rng = False
        super().__init__(seed, record)
        self.seed_read = False  # SimEnv.__init__ itself does not count

    @property
    def seed(self) -> int:
        if not self._in_rng:
            self.seed_read = True
        return self._seed

    @seed.setter
    def seed(self, value: int) -> None:
        self._seed = value

    def rng(self, name: str) -> np.random.Generator:
        gen = self._streams.get(name)
        if gen is None:
            self._in_rng = True
            try:
                gen = super().rng(name)
            finally:
                self._in_rng = False
            self._initial[name] = gen.bit_generator.state
        return gen

    def used_seed(self) -> bool:
        """True if the seed was read directly or a named stream was drawn from."""
        if self.seed_read:
            return True
        return any(gen.bit_generator.state != self._initial.get(name) for name, gen in self._streams.items())


class DryRunEnv(SimEnv):
    """The environment of a dry run (``netsim validate``): everything is built on it as for a run, and it is never
    run. Programs see ``ctx.dry_run`` (what they make for the run, such as a control design, stays unclaimed)."""

    def run(self, until_ns: int) -> None:
        raise RuntimeError("a dry-run environment is never run; build the scenario without dry_run to run it")
