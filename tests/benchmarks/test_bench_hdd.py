"""HDD benchmark (opt-in: pytest -m benchmark -s): wall time per case and TTS case vs a plain numpy loop."""

import time
from pathlib import Path

import numpy as np
import pytest

from netsim.runner import run

SCEN = Path(__file__).resolve().parents[2] / "scenarios"


def _numpy_tts_loop(n=464):
    """The same closed loop as hdd_case1 in plain numpy: plant update, MRCI step, nothing else."""
    from models.hdd import hdd_model
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


@pytest.mark.benchmark
def test_bench_hdd_cases_and_tts_vs_numpy():
    run(SCEN / "hdd_case1.yaml", write=False)  # warm-up: imports, model and design caches
    walls = {}
    for n in range(1, 7):
        t0 = time.perf_counter()
        res = run(SCEN / f"hdd_case{n}.yaml", write=False)
        walls[n] = time.perf_counter() - t0
        assert res.meta["status"] == "ok"
    # the TTS case alone, without its (absent) baseline; repeated for a stable figure
    reps = 5
    t0 = time.perf_counter()
    for _ in range(reps):
        res1 = run(SCEN / "hdd_case1.yaml", write=False)
    t_sim = (time.perf_counter() - t0) / reps
    t0 = time.perf_counter()
    for _ in range(50):
        ys = _numpy_tts_loop()
    t_np = (time.perf_counter() - t0) / 50
    ise_np = float(np.sqrt(np.sum((1 - ys) ** 2)))
    for n, w in walls.items():
        print(f"hdd_case{n}: {w:.3f} s wall (including its Case 1 baseline run for n >= 2)")
    print(f"TTS case: netsim {t_sim * 1e3:.1f} ms, numpy loop {t_np * 1e3:.2f} ms, ratio {t_sim / t_np:.1f}x "
          f"(ISE netsim {float(res1.metrics['ISE']):.6f} vs numpy {ise_np:.6f})")
