"""Speed of the 2WD cart study (opt-in: ``pytest -m benchmark -s tests/models/unicycle/test_unicycle_bench.py``).

Prints: one netsim run of ``unicycle_lqr.yaml`` (IR sensors, EKF + LQR and drive on their nodes over CAN)
against a plain numpy loop of the same EKF + LQR written here (no network, no kernel), and 200 Monte-Carlo runs
of the scenario on the local process pool (``UNICYCLE_BENCH_RUNS`` to change the count).
"""

from __future__ import annotations

import json
import math
import os
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pytest

import netsim

SCENARIO = Path(__file__).resolve().parents[3] / "scenarios" / "unicycle_lqr.yaml"


def _numpy_loop(seed: int) -> float:
    """The same EKF (eqs 10-17) and cart-frame LQR (eqs 24-27) as plain numpy, 1000 steps; returns the final error."""
    from netsim.models.unicycle.design import Trajectory, lqr_gain

    rng = np.random.default_rng(seed)
    ts, alpha, beta, gamma = 0.01, 0.075, 0.065, 0.078
    Q = np.diag([8e-9, 9e-8, 9e-7])
    R = (0.0198, 0.09)
    traj = Trajectory()
    gains = {v: lqr_gain(v) for v in (0.03, 0.02, 0.015)}
    x = np.array([-0.3, -0.2, 0.0])
    P = np.diag([1e-3, 1e-3, 7.6e-3])
    xi = x + np.sqrt(np.diag(P)) * rng.standard_normal(3)
    for k in range(traj.n + 1):
        t = k * ts
        for src, on, every in ((0, t < 4 or t >= 6, 2), (1, t < 4, 4)):
            if on and k % every == 0:
                c, s = math.cos(xi[2]), math.sin(xi[2])
                z = -(xi[1] + alpha * s) if src == 0 else -(xi[0] + beta * c + gamma * s)
                z += math.sqrt(R[src]) * rng.standard_normal()
                c, s = math.cos(x[2]), math.sin(x[2])
                if src == 0:
                    h, H = -(x[1] + alpha * s), np.array([0.0, -1.0, -alpha * c])
                else:
                    h, H = -(x[0] + beta * c + gamma * s), np.array([-1.0, 0.0, beta * s - gamma * c])
                PH = P @ H
                K = PH / (H @ PH + R[src])
                x = x + K * (z - h)
                IKH = np.eye(3) - np.outer(K, H)
                P = IKH @ P @ IKH.T + R[src] * np.outer(K, K)
        ref, uref = traj.at(k)
        e = ref - x
        c, s = math.cos(x[2]), math.sin(x[2])
        ec = np.array([c * e[0] + s * e[1], -s * e[0] + c * e[1], math.atan2(math.sin(e[2]), math.cos(e[2]))])
        v, w = -gains[float(uref[0])] @ ec
        A = np.array([[1, 0, -ts * v * math.sin(x[2])], [0, 1, ts * v * math.cos(x[2])], [0, 0, 1.0]])
        x = x + ts * np.array([v * math.cos(x[2]), v * math.sin(x[2]), w])
        P = A @ P @ A.T + Q
        half = 0.5 * w * ts
        sc = math.sin(half) / half if half else 1.0
        xi = xi + np.array([v * ts * sc * math.cos(xi[2] + half), v * ts * sc * math.sin(xi[2] + half), w * ts])
        xi = xi + np.sqrt(np.diag(Q)) * rng.standard_normal(3)
    return float(np.abs(xi - x).max())


def _one(seed: int) -> str:
    return netsim.run(SCENARIO, seed=seed).status


@pytest.mark.benchmark
def test_bench_single_run_against_numpy_and_pool():
    _one(1)  # warm-up: imports, python-control
    _numpy_loop(1)
    repeats = int(os.environ.get("UNICYCLE_BENCH_REPEATS", "7"))
    t_net, t_np, statuses = [], [], []
    for i in range(repeats):  # interleaved, best of each: the machine is shared, the minimum is the least disturbed
        t0 = time.perf_counter()
        statuses.append(_one(2 + i))
        t_net.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        err = _numpy_loop(2 + i)
        t_np.append(time.perf_counter() - t0)
    ratio = min(t_net) / min(t_np)
    print(f"\nunicycle_lqr: one netsim run {min(t_net):.3f} s (median {sorted(t_net)[repeats // 2]:.3f}), plain numpy "
          f"EKF + LQR loop {min(t_np):.3f} s (median {sorted(t_np)[repeats // 2]:.3f}), ratio {ratio:.1f}x "
          f"(target <= 5x); numpy loop final error {err:.3g}")
    n = int(os.environ.get("UNICYCLE_BENCH_RUNS", "200"))
    workers = os.cpu_count() or 1
    t0 = time.perf_counter()
    with ProcessPoolExecutor(workers) as ex:
        statuses += list(ex.map(_one, range(100, 100 + n), chunksize=max(1, n // (4 * workers))))
    wall = time.perf_counter() - t0
    print(f"{n} Monte-Carlo runs of the 10 s trajectory on {workers} processes: {wall:.1f} s, {n / wall:.2f} runs/s")
    out = Path(__file__).resolve().parents[3] / "reports" / "unicycle" / "speed.json"
    if out.parent.is_dir():  # read by `netsim report unicycle` (its Speed section)
        out.write_text(json.dumps({"ratio": ratio, "repeats": repeats, "netsim_s": min(t_net), "numpy_s": min(t_np),
                                   "pool_runs": n, "pool_wall_s": wall, "pool_workers": workers,
                                   "load_average": os.getloadavg()[0]}, indent=1))
    assert all(s == "ok" for s in statuses)
    assert ratio < 10.0  # the numpy-heavy version of the programs was 10.4x-10.8x; the float one 3-6x
