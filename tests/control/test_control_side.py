"""The control side (NUMRE + MRCI + eq 22) in the plain-numpy loop, on a small plant."""

import numpy as np
import pytest

from netsim.control import (
    ControllerTrigger,
    ControlSide,
    MixedTrigger,
    MrciController,
    Numre,
    TimeTriggered,
    decompose,
    simulate_loop,
)

# a lightly damped 2nd-order plant at the fast rate, PI-like controller with a fast lead
AP = np.array([[1.0, 0.01], [-0.05, 0.97]])
BP = np.array([[0.0], [0.01]])
CP = np.array([[1.0, 0.0]])
CNUM = np.polymul([2.0, -1.9], [1.0, -0.5])
CDEN = np.polymul([1.0, -1.0], [1.0, 0.2])


def _loop(sensor, est_h=None, ctrl_trig=None, n=300):
    ctrl = MrciController(decompose(CNUM, CDEN, m=1, n_slow=1))
    est = None
    if est_h is not None:
        est = Numre(AP, BP, CP, BP, [[1e-4]], [[1e-4]], h=est_h)
    side = ControlSide(ctrl, lambda k: 1.0, estimator=est, trigger=ctrl_trig)
    return simulate_loop(AP, BP, CP, side, sensor, n, reference=lambda k: 1.0), side


def test_numre_restores_time_triggered_output_without_noise_when_packets_cover_the_gaps():
    tts, _ = _loop(TimeTriggered())
    et, side = _loop(MixedTrigger(0.0, 1e-4), est_h=400)
    assert et.n_sc < 0.5 * tts.n_sc  # fewer samples ...
    assert np.max(np.abs(et.y - tts.y)) < 1e-9  # ... same output (exact model, no noise)
    assert side.horizon_violations == 0


def test_horizon_shorter_than_multiplicity_is_counted():
    et, side = _loop(MixedTrigger(0.0, 1e-4), est_h=2)
    assert side.N_max > 2 and side.horizon_violations > 0


def test_without_estimator_event_sampling_changes_the_output():
    tts, _ = _loop(TimeTriggered())
    et, _ = _loop(MixedTrigger(0.0, 1e-4), ctrl_trig=ControllerTrigger(0.0, 1e-4))
    assert et.n_ca <= et.n_sc < tts.n_sc
    assert np.max(np.abs(et.y - tts.y)) > 1e-4


def test_controller_condition_suppresses_packets_and_estimator_tracks_applied_actions():
    et, side = _loop(MixedTrigger(0.0, 1e-4), est_h=400, ctrl_trig=ControllerTrigger(0.0, 1e-3))
    assert et.n_ca < et.n_sc
    # the estimator predicts with the actions the actuator really applied: y_hat equals y (no noise)
    arrived = et.sent_sc
    assert np.max(np.abs(et.y_hat[arrived] - et.y[arrived])) < 1e-9
