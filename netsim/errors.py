"""Exceptions that carry a message for the user.

Everything a user can cause (a bad scenario, an impossible parameter, an unstable loop) raises a subclass of
:class:`NetsimError`. The CLI prints these without a traceback; anything else is a bug in netsim.
"""

from __future__ import annotations

__all__ = [
    "NetsimError",
    "ConfigError",
    "BuildError",
    "DivergenceError",
    "LivelockError",
    "SimulationError",
]


class NetsimError(Exception):
    """Base class of errors caused by user input; the message says what to change."""


class ConfigError(NetsimError):
    """A scenario or parameter value is invalid.

    Parameters
    ----------
    message
        What is wrong and what to change.
    path
        Dotted YAML path of the offending value (``nodes.ctrl.tasks[1].period``), when known.
    """

    def __init__(self, message: str, path: str | None = None) -> None:
        self.path = path
        self.message = message
        # args hold the constructor arguments so copies made from ``type(exc)(*exc.args)`` (simpy does this)
        # are equal to the original
        super().__init__(message, path)

    def __str__(self) -> str:
        return f"{self.path}: {self.message}" if self.path else self.message


class BuildError(ConfigError):
    """Raised while turning a valid description into runtime objects (e.g. a task body that is no generator)."""


class SimulationError(NetsimError):
    """The simulation could not go on (integrator failure, impossible request at run time)."""


class DivergenceError(SimulationError):
    """The plant state blew up (NaN/Inf or beyond the divergence bound) at ``time_ns``."""

    def __init__(self, message: str, time_ns: int) -> None:
        self.time_ns = time_ns
        super().__init__(message, time_ns)

    def __str__(self) -> str:
        return str(self.args[0])


class LivelockError(SimulationError):
    """Zero-time activity repeated without time advancing; ``involved`` names the tasks/handlers."""

    def __init__(self, message: str, involved: list[str]) -> None:
        self.involved = involved
        super().__init__(message, involved)

    def __str__(self) -> str:
        return str(self.args[0])
