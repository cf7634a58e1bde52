"""Finite-difference velocity baselines: exact on a ramp, first-order filter response, missing samples."""

import math

import numpy as np
import pytest

from netsim.control.baselines import FiniteDifferenceVelocity
from netsim.errors import ConfigError, SimulationError


def run(est, positions, times=None, skip=()):
    out = []
    for k, p in enumerate(positions):
        if k not in skip:
            est.correct(p, None if times is None else times[k])
        out.append(est.x_hat.copy())
        est.predict(None)
    return np.array(out)


def test_raw_difference_is_exact_on_a_ramp_with_a_missing_sample():
    h = 0.01
    xs = run(FiniteDifferenceVelocity(h), [2.0 * k * h for k in range(20)], skip={7})
    assert xs[0, 1] == 0.0  # no previous sample yet
    np.testing.assert_allclose(xs[1:, 1], 2.0, rtol=1e-12)  # sample 8 differences over 2 h
    np.testing.assert_array_equal(xs[7], xs[6])  # held while missing


def test_measurement_times_take_care_of_jitter():
    rng = np.random.default_rng(0)
    t = np.cumsum(0.01 + 0.002 * rng.random(30))
    xs = run(FiniteDifferenceVelocity(0.01), 3.0 * t - 1.0, times=t)
    np.testing.assert_allclose(xs[1:, 1], 3.0, rtol=1e-10)


def test_low_pass_velocity_is_the_first_order_step_response():
    h, fc = 0.001, 20.0
    xs = run(FiniteDifferenceVelocity(h, cutoff_hz=fc), [1.5 * k * h for k in range(50)])
    a = math.exp(-h * 2 * math.pi * fc)
    # raw velocity 1.5 from sample 1 on: v_f[k] = 1.5 (1 - a^k), the exact discretisation of tau dv/dt = v - v_f
    want = np.array([0.0] + [1.5 * (1 - a**k) for k in range(1, 50)])
    np.testing.assert_allclose(xs[:, 1], want, rtol=1e-12, atol=1e-15)


def test_low_pass_attenuates_quantisation_noise():
    h = 0.001
    t = np.arange(2000) * h
    p = np.floor((0.43 * t) / 1e-4) * 1e-4  # 0.1 mm encoder on a 0.43 m/s ramp
    raw = run(FiniteDifferenceVelocity(h), p)[200:, 1]
    filt = run(FiniteDifferenceVelocity(h, cutoff_hz=5.0), p)[200:, 1]
    # raw differences are 4 or 5 quanta per 1 ms sample: 0.4 or 0.5 m/s (std about 0.046); a 5 Hz first-order
    # filter averages over about 30 samples
    assert np.std(raw - 0.43) > 0.04
    assert np.std(raw - 0.43) > 5 * np.std(filt - 0.43)


@pytest.mark.parametrize(
    ("kw", "match"), [(dict(h=0.0), "h must be a positive"), (dict(h=0.01, cutoff_hz=-1.0), "cutoff_hz")]
)
def test_bad_parameters(kw, match):
    with pytest.raises(ConfigError, match=match):
        FiniteDifferenceVelocity(**kw)


def test_times_must_increase():
    est = FiniteDifferenceVelocity(0.01)
    est.correct(0.0, 1.0)
    est.predict()
    with pytest.raises(SimulationError, match="sample times must increase"):
        est.correct(0.0, 1.0)
