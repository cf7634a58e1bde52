"""An LTI plant read and written at a few recurring step lengths applies ready steps (issue 29, calls per period).

A sensor read every 1 ms and an actuation 0.2 ms after it make the plant alternate steps of 0.2 ms and 0.8 ms; once
both are known, advancing takes no transition-cache look-up (no ``transition`` call), and the state is still the
exact zero-order-hold one, recomputed here with scipy's matrix exponential.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

from netsim.plant import LTIPlant
from netsim.timebase import MS, S, US

A = np.array([[0.0, 1.0], [0.0, -1.0]])  # the DC servo 1000 / (s (s + 1)): angle and angular velocity
B = np.array([[0.0], [1000.0]])
C = np.array([[1.0, 0.0]])


def _zoh(h_ns: int) -> tuple[np.ndarray, np.ndarray]:
    """Exact ZOH step of length ``h_ns`` from the augmented matrix exponential (independent of the plant)."""
    aug = np.zeros((3, 3))
    aug[:2, :2] = A * (h_ns / S)
    aug[:2, 2:] = B * (h_ns / S)
    e = scipy.linalg.expm(aug)
    return e[:2, :2], e[:2, 2]


def test_alternating_step_lengths_apply_ready_steps_and_stay_exact(monkeypatch):
    plant = LTIPlant(A, B, C, x0=[0.1, 0.0])
    lookups: list[int] = []
    transition = plant.transition

    def counting(h_ns: int):
        lookups.append(h_ns)
        return transition(h_ns)

    monkeypatch.setattr(plant, "transition", counting)
    x, held = np.array([0.1, 0.0]), 0.0  # the state and the input the plant holds, tracked by the test
    steps = {h: _zoh(h) for h in (200 * US, 800 * US)}
    for k in range(50):
        if k:  # from the last write (k - 1 ms + 0.2 ms) to this read (k ms)
            Ad, Bd = steps[800 * US]
            x = Ad @ x + Bd * held
        y = plant.output_value(0, k * MS)
        assert y == pytest.approx(x[0], rel=1e-12, abs=1e-15)
        Ad, Bd = steps[200 * US]  # from the read to the write, 0.2 ms later, with the old input held
        x = Ad @ x + Bd * held
        held = -2.0 * y  # a proportional law, so the input changes every period
        plant.set_input(0, held, k * MS + 200 * US)
    # one look-up per step length, the first time it is used (the 0.2 ms step first, then the 0.8 ms one)
    assert lookups == [200 * US, 800 * US]
    np.testing.assert_allclose(plant.state(49 * MS + 200 * US), x, rtol=1e-12, atol=1e-15)


def test_many_step_lengths_still_give_the_exact_state():
    # more distinct lengths than the memo keeps: it is cleared and refilled, the steps stay exact
    plant = LTIPlant(A, B, C, x0=[0.0, 0.0])
    x, t = np.zeros(2), 0
    for k in range(40):
        h = (k % 13 + 1) * 37 * US
        plant.set_input(0, float(np.sin(k)), t)
        Ad, Bd = _zoh(h)
        x = Ad @ x + Bd * float(np.sin(k))
        t += h
        np.testing.assert_allclose(plant.state(t), x, rtol=1e-12, atol=1e-15)
