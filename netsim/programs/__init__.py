"""Task and handler programs: the thin wrappers that run :mod:`netsim.control` objects inside kernels.

A program reads inputs (``analog_in``, received messages), calls a plain numeric object (a PID, an event trigger,
a control side), charges its execution time and sends or actuates, all as requests yielded to its kernel
(:mod:`netsim.kernel.requests`). Scenario tasks name programs by their registered names (``netsim list programs``).

``basic``
    the generic loop programs: ``idle``, ``sampler``, ``controller``, ``actuator``, ``interference``,
    ``periodic_controller`` (TrueTime's example code functions).
``event_triggered``
    the event-triggered multi-rate loop of Cuenca et al.: ``et_sensor``, ``et_controller``, ``playout_actuator``.

Case-study programs live with their case study in ``models/`` (e.g. ``models/cart/programs.py``). A new program
is a class with a nested ``Params`` model and an ``@register("program", NAME)`` line in a module of this package
(copy ``basic.Sampler``); :func:`netsim.registry.load_plugins` imports every module here.
"""

from __future__ import annotations

from netsim.programs.basic import (
    BROADCAST,
    Actuator,
    Controller,
    Idle,
    Interference,
    PeriodicController,
    ProgramContext,
    Sampler,
)

__all__ = [
    "BROADCAST",
    "ProgramContext",
    "Idle",
    "Sampler",
    "Controller",
    "Actuator",
    "Interference",
    "PeriodicController",
]
