"""HDD benchmark (opt-in: pytest -m benchmark -s): wall time per case, TTS case vs plain numpy loops, sweep point.

What the ratios measure (printed with the figures):

* ``simulation``: building the runtime objects from the validated scenario and running the event loop
  (kernels, switched Ethernet, plant, programs) -- the work a co-simulator adds to the control loop itself;
* ``run()``: everything ``netsim.run(path, write=False)`` does: YAML parsing (libyaml; positions are parsed
  only for a problem to report), validation, the simulation, the result tables and the metrics.

Both are compared with two plain loops of the same closed loop measured in the same process: the minimal
plant + MRCI loop below, and :func:`netsim.control.reference_loop.simulate_loop` (plant, trigger, control
side, playout buffer). Times are the best of interleaved repetitions (the machine is shared).
"""

import copy
import json
import logging
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

from netsim.runner import clear_baseline_cache, run, run_point
from netsim.build.builder import build
from netsim.scenario.loader import load_scenario

SCEN = Path(__file__).resolve().parents[2] / "scenarios"


def _numpy_tts_loop(n=464):
    """The same closed loop as hdd_case1 in plain numpy: plant update, MRCI step, nothing else."""
    from netsim.models.hdd import hdd_model
    from netsim.control import MrciController, decompose

    m = hdd_model()
    ctrl = MrciController(decompose(m.controller_num, m.controller_den, m=2))
    A, b, c = m.Ap, m.Bp[:, 0], m.Cp[0]
    x = np.zeros(10)
    ys = np.empty(n)
    for k in range(n):
        y = float(c @ x)
        ys[k] = y
        u = ctrl.step(k, 1.0 - y)
        x = A @ x + b * u
    return ys


def _reference_loop(n=464):
    """hdd_case1 through netsim.control.reference_loop.simulate_loop (control side + playout, ideal timing)."""
    from netsim.models.hdd import hdd_model
    from netsim.control import ControlSide, MrciController, TimeTriggered, decompose, simulate_loop

    m = hdd_model()
    side = ControlSide(MrciController(decompose(m.controller_num, m.controller_den, m=2)), lambda k: 1.0)
    return simulate_loop(m.Ap, m.Bp, m.Cp, side, TimeTriggered(), n, reference=lambda k: 1.0)


def _best(fn, reps):
    """Best CPU time of ``reps`` calls (process time: on a shared machine wall time counts the others' work)."""
    best = float("inf")
    for _ in range(reps):
        t0 = time.process_time()
        fn()
        best = min(best, time.process_time() - t0)
    return best


@pytest.mark.benchmark
def test_bench_hdd_cases_and_tts_vs_numpy():
    run(SCEN / "hdd_case1.yaml", write=False)  # warm-up: imports, model and design caches
    walls = {}
    for n in range(1, 7):
        clear_baseline_cache()
        t0 = time.perf_counter()
        res = run(SCEN / f"hdd_case{n}.yaml", write=False)
        walls[n] = time.perf_counter() - t0
        assert res.meta["status"] == "ok"
    sc = load_scenario(SCEN / "hdd_case1.yaml")

    def simulate():
        build(sc).run()

    def event_loop() -> float:
        s = build(sc)
        t0 = time.process_time()
        s.run()
        return time.process_time() - t0

    t_sim, t_run, t_np, t_ref, t_loop = (float("inf"),) * 5
    for _ in range(7):  # interleaved, best of each
        t_sim = min(t_sim, _best(simulate, 1))
        t_loop = min(t_loop, event_loop())
        t_run = min(t_run, _best(lambda: run(SCEN / "hdd_case1.yaml", write=False), 1))
        t_np = min(t_np, _best(_numpy_tts_loop, 3))
        t_ref = min(t_ref, _best(_reference_loop, 3))
    res1 = run(SCEN / "hdd_case1.yaml", write=False)
    ys = _numpy_tts_loop()
    ise_np = float(np.sqrt(np.sum((1 - ys) ** 2)))
    for n, w in walls.items():
        print(f"hdd_case{n}: {w:.3f} s wall (run(), not written; including its Case 1 baseline run for n >= 2)")
    print(f"TTS case (464 periods): simulation (build + event loop) {t_sim * 1e3:.1f} ms, run() {t_run * 1e3:.1f} ms; "
          f"plain numpy loop {t_np * 1e3:.2f} ms, reference_loop.simulate_loop {t_ref * 1e3:.2f} ms")
    print(f"  ratio simulation / numpy loop {t_sim / t_np:.1f}x, / simulate_loop {t_sim / t_ref:.1f}x; "
          f"ratio run() / numpy loop {t_run / t_np:.1f}x, / simulate_loop {t_run / t_ref:.1f}x "
          f"(ISE netsim {float(res1.metrics['et.ISE']):.6f} vs numpy {ise_np:.6f})")
    print(f"  event loop only {t_loop * 1e3:.1f} ms ({t_loop / 464 * 1e6:.1f} us per control period): "
          f"{t_loop / t_np:.1f}x the numpy loop (issue 19 targets: event loop <= 5x, run() <= 8x)")
    # the ratio compares like with like only if both loops computed the same closed loop: the TTS ISE of eq (23)
    # from netsim must equal the one of the plain loop written in this file
    assert float(res1.metrics["et.ISE"]) == pytest.approx(ise_np, rel=1e-9)


@pytest.mark.benchmark
def test_bench_hdd_sweep_point(tmp_path):
    """Cost of one point of the 21 x 21 GPI sweep (hdd_case3 + its TTS baseline), as the sweep worker runs it."""
    logging.disable(logging.WARNING)  # h < N_max warnings at the grid's extreme thresholds
    try:
        raw = yaml.safe_load((SCEN / "hdd_case3.yaml").read_text())
        ss = np.logspace(-9, -1, 21)
        sc = np.logspace(-4, 0.2411478624117, 21)
        points = [(i, j) for i in range(0, 21, 4) for j in range(0, 21, 4)]

        def raw_at(i, j):
            r = copy.deepcopy(raw)
            sensor = r["nodes"]["sensor"]["handlers"][0]["params"]
            ctrl = r["nodes"]["controller"]["tasks"][0]["params"]
            sensor["sigma_s"] = sensor["delta_s"] = float(ss[i])
            ctrl["sigma_c"] = ctrl["delta_c"] = float(sc[j])
            return r

        run_point(raw_at(10, 10), tmp_path / "warm", 1)
        walls = {}
        for cached in (True, False):
            t0 = time.perf_counter()
            for i, j in points:
                if not cached:
                    clear_baseline_cache()
                run_point(raw_at(i, j), tmp_path / f"p{i}_{j}_{cached}", 1000 + 21 * i + j)
            walls[cached] = (time.perf_counter() - t0) / len(points)
    finally:
        logging.disable(logging.NOTSET)
    print(f"HDD sweep point (run_point on hdd_case3, run folder written; {len(points)} points of the 21 x 21 grid, "
          f"each with its own seed): {walls[True] * 1e3:.0f} ms per point with the baseline cache, "
          f"{walls[False] * 1e3:.0f} ms when the TTS baseline is re-run; 441 points on 2 workers ~ "
          f"{441 * walls[True] / 2:.0f} s of runs (without the executor's overhead)")
    # every point really ran: each wrote its run folder with an ok status
    statuses = [json.loads((tmp_path / f"p{i}_{j}_{c}" / "meta.json").read_text())["status"]
                for i, j in points for c in (True, False)]
    assert statuses == ["ok"] * (2 * len(points))
