"""The fixed-step RK4 integrator of nonlinear plants (``plant.integrator: {method: rk4, max_step}``, issue 29):
its error against the matrix exponential of a linear plant, guards on its interpolant, the pendulum's metrics
against a tight-tolerance solve_ivp reference, and the option's validation with paths."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import expm

import netsim
from netsim.env import SimEnv
from netsim.errors import ConfigError
from netsim.io import Encoder
from netsim.plant import NonlinearPlant
from netsim.plant.nonlinear import stick_slip_modes
from netsim.scenario import check_scenario
from netsim.timebase import MS, S, US

# a damped oscillator with one input: eigenvalues -0.5 +- 3.1j, ||A|| ~ 10
A = np.array([[0.0, 1.0], [-10.0, -1.0]])
B = np.array([[0.0], [2.0]])


def _linear(max_step_s: float, x0=(1.0, 0.0)) -> NonlinearPlant:
    plant = NonlinearPlant(lambda t, x, u, p: A @ x + B @ u, lambda t, x, u, p: x, 2, 1, 2, x0=list(x0))
    plant.set_integrator("rk4", max_step=max_step_s)
    return plant


def _augmented() -> np.ndarray:
    """``[[A, B], [0, 0]]``: the linear plant under a held input as an autonomous system of ``z = [x; u]``."""
    M = np.zeros((3, 3))
    M[:2, :2], M[:2, 2:] = A, B
    return M


def _taylor4(M: np.ndarray) -> np.ndarray:
    """``I + M + M^2/2 + M^3/6 + M^4/24``: what one classical RK4 step does to a linear autonomous system
    (its stability function is the degree-4 Taylor polynomial of the exponential)."""
    out, term = np.eye(len(M)), np.eye(len(M))
    for k in range(1, 5):
        term = term @ M / k
        out = out + term
    return out


def test_rk4_step_on_a_linear_plant_is_the_taylor_polynomial_of_expm():
    h = 10 * MS
    plant = _linear(h / S)
    plant.set_input(0, 0.7, 0)
    z = np.array([1.0, 0.0, 0.7])
    P = _taylor4(_augmented() * (h / S))
    for k in range(1, 51):
        z = P @ z
        assert plant.state(k * h) == pytest.approx(z[:2], rel=1e-13, abs=1e-15)


def test_rk4_local_error_on_a_linear_plant_is_within_the_fifth_order_bound():
    # One step from z: |exp(hM) z - T4(hM) z| <= ||hM||^5 / 5! * e^||hM|| * |z| (the Taylor remainder).
    for h_ms in (1, 5, 20):
        h = h_ms * MS
        plant = _linear(h / S, x0=(0.3, -1.2))
        plant.set_input(0, 0.4, 0)
        z = np.array([0.3, -1.2, 0.4])
        hm = _augmented() * (h / S)
        exact = expm(hm) @ z
        nrm = np.linalg.norm(hm, 2)
        bound = nrm**5 / 120.0 * math.exp(nrm) * np.linalg.norm(z)
        err = np.linalg.norm(plant.state(h) - exact[:2])
        assert 0 < err <= bound


def test_rk4_global_error_on_a_linear_plant_falls_with_the_fourth_power_of_the_step():
    # 2 s under a held input, sampled every 20 ms; halving max_step divides the error by about 2^4 = 16.
    z0 = np.array([1.0, 0.0, 0.5])

    def error(max_step_ms: float) -> float:
        plant = _linear(max_step_ms / 1e3)
        plant.set_input(0, 0.5, 0)
        return max(np.linalg.norm(plant.state(k * 20 * MS) - (expm(_augmented() * k * 0.02) @ z0)[:2])
                   for k in range(1, 101))

    e10, e5, e2_5 = error(10.0), error(5.0), error(2.5)
    assert e10 < 1e-4
    assert 12 < e10 / e5 < 20 and 12 < e5 / e2_5 < 20


def test_segments_shorter_than_max_step_take_one_step_each():
    plant = _linear(1e-3)
    for k in range(1, 11):
        plant.advance_to(k * 300 * US)  # 0.3 ms segments: one step of 4 evaluations each
    assert plant.rhs_evaluations == 40
    plant.advance_to(3 * MS + 2500 * US)  # a 2.5 ms segment: ceil(2.5) = 3 equal steps
    assert plant.rhs_evaluations == 52


def test_rk4_cart_sticks_where_the_guard_crosses_on_the_interpolant():
    # As test_cart_sticks_exactly_and_breaks_away_above_static_friction (test_nonlinear_plant.py) with 10 ms
    # RK4 steps: sliding with v' = -1.1 until v = 0 at 0.3/1.1 s (mid-step), position 0.3^2 / 2.2 there; the
    # motion is quadratic, so RK4 and its Hermite interpolant are exact and the bisection (1 ns) sets the error.
    def f(t, x, u, p):
        return np.array([x[1], u[0]])

    modes, select = stick_slip_modes(f, velocity=1, applied_force=lambda t, x, u, p: u[0], coulomb=0.5, static=0.7)
    plant = NonlinearPlant(f, lambda t, x, u, p: x[:1], 2, 1, 1, x0=[0.0, 0.3], modes=modes, select_mode=select,
                           method="rk4", max_step=0.01)
    plant.set_input(0, -0.6, 0)
    x = plant.state(1 * S)
    assert plant.mode == "stick" and x[1] == 0.0
    assert x[0] == pytest.approx(0.09 / 2.2, rel=1e-8)
    plant.set_input(0, 0.8, 1 * S)
    x = plant.state(2 * S)
    assert plant.mode == "slip+"
    assert x[1] == pytest.approx(0.3, rel=1e-12)
    assert x[0] == pytest.approx(0.09 / 2.2 + 0.15, rel=1e-8)


def _encoder_edges(mode: str, integrator: dict) -> list:
    """Edges of an encoder (512 counts per turn, 20 us ticks) on a swinging undamped pendulum over 0.5 s."""
    env = SimEnv(seed=0)

    def f(t, x, u, p):
        return np.array([x[1], -9.81 * math.sin(x[0])])

    plant = NonlinearPlant(f, lambda t, x, u, p: x[:1], 2, 1, 1, x0=[1.0001, 0.0], **integrator)
    plant.bind(env)
    edges: list = []
    Encoder(plant, 0, step=2 * math.pi / 512, tick_ns=20 * US, mode=mode).start(env, lambda *e: edges.append(e))
    env.run(S // 2)
    return edges


def test_exact_encoder_on_an_rk4_plant_reports_the_polled_edges():
    # the exact encoder predicts band crossings on the RK4 steps' Hermite interpolant; polling reads the plant
    # at every tick; both must give the edges solve_ivp (rtol 1e-8) gives
    rk4 = {"method": "rk4", "max_step": 1e-3}
    exact = _encoder_edges("exact", rk4)
    assert len(exact) > 50
    assert exact == _encoder_edges("polling", rk4)
    assert exact == _encoder_edges("exact", {})


# ------------------------------------------------------------------------------------------------- the pendulum
PENDULUM = "scenarios/pendulum_lqr.yaml"
RK4 = {"method": "rk4", "max_step": "1 ms"}


def _pendulum_metrics(integrator: dict, duration: str = "2 s") -> dict[str, float]:
    result = netsim.run(PENDULUM, overrides={"plant.integrator": integrator, "duration": duration})
    assert result.status == "ok"
    return {k: v for k, v in result.metrics.items() if k.startswith("pendulum.")}


def test_rk4_pendulum_metrics_are_within_1e_6_of_a_tight_solve_ivp_reference():
    # The reference is computed here: solve_ivp (RK45) at rtol 1e-10, atol 1e-12 on the same run (same seed,
    # so the same noise). Measured: the rk4 metrics (1 ms steps) differ from it by at most 5.7e-9 relative
    # (the default solve_ivp, rtol 1e-8: 2.5e-12).
    ref = _pendulum_metrics({"method": "solve_ivp", "rtol": 1e-10, "atol": 1e-12})
    rk4 = _pendulum_metrics(RK4)
    assert set(rk4) == set(ref) and len(ref) >= 10
    for key, want in ref.items():
        assert rk4[key] == pytest.approx(want, rel=1e-6, abs=1e-300), key
    assert _pendulum_metrics(RK4) == rk4  # reproducible: the same run gives the same floats


# ------------------------------------------------------------------------------------------------- validation
def _problems(integrator: object, plant: dict | None = None) -> list[str]:
    raw = netsim.load_scenario(PENDULUM).resolved_dict()
    raw["plant"] = {**(plant or raw["plant"]), "integrator": integrator}
    return [f"{p.path}: {p.message}" for p in check_scenario(raw) if p.severity == "error"]


@pytest.mark.parametrize(
    ("integrator", "where", "words"),
    [
        ({"method": "rk4"}, "plant.integrator", "needs max_step"),
        ({"method": "rk4", "max_step": "1 ms", "rtol": 1e-9}, "plant.integrator", "rtol apply to method solve_ivp"),
        ({"method": "euler", "max_step": "1 ms"}, "plant.integrator.method", ""),
        ({"method": "rk4", "max_step": "-1 ms"}, "plant.integrator.max_step", ""),
        ({"method": "solve_ivp", "rtol": 0}, "plant.integrator.rtol", ""),
        ({"method": "rk4", "max_step": "1 ms", "stepsize": 1}, "plant.integrator.stepsize", ""),
    ],
)
def test_bad_integrator_is_refused_at_its_path(integrator, where, words):
    problems = _problems(integrator)
    assert any(p.startswith(where + ":") and words in p for p in problems), problems


def test_integrator_on_an_lti_plant_is_refused_at_its_path():
    lti = {"type": "ss", "A": [[0, 1], [0, 0]], "B": [[0], [1]], "C": [[1, 0], [0, 1]], "D": 0,
           "outputs": ["theta", "alpha"], "inputs": ["u"],
           "record_grid": "5 ms"}  # the pendulum metric reads theta and alpha, recorded on this grid
    problems = _problems(RK4, lti)
    assert any(p.startswith("plant.integrator:") and "propagated exactly" in p for p in problems), problems


def test_set_integrator_refuses_bad_settings():
    plant = _linear(1e-3)
    with pytest.raises(ConfigError, match="needs a finite positive max_step"):
        plant.set_integrator("rk4")
    with pytest.raises(ConfigError, match="solve_ivp only"):
        plant.set_integrator("rk4", max_step=1e-3, rtol=1e-6)
    with pytest.raises(ConfigError, match="'solve_ivp' or 'rk4'"):
        plant.set_integrator("euler")
    plant.advance_to(1 * MS)
    with pytest.raises(ConfigError, match="before the simulation starts"):
        plant.set_integrator("solve_ivp")
