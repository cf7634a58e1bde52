"""Closed-form cart motion with friction, and the numpy reference simulation's encoder edges."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from netsim.models.cart.controllers import CartController, make_controller
from netsim.models.cart.dynamics import propagate
from netsim.models.cart.encoding import Quantizer
from netsim.models.cart.friction import Friction, FrictionParams
from netsim.models.cart.sim import simulate
from netsim.models.cart.tuning import pure_pi_tuning


@pytest.mark.parametrize("td", [None, 0.23])
def test_propagate_matches_ode_through_a_friction_stop(td):
    # cart moving at 0.3 m/s, command -1 and friction 2 decelerate it: stop at 0.1 s (no Td), then stuck
    # because |u| = 1 <= breakaway 2. Independent check: integrate the ODE up to the stop event.
    p0, v0, u, f = 0.0, 0.3, -1.0, 2.0
    tau = np.linspace(0, 0.2, 41)
    p, v = propagate(p0, v0, u, f, f, tau, td)

    def rhs(t, x):
        return [x[1], u - f * np.sign(x[1]) - (x[1] / td if td else 0.0)]

    stop = lambda t, x: x[1]  # noqa: E731
    stop.terminal = True
    sol = solve_ivp(rhs, (0, 0.2), [p0, v0], events=stop, rtol=1e-10, atol=1e-12, dense_output=True)
    t_stop = sol.t_events[0][0]
    if td is None:
        assert t_stop == pytest.approx(0.1)  # 0.3 / (1 + 2)
    p_stop = sol.y_events[0][0][0]
    for ti, pi, vi in zip(tau, p, v):
        if ti < t_stop:
            assert pi == pytest.approx(sol.sol(ti)[0], abs=1e-9)
            assert vi == pytest.approx(sol.sol(ti)[1], abs=1e-9)
        else:
            assert pi == pytest.approx(p_stop, abs=1e-9) and vi == 0.0


def test_breakaway_needs_command_above_friction():
    tau = np.array([0.01])
    assert propagate(0.0, 0.0, 1.9, 2.0, 2.0, tau)[0][0] == 0.0
    p, v = propagate(0.0, 0.0, 3.0, 2.0, 2.0, tau)
    assert v[0] == pytest.approx(0.01) and p[0] == pytest.approx(0.5 * 1.0 * 1e-4)


def test_friction_varies_faster_at_the_far_end_and_is_reproducible():
    params = FrictionParams(model="modes6")
    fr = Friction.draw(params, seed=3)
    assert np.array_equal(fr.levels(np.linspace(0, 1, 50)), Friction.draw(params, seed=3).levels(np.linspace(0, 1, 50)))
    assert not np.array_equal(fr.freqs, Friction.draw(params, seed=4).freqs)
    # the local wavelength lambda0/(1 + gamma p): d phi/dp = (1 + 3p)/0.1 -> 10 per m at 0, 40 per m at 1 m
    eps = 1e-6
    assert (fr.phase(eps) - fr.phase(0)) / eps == pytest.approx(10.0, rel=1e-4)
    assert (fr.phase(1 + eps) - fr.phase(1)) / eps == pytest.approx(40.0, rel=1e-4)
    lv = fr.levels(np.linspace(0, 1, 20001))
    assert lv.mean() == pytest.approx(2.0, rel=0.15) and lv.min() >= 0.2 - 1e-12


def test_default_friction_is_the_inband_model_inside_the_loop_bandwidth():
    fr = Friction.draw(FrictionParams(), seed=1)
    assert fr.params.model == "inband" and fr.params.wavelength == 3.3 and fr.params.modes == 1
    # omega(p) = 2 pi v f (1 + gamma p) / lambda0 with f in [0.9, 1.1], v = 0.8, gamma = 9, lambda0 = 3.3:
    # 2 pi 0.8 0.9 3.7 / 3.3 = 5.07 at 0.3 m, 2 pi 0.8 1.1 10 / 3.3 = 16.8 at 1 m
    lo, hi = fr.omega_range(0.8, 0.3, 1.0)
    assert 5.07 - 1e-9 <= lo and hi <= 16.8 and hi / lo == pytest.approx(10.0 / 3.7)
    # the modes6 model varies at 2 pi 0.8 0.5 1.9 / 0.1 = 47.8 rad/s or faster: above every crossover tested
    assert Friction.draw(FrictionParams(model="modes6"), seed=1).omega_range(0.8, 0.3, 1.0)[0] >= 47.7
    # one unit-RMS mode: the level's RMS variation along many wavelengths is a = 30 % of F0 = 2
    p = np.linspace(0.0, 30.0, 300001)
    assert np.std(fr.levels(p)) == pytest.approx(0.6, rel=0.02)


def test_friction_preset_fields_can_be_overridden_and_unknown_models_are_refused():
    assert FrictionParams(model="modes6", wavelength=0.2).wavelength == 0.2
    assert FrictionParams(model="modes6").modes == 6
    assert Friction.draw(FrictionParams(model="constant"), seed=5).levels(np.array([0.1, 0.9])).tolist() == [2.0, 2.0]
    with pytest.raises(ValueError, match="inband"):
        FrictionParams(model="sixmodes")


class _Constant(CartController):
    """A controller that always commands the same uV (for open-loop checks)."""

    def __init__(self, uv):
        super().__init__(pure_pi_tuning(10.0), Quantizer(1e-3), 1_000_000)
        self.uv = uv

    def update(self, t_ns, count, direction, stamp_ns, vref):
        self.u = self.ku * self.uv
        return self.uv


def test_sim_edges_are_stamped_at_the_next_isr_tick():
    # frictionless, uV = 0.1 -> a = 2.55 m/s^2, p = a t^2 / 2. With q = 6 (3.2 mm, round) the edge into
    # count n is at p = (n - 1/2) 3.2 mm, i.e. t_n = sqrt(2 (n - 1/2) 0.0032 / a); the ISR stamps it at
    # the next 10 us tick.
    run = simulate(_Constant(0.1), Friction.none(), vref=0.5, q=6, distance=0.05, duration=1.0)
    a = 25.5 * 0.1
    n = np.arange(1, len(run.edge_times) + 1)
    t_edge = np.sqrt(2 * (n - 0.5) * 0.0032 / a)
    want = np.ceil(t_edge / 1e-5 - 1e-9) * 1e-5
    np.testing.assert_allclose(run.edge_times, want, atol=1e-9)
    assert len(run.edge_times) >= 15
    assert run.reached and run.t_reach == pytest.approx(math.ceil(math.sqrt(0.1 / a) * 1000) / 1000)


def test_friction_that_blocks_the_cart_is_reported_not_hung():
    fr = Friction.draw(FrictionParams(coulomb=30.0, variation=0.0), seed=0)  # above Ku = 25.5
    run = simulate(make_controller("full_event", 20.0, Quantizer.from_bits(6)), fr, vref=0.8, duration=0.5)
    assert not run.reached and math.isnan(run.t_reach)
    assert run.t[-1] == pytest.approx(0.5) and np.all(run.p == 0.0)


def test_event_control_settles_at_vref_on_a_uniform_track():
    fr = Friction.draw(FrictionParams(variation=0.0), seed=0)
    run = simulate(make_controller("full_event", 20.0, Quantizer.from_bits(6)), fr, vref=0.8)
    w = run.p > 0.3
    assert run.reached
    assert abs(run.v[w].mean() / 0.8 - 1) < 0.01  # integral action: no steady-state error
    assert run.u[w].mean() == pytest.approx(2.0, rel=0.02)  # the command balances the 2 m/s^2 friction
