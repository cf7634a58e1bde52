"""The default integrator of nonlinear plants without ``solve_ivp`` calls (issue 29): one scipy Runge-Kutta solver
per plant, re-armed per segment (:class:`netsim.plant.integrator.RkSegments`), must end every segment on the very
bits ``scipy.integrate.solve_ivp`` gives, so that the default path's outputs (and the golden traces) do not move.
Every expected value here is computed by ``solve_ivp`` itself, called in the test."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from netsim.errors import ConfigError, SimulationError
from netsim.models.pendulum.model import PendulumParams, dynamics
from netsim.plant import NonlinearPlant
from netsim.plant.integrator import RkSegments
from netsim.timebase import MS, S, US

P = PendulumParams()


@pytest.mark.parametrize("method", ["RK45", "RK23", "DOP853"])
@pytest.mark.parametrize("max_step", [math.inf, 2e-4])
def test_rearmed_solver_ends_each_segment_on_solve_ivps_bits(method, max_step):
    rng = np.random.default_rng(7)
    seg = RkSegments.make(method, 4, 1e-8, 1e-10, max_step)
    assert seg is not None
    for _ in range(40):  # one solver object, 40 unrelated segments of 0.1-20 ms, inputs and states at random
        x = rng.uniform(-1.0, 1.0, 4)
        u = np.array([rng.uniform(-3.0, 3.0)])
        t0 = float(rng.uniform(0.0, 5.0))
        t1 = t0 + float(rng.uniform(1e-4, 2e-2))

        def f(t, y, u=u):
            return dynamics(t, y, u, P)

        want = solve_ivp(f, (t0, t1), x, method=method, rtol=1e-8, atol=1e-10, max_step=max_step)
        got = seg.solve(f, t0, t1, x)
        assert got.status == want.status == 0
        assert got.t[-1] == want.t[-1] == t1
        assert np.array_equal(got.y[:, -1], want.y[:, -1])  # bit for bit, not approximately


def test_only_scipys_explicit_runge_kutta_methods_are_rearmed():
    assert RkSegments.make("LSODA", 4, 1e-8, 1e-10, math.inf) is None
    assert RkSegments.make("Radau", 4, 1e-8, 1e-10, math.inf) is None
    assert RkSegments.make("RK45", 0, 1e-8, 1e-10, math.inf) is None  # no state: solve_ivp's own corner case


def _pendulum_plant(rearm: bool, method: str = "RK45") -> NonlinearPlant:
    plant = NonlinearPlant(dynamics, lambda t, x, u, p: x[[0, 2]], 4, 1, 2, params=P, x0=[0.0, 0.0, 0.2, 0.0],
                           method=method)
    if not rearm:
        plant._rk_segments = None  # the path before issue 29: one solve_ivp call per segment
    return plant


@pytest.mark.parametrize("method", ["RK45", "DOP853"])
def test_pendulum_plant_states_equal_the_solve_ivp_path_bit_for_bit(method):
    # 400 segments of 0.35-1.2 ms with a new input each (as a 5 ms loop with a 1 ms held disturbance makes them)
    rng = np.random.default_rng(3)
    new, old = _pendulum_plant(True, method), _pendulum_plant(False, method)
    t = 0
    for _ in range(400):
        t += int(rng.integers(350, 1200)) * US
        v = float(rng.uniform(-3.0, 3.0))
        for plant in (new, old):
            plant.advance_to(t)
            plant.set_input(0, v, t)
        assert np.array_equal(new.state(t), old.state(t))
    assert new.rhs_evaluations == old.rhs_evaluations  # the same right-hand-side calls, counted the same way


def test_rate_noise_and_failures_take_the_same_path_as_solve_ivp():
    # held state-noise rates enter the right-hand side of both paths alike
    new, old = _pendulum_plant(True), _pendulum_plant(False)
    for plant in (new, old):
        plant._rate = np.array([0.0, 0.3, 0.0, -0.2])
        plant.advance_to(40 * MS)
    assert np.array_equal(new.state(), old.state())

    def bad(t, x, u, p):  # NaN after 0.5 s: the step is rejected down to nothing, and the solver gives up
        return np.array([math.nan if t > 0.5 else 1.0])

    messages = []
    for rearm in (True, False):
        plant = NonlinearPlant(bad, lambda t, x, u, p: x, 1, 1, 1, max_step=0.01)
        if not rearm:
            plant._rk_segments = None
        with pytest.raises(SimulationError, match=r"t = 0\.5") as info:
            plant.advance_to(1 * S)
        messages.append(str(info.value))
    assert messages[0] == messages[1]


def test_a_non_positive_max_step_is_refused_when_the_integrator_is_chosen():
    # scipy's own check (ValueError) now runs when the re-armed solver is built: the plant says it first
    with pytest.raises(ConfigError, match="max_step must be positive"):
        NonlinearPlant(lambda t, x, u, p: -x, lambda t, x, u, p: x, 1, 1, 1, max_step=0.0)
