"""netsim: TrueTime-style co-simulation of networked control systems on simpy.

The public entry points are imported lazily so that ``import netsim`` (and ``netsim --help``) stays fast:
``netsim.run``, ``netsim.load_scenario``, ``netsim.run_sweep``, ``netsim.make_report``, ``netsim.RunResult``;
``dir(netsim)`` lists them. ``netsim.run`` from Python writes a run folder only when asked (``out=`` or
``write=True``); the ``netsim run`` command always writes one.

No top-level name is also a submodule's name: ``netsim.sweep`` and ``netsim.report`` are always the modules
(:mod:`netsim.sweep`, :mod:`netsim.report`). Before issue 27 they were the functions until the module was first
imported (by a run, say), and modules after it. Calling either module still runs the function, with a
``DeprecationWarning`` naming ``netsim.run_sweep`` / ``netsim.make_report``
(:func:`netsim.lazy_import.callable_module`).

``netsim.run(..., allow_plugins=True)`` and ``netsim.load_scenario(..., allow_plugins=True)`` let a scenario run
the plugin files its ``plugins:`` list names (default: the user's settings, :mod:`netsim.trust`; see the
README's "Security" section).

Importing netsim pins BLAS to one thread and, on x86-64 CPUs with AVX2, to OpenBLAS's Haswell kernels, so that
the same scenario and seed give byte-identical files on every such machine (:mod:`netsim.blas`); a value the user
already set in the environment is kept. This takes effect only if netsim is imported before numpy.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from netsim.results import RunResult

from netsim.blas import configure as _configure_blas

# one BLAS thread, and the same OpenBLAS kernels on every x86-64 machine, before numpy is imported (netsim.blas)
_configure_blas()

__version__ = "0.1.0"

__all__ = ["__version__", "run", "load_scenario", "run_sweep", "make_report", "RunResult"]

#: Exported name -> (module, attribute), imported on first use. No name here is a submodule of netsim: a
#: submodule's import sets the package attribute of its name, which would replace the lazy name.
_LAZY = {
    "load_scenario": ("netsim.scenario", "load_scenario"),
    "make_report": ("netsim.report", "report"),
    "run_sweep": ("netsim.sweep.run", "run_sweep"),
    "RunResult": ("netsim.results", "RunResult"),
}

#: Submodules read as ``netsim.<name>`` before they are imported (they were functions once: callable, deprecated).
_SUBMODULES = ("report", "sweep")


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
) -> RunResult:
    """Run one scenario from Python; the result is complete in memory, and a run folder is written only when
    asked for.

    Parameters
    ----------
    source : str, pathlib.Path, Mapping or netsim.scenario.Scenario
        Scenario file path, a mapping with the scenario's content, or a loaded ``Scenario``
        (:func:`load_scenario`).
    out : str or pathlib.Path, optional
        Write the run folder here (anywhere; implies ``write=True``).
    write : bool, optional
        True: write the run folder (to ``out``, else ``reports/<output.dir>`` or ``reports/<name>/<run-id>/``
        as ``netsim run`` does). Default: only when ``out`` is given (``netsim run`` always writes one).
    seed : int, optional
        The scenario's seed (default: the scenario's own).
    overrides : Mapping[str, Any], optional
        ``{"dotted.path": value}`` changes, applied before the one validation.
    plot : bool, default False
        With a run folder: also write its PNG figures (``result.plot()`` returns them as matplotlib figures).
    progress : Callable[[int, int], None], optional
        ``progress(t_ns, t_end_ns)`` callback, about every 1 % of simulated time.
    allow_plugins : bool, optional
        Whether the Python files the scenario's ``plugins:`` list names may run (None: the user's settings).

    Returns
    -------
    RunResult
        Tables (``signals``, ``jobs``, ``messages``), ``metrics``, ``meta`` with ``status``; ``out_dir`` is
        the run folder or None.

    Examples
    --------
    >>> import netsim
    >>> result = netsim.run("scenarios/dc_servo_can.yaml", seed=3)          # doctest: +SKIP
    >>> result.status, result.metrics["y.ISE"]                              # doctest: +SKIP
    >>> result.plot()                                                       # doctest: +SKIP
    """
    import importlib

    # the package sits in the foundation layer: the runner is looked up lazily, as the names of _LAZY are
    _run = importlib.import_module("netsim.runner").run
    return _run(source, out=out, write=(out is not None) if write is None else bool(write), seed=seed,
                overrides=overrides, plot=plot, progress=progress, allow_plugins=allow_plugins)


def __getattr__(name: str) -> Any:
    import importlib

    if name in _LAZY:
        module, attr = _LAZY[name]
        return getattr(importlib.import_module(module), attr)
    if name in _SUBMODULES:  # importing it sets the attribute: this runs once
        return importlib.import_module(f"netsim.{name}")
    raise AttributeError(f"module 'netsim' has no attribute {name!r}")


def __dir__() -> list[str]:
    """The public API for tab completion (the lazy names included), and the module's dunder attributes."""
    return sorted(set(__all__) | {name for name in globals() if name.startswith("__")})
