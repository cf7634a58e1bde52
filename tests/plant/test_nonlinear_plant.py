"""Nonlinear plants: accuracy, energy drift, stick-slip friction without chattering, failures."""

from __future__ import annotations

import math

import numpy as np
import pytest

from netsim.env import SimEnv
from netsim.errors import ConfigError, DivergenceError, SimulationError
from netsim.plant import NonlinearPlant
from netsim.plant.nonlinear import Mode, stick_slip_modes
from netsim.io.signals import make_signal
from netsim.timebase import MS, S

G_L = 9.81  # g / l of a 1 m pendulum


def _pendulum(x0) -> NonlinearPlant:
    def f(t, x, u, p):
        return np.array([x[1], -G_L * math.sin(x[0]) + u[0]])

    return NonlinearPlant(f, lambda t, x, u, p: x[:1], 2, 1, 1, x0=x0)


def test_linear_dynamics_match_closed_form_to_integrator_tolerance():
    plant = NonlinearPlant(lambda t, x, u, p: -3.0 * x + 2.0 * u, lambda t, x, u, p: x, 1, 1, 1, x0=[1.0])
    rng = np.random.default_rng(1)
    x, t = 1.0, 0
    for _ in range(100):
        h = int(rng.integers(1, 50)) * MS
        u = float(rng.uniform(-1, 1))
        plant.set_input(0, u, t)
        t += h
        e = math.exp(-3.0 * h / S)
        x = e * x + (1 - e) * 2.0 * u / 3.0
        # default tolerances rtol 1e-8, atol 1e-10
        assert plant.output(t)[0] == pytest.approx(x, rel=1e-7, abs=1e-9)


def test_pendulum_energy_drift_is_bounded():
    # Undamped pendulum from 1 rad, sampled every 10 ms for 10 s (1000 restarts of the integrator) with the
    # default tolerances (RK45, rtol 1e-8, atol 1e-10). Measured drift of E = w^2/2 - (g/l) cos(theta):
    # 1.9e-11 relative after 10 s (2.0e-10 after 100 s: linear growth). We pin 1e-9 for 10 s.
    plant = _pendulum([1.0, 0.0])

    def energy(x):
        return 0.5 * x[1] ** 2 - G_L * math.cos(x[0])

    e0 = energy(plant.state(0))
    drift = max(abs(energy(plant.state(k * 10 * MS)) - e0) / abs(e0) for k in range(1, 1001))
    assert drift < 1e-9


def _friction_plant(v0: float) -> NonlinearPlant:
    def f(t, x, u, p):  # unit mass, force u, friction added by the modes
        return np.array([x[1], u[0]])

    modes, select = stick_slip_modes(
        f, velocity=1, applied_force=lambda t, x, u, p: u[0], coulomb=0.5, static=0.7
    )
    return NonlinearPlant(f, lambda t, x, u, p: x[:1], 2, 1, 1, x0=[0.0, v0], modes=modes, select_mode=select)


def test_cart_sticks_exactly_and_breaks_away_above_static_friction():
    plant = _friction_plant(0.3)
    plant.set_input(0, -0.6, 0)
    # sliding: v' = -0.6 - 0.5 = -1.1 until v = 0 at 0.3/1.1 s, position 0.3^2 / (2 * 1.1); then |F| = 0.6
    # < 0.7 static: stuck, v exactly 0.
    p_stop = 0.09 / 2.2
    x = plant.state(1 * S)
    assert plant.mode == "stick"
    assert x[1] == 0.0
    assert x[0] == pytest.approx(p_stop, rel=1e-8)
    plant.set_input(0, 0.8, 1 * S)  # above static friction: v' = 0.8 - 0.5 = 0.3
    x = plant.state(2 * S)
    assert plant.mode == "slip+"
    assert x[1] == pytest.approx(0.3, rel=1e-8)
    assert x[0] == pytest.approx(p_stop + 0.15, rel=1e-8)


def test_friction_stick_scenario_does_not_stall_the_integrator():
    # Random forces around the static threshold every 1 ms for 1 s: the cart keeps sticking and slipping.
    env = SimEnv(seed=4)
    plant = _friction_plant(0.0)
    plant.bind(env)

    def controller():
        rng = env.rng("test.force")
        while True:
            plant.set_input(0, float(rng.uniform(-1.5, 1.5)))
            yield env.timeout(1 * MS)

    env.process(controller())
    env.run(1 * S)
    assert plant.mode_switches > 50  # it does stick and slip repeatedly
    # RK45 costs 6 RHS evaluations per step; a 1 ms smooth segment needs one or two steps. Allow 5 steps per
    # segment and mode switch (measured: about 11 evaluations per segment).
    assert plant.rhs_evaluations < 30 * (1000 + plant.mode_switches)


def test_sine_disturbance_enters_the_rhs():
    plant = NonlinearPlant(lambda t, x, u, p: u, lambda t, x, u, p: x, 1, 1, 1)
    plant.add_disturbance(0, make_signal({"type": "sine", "amplitude": 2.0, "frequency": 1.0}))
    assert plant.output(250 * MS)[0] == pytest.approx(2 / (2 * math.pi), rel=1e-7)


def test_finite_time_blow_up_is_reported_with_its_time():
    plant = NonlinearPlant(lambda t, x, u, p: x**2, lambda t, x, u, p: x, 1, 1, 1, x0=[1.0])
    # x = 1 / (1 - t) blows up at t = 1 s: it passes the divergence bound 1e12 at t = 1 - 1e-12
    with pytest.raises(DivergenceError, match=r"plant diverged at t = (0\.99|1 )"):
        plant.advance_to(2 * S)


def test_integrator_failure_names_the_time():
    def f(t, x, u, p):
        return np.array([math.nan if t > 0.5 else 1.0])

    plant = NonlinearPlant(f, lambda t, x, u, p: x, 1, 1, 1, max_step=0.01)
    with pytest.raises(SimulationError, match=r"t = 0\.5"):
        plant.advance_to(1 * S)


def test_divergence_bound_applies():
    plant = NonlinearPlant(lambda t, x, u, p: x, lambda t, x, u, p: x, 1, 1, 1, x0=[1.0], divergence_bound=100.0)
    with pytest.raises(DivergenceError, match="plant diverged at t = "):
        plant.advance_to(10 * S)  # e^10 > 100


def test_bad_configuration_is_reported():
    with pytest.raises(ConfigError, match="h returns 2 values"):
        NonlinearPlant(lambda t, x, u, p: x, lambda t, x, u, p: x, 2, 1, 1)
    with pytest.raises(ConfigError, match="select_mode"):
        NonlinearPlant(lambda t, x, u, p: x, lambda t, x, u, p: x, 1, 1, 1, modes={"a": Mode()})
    with pytest.raises(ConfigError, match="initial_mode"):
        NonlinearPlant(lambda t, x, u, p: x, lambda t, x, u, p: x, 1, 1, 1, initial_mode="b")
