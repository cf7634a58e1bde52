"""Exact propagation of continuous LTI plants: closed forms, stiff plants, the transition cache, disturbances."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
from scipy.linalg import expm

from netsim.env import SimEnv
from netsim.errors import BuildError, ConfigError, DivergenceError, SimulationError
from netsim.plant import LTIDisturbance, LTIPlant
from netsim.io.signals import make_signal
from netsim.timebase import MS, S, US


def _double_integrator(**kw) -> LTIPlant:
    return LTIPlant([[0.0, 1.0], [0.0, 0.0]], [0.0, 1.0], [1.0, 0.0], 0.0, **kw)


def test_double_integrator_piecewise_constant_input_matches_closed_form():
    rng = np.random.default_rng(11)
    plant = _double_integrator(x0=[0.25, -0.5])
    # Reference: p(t+h) = p + v h + u h^2 / 2, v(t+h) = v + u h, in exact rational arithmetic.
    p, v = Fraction(1, 4), Fraction(-1, 2)
    t = 0
    for _ in range(200):
        h = int(rng.integers(1, 5_000)) * US + int(rng.integers(0, 1000))
        u = Fraction(int(rng.integers(-1000, 1000)), 256)
        plant.set_input(0, float(u), t)
        t += h
        hs = Fraction(h, S)
        p, v = p + v * hs + u * hs * hs / 2, v + u * hs
        x = plant.state(t)
        assert x[0] == pytest.approx(float(p), rel=1e-12, abs=1e-12 * abs(float(v)))
        assert x[1] == pytest.approx(float(v), rel=1e-12, abs=1e-12)


def test_first_order_plant_matches_closed_form():
    a, b = 3.0, 2.0
    plant = LTIPlant([[-a]], [[b]], [[1.0]], [[0.0]], x0=[1.0])
    rng = np.random.default_rng(5)
    x, t = 1.0, 0
    for _ in range(300):
        h = int(rng.integers(1, 20_000)) * US
        u = float(rng.uniform(-1.0, 1.0))
        plant.set_input(0, u, t)
        t += h
        # x(t+h) = e^{-a h} x + (1 - e^{-a h}) b u / a, with expm1 for accuracy at small a h
        e = math.expm1(-a * h / S)
        x = x + e * x - e * b * u / a
        assert plant.output(t)[0] == pytest.approx(x, rel=1e-12, abs=1e-15)


def test_one_matrix_exponential_per_distinct_step_length():
    plant = _double_integrator()
    t = 0
    for k in range(1000):
        t += (1 + k % 3) * MS  # three distinct step lengths
        plant.set_input(0, math.sin(k), t)
    assert plant.transition_cache_info()["expm"] == 3


def _stiff_system() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    # Five complex pole pairs with natural frequencies 10 .. 1e5 rad/s, slow ones lightly damped so the
    # comparison is not just a steady state; an orthogonal change of basis makes A dense but normal-conditioned.
    blocks = []
    for w, z in zip(np.logspace(1, 5, 5), (0.01, 0.05, 0.2, 0.5, 0.7)):
        blocks.append(np.array([[-z * w, w * math.sqrt(1 - z * z)], [-w * math.sqrt(1 - z * z), -z * w]]))
    lam = np.zeros((10, 10))
    for i, blk in enumerate(blocks):
        lam[2 * i : 2 * i + 2, 2 * i : 2 * i + 2] = blk
    Q, _ = np.linalg.qr(np.random.default_rng(3).standard_normal((10, 10)))
    A = Q @ lam @ Q.T
    B = Q @ np.linspace(1.0, 2.0, 10).reshape(10, 1) * 1e3
    x0 = Q @ np.linspace(-1.0, 1.0, 10)
    return A, B, x0


def _stiff_run(steps: int) -> float:
    A, B, x0 = _stiff_system()
    plant = LTIPlant(A, B, np.eye(10), None, x0=x0)
    plant.set_input(0, 0.3, 0)
    h = 20 * US
    for k in range(1, steps + 1):
        plant.advance_to(k * h)
    T = steps * h / S
    M = np.zeros((11, 11))
    M[:10, :10], M[:10, 10:] = A * T, B * T
    E = expm(M)
    ref = E[:10, :10] @ x0 + E[:10, 10] * 0.3
    return float(np.linalg.norm(plant.state() - ref) / np.linalg.norm(ref))


def test_stiff_tenth_order_plant_has_no_drift_over_1e5_steps():
    # Round-off per step is ~1e-16 of |x| and the transition is a contraction here, so after N steps the
    # error is bounded by about N * eps = 1e5 * 2.2e-16 = 2e-11 (relative); we allow 1e-9.
    assert _stiff_run(100_000) < 1e-9


@pytest.mark.slow
def test_stiff_tenth_order_plant_has_no_drift_over_1e6_steps():
    # Same bound with N = 1e6: N * eps = 2e-10; we allow 1e-8.
    assert _stiff_run(1_000_000) < 1e-8


def test_step_disturbance_switches_exactly_at_the_jump():
    # x' = d with d = 0 before 0.1 s and 2 after: x(0.25 s) = 2 * 0.15 = 0.3 even though the plant is only
    # sampled at 0.25 s (the propagation is split at 0.1 s).
    plant = LTIPlant([[0.0]], [[1.0]], [[1.0]], None)
    plant.add_disturbance(0, {"type": "step", "at": "0.1 s", "value": 2.0})
    assert plant.output(250 * MS)[0] == pytest.approx(0.3, rel=1e-14)


def test_square_disturbance_adds_to_held_input():
    plant = LTIPlant([[0.0]], [[1.0]], [[1.0]], None)
    plant.add_disturbance(0, make_signal({"type": "square", "amplitude": 1.0, "period": "10 ms"}))
    plant.set_input(0, 0.5, 0)
    # integral over 25 ms of (0.5 + square): square integrates to +5 -5 +5 = 5 ms
    assert plant.output(25 * MS)[0] == pytest.approx(0.5 * 0.025 + 0.005, rel=1e-13)


def test_sine_disturbance_is_exact():
    # x' = 2 sin(2 pi t) -> x(t) = 2 (1 - cos(2 pi t)) / (2 pi)
    plant = LTIPlant([[0.0]], [[1.0]], [[1.0]], None)
    plant.add_disturbance(0, make_signal({"type": "sine", "amplitude": 2.0, "frequency": 1.0}))
    for t in (250 * MS, 700 * MS, 1300 * MS):
        ts = t / S
        assert plant.output(t)[0] == pytest.approx(2 * (1 - math.cos(2 * math.pi * ts)) / (2 * math.pi), rel=1e-12)


def test_continuous_disturbance_model_is_appended_to_the_state():
    # x' = -x + d, d = xd with xd' = -10 xd, xd(0) = 1 (no noise):
    # x(t) = (e^{-t} - e^{-10 t}) / 9
    plant = LTIPlant([[-1.0]], [[1.0]], [[1.0]], None)
    plant.add_disturbance(0, LTIDisturbance([[-10.0]], [1.0], [1.0], x0=[1.0]))
    for t in (10 * MS, 100 * MS, 1 * S):
        ts = t / S
        assert plant.output(t)[0] == pytest.approx((math.exp(-ts) - math.exp(-10 * ts)) / 9, rel=1e-12)
    assert plant.augmented_state.shape == (2,)


def test_discrete_disturbance_model_follows_its_recursion():
    # eq (2) of Cuenca et al. without noise: xd[k+1] = Ad xd[k], d[k] = Cd xd[k], held over each period T.
    Ad = np.array([[1.0, 0.0], [-0.5, 0.9]])
    Cd = np.array([[0.0, 1.0]])
    T = 1 * MS
    plant = LTIPlant([[0.0]], [[1.0]], [[1.0]], None)
    plant.add_disturbance(0, LTIDisturbance(Ad, [0.0, 1.0], Cd, dt_ns=T, x0=[1.0, 0.0]))
    xd, x = np.array([1.0, 0.0]), 0.0
    for k in range(50):
        x += (Cd @ xd)[0] * T / S
        xd = Ad @ xd
    assert plant.output(50 * T)[0] == pytest.approx(x, rel=1e-12, abs=1e-15)


def test_from_system_accepts_transfer_functions_and_mimo():
    import control

    plant = LTIPlant.from_system(control.tf([1000.0], [1.0, 1.0, 0.0]))
    plant.set_input(0, 1.0, 0)
    # 1000/(s(s+1)) step response: 1000 (t - 1 + e^{-t})
    assert plant.output(2 * S)[0] == pytest.approx(1000 * (2 - 1 + math.exp(-2)), rel=1e-10)
    mimo = control.ss(np.diag([-1.0, -2.0]), np.eye(2), np.eye(2), np.zeros((2, 2)), inputs=["a", "b"])
    plant = LTIPlant.from_system(mimo)
    assert plant.input_names == ["a", "b"]
    plant.set_input("b", 2.0, 0)
    assert plant.output(1 * S)[1] == pytest.approx(1 - math.exp(-2), rel=1e-12)


@pytest.mark.parametrize(
    "A, B, C, word",
    [
        ([[0.0, 1.0]], [[0.0], [1.0]], [[1.0, 0.0]], "A must be square"),
        ([[0.0, 1.0], [0.0, 0.0]], [[0.0], [1.0], [2.0]], [[1.0, 0.0]], "matrix B"),
        ([[0.0, 1.0], [0.0, 0.0]], [[0.0], [1.0]], [[1.0, 0.0, 0.0]], "matrix C"),
        ([[0.0, float("nan")], [0.0, 0.0]], [[0.0], [1.0]], [[1.0, 0.0]], "matrix A contains NaN"),
        ([[0.0, 1.0], [0.0, 0.0]], [[0.0], [float("inf")]], [[1.0, 0.0]], "matrix B contains NaN or Inf"),
    ],
)
def test_bad_matrices_raise_config_error_naming_the_matrix(A, B, C, word):
    with pytest.raises(ConfigError, match=word):
        LTIPlant(A, B, C, None)


def test_mismatched_d_and_bad_noise_raise():
    with pytest.raises(ConfigError, match="matrix D"):
        LTIPlant([[0.0]], [[1.0]], [[1.0]], [[0.0, 1.0]])
    with pytest.raises(ConfigError, match="positive semi-definite"):
        LTIPlant([[0.0]], [[1.0]], [[1.0]], None, process_noise=[[-1.0]])


def test_improper_transfer_function_is_rejected():
    import control

    with pytest.raises(ConfigError, match="not proper"):
        LTIPlant.from_system(control.tf([1.0, 0.0, 1.0], [1.0, 1.0]))
    with pytest.raises(ConfigError, match="DiscretePlant"):
        LTIPlant.from_system(control.tf([1.0], [1.0, -0.5], 0.01))


def test_unstable_loop_raises_divergence_error_with_time():
    plant = LTIPlant([[1.0]], [[1.0]], [[1.0]], None, x0=[1.0], divergence_bound=1e6)
    with pytest.raises(DivergenceError, match=r"plant diverged at t = ") as info:
        for k in range(1, 100):
            plant.advance_to(k * S)
    # e^t exceeds 1e6 first at t = 14 s (e^13 = 4.4e5, e^14 = 1.2e6)
    assert info.value.time_ns == 14 * S


def test_time_cannot_go_backwards_and_inputs_must_be_finite():
    plant = _double_integrator()
    plant.advance_to(2 * MS)
    with pytest.raises(SimulationError, match="backwards"):
        plant.advance_to(1 * MS)
    with pytest.raises(SimulationError, match="non-finite"):
        plant.set_input(0, float("nan"), 3 * MS)
    with pytest.raises(ConfigError, match="no input 'torque'"):
        plant.set_input("torque", 1.0, 3 * MS)


def test_noisy_plant_needs_an_environment_and_disturbances_come_first():
    plant = _double_integrator(process_noise=[0.0, 1.0])
    with pytest.raises(BuildError, match="bind"):
        plant.advance_to(1 * MS)
    plant = _double_integrator()
    plant.advance_to(1 * MS)
    with pytest.raises(BuildError, match="before the simulation starts"):
        plant.add_disturbance(0, 1.0)


def test_record_grid_and_event_recording():
    env = SimEnv(seed=0)
    plant = _double_integrator(x0=[0.0, 1.0], output_names=["pos"], name="cart")
    plant.bind(env, record_events=True, record_grid_ns=10 * MS)
    env.run(50 * MS)
    rec = env.recorder
    assert rec.times["pos"] == [0, 10 * MS, 20 * MS, 30 * MS, 40 * MS, 50 * MS]
    assert rec.values["pos"][-1] == pytest.approx(0.05, rel=1e-14)  # p = v t
    assert rec.times["cart.x[0]"][-1] == 50 * MS


def test_input_change_listeners_are_called_with_the_instant():
    plant = _double_integrator()
    seen = []
    plant.on_input_change(seen.append)
    plant.set_input(0, 1.0, 5 * MS)
    plant.set_input(0, 1.0, 6 * MS)  # same value: no change
    plant.set_input(0, 2.0, 7 * MS)
    assert seen == [5 * MS, 7 * MS]


def test_generic_callable_disturbance_is_held_between_propagation_instants():
    # a ramp d = t is not piecewise constant: it is sampled at each propagation start and held, so
    # x' = d propagated in 1 ms steps gives the left Riemann sum sum_{k<1000} k 1e-3 * 1e-3 = 0.4995
    plant = LTIPlant([[0.0]], [[1.0]], [[1.0]], None)
    plant.add_disturbance(0, make_signal({"type": "ramp", "slope": 1.0}))
    for k in range(1, 1001):
        plant.advance_to(k * MS)
    assert plant.output()[0] == pytest.approx(0.4995, rel=1e-12)
