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

from netsim.sweep.executor import SchedulerLost, SchedulerUnreachable
from netsim.sweep.run import SweepResult, run_sweep
from netsim.sweep.spec import Point, Sweep, SweepSpec, derive_seed, expand_points, load_sweep

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
