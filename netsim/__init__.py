"""netsim: TrueTime-style co-simulation of networked control systems on simpy.

The public entry points are imported lazily so that ``import netsim`` (and ``netsim --help``) stays fast:
``netsim.run``, ``netsim.load_scenario``, ``netsim.report``, ``netsim.sweep``, ``netsim.RunResult``; ``dir(netsim)``
lists them. ``netsim.run`` from Python writes a run folder only when asked (``out=`` or ``write=True``); the
``netsim run`` command always writes one.

``netsim.run(..., allow_plugins=True)`` and ``netsim.load_scenario(..., allow_plugins=True)`` let a scenario run
the plugin files its ``plugins:`` list names (default: the user's settings, :mod:`netsim.trust`; see the
README's "Security" section).

Importing netsim pins BLAS to one thread and, on x86-64 CPUs with AVX2, to OpenBLAS's Haswell kernels, so that
the same scenario and seed give byte-identical files on every such machine (:mod:`netsim.blas`); a value the user
already set in the environment is kept. This takes effect only if netsim is imported before numpy.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from collections.abc import Callable, Mapping
    from pathlib import Path

from netsim.blas import configure as _configure_blas

# one BLAS thread, and the same OpenBLAS kernels on every x86-64 machine, before numpy is imported (netsim.blas)
_configure_blas()

__version__ = "0.1.0"

__all__ = ["__version__", "run", "load_scenario", "report", "sweep", "RunResult"]

_LAZY = {
    "load_scenario": ("netsim.scenario", "load_scenario"),
    "report": ("netsim.report", "report"),
    "sweep": ("netsim.sweep", "run_sweep"),
    "RunResult": ("netsim.results", "RunResult"),
}


def run(
    source: Any,
    *,
    out: str | Path | None = None,
    write: bool | None = None,
    seed: int | None = None,
    overrides: Mapping[str, Any] | None = None,
    plot: bool = False,
    progress: Callable[[int, int], None] | None = None,
    allow_plugins: bool | None = None,
) -> Any:
    """Run one scenario from Python; the result is complete in memory, and a run folder is written only when
    asked for.

    Parameters
    ----------
    source
        Scenario file path, a mapping with the scenario's content, or a loaded ``Scenario``
        (:func:`load_scenario`).
    out
        Write the run folder here (anywhere; implies ``write=True``).
    write
        True: write the run folder (to ``out``, else ``reports/<output.dir>`` or ``reports/<name>/<run-id>/``
        as ``netsim run`` does). Default: only when ``out`` is given (``netsim run`` always writes one).
    seed, overrides
        The scenario's seed, and ``{"dotted.path": value}`` changes, applied before the one validation.
    plot
        With a run folder: also write its PNG figures (``result.plot()`` returns them as matplotlib figures).
    progress
        Optional ``progress(t_ns, t_end_ns)`` callback, about every 1 % of simulated time.
    allow_plugins
        Whether the Python files the scenario's ``plugins:`` list names may run (None: the user's settings).

    Returns
    -------
    netsim.results.RunResult
        Tables (``signals``, ``jobs``, ``messages``), ``metrics``, ``meta`` with ``status``; ``out_dir`` is
        the run folder or None.
    """
    import importlib

    # the package sits in the foundation layer: the runner is looked up lazily, as the names of _LAZY are
    _run = importlib.import_module("netsim.runner").run
    return _run(source, out=out, write=(out is not None) if write is None else bool(write), seed=seed,
                overrides=overrides, plot=plot, progress=progress, allow_plugins=allow_plugins)


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        import importlib

        module, attr = _LAZY[name]
        return getattr(importlib.import_module(module), attr)
    raise AttributeError(f"module 'netsim' has no attribute {name!r}")


def __dir__() -> list[str]:
    """The public API for tab completion (the lazy names included), and the module's dunder attributes."""
    return sorted(set(__all__) | {name for name in globals() if name.startswith("__")})
