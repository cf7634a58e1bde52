"""Random disturbances from a scenario's ``process_noise`` entries (issue 26 section 6, :mod:`netsim.plant.noise`).

Every expected value here is computed independently of the plant code: the draws are re-created from the stream
the module documents (``stream_seed(seed, name)``), and the propagation is done with ``scipy.linalg.expm`` or
the closed-form solution of the test plant.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import expm

import netsim
from netsim.env import SimEnv, stream_seed
from netsim.errors import ConfigError
from netsim.plant import LTIPlant, NonlinearPlant
from netsim.scenario.loader import check_scenario
from netsim.timebase import MS

A = np.array([[0.0, 1.0], [-4.0, -0.6]])
B = np.array([[0.0], [1.0]])
C = np.array([[1.0, 0.0]])


def _stream(seed: int, name: str) -> np.random.Generator:
    return np.random.Generator(np.random.PCG64(stream_seed(seed, name)))


def _zoh(h_s: float) -> tuple[np.ndarray, np.ndarray]:
    M = np.zeros((3, 3))
    M[:2, :2], M[:2, 2:] = A * h_s, B * h_s
    E = expm(M)
    return E[:2, :2], E[:2, 2:]


def test_held_input_noise_is_the_exact_zoh_response_to_the_drawn_sequence():
    # Input noise sigma 0.3 held over 10 ms: the plant sees u + 0.3 e_k on [10k ms, 10(k+1) ms), e_0 drawn at the
    # start. The plant is read at irregular instants (7, 23, 41 ms): the held noise is piecewise constant, so the
    # state must equal the exact ZOH propagation over the sample intervals, to rounding.
    env = SimEnv(seed=11)
    plant = LTIPlant(A, B, C, None, x0=[1.0, 0.0], input_names=["u"], name="p")
    plant.set_process_noise({"inputs": ["u"], "sigma": 0.3, "sample": "10 ms"})
    plant.bind(env)
    got = [plant.state(t * MS) for t in (7, 23, 41)]

    e = 0.3 * _stream(11, "plant.p.disturbance.u").standard_normal(5)
    x = np.array([1.0, 0.0])
    t = 0
    want = []
    for stop in (7, 23, 41):
        while t < stop:
            end = min(stop, (t // 10 + 1) * 10)
            Ad, Bd = _zoh((end - t) * 1e-3)
            x = Ad @ x + Bd[:, 0] * e[t // 10]
            t = end
        want.append(x.copy())
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-15)


def test_input_noise_in_a_scenario_is_fixed_by_the_seed_alone():
    def run(seed: int) -> list[float]:
        sc = {"name": "n", "seed": seed, "duration": "100 ms",
              "plant": {"type": "tf", "num": [1.0], "den": [1.0, 1.0], "inputs": ["u"], "outputs": ["y"],
                        "process_noise": {"inputs": ["u"], "sigma": 1.0, "sample": "5 ms"},
                        "record_grid": "10 ms"}}
        return list(netsim.run(sc).signals["y"])

    first, again, other = run(3), run(3), run(4)
    assert first == again
    assert first != other
    assert max(abs(v) for v in first) > 0.0  # the noise reached the plant


def test_state_noise_adds_random_walk_increments_to_a_plugin_plant():
    # The unicycle (seed 001's two-wheel cart) at rest, no noise of its own: the pose moves only by the slip
    # increments. x and theta take sigma_i * sqrt(0.01 s) * e at 10, 20, ..., 90 ms (9 instants before 95 ms),
    # drawn from plant.unicycle.state_noise two at a time (x, theta).
    from netsim.models.unicycle.plant import unicycle

    env = SimEnv(seed=2)
    plant = unicycle(pose0=[0.1, 0.2, 0.3])
    plant.set_process_noise({"states": ["x", "theta"], "sigma": [0.02, 0.05], "sample": "10 ms"})
    plant.bind(env)
    got = plant.state(95 * MS)
    draws = _stream(2, "plant.unicycle.state_noise").standard_normal((9, 2))
    inc = (draws * np.array([0.02, 0.05]) * math.sqrt(0.01)).sum(axis=0)
    np.testing.assert_allclose(got, [0.1 + inc[0], 0.2, 0.3 + inc[1]], rtol=0, atol=1e-15)


def test_state_noise_jumps_after_the_integrator_reaches_each_sample_instant():
    # x' = -x integrated by solve_ivp with a 1 at t = 0; a jump sigma sqrt(T) e_k at T = 20 ms and 40 ms. Closed
    # form at 50 ms: ((e^{-0.02} + j1) e^{-0.02} + j2) e^{-0.01}.
    env = SimEnv(seed=9)
    plant = NonlinearPlant(lambda t, x, u, p: -x, lambda t, x, u, p: x, n_states=1, n_inputs=1, n_outputs=1,
                           x0=[1.0], name="nl", rtol=1e-11, atol=1e-13)
    plant.add_state_noise([0], 0.5, 20 * MS)
    plant.bind(env)
    j1, j2 = 0.5 * math.sqrt(0.02) * _stream(9, "plant.nl.state_noise").standard_normal(2)
    want = ((math.exp(-0.02) + j1) * math.exp(-0.02) + j2) * math.exp(-0.01)
    assert plant.state(50 * MS)[0] == pytest.approx(want, rel=1e-9)


@pytest.mark.parametrize("sample_ms", [2, 25])
def test_state_noise_variance_grows_as_sigma_squared_times_time_whatever_the_sample(sample_ms):
    # A pure integrator state (A = 0) with increments only: Var x(t) = sigma^2 t = 4 * 0.1 = 0.4 for both samples.
    # 600 seeds: the sample variance of a normal has relative standard error sqrt(2/599) = 5.8 %; allow 4 of them.
    finals = []
    for seed in range(600):
        plant = LTIPlant([[0.0]], [[0.0]], [[1.0]], None, name="w")
        plant.add_state_noise([0], 2.0, sample_ms * MS)
        plant.bind(SimEnv(seed=seed))
        finals.append(plant.state(100 * MS + 1)[0])
    assert np.var(finals, ddof=1) == pytest.approx(0.4, rel=4 * math.sqrt(2 / 599))


def test_input_noise_sigma_per_input_on_a_two_input_plant():
    # y' = u1 + u2 (one state): noise only on u2 (sigma 0 on u1 draws nothing). x(30 ms) = 0.01 * sum of 3 draws.
    env = SimEnv(seed=1)
    plant = LTIPlant([[0.0]], [[1.0, 1.0]], [[1.0]], None, input_names=["a", "b"], name="two")
    plant.set_process_noise([{"inputs": ["a", "b"], "sigma": [0.0, 2.0], "sample": "10 ms"}])
    plant.bind(env)
    e = 2.0 * _stream(1, "plant.two.disturbance.b").standard_normal(3)
    assert plant.state(30 * MS)[0] == pytest.approx(0.01 * e.sum(), rel=1e-12)


@pytest.mark.parametrize(
    ("noise", "words"),
    [
        ({"states": [0], "inputs": ["u"], "sigma": 1.0, "sample": "1 ms"}, "either 'states'"),
        ({"states": [0, 1], "sigma": [1.0], "sample": "1 ms"}, "sigma has 1 values for 2 states"),
        ({"inputs": ["u"], "sigma": -1.0, "sample": "1 ms"}, ">= 0"),
        ({"inputs": ["u"], "sigma": 1.0, "sample": "1 ms", "model": "increment"}, "does not apply to inputs"),
        ({"inputs": ["u"], "sigma": 1.0}, "sample"),
    ],
)
def test_bad_noise_entries_are_refused_at_their_path(noise, words):
    sc = {"name": "n", "duration": "10 ms",
          "plant": {"type": "ss", "A": A.tolist(), "B": B.tolist(), "C": C.tolist(), "inputs": ["u"],
                    "outputs": ["y"], "process_noise": noise}}
    errors = [p for p in check_scenario(sc) if p.severity == "error"]
    assert errors, "the bad entry was accepted"
    assert any(words in p.message and "process_noise" in p.path for p in errors), errors
    with pytest.raises(Exception):
        netsim.run(sc)


def test_noise_on_an_unknown_state_is_refused_by_validate_and_run():
    sc = {"name": "n", "duration": "10 ms",
          "plant": {"type": "ss", "A": A.tolist(), "B": B.tolist(), "C": C.tolist(), "inputs": ["u"],
                    "outputs": ["y"], "process_noise": {"states": ["speed"], "sigma": 1.0, "sample": "1 ms"}}}
    errors = [p for p in check_scenario(sc) if p.severity == "error"]
    assert any("has no state 'speed'" in p.message and p.path.startswith("plant.process_noise") for p in errors), errors
    with pytest.raises(ConfigError, match="has no state 'speed'"):
        netsim.run(sc)


def test_held_input_noise_drives_a_nonlinear_plant_through_its_solver():
    # x' = u integrated by solve_ivp, u = 0.4 e_k held over 5 ms: x(12 ms) = 0.005 (e_0 + e_1) + 0.002 e_2, times 0.4
    env = SimEnv(seed=4)
    plant = NonlinearPlant(lambda t, x, u, p: u, lambda t, x, u, p: x, n_states=1, n_inputs=1, n_outputs=1,
                           input_names=["u"], name="nl")
    plant.add_input_noise("u", 0.4, 5 * MS)
    plant.bind(env)
    e = 0.4 * _stream(4, "plant.nl.disturbance.u").standard_normal(3)
    assert plant.state(12 * MS)[0] == pytest.approx(0.005 * (e[0] + e[1]) + 0.002 * e[2], rel=1e-9)


@pytest.mark.parametrize(("noise", "words"), [
    (0.1, "takes process noise as entries"),  # an intensity: only LTI and discrete plants take one
    ({"inputs": ["omega_L"], "sigma": 0.1, "sample": "10 ms"}, "put the noise on its states instead"),
])
def test_a_plant_that_cannot_take_a_noise_form_says_what_to_write(noise, words):
    sc = {"name": "u", "duration": "20 ms", "plant": {"model": "unicycle", "process_noise": noise}}
    errors = [p for p in check_scenario(sc) if p.severity == "error"]
    assert any(words in p.message and p.path == "plant.process_noise" for p in errors), errors


def test_entries_given_to_the_constructor_act_as_set_later():
    entries = [{"inputs": ["u"], "sigma": 0.3, "sample": "2 ms"}, {"states": [1], "sigma": 0.1, "sample": "3 ms"}]
    given = LTIPlant(A, B, C, None, input_names=["u"], name="p", process_noise=entries)
    later = LTIPlant(A, B, C, None, input_names=["u"], name="p")
    later.set_process_noise(entries)
    for plant in (given, later):
        plant.bind(SimEnv(seed=8))
    np.testing.assert_array_equal(given.state(20 * MS), later.state(20 * MS))
    assert np.all(given.state(20 * MS) != 0.0)


def test_held_state_rate_on_an_lti_plant_is_propagated_exactly():
    # model: rate on state 0 (the position of the oscillator A): dx0/dt gets 0.5 e_k held over [5k, 5(k+1)) ms,
    # e_0 drawn at the start. Reference: the exact ZOH of x' = A x + E r with E = [1, 0]', read at 3, 12, 17 ms.
    env = SimEnv(seed=21)
    plant = LTIPlant(A, B, C, None, x0=[0.2, 0.0], input_names=["u"], name="p")
    plant.set_process_noise({"states": [0], "sigma": 0.5, "sample": "5 ms", "model": "rate"})
    plant.bind(env)
    got = [plant.state(t * MS) for t in (3, 12, 17)]

    r = 0.5 * _stream(21, "plant.p.state_noise").standard_normal(4)
    x, t, want = np.array([0.2, 0.0]), 0, []
    for stop in (3, 12, 17):
        while t < stop:
            end = min(stop, (t // 5 + 1) * 5)
            M = np.zeros((3, 3))
            M[:2, :2], M[0, 2] = A * (end - t) * 1e-3, (end - t) * 1e-3
            E = expm(M)
            x = E[:2, :2] @ x + E[:2, 2] * r[t // 5]
            t = end
        want.append(x.copy())
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-15)


def test_held_state_rate_on_a_nonlinear_plant_adds_to_its_right_hand_side():
    # x' = -x + r_k, r_k = 2 e_k held over 10 ms from x = 1: per interval x <- r + (x - r) e^{-h}; read at 25 ms
    env = SimEnv(seed=5)
    plant = NonlinearPlant(lambda t, x, u, p: -x, lambda t, x, u, p: x, n_states=1, n_inputs=1, n_outputs=1,
                           x0=[1.0], name="nl", rtol=1e-11, atol=1e-13)
    plant.add_state_noise([0], 2.0, 10 * MS, model="rate")
    plant.bind(env)
    r = 2.0 * _stream(5, "plant.nl.state_noise").standard_normal(3)
    x = 1.0
    for k, h in enumerate((0.01, 0.01, 0.005)):
        x = r[k] + (x - r[k]) * math.exp(-h)
    assert plant.state(25 * MS)[0] == pytest.approx(x, rel=1e-9)


def test_a_plant_with_its_own_integrator_refuses_a_held_state_rate():
    sc = {"name": "u", "duration": "20 ms", "plant": {"model": "unicycle", "process_noise": {
        "states": ["x"], "sigma": 0.1, "sample": "10 ms", "model": "rate"}}}
    errors = [p for p in check_scenario(sc) if p.severity == "error"]
    assert any("does not take a held rate" in p.message and p.path == "plant.process_noise" for p in errors), errors
