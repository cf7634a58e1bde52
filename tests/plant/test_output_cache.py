"""The LTI plants' output cache and propagation fast paths: never a stale or different value.

Every expected value is recomputed in the test from the plant's own state and the inputs the test set
(``y = C x + D u``), or from an independent numpy recursion, so a stale cache shows up as a mismatch.
"""

from __future__ import annotations

import numpy as np
import pytest

from netsim.env import SimEnv
from netsim.plant import DiscretePlant, LTIDisturbance, LTIPlant
from netsim.io.signals import make_signal
from netsim.timebase import MS, S, US

AD = np.array([[0.9, 0.2], [-0.1, 0.8]])
BD = np.array([[0.0], [1.0]])
CD = np.array([[1.0, 2.0]])
DD = np.array([[0.5]])  # a direct feedthrough, so that an input change shows in the output at once


def _discrete(**kw) -> DiscretePlant:
    return DiscretePlant(AD, BD, CD, DD, 1 * MS, x0=[1.0, -1.0], **kw)


def _recomputed(plant, u: float) -> float:
    """``C x + D u`` from the plant's current state and the effective input ``u`` known to the test."""
    C = plant.Cd if isinstance(plant, DiscretePlant) else plant.C
    D = plant.Dd if isinstance(plant, DiscretePlant) else plant.D
    return float(C[0] @ plant.state() + D[0, 0] * u)


@pytest.mark.parametrize("kind", ["discrete", "continuous"])
def test_output_at_one_instant_is_the_callers_own_and_refreshed_by_set_input(kind):
    plant = _discrete() if kind == "discrete" else LTIPlant([[-1.0, 0.5], [0.0, -2.0]], BD, CD, DD, x0=[1.0, -1.0])
    t = 2 * MS + 300 * US
    y1 = plant.output(t)
    expected = _recomputed(plant, 0.0)
    assert plant.output(t)[0] == y1[0] == plant.output_value(0, t) == pytest.approx(expected, abs=1e-15)
    y1[0] = 3.0  # the caller's copy: the plant's cached value is untouched
    assert plant.output(t)[0] == plant.output_value(0, t) == pytest.approx(expected, abs=1e-15)
    plant.set_input(0, 2.0, t)  # same instant: only the input changes
    assert plant.output(t)[0] == pytest.approx(_recomputed(plant, 2.0), abs=1e-15)
    assert plant.output(t)[0] - expected == pytest.approx(0.5 * 2.0)  # D u
    plant.set_inputs([-1.0], t)
    assert plant.output_value(0, t) == pytest.approx(_recomputed(plant, -1.0), abs=1e-15)


def test_set_state_at_the_same_instant_refreshes_the_output():
    plant = _discrete()
    t = 1 * MS + 500 * US
    plant.set_input(0, 1.0, t)
    before = plant.output(t)[0]
    plant.set_state([3.0, 4.0], t)
    assert plant.output(t)[0] == 1.0 * 3.0 + 2.0 * 4.0 + 0.5 * 1.0 != before


def test_disturbance_jump_between_updates_refreshes_the_output():
    # a step disturbance at 2.5 ms: between updates, so only D d changes the output there
    plant = _discrete()
    plant.add_disturbance(0, make_signal({"type": "step", "at": "2.5 ms", "value": 4.0}))
    y_before = plant.output(2 * MS + 400 * US)[0]
    assert plant.output(2 * MS + 400 * US)[0] == y_before == pytest.approx(_recomputed(plant, 0.0), abs=1e-15)
    assert plant.output(2 * MS + 500 * US)[0] == pytest.approx(_recomputed(plant, 4.0), abs=1e-15)
    assert plant.output(2 * MS + 500 * US)[0] - y_before == pytest.approx(0.5 * 4.0)


def test_sine_disturbance_output_follows_time_between_updates():
    # with a sine on the input and D != 0 the output changes between updates although the state is held
    sine = make_signal({"type": "sine", "amplitude": 1.0, "frequency": 50.0})
    plant = _discrete()
    plant.add_disturbance(0, sine)
    for t in (1 * MS + 100 * US, 1 * MS + 200 * US, 1 * MS + 200 * US, 1 * MS + 700 * US):
        assert plant.output_value(0, t) == pytest.approx(_recomputed(plant, float(sine(t))), abs=1e-15)


def test_process_noise_updates_refresh_the_output():
    env = SimEnv(seed=3)
    plant = _discrete(process_noise=[1e-2, 1e-2])
    plant.bind(env)
    seen = set()
    for k in range(1, 20):
        t = k * MS
        plant.output(t - 1)  # cached before the update
        y = plant.output(t)[0]
        assert y == pytest.approx(_recomputed(plant, 0.0), abs=1e-15)
        seen.add(y)
    assert len(seen) == 19  # the noise makes every update distinct


def test_discrete_disturbance_model_update_refreshes_the_output():
    env = SimEnv(seed=5)
    plant = _discrete()
    plant.add_disturbance(0, LTIDisturbance([[0.9]], [1.0], [1.0], dt_ns=700 * US, noise_cov=1.0))
    plant.bind(env)
    for k in range(1, 30):
        t = k * 350 * US
        y = plant.output(t)[0]
        d = float(plant._sources[0].value)
        assert y == pytest.approx(_recomputed(plant, d), abs=1e-14)


def test_fine_grained_advances_match_the_recursion_bit_for_bit():
    # the fast paths (no update due: move the clock; t == now: nothing) against the plain recursion,
    # with the input changed between updates and the update grid offset
    rng = np.random.default_rng(7)
    plant = _discrete(offset_ns=250 * US)
    x = np.array([1.0, -1.0])
    u = 0.0
    t_update = 250 * US
    for k in range(200):
        t = k * 130 * US + int(rng.integers(0, 50)) * US
        while t_update <= t:
            x = AD.dot(x) + BD.dot(np.array([u]))
            t_update += 1 * MS
        np.testing.assert_array_equal(plant.state(t), x)
        assert plant.output(t)[0] == plant.output(t)[0] == CD[0].dot(x) + DD[0, 0] * u
        if k % 3 == 0:
            u = float(rng.normal())
            plant.set_input(0, u, t)


def test_listeners_see_noisy_updates_on_the_fast_path():
    env = SimEnv(seed=1)
    plant = _discrete(process_noise=[1e-3, 1e-3])
    plant.bind(env)
    calls: list[int] = []
    plant.on_input_change(calls.append)
    plant.advance_to(500 * US)  # no update: no notification
    plant.advance_to(2 * MS + 1)  # updates at 1 ms and 2 ms, notified once at the plant's new time
    assert calls == [2 * MS + 1]
    plant.advance_to(int(0.5 * S))
    assert calls[-1] == int(0.5 * S) and len(calls) == 2


def test_output_value_and_record_grid_agree_with_output_on_a_mimo_plant():
    # two outputs: output_value(i) and the record_grid samples are the entries of output(), bit for bit
    env = SimEnv(seed=0)
    plant = DiscretePlant(AD, BD, [[1.0, 2.0], [-1.0, 0.5]], [[0.5], [0.0]], 1 * MS, x0=[1.0, -1.0],
                          output_names=["a", "b"])
    plant.bind(env, record_grid_ns=700 * US, grid_prefix="g.")
    plant.set_input(0, 0.3, 0)
    env.run(10 * MS)
    times = env.recorder.times["g.a"]
    assert times == list(range(0, 10 * MS + 1, 700 * US))
    replay = DiscretePlant(AD, BD, [[1.0, 2.0], [-1.0, 0.5]], [[0.5], [0.0]], 1 * MS, x0=[1.0, -1.0])
    replay.set_input(0, 0.3, 0)
    for k, t in enumerate(times):
        y = replay.output(t)
        assert [replay.output_value(0, t), replay.output_value(1, t)] == y.tolist()
        assert env.recorder.values["g.a"][k] == y[0] and env.recorder.values["g.b"][k] == y[1]
