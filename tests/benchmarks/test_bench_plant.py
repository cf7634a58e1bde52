"""Plant and encoder speed (opt in: ``pytest -m benchmark -s tests/benchmarks/test_bench_plant.py``)."""

from __future__ import annotations

import time

import numpy as np
import pytest

from netsim.env import SimEnv
from netsim.io import Encoder
from netsim.plant import LTIPlant
from netsim.timebase import S, US

pytestmark = pytest.mark.benchmark


def _lti(n: int) -> LTIPlant:
    rng = np.random.default_rng(n)
    A = rng.standard_normal((n, n)) - 3.0 * np.eye(n) * np.sqrt(n)
    return LTIPlant(A, rng.standard_normal((n, 1)), rng.standard_normal((1, n)), None)


@pytest.mark.parametrize("n", [2, 10])
def test_bench_lti_steps_per_second(n):
    steps = 200_000
    h = 20 * US
    plant = _lti(n)
    plant.set_input(0, 1.0, 0)
    t0 = time.perf_counter()
    for k in range(1, steps + 1):
        plant.advance_to(k * h)
    dt = time.perf_counter() - t0
    # baseline in the same process: the bare numpy update the plant performs per step, with the same product
    # call the plant uses (ndarray.dot, see netsim.plant.matvec), so the ratio compares like with like
    G, _ = plant.transition(h)
    zu = np.zeros(n + 1)
    zu[n] = 1.0
    gdot = G.dot
    t0 = time.perf_counter()
    for _ in range(steps):
        zu[:n] = gdot(zu)
    base = time.perf_counter() - t0
    rate = steps / dt
    print(f"\nLTI n={n}: {rate:,.0f} steps/s ({dt / steps * 1e6:.2f} us/step); bare numpy update "
          f"{steps / base:,.0f}/s; overhead x{dt / base:.2f}")
    # Issue 4's target is >= 100 000 steps/s for n = 10 on an idle core (the bare update alone runs at
    # ~1 M/s there). Wall rates swing with machine load, so the assertion is on the ratio to the bare update
    # measured in this process: the plant's bookkeeping may cost at most 4x the matrix product itself.
    if n == 10:
        print(f"target >= 100 000 steps/s for n = 10: {'met' if rate >= 100_000 else 'NOT met (machine load?)'}")
    assert dt / base <= 4.0


def test_bench_encoder_exact_vs_polling():
    # the cart of Henningsson & Cervin: 100 kHz ISR, 0.8 m/s for 2 s, delta = 3.2 mm (500 edges); the start
    # position is offset so that no crossing falls exactly on a tick
    def run(mode: str) -> tuple[list, float]:
        env = SimEnv(seed=0)
        plant = LTIPlant([[0.0, 1.0], [0.0, 0.0]], [0.0, 1.0], [1.0, 0.0], None, x0=[1.234e-5, 0.8])
        plant.bind(env)
        edges: list = []
        Encoder(plant, 0, step=3.2e-3, tick_ns=10 * US, mode=mode).start(env, lambda *e: edges.append(e))
        t0 = time.perf_counter()
        env.run(2 * S)
        return edges, time.perf_counter() - t0

    run("exact")  # warm-up (imports, first matrix exponentials)
    exact, t_exact = run("exact")
    polled, t_poll = run("polling")
    assert exact == polled and len(exact) == 500
    ratio = t_poll / t_exact
    print(f"\nencoder: exact {len(exact) / t_exact:,.0f} edges/s ({t_exact * 1e3:.1f} ms), polling "
          f"{len(polled) / t_poll:,.0f} edges/s ({t_poll * 1e3:.1f} ms); exact is x{ratio:.1f} faster")
    assert ratio >= 20
