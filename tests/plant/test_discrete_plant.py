"""Discrete-time plants: updates at multiples of dt, held outputs, the input-timing convention."""

from __future__ import annotations

import numpy as np
import pytest

from netsim.env import SimEnv
from netsim.errors import ConfigError, DivergenceError
from netsim.plant import DiscretePlant, LTIDisturbance
from netsim.timebase import MS, US


def _plant(**kw) -> DiscretePlant:
    return DiscretePlant([[1.0, 0.1], [0.0, 1.0]], [[0.005], [0.1]], [[1.0, 0.0]], [[0.0]], 1 * MS, **kw)


def test_state_updates_at_multiples_of_dt_and_output_is_held():
    plant = _plant(x0=[0.0, 1.0])
    assert plant.output(999 * US)[0] == 0.0  # no update yet
    assert plant.output(1 * MS)[0] == pytest.approx(0.1)  # x1 = Ad x0
    assert plant.output(1 * MS + 999 * US)[0] == pytest.approx(0.1)  # held
    assert plant.output(3 * MS)[0] == pytest.approx(0.3)


def test_input_written_at_an_update_instant_acts_from_the_next_update():
    plant = _plant()
    plant.set_input(0, 1.0, 2 * MS)  # the update at 2 ms already used u = 0
    np.testing.assert_allclose(plant.state(2 * MS), [0.0, 0.0])
    np.testing.assert_allclose(plant.state(3 * MS), [0.005, 0.1])
    plant.set_input(0, 0.0, 3 * MS + 500 * US)  # mid-interval: the 4 ms update sees u = 0
    np.testing.assert_allclose(plant.state(4 * MS), [0.005 + 0.01, 0.1])


def test_matches_the_recursion_over_many_steps():
    Ad = np.array([[0.9, 0.2], [-0.1, 0.8]])
    Bd = np.array([[0.0], [1.0]])
    plant = DiscretePlant(Ad, Bd, [[1.0, 1.0]], [[0.5]], 100 * US, x0=[1.0, -1.0])
    rng = np.random.default_rng(0)
    x = np.array([1.0, -1.0])
    for k in range(1, 200):
        u = float(rng.normal())
        plant.set_input(0, u, k * 100 * US - 50 * US)
        x = Ad @ x + Bd[:, 0] * u
        assert plant.output(k * 100 * US)[0] == pytest.approx(x.sum() + 0.5 * u, rel=1e-12, abs=1e-12)


def test_discrete_disturbance_model_matches_augmented_eq2():
    # Cuenca et al. eq (2) augmented with eq (1): [xp; xd]+ = [[Ap, Bp Cd], [0, Ad]] [xp; xd] (no noise)
    Ap, Bp = np.array([[0.95]]), np.array([[0.1]])
    Ad, Cd = np.array([[1.0, 0.0], [-0.5, 0.9]]), np.array([[0.0, 1.0]])
    T = 1 * MS
    plant = DiscretePlant(Ap, Bp, [[1.0]], [[0.0]], T)
    plant.add_disturbance(0, LTIDisturbance(Ad, [0.0, 1.0], Cd, dt_ns=T, x0=[1.0, 0.0]))
    big = np.block([[Ap, Bp @ Cd], [np.zeros((2, 1)), Ad]])
    z = np.array([0.0, 1.0, 0.0])
    for k in range(1, 30):
        z = big @ z
        assert plant.output(k * T)[0] == pytest.approx(z[0], rel=1e-12, abs=1e-15)


def test_from_system_and_bad_input():
    import control

    plant = DiscretePlant.from_system(control.ss([[0.5]], [[1.0]], [[1.0]], [[0.0]], 0.002))
    assert plant.dt_ns == 2 * MS
    with pytest.raises(ConfigError, match="LTIPlant"):
        DiscretePlant.from_system(control.tf([1.0], [1.0, 1.0]))
    with pytest.raises(ConfigError, match="dt_ns"):
        DiscretePlant([[1.0]], [[1.0]], [[1.0]], [[0.0]], 0)
    with pytest.raises(ConfigError, match="continuous disturbance"):
        _plant().add_disturbance(0, LTIDisturbance([[-1.0]], [1.0], [1.0]))


def test_unstable_discrete_plant_diverges_at_the_update_instant():
    plant = DiscretePlant([[2.0]], [[0.0]], [[1.0]], [[0.0]], 1 * MS, x0=[1.0], divergence_bound=1000.0)
    with pytest.raises(DivergenceError) as info:
        plant.advance_to(100 * MS)
    assert info.value.time_ns == 10 * MS  # 2^10 = 1024 > 1000 first at the 10th update


def test_process_noise_draws_from_the_named_stream():
    env = SimEnv(seed=3)
    plant = _plant(process_noise=[0.0, 1e-4], name="d")
    plant.bind(env)
    a = plant.state(5 * MS)
    ref_rng = SimEnv(seed=3).rng("plant.d.process")
    L = np.diag([0.0, 1e-2])
    x = np.zeros(2)
    for _ in range(5):
        x = np.array([[1.0, 0.1], [0.0, 1.0]]) @ x + L @ ref_rng.standard_normal(2)
    np.testing.assert_allclose(a, x, rtol=1e-12, atol=1e-15)


def test_sine_disturbance_on_a_discrete_plant_is_held_over_each_step_from_its_start():
    # x+ = x + u with u = sin(2 pi 250 t) sampled at the start of each 1 ms step (as a held input would be):
    # u(0) = 0, u(1 ms) = 1, u(2 ms) = 0, u(3 ms) = -1, u(4 ms) = 0, so x at k ms = 0, 0, 1, 1, 0, 0 (by hand)
    from netsim.io.signals import make_signal
    from netsim.timebase import MS

    plant = DiscretePlant([[1.0]], [[1.0]], [[1.0]], [[0.0]], 1 * MS)
    plant.add_disturbance(0, make_signal({"type": "sine", "amplitude": 1.0, "frequency": 250.0}))
    ys = [float(plant.output(k * MS)[0]) for k in range(6)]
    np.testing.assert_allclose(ys, [0, 0, 1, 1, 0, 0], atol=1e-12)
