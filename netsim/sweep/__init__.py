"""Parameter sweeps: factor grids over scenario fields, run in parallel (process pool or Dask), resumable.

Examples
--------
>>> from netsim.sweep import run_sweep
>>> result = run_sweep("scenarios/hdd_gpi_sweep.yaml", workers=2)     # doctest: +SKIP
>>> result.summary.head()                                              # doctest: +SKIP
>>> print(result.describe())                                           # doctest: +SKIP

The sweep file format is described in :mod:`netsim.sweep.spec`; the output folder in :mod:`netsim.sweep.run`;
the ``summary.csv`` columns in :mod:`netsim.sweep.summary`; the GPI surface and its optimum in
:mod:`netsim.sweep.surface`; ``netsim batch`` (many scenario files in parallel) in :mod:`netsim.sweep.batch`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from netsim.lazy_import import callable_module, lazy_exports

if TYPE_CHECKING:  # pragma: no cover
    from netsim.sweep.executor import SchedulerLost, SchedulerUnreachable
    from netsim.sweep.run import SweepResult, run_sweep
    from netsim.sweep.spec import Point, Sweep, SweepSpec, derive_seed, expand_points, load_sweep

#: Where each public name lives; imported on first use (PEP 562), so that ``netsim.sweep.check`` (which
#: ``netsim run`` and ``netsim validate`` use to tell a sweep file) does not import numpy, pandas and the pool.
_WHERE = {
    "SchedulerLost": "executor", "SchedulerUnreachable": "executor", "SweepResult": "run", "run_sweep": "run",
    "Point": "spec", "Sweep": "spec", "SweepSpec": "spec", "derive_seed": "spec", "expand_points": "spec",
    "load_sweep": "spec",
}


__getattr__, __dir__ = lazy_exports(__name__, {name: f"netsim.sweep.{where}" for name, where in _WHERE.items()})
callable_module(__name__, "netsim.sweep.run:run_sweep", "netsim.run_sweep")  # it was the function once (issue 27)

__all__ = [
    "run_sweep",
    "load_sweep",
    "SweepResult",
    "SweepSpec",
    "Sweep",
    "Point",
    "expand_points",
    "derive_seed",
    "SchedulerUnreachable",
    "SchedulerLost",
]
