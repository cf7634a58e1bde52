"""Cart benchmarks (opt-in: pytest -m benchmark -s tests/benchmarks/test_bench_cart.py).

1. One 1 m run at q = 6 with the 100 kHz encoder ISR modelled, through netsim (exact and polling encoder
   modes), against a plain numpy loop of the same cart and controller written here: wall time, simulated
   control periods per second, and the ratio (target <= 10x the plain loop).
2. The whole Fig. 2 sweep (75 runs) through netsim.runner in parallel processes (target < 2 min).
"""

import math
import time

import numpy as np
import pytest

from models.cart.controllers import make_controller
from models.cart.encoding import Quantizer
from models.cart.friction import Friction, FrictionParams

pytestmark = pytest.mark.benchmark


def _plain_loop(friction, wc=40.0, q=6, vref=0.8, h=1e-3, tick=1e-5, ku=25.5):
    """The cart, the 10 us ISR and the Full Event controller in a bare loop (ISR polled at every tick)."""
    ctrl = make_controller("full_event", wc, Quantizer.from_bits(q, rounding="floor"))
    delta = 5e-5 * 2**q
    p = v = 0.0
    count, direction, stamp = 0, 0, -1
    n_ticks = int(round(h / tick))
    k = 0
    while p < 1.0 and k < 5000:
        t_ns = k * 1_000_000
        uv = ctrl.update(t_ns, count, direction, stamp, vref)
        f = friction.level(p)
        u = ku * uv
        for j in range(1, n_ticks + 1):  # the ISR: advance the cart by one tick, read the encoder
            a = u - math.copysign(f, v) if v != 0.0 else (0.0 if abs(u) <= f else u - math.copysign(f, u))
            p += v * tick + 0.5 * a * tick * tick
            v += a * tick
            c = math.floor(p / delta)
            if c != count:
                direction, count, stamp = (1 if c > count else -1), c, t_ns + j * 10_000
        k += 1
    return k


def test_bench_one_run_vs_plain_loop():
    from netsim.registry import load_plugins
    from netsim.runner import run

    load_plugins()
    fr = Friction.draw(FrictionParams(), seed=1)
    t0 = time.perf_counter()
    periods = _plain_loop(fr)
    plain = time.perf_counter() - t0
    print(f"\nplain numpy loop: {periods} control periods (1 m), {plain:.3f} s, {periods / plain:,.0f} periods/s")
    from models.cart.sim import simulate

    t0 = time.perf_counter()
    ref = simulate(make_controller("full_event", 40.0, Quantizer.from_bits(6, rounding="floor")), fr,
                   duration=3.0, rounding="floor")
    vec = time.perf_counter() - t0
    print(f"vectorized reference sim (models.cart.sim): {len(ref.t)} periods, {vec:.3f} s")
    for mode in ("exact", "polling"):
        # the JMAP metric (two QPs, ~0.2 s) is evaluation, not simulation: off here
        ov = {"duration": f"{periods / 1000:.3f} s", "io.enc.mode": mode, "metrics[0].params.jmap": False}
        if mode == "polling":
            ov["nodes.cart.handlers[0].trigger"] = {"timer": {"period": "10 us"}}
        t0 = time.perf_counter()
        res = run("scenarios/cart.yaml", write=False, overrides=ov)
        wall = time.perf_counter() - t0
        assert res.ok, res.meta
        print(f"netsim ({mode} encoder): {wall:.3f} s, {periods / wall:,.0f} periods/s, ratio {wall / plain:.1f}x "
              f"the plain loop; CPU utilization {res.metrics.get('cpu.cart.utilization', float('nan')):.3f}")
    assert periods > 1000


def test_bench_fig2_sweep_wall_time():
    from models.cart.report import _run_all, fig2_points

    t0 = time.perf_counter()
    df = _run_all(fig2_points(), "netsim", None)
    wall = time.perf_counter() - t0
    print(f"\nFig. 2 sweep: {len(df)} runs through netsim.runner in {wall:.1f} s "
          f"(target < 120 s); failed: {(df.status != 'ok').sum()}")
    assert len(df) == 75 and np.isfinite(df.sigma_u).all()
