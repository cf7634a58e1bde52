"""netsim: TrueTime-style co-simulation of networked control systems on simpy.

The public entry points are imported lazily so that ``import netsim`` (and ``netsim --help``) stays fast:
``netsim.run``, ``netsim.load_scenario``, ``netsim.report``, ``netsim.sweep``.

``netsim.run(..., allow_plugins=True)`` and ``netsim.load_scenario(..., allow_plugins=True)`` let a scenario run
the plugin files its ``plugins:`` list names (default: the user's settings, :mod:`netsim.trust`; see the
README's "Security" section).

Importing netsim pins BLAS to one thread and, on x86-64 CPUs with AVX2, to OpenBLAS's Haswell kernels, so that
the same scenario and seed give byte-identical files on every such machine (:mod:`netsim.blas`); a value the user
already set in the environment is kept. This takes effect only if netsim is imported before numpy.
"""

from __future__ import annotations

from typing import Any

from netsim.blas import configure as _configure_blas

# one BLAS thread, and the same OpenBLAS kernels on every x86-64 machine, before numpy is imported (netsim.blas)
_configure_blas()

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
