"""netsim.models.cart.plant._segment_end (one call per friction segment in CartPlant.predict_exit, issue 19) against the
calls it replaces: propagate1 at the segment's end, stop_time of its first piece and propagate1 at that stop
time. Bit-identical results are required (the exact encoder's wake-up ticks, hence the golden traces, depend
on them)."""

import math

import numpy as np

from netsim.models.cart.dynamics import propagate1, stop_time
from netsim.models.cart.plant import _segment_end


def _bits(x: float) -> bytes:
    return np.float64(x).tobytes()


def test_segment_end_is_bit_identical_to_propagate1_and_stop_time():
    rng = np.random.default_rng(1919)
    seen = {"rest": 0, "start": 0, "no_stop": 0, "stop_stuck": 0, "stop_move": 0}
    for _ in range(20000):
        p0 = float(rng.uniform(-0.1, 1.2))
        v0 = 0.0 if rng.random() < 0.15 else float(rng.uniform(-1.0, 1.0))
        f = float(rng.uniform(0.0, 8.0))
        fs = f * float(rng.uniform(1.0, 1.5))
        u = float(rng.uniform(-25.5, 25.5))
        r = rng.random()
        if r < 0.15:  # a command near the breakaway level: stuck or just moving
            u = math.copysign(fs, v0 if v0 else 1.0) * float(rng.uniform(0.9, 1.1))
        elif r < 0.55:  # the friction stops the cart inside the segment, then stuck or moving back
            s = 1.0 if rng.random() < 0.5 else -1.0
            f = float(rng.uniform(1.0, 8.0))
            fs = f * float(rng.uniform(1.0, 1.5))
            u = s * f * float(rng.uniform(-3.0, 0.95))
            v0 = -(u - s * f) * float(rng.uniform(0.0, 1.5e-3))
        tau = int(rng.integers(1, 1_000_001)) * 1e-9
        if rng.random() < 0.05:
            u = math.copysign(f, v0) if v0 else u  # a == 0: constant velocity
        pe, ve, ts, p_ts = _segment_end(p0, v0, u, f, fs, tau)
        want_p, want_v = propagate1(p0, v0, u, f, fs, tau, None)
        want_ts = stop_time(v0, u - math.copysign(f, v0), None) if v0 != 0.0 else math.inf
        assert (_bits(pe), _bits(ve)) == (_bits(want_p), _bits(want_v))
        assert _bits(ts) == _bits(want_ts)
        if want_ts < tau:
            assert _bits(p_ts) == _bits(propagate1(p0, v0, u, f, fs, want_ts, None)[0])
        if v0 == 0.0:
            seen["rest" if abs(u) <= fs else "start"] += 1
        elif want_ts >= tau:
            seen["no_stop"] += 1
        else:
            seen["stop_stuck" if abs(u) <= fs else "stop_move"] += 1
    # every branch of the closed form is exercised
    assert min(seen.values()) > 200, seen
