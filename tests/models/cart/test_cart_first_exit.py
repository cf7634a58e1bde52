"""netsim.models.cart.plant.first_exit (bisection on the scalar closed form) against the array form it replaces:
every tick evaluated with netsim.models.cart.dynamics.propagate, the first tick whose band differs."""

import math

import numpy as np
import pytest

from netsim.models.cart.dynamics import propagate
from netsim.models.cart.plant import first_exit


def _first_exit_arrays(p0, v0, u, f, fs, off, tick, n, output, step, count):
    """The array form (what CartPlant.predict_exit computed before issue 19's change): -1 when none."""
    tau = (off + tick * np.arange(n)) * 1e-9
    p, v = propagate(p0, v0, u, f, fs, tau, None)
    bad = np.floor((p if output == 0 else v) / step) != count
    return int(np.argmax(bad)) if bad.any() else -1


@pytest.mark.parametrize("output", [0, 1])
def test_first_exit_matches_every_tick(output):
    rng = np.random.default_rng(19)
    step = 5e-5 * 2**6 if output == 0 else 0.05
    found = stops = 0
    for _ in range(4000):
        p0 = float(rng.uniform(0.0, 1.0))
        v0 = 0.0 if rng.random() < 0.2 else float(rng.uniform(-1.0, 1.0))
        u = float(rng.uniform(-25.5, 25.5))
        f = float(rng.uniform(0.0, 8.0))
        fs = f * float(rng.uniform(1.0, 1.5))
        r = rng.random()
        if r < 0.2:  # a command the friction nearly cancels: slow motion, stuck
            u = math.copysign(f, v0 if v0 else 1.0) * float(rng.uniform(0.9, 1.1))
        elif r < 0.6:  # the friction stops the cart inside the window (then stuck or moving back)
            s = 1.0 if rng.random() < 0.5 else -1.0
            f = float(rng.uniform(1.0, 8.0))
            fs = f * float(rng.uniform(1.0, 1.5))
            u = s * f * float(rng.uniform(-3.0, 0.95))
            v0 = -(u - s * f) * float(rng.uniform(0.0, 1.5e-3))
        tick = 10_000
        off = int(rng.integers(0, 100)) * tick
        n = int(rng.integers(1, 101))
        y0 = p0 if output == 0 else v0
        count = math.floor(y0 / step) + int(rng.integers(-1, 2)) * (rng.random() < 0.1)
        a = u - math.copysign(f, v0) if v0 else 0.0
        if v0 and a and (a > 0) != (v0 > 0) and -v0 / a < (off + (n - 1) * tick) * 1e-9:
            stops += 1
        want = _first_exit_arrays(p0, v0, u, f, fs, off, tick, n, output, step, count)
        assert first_exit(p0, v0, u, f, fs, off, tick, n, output, step, count) == want
        found += want >= 0
    # the draws exercise both outcomes and motions that stop inside the window
    assert found > 400 and stops > 400


def test_first_exit_at_the_stop_tick():
    # the velocity reaches zero exactly at a tick (v0 = 0.5, a = -50: ts = 10 ms = tick 10): the array form
    # evaluates that tick on the stopped piece (v = 0), so a velocity band [0, step) holds it
    args = dict(p0=0.0, v0=0.5, u=-40.0, f=10.0, fs=60.0, off=0, tick=1_000_000, n=15)
    for output, step, count in ((1, 0.05, 0), (1, 0.05, 9), (0, 1e-3, 2)):
        want = _first_exit_arrays(**args, output=output, step=step, count=count)
        assert first_exit(**args, output=output, step=step, count=count) == want
