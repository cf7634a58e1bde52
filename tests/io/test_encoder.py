"""Encoders: exact edge prediction gives the same (count, direction, stamp) sequence as polling."""

from __future__ import annotations

import math

import numpy as np
import pytest

from netsim.env import SimEnv
from netsim.errors import ConfigError
from netsim.io import Encoder, encoder_step
from netsim.plant import DiscretePlant, LTIPlant, NonlinearPlant
from netsim.plant.nonlinear import stick_slip_modes
from netsim.timebase import MS, S, US


def _cart(x0) -> LTIPlant:
    return LTIPlant([[0.0, 1.0], [0.0, 0.0]], [0.0, 1.0], [1.0, 0.0], None, x0=x0, name="cart")


def _run(make_plant, mode: str, *, step: float, tick: int, duration: int, seed: int = 0, inputs=True,
         disturbance=None):
    """Run a plant with random piecewise-constant inputs at random instants and record the encoder edges."""
    env = SimEnv(seed=seed)
    plant = make_plant()
    if disturbance is not None:
        plant.add_disturbance(0, disturbance)
    plant.bind(env)
    edges: list[tuple[int, int, int]] = []
    enc = Encoder(plant, 0, step=step, tick_ns=tick, mode=mode)
    enc.start(env, lambda c, d, s: edges.append((c, d, s)))

    def actuator():
        rng = env.rng("test.inputs")
        while True:
            plant.set_input(0, float(rng.uniform(-3.0, 3.0)))
            # random instants, mostly off the tick grid
            yield env.timeout(int(rng.integers(100 * US, 5 * MS)))

    if inputs:
        env.process(actuator())
    env.run(duration)
    return edges, enc


def test_exact_and_polling_give_identical_edges_on_a_random_trajectory():
    kw = dict(step=1e-4, tick=10 * US, duration=400 * MS, seed=3)
    exact, enc_e = _run(lambda: _cart([0.0, 0.05]), "exact", **kw)
    polled, enc_p = _run(lambda: _cart([0.0, 0.05]), "polling", **kw)
    assert len(exact) > 100
    assert {d for _, d, _ in exact} == {-1, 1}  # it moves both ways
    assert exact == polled
    assert enc_e.wakeups < enc_p.wakeups / 5


def test_exact_and_polling_agree_with_a_step_disturbance():
    kw = dict(step=2e-4, tick=10 * US, duration=150 * MS, seed=8,
              disturbance={"type": "step", "at": "73.3333 ms", "value": -2.0})
    exact, _ = _run(lambda: _cart([0.0, 0.0]), "exact", **kw)
    polled, _ = _run(lambda: _cart([0.0, 0.0]), "polling", **kw)
    assert len(exact) > 20
    assert exact == polled


@pytest.mark.parametrize("v, x0", [(0.8, 1.234e-4), (-0.37, 0.0511), (0.05, -0.0007)])
def test_edge_count_equals_travelled_distance_over_delta_for_monotone_motion(v, x0):
    delta = 3.2e-3
    duration = 1 * S
    edges, enc = _run(lambda: _cart([x0, v]), "exact", step=delta, tick=10 * US, duration=duration, inputs=False)
    x1 = x0 + v * duration / S
    # every level k*delta between x0 and x1 is crossed once: |floor(x1/delta) - floor(x0/delta)| edges
    assert len(edges) == abs(math.floor(x1 / delta) - math.floor(x0 / delta))
    assert enc.count == math.floor(x1 / delta)
    assert all(d == (1 if v > 0 else -1) for _, d, _ in edges)
    assert all(s % (10 * US) == 0 for _, _, s in edges)  # stamps are ISR ticks


def test_edge_is_stamped_at_the_first_tick_after_the_crossing():
    # x = 0.8 t + 1e-5 crosses 3.2 mm at t = (3.2e-3 - 1e-5) / 0.8 = 3.9875 ms: the 10 us ISR sees it at 3.99 ms
    edges, _ = _run(lambda: _cart([1e-5, 0.8]), "exact", step=3.2e-3, tick=10 * US, duration=5 * MS, inputs=False)
    assert edges == [(1, 1, 3_990_000)]


def test_several_edges_in_one_tick_are_reported_once_with_the_last_count():
    # 20 m/s with delta 0.1 mm: two levels per 10 us tick; both modes report every tick with a jump of 2
    kw = dict(step=1e-4, tick=10 * US, duration=1 * MS, inputs=False)
    exact, _ = _run(lambda: _cart([5e-5, 20.0]), "exact", **kw)
    polled, _ = _run(lambda: _cart([5e-5, 20.0]), "polling", **kw)
    assert exact == polled
    counts = [c for c, _, _ in exact]
    assert np.all(np.diff(counts) == 2)
    assert len(exact) == 100


def test_exact_and_polling_agree_on_a_stick_slip_cart():
    def f(t, x, u, p):
        return np.array([x[1], u[0]])

    def make():
        modes, select = stick_slip_modes(f, velocity=1, applied_force=lambda t, x, u, p: u[0], coulomb=0.5,
                                         static=0.7)
        return NonlinearPlant(f, lambda t, x, u, p: x[:1], 2, 1, 1, x0=[0.0, 0.1], modes=modes,
                              select_mode=select)

    kw = dict(step=5e-5, tick=10 * US, duration=30 * MS, seed=2)
    exact, _ = _run(make, "exact", **kw)
    polled, _ = _run(make, "polling", **kw)
    assert len(exact) > 10
    assert exact == polled


def test_exact_and_polling_agree_on_a_discrete_plant():
    def make():
        return DiscretePlant([[1.0, 1e-4], [0.0, 1.0]], [[0.0], [1e-4]], [[1.0, 0.0]], [[0.0]], 100 * US,
                             x0=[0.0, 0.1])

    kw = dict(step=1e-5, tick=10 * US, duration=100 * MS, seed=5)
    exact, _ = _run(make, "exact", **kw)
    polled, _ = _run(make, "polling", **kw)
    assert len(exact) > 50
    assert exact == polled
    assert all(s % (100 * US) == 0 for _, _, s in exact)  # the output only moves at updates


def test_encoder_step_helper_and_bad_parameters():
    # the cart: 5e-5 m resolution with 6 low bits dropped gives 3.2 mm (Henningsson & Cervin, section II)
    assert encoder_step(5e-5, 6) == pytest.approx(3.2e-3)
    plant = _cart([0.0, 0.0])
    enc = Encoder(plant, 0, step=5e-5, q=6, tick_ns=10 * US)
    assert enc.delta == pytest.approx(3.2e-3)
    with pytest.raises(ConfigError, match="step"):
        Encoder(plant, 0, step=0.0, tick_ns=10 * US)
    with pytest.raises(ConfigError, match="mode"):
        Encoder(plant, 0, step=1e-3, tick_ns=10 * US, mode="fast")
    with pytest.raises(ConfigError, match="tick"):
        Encoder(plant, 0, step=1e-3, tick_ns=0)


def test_on_edge_can_change_the_input_synchronously():
    # an ISR that brakes the cart at each edge: the prediction must follow the new input
    def run(mode):
        env = SimEnv(seed=0)
        plant = _cart([0.0, 0.5])
        plant.bind(env)
        edges = []

        def isr(c, d, s):
            edges.append((c, d, s))
            plant.set_input(0, -2.0 if c > 3 else 1.0, s)

        Encoder(plant, 0, step=1e-3, tick_ns=10 * US, mode=mode).start(env, isr)
        env.run(200 * MS)
        return edges

    exact = run("exact")
    assert len(exact) > 5
    assert exact == run("polling")


def test_exact_mode_on_a_noisy_plant_reports_the_count_it_sees():
    # With process noise the two modes agree in distribution only; each report must still be the count of
    # the plant output at its stamp.
    env = SimEnv(seed=1)
    plant = LTIPlant([[0.0, 1.0], [0.0, -1.0]], [0.0, 1.0], [1.0, 0.0], None, x0=[0.0, 0.2],
                     process_noise=[0.0, 0.05])
    plant.bind(env)
    delta = 1e-4
    seen = []

    def isr(c, d, s):
        seen.append((c, math.floor(plant.output(s)[0] / delta)))

    def actuator():
        while True:
            plant.set_input(0, 0.2 * math.sin(env.now / S * 7))
            yield env.timeout(1 * MS)

    env.process(actuator())
    Encoder(plant, 0, step=delta, tick_ns=10 * US).start(env, isr)
    env.run(200 * MS)
    assert len(seen) > 50
    assert all(c == ref for c, ref in seen)


def test_exact_and_polling_agree_with_a_noisy_discrete_disturbance_model():
    # the disturbance draws its noise at its own instants (every 1 ms), whatever the plant's propagation
    # steps, so both modes see the same sample path; the exact encoder must stop predicting at each draw
    from netsim.plant import LTIDisturbance

    def make():
        plant = _cart([0.0, 0.02])
        plant.add_disturbance(0, LTIDisturbance([[0.9]], [1.0], [1.0], dt_ns=1 * MS, noise_cov=4.0))
        return plant

    kw = dict(step=2e-5, tick=10 * US, duration=100 * MS, inputs=False)
    exact, enc = _run(make, "exact", **kw)
    polled, _ = _run(make, "polling", **kw)
    assert len(exact) > 20
    assert exact == polled
