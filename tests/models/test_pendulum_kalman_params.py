"""``pendulum_kalman`` designs Qn on the scenario's own plant parameters (issue 26 section 7: it used the defaults).

The expected gain is computed here without the model module's linearisation or noise code: the Jacobian of the
nonlinear dynamics by central differences, python-control's ``c2d`` for the ZOH and for each 1 ms disturbance
hold, and ``control.dlqe`` for the DARE (its gain is the predictor form ``A M C' (C M C' + R)^-1``; the toolbox
filter's steady-state gain is the current form ``M C' (C M C' + R)^-1``, so ``dlqe``'s equals ``A`` times it).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import netsim  # noqa: F401 - pins BLAS before numpy work
from netsim.models.pendulum.model import PendulumParams, dynamics
from netsim.errors import ConfigError
from netsim.build.builder import build
from netsim.scenario.loader import load_scenario

control = pytest.importorskip("control")

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "pendulum_lqr.yaml"
KALMAN = {"nodes.rip.tasks[0].params.estimator": {"type": "pendulum_kalman"}}
OTHER = {"mp": 0.05, "Lp": 0.2, "mr": 0.12, "Rm": 6.0}  # a heavier, longer pendulum, a stronger motor
H = 0.005  # the task's period
HOLD, STD = 0.001, 0.05  # pendulum_kalman's defaults: the voltage disturbance held 1 ms, std 0.05 V
SENSOR_VAR = (2 * math.pi / 2048) ** 2 / 12  # encoder step^2 / 12: pendulum_kalman's default Rn per angle


def _expected_predictor_gain(params: PendulumParams) -> np.ndarray:
    eps = 1e-6
    A = np.zeros((4, 4))
    for j in range(4):
        dx = np.zeros(4)
        dx[j] = eps
        A[:, j] = (dynamics(0.0, dx, [0.0], params) - dynamics(0.0, -dx, [0.0], params)) / (2 * eps)
    B = ((dynamics(0.0, np.zeros(4), [eps], params) - dynamics(0.0, np.zeros(4), [-eps], params)) / (2 * eps))
    B = B.reshape(4, 1)
    C = np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]])
    D = np.zeros((2, 1))
    Ad = np.asarray(control.c2d(control.ss(A, B, C, D), H, "zoh").A)
    hold = control.c2d(control.ss(A, B, C, D), HOLD, "zoh")
    Ah, Bh = np.asarray(hold.A), np.asarray(hold.B)
    n = round(H / HOLD)
    Qn = STD**2 * sum(np.linalg.matrix_power(Ah, n - 1 - j) @ Bh @ Bh.T @ np.linalg.matrix_power(Ah, n - 1 - j).T
                      for j in range(n))
    L, _, _ = control.dlqe(Ad, np.eye(4), C, Qn, SENSOR_VAR * np.eye(2))
    return Ad, np.asarray(L)


def _built_filter(plant_params: dict):
    scenario = load_scenario(SCENARIO, {**KALMAN, **{f"plant.params.{k}": v for k, v in plant_params.items()}})
    return build(scenario).programs["rip.control"].estimator


def test_the_kalman_gain_follows_the_scenarios_plant_parameters():
    kf = _built_filter(OTHER)
    Ad, want = _expected_predictor_gain(PendulumParams(**OTHER))
    got = Ad @ kf.K_ss
    assert np.allclose(got, want, rtol=1e-4, atol=1e-9), np.max(np.abs(got - want) / np.abs(want))
    # the gain of the default parameters (what was built before) is far from it: the test can tell them apart
    _, default = _expected_predictor_gain(PendulumParams())
    assert np.max(np.abs(default - want) / np.abs(want)) > 0.2


def test_the_default_plant_still_gets_the_default_gain():
    kf = _built_filter({})
    Ad, want = _expected_predictor_gain(PendulumParams())
    assert np.allclose(Ad @ kf.K_ss, want, rtol=1e-4, atol=1e-9)


def test_another_plant_is_refused_with_a_message():
    from netsim.models.pendulum.estimators import KalmanPart, _KalmanParams
    from netsim.control.parts import Design

    Ad = np.eye(4)
    with pytest.raises(ConfigError, match="furuta_pendulum"):
        KalmanPart.build(_KalmanParams(), Design(A=Ad, B=np.ones((4, 1)), C=np.eye(4)[[0, 2]], period_s=H))


def test_validate_refuses_it_on_another_plant_at_the_estimator():
    from netsim.scenario.loader import check_scenario

    servo = SCENARIO.parent / "dc_servo_lqr_kalman.yaml"
    problems = check_scenario(servo, {"nodes.controller.tasks[0].params.estimator": {"type": "pendulum_kalman"}})
    errors = [p for p in problems if p.severity == "error"]
    assert [p.path for p in errors] == ["nodes.controller.tasks[0].params.estimator"]
    assert "furuta_pendulum" in errors[0].message
