"""Benchmark: the 21 x 21 HDD GPI sweep on the local process pool, and the executor's per-point overhead.

Run with ``pytest -m benchmark -s tests/benchmarks/test_bench_sweep.py``. Prints the wall time of the full
sweep (target < 60 s on 2 cores), points per second, and the per-point cost of the sweep machinery (process
pool, chunking, scenario hash, point record) against calling the point function directly in this process.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest
import yaml

from netsim.sweep import load_sweep, run_sweep

ROOT = Path(__file__).resolve().parents[2]
SWEEP = ROOT / "scenarios" / "hdd_gpi_sweep.yaml"


def noop_point(raw, out, seed):
    """A point that does nothing: what is left is the executor's own cost.

    It writes the ``meta.json`` a run writes (seed and scenario hash), so the sweep reads the hash from it as it
    does for a real point, instead of validating the scenario to compute it."""
    import json

    (Path(out) / "meta.json").write_text(json.dumps({"seed": seed, "scenario_hash": "noop"}), encoding="utf-8")
    return {"et.GPI": float(seed % 7)}  # the surface column of hdd_gpi_sweep.yaml (et_control names it et.GPI)


@pytest.mark.benchmark
def test_bench_executor_overhead_per_point(tmp_path: Path) -> None:
    sweep = load_sweep(SWEEP)
    n = len(sweep.points)
    t0 = time.perf_counter()
    for p in sweep.points:
        noop_point(sweep.point_raw(p), tmp_path, p.seed)
    direct = (time.perf_counter() - t0) / n
    from netsim.sweep.run import _refuse_invalid

    _refuse_invalid(SWEEP)  # warm-up: imports, plugin registry, the HDD design cache
    t0 = time.perf_counter()
    _refuse_invalid(SWEEP)  # once per sweep: the base scenario and every factor level checked before anything runs
    check = time.perf_counter() - t0
    print(f"\nup-front check of the sweep file: {check:.2f} s ({check / n * 1e3:.1f} ms per point of this sweep)")
    for label, kwargs in (("serial", {"workers": 1}), ("pool", {"workers": os.cpu_count()})):
        t0 = time.perf_counter()
        res = run_sweep(SWEEP, out=tmp_path / label, point_fn=noop_point, progress=False, **kwargs)
        wall = time.perf_counter() - t0
        assert res.n_ok == n
        per = (wall - check) / n
        print(f"\n{label:6s}: {n} no-op points in {wall:.2f} s = {per * 1e3:.2f} ms/point wall without the check "
              f"(direct call {direct * 1e3:.2f} ms/point -> machinery {(per - direct) * 1e3:.2f} ms/point; issue 19 "
              f"target: pool overhead < 5 ms/point)")


def _cpu_s() -> float:
    """CPU seconds of this process and of its finished children (the pool's workers, once it is shut down)."""
    import resource

    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


@pytest.mark.benchmark
@pytest.mark.parametrize("runs", ["full", "metrics"])
def test_bench_hdd_gpi_sweep_local_pool(tmp_path: Path, runs: str) -> None:
    """The GPI sweep with ``runs: full`` (each point writes its whole run folder) and as shipped, ``runs: metrics``
    (each point writes metrics.csv and meta.json only). Besides the wall rate it prints the CPU seconds per point (workers included) and the rate two
    idle cores would give, ``2 / CPU per point``: on a machine shared with other work the wall rate measures the
    load as much as the sweep."""
    from functools import partial

    from netsim.runner import run_point

    text = SWEEP.read_text(encoding="utf-8").replace("base: hdd_case3.yaml", f"base: {SWEEP.parent / 'hdd_case3.yaml'}")
    text = "\n".join(line for line in text.splitlines() if not line.startswith("runs:"))
    path = tmp_path / "gpi.yaml"
    path.write_text(text + f"\nruns: {runs}\n", encoding="utf-8")
    sweep = load_sweep(path)
    n = len(sweep.points)
    sample = [sweep.points[i] for i in (0, n // 2, n - 1)]
    point = partial(run_point, tables=runs == "full")
    point(sweep.point_raw(sample[0]), tmp_path / "warm", sample[0].seed)  # imports, registry, caches
    t0, c0 = time.perf_counter(), time.process_time()
    for k, p in enumerate(sample):
        point(sweep.point_raw(p), tmp_path / f"direct{k}", p.seed)
    direct = (time.perf_counter() - t0) / len(sample)
    direct_cpu = (time.process_time() - c0) / len(sample)
    workers = os.cpu_count() or 1
    t0, c0 = time.perf_counter(), _cpu_s()
    res = run_sweep(path, out=tmp_path / "gpi", workers=workers, progress=False)
    wall, cpu = time.perf_counter() - t0, (_cpu_s() - c0) / n
    per_point = wall * workers / n
    print(f"\nHDD GPI sweep (runs: {runs}) {n} points on {workers} workers: {wall:.1f} s wall, "
          f"{n / wall:.2f} points/s (issue 19 target >= 25 points/s on 2 workers), {res.n_failed} failed, "
          f"load average {os.getloadavg()[0]:.1f}")
    print(f"CPU per point, workers and pool included: {cpu * 1e3:.1f} ms -> {workers / cpu:.1f} points/s on "
          f"{workers} idle cores; direct run_point {direct_cpu * 1e3:.1f} ms CPU ({direct * 1e3:.1f} ms wall)")
    print(f"through the pool: {per_point * 1e3:.1f} ms/point-worker wall -> overhead {(per_point - direct) * 1e3:+.1f} "
          f"ms/point (target < 5 ms; includes the sweep's up-front check of its factor levels); bound by the point "
          f"itself: {workers / direct:.1f} points/s")
    if res.optimum:
        from netsim.sweep.surface import describe_optimum

        print(describe_optimum(res.optimum))
    assert res.n_runs == n
