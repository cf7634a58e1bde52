"""Friction.level's one-mode fast path (parameters read once at construction, issue 19) against the formula
written out from the parameters (what level computed before): bit-identical on random positions, for the
presets with one mode and for explicit parameters that hit the floor."""

import math

import numpy as np
import pytest

from netsim.models.cart.friction import Friction, FrictionParams


def _level_formula(fr: Friction, p: float) -> float:
    pr = fr.params
    w = 2.0 * math.pi * float(fr.freqs[0])
    g = float(fr.amps[0]) * math.cos(w * ((p + 0.5 * pr.speedup * p * p) / pr.wavelength) + float(fr.phases[0]))
    return pr.coulomb * max(pr.floor, 1.0 + pr.variation * g)


@pytest.mark.parametrize("params", [FrictionParams(), FrictionParams(variation=1.5, floor=0.3),
                                    FrictionParams(speedup=0.0, wavelength=0.7, coulomb=3.1)])
def test_one_mode_level_is_the_formula(params):
    rng = np.random.default_rng(7)
    floored = 0
    for seed in range(5):
        fr = Friction.draw(params, seed=seed)
        for p in rng.uniform(-0.2, 1.3, 4000):
            got = fr.level(float(p))
            want = _level_formula(fr, float(p))
            assert np.float64(got).tobytes() == np.float64(want).tobytes()
            floored += got == params.coulomb * params.floor
    # the variation = 1.5 case reaches the floor (1 - 1.5 |g| < 0.3 somewhere): the max() branch is exercised
    assert (floored > 0) == (params.variation > 1.0)


def test_level_without_variation_or_friction():
    assert Friction.draw(FrictionParams(model="constant")).level(0.4) == 2.0  # F0 of every preset
    assert Friction.none().level(0.4) == 0.0
    assert Friction.draw(FrictionParams(coulomb=0.0)).level(0.4) == 0.0
