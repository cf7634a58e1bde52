"""The ``ekf`` estimator's messages for a model that blows up say what to change (h14f, issue 14's standard):
the Runge-Kutta prediction of a stiff model over a long period diverges, and ``substeps`` is the fix."""

from __future__ import annotations

import numpy as np
import pytest

from netsim.control.model_ekf import ModelEKF
from netsim.errors import ConfigError


def stiff_f(t, x, u, p):
    """x' = -1000 x: RK4 with step dt is stable only for 1000 dt <= 2.785 (its real stability limit)."""
    return -1000.0 * x


def h(t, x, u, p):
    return np.array([x[0]])


def test_a_prediction_that_diverges_at_x0_names_substeps_as_the_fix():
    """Period 1 s in 4 steps: 1000 * 0.25 = 250 far outside RK4's limit; its growth factor per step
    (1 - z + z^2/2 - z^3/6 + z^4/24 at z = 250, about 1.6e8) overflows float over the 4 steps of x0 = 1e300."""
    with np.errstate(over="ignore", invalid="ignore"), pytest.raises(ConfigError) as info:
        ModelEKF(stiff_f, h, None, 1, 1, [0], 1.0, 1e-6, 1e-4, x0=[1e300], substeps=4)
    assert "raise 'substeps'" in str(info.value) and "check x0" in str(info.value)


def test_enough_substeps_make_the_same_model_usable():
    """1000 steps per 1 s: 1000 * 1e-3 = 1 < 2.785, stable; x0 = 1 decays to ~0 in one period (e^-1000)."""
    ekf = ModelEKF(stiff_f, h, None, 1, 1, [0], 1.0, 1e-6, 1e-4, x0=[1.0], substeps=1000)
    ekf.predict(np.zeros(1))
    assert abs(float(ekf.x[0])) < 1e-12
