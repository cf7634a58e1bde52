"""Benchmark (issue 29, sweep row): the HDD GPI sweep on 2 workers, against the simulation alone.

Run with ``pytest -m benchmark -s tests/benchmarks/test_bench_sweep_gpi.py``. ``NETSIM_BENCH_GPI_NUM`` sets the
grid side (default 21, the shipped 21 x 21 grid; a smaller side runs the same points' kind on fewer levels).

Prints, for ``runs: metrics`` as shipped:

* points per second (wall) on 2 workers, and the load average (the wall rate on a shared machine measures the
  load as much as the sweep);
* CPU milliseconds per point, pool, workers and the parent's up-front check and summary included (less
  sensitive to the load);
* the baseline measured in this same process: the CPU of the simulation alone (a built point's event loop, no
  loading, building, metrics or files) per point, and the ratio of the sweep's CPU per point to it. The issue's
  target (>= 40 points/s on 2 idle cores) needs a sweep CPU per point <= 50 ms.
"""

from __future__ import annotations

import os
import resource
import time
from pathlib import Path

import pytest

from netsim.sweep import load_sweep, run_sweep

ROOT = Path(__file__).resolve().parents[2]
SWEEP = ROOT / "scenarios" / "hdd_gpi_sweep.yaml"
WORKERS = 2


def _cpu_s() -> tuple[float, float]:
    """CPU seconds of this process, and of its finished children (the pool's workers, once it is shut down)."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime, kids.ru_utime + kids.ru_stime


def _grid_file(tmp_path: Path, num: int) -> Path:
    """The shipped sweep with its base named by absolute path and ``num`` levels per factor."""
    text = SWEEP.read_text(encoding="utf-8").replace("base: hdd_case3.yaml", f"base: {SWEEP.parent / 'hdd_case3.yaml'}")
    text = text.replace("num: 21}", f"num: {num}}}")
    path = tmp_path / "gpi.yaml"
    path.write_text(text, encoding="utf-8")
    return path


def _simulation_only_cpu(path: Path, sample: int) -> float:
    """CPU seconds per point of the event loop alone, over ``sample`` points spread over the grid."""
    from netsim.build.builder import build
    from netsim.scenario.loader import load_scenario

    sweep = load_sweep(path)
    n = len(sweep.points)
    picks = [sweep.points[(k * (n - 1)) // max(1, sample - 1)] for k in range(sample)]
    total = 0.0
    for p in picks:
        sim = build(load_scenario({**sweep.point_raw(p), "seed": p.seed}))
        c0 = time.process_time()
        sim.run()
        total += time.process_time() - c0
    return total / len(picks)


@pytest.mark.benchmark
def test_bench_gpi_sweep_two_workers_against_simulation_alone(tmp_path: Path) -> None:
    num = int(os.environ.get("NETSIM_BENCH_GPI_NUM", "21"))
    path = _grid_file(tmp_path, num)
    n = num * num
    _simulation_only_cpu(path, 1)  # warm-up: imports, plugin registry, the HDD design cache
    before = _simulation_only_cpu(path, 9)
    load = os.getloadavg()[0]
    t0, c0 = time.perf_counter(), _cpu_s()
    res = run_sweep(path, out=tmp_path / "gpi", workers=WORKERS, progress=False)
    wall, c1 = time.perf_counter() - t0, _cpu_s()
    parent, workers = (c1[0] - c0[0]) / n, (c1[1] - c0[1]) / n
    after = _simulation_only_cpu(path, 9)  # before and after the sweep: a load that changed meanwhile shows
    sim_cpu = (before + after) / 2
    cpu = parent + workers
    bad = res.summary[res.summary["status"] != "ok"]
    assert res.n_ok == n, bad[["status", "error"]].head().to_string()
    print(f"\nGPI sweep {num}x{num} = {n} points, {WORKERS} workers: {wall:.2f} s wall = {n / wall:.1f} points/s "
          f"(target >= 40), load average {load:.2f} before it ran")
    print(f"CPU per point (parent + workers): {cpu * 1e3:.1f} ms -> {WORKERS / cpu:.1f} points/s on {WORKERS} idle "
          f"cores (parent {parent * 1e3:.1f} ms: up-front check, summary, surface; workers {workers * 1e3:.1f} ms)")
    print(f"simulation alone {before * 1e3:.1f} / {after * 1e3:.1f} ms CPU per point before / after the sweep "
          f"(9 points spread over the grid) -> ratio {cpu / sim_cpu:.2f}x (workers alone "
          f"{workers / sim_cpu:.2f}x)")
