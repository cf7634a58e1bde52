"""netsim: TrueTime-style co-simulation of networked control systems on simpy.

The public entry points are imported lazily so that ``import netsim`` (and ``netsim --help``) stays fast:
``netsim.run``, ``netsim.load_scenario``, ``netsim.report``, ``netsim.sweep``.

``netsim.run(..., allow_plugins=True)`` and ``netsim.load_scenario(..., allow_plugins=True)`` let a scenario run
the plugin files its ``plugins:`` list names (default: the user's settings, :mod:`netsim.trust`; see the
README's "Security" section).
"""

from __future__ import annotations

from typing import Any

__version__ = "0.1.0"

__all__ = ["__version__", "run", "load_scenario", "report", "sweep"]

_LAZY = {
    "run": ("netsim.runner", "run"),
    "load_scenario": ("netsim.scenario", "load_scenario"),
    "report": ("netsim.report", "report"),
    "sweep": ("netsim.sweep", "run_sweep"),
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        import importlib

        module, attr = _LAZY[name]
        return getattr(importlib.import_module(module), attr)
    raise AttributeError(f"module 'netsim' has no attribute {name!r}")
