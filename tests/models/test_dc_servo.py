"""DC servo model: its state space equals TrueTime's 1000/(s(s+1)) (checked with python-control)."""

import numpy as np
import pytest

from netsim.models.dc_servo import DcServoParams, dc_servo_matrices


def test_state_space_realises_the_transfer_function():
    import control

    A, B, C, D = dc_servo_matrices()
    g = control.ss2tf(control.ss(A, B, C, D))
    want = control.tf([1000.0], [1.0, 1.0, 0.0])
    np.testing.assert_allclose(np.trim_zeros(np.ravel(g.num[0][0])), [1000.0])
    np.testing.assert_allclose(np.ravel(g.den[0][0]), np.ravel(want.den[0][0]))


def test_count_servos_are_independent_blocks():
    A, B, C, D = dc_servo_matrices(1000.0, 1.0, 3)
    assert A.shape == (6, 6) and B.shape == (6, 3) and C.shape == (3, 6)
    # input 2 only drives servo 2's velocity
    assert np.flatnonzero(B[:, 1]).tolist() == [3]
    assert np.flatnonzero(C[2]).tolist() == [4]


def test_plant_from_registry_steps_like_the_closed_form():
    pytest.importorskip("netsim.plant")
    from netsim.registry import lookup

    factory = lookup("plant", "dc_servo")
    plant = factory(factory.Params())
    from netsim.env import SimEnv

    plant.bind(SimEnv(seed=0))
    plant.set_input(0, 0.001, 0)
    # y(t) for a unit... step u=c from rest: y = K c (t - 1 + e^{-t}) with K=1000, a=1
    t = 0.5
    y = float(plant.output(int(t * 1e9))[0])
    assert y == pytest.approx(1000 * 0.001 * (t - 1 + np.exp(-t)), rel=1e-9)


def test_params_reject_unknown_keys():
    with pytest.raises(ValueError):
        DcServoParams(gian=3)
