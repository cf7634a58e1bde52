"""hdd_case1 ``run()`` against the repo's plain numpy TTS loop, with calls and heap entries per period (issue 29,
first row).

Opt in: ``pytest -m benchmark -s tests/benchmarks/test_bench_hdd_overhead.py``.

The numpy loop is :func:`tests.benchmarks.test_bench_hdd._numpy_tts_loop` (plant update and MRCI step of the
same closed loop, nothing else). Printed, as CPU-time medians of interleaved rounds in one process (the machine is
shared; the load average is printed):

* ``run()``: ``netsim.run(hdd_case1, write=False)`` (YAML, validation, build, event loop, tables, metrics), over
  the numpy loop (issue 29 target <= 8x);
* the event loop alone over the numpy loop, and what lies outside it (``run()`` minus the loop) in ms and over
  the numpy loop (issue 29: down to about 10 ms);
* per control period (464): heap entries pushed by the event loop, and Python calls (cProfile's count, builtins
  included) of the event loop and of the whole ``run()``.

Asserted: netsim's TTS ISE equals the numpy loop's to 1e-9, so both computed the same closed loop.
"""

from __future__ import annotations

import cProfile
import os
import pstats
import statistics
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from netsim.build.builder import build
from netsim.runner import clear_baseline_cache, run
from netsim.scenario.loader import load_scenario
from tests.benchmarks.test_bench_hdd import _numpy_tts_loop

CASE1 = Path(__file__).resolve().parents[2] / "scenarios" / "hdd_case1.yaml"
PERIODS = 464  # 9.28 ms at T = 20 us


def _cpu(fn: Any, reps: int = 1) -> float:
    """CPU time of one call (the mean of ``reps`` calls)."""
    t0 = time.process_time()
    for _ in range(reps):
        fn()
    return (time.process_time() - t0) / reps


def _calls(fn: Any) -> int:
    prof = cProfile.Profile()
    prof.enable()
    fn()
    prof.disable()
    return int(pstats.Stats(prof).total_calls)  # type: ignore[attr-defined]


def _run() -> Any:
    clear_baseline_cache()  # hdd_case1 is its own baseline: run it, not a cached copy
    return run(CASE1, write=False)


@pytest.mark.benchmark
def test_bench_hdd_case1_run_against_numpy_tts_loop():
    res = _run()  # warm-up: imports, model and design caches
    ys = _numpy_tts_loop()
    ise_np = float(np.sqrt(np.sum((1.0 - ys) ** 2)))
    assert float(res.metrics["et.ISE"]) == pytest.approx(ise_np, rel=1e-9)
    sc = load_scenario(CASE1)

    def loop_only() -> float:
        sim = build(sc)
        t0 = time.process_time()
        sim.run()
        return time.process_time() - t0

    load = os.getloadavg()
    t_run, t_loop, t_np = [], [], []
    for _ in range(9):  # interleaved rounds
        t_np.append(_cpu(_numpy_tts_loop, reps=5))
        t_run.append(_cpu(_run))
        t_loop.append(loop_only())
    med = statistics.median
    r, lp, n = med(t_run), med(t_loop), med(t_np)
    sim = build(sc)
    calls_loop = _calls(sim.run)
    entries = sim.env.sim.events_scheduled()
    calls_run = _calls(_run)
    print(f"\n[bench] hdd_case1 ({PERIODS} periods); load average {load[0]:.2f} before, {os.getloadavg()[0]:.2f} "
          f"after; CPU medians of 9 interleaved rounds")
    print(f"[bench]   numpy TTS loop {n * 1e3:.2f} ms; run() {r * 1e3:.1f} ms = {r / n:.1f}x (target <= 8x); "
          f"event loop {lp * 1e3:.1f} ms = {lp / n:.1f}x; outside the loop {(r - lp) * 1e3:.1f} ms = "
          f"{(r - lp) / n:.1f}x (target about 10 ms)")
    print(f"[bench]   per period: {entries / PERIODS:.1f} heap entries, {calls_loop / PERIODS:.0f} calls in the "
          f"event loop (target about 110), {calls_run / PERIODS:.0f} in the whole run() (cProfile, builtins included)")
