"""Plants a scenario describes (``plant: {type: ss|tf}``) and python-control systems given from Python (issue 16)."""

from __future__ import annotations

import control
import numpy as np
import pytest
import scipy.signal

import netsim
from netsim.plant.described import plant_spec_from_system
from netsim.scenario import load_scenario
from netsim.scenario import build
from netsim.scenario.problems import ScenarioError

# a stable third-order plant with a zero: 1 (s + 2) / (s^3 + 3 s^2 + 2 s + 1) (Routh: 3 * 2 > 1, stable)
NUM, DEN = [1.0, 2.0], [1.0, 3.0, 2.0, 1.0]


def _open_loop(plant: dict, duration: str = "4 s") -> dict:
    """A scenario whose plant input is a square wave (a disturbance on input u), output y recorded every 1 ms."""
    return {
        "name": "open_loop",
        "duration": duration,
        "plant": {**plant, "disturbances": {"u": "w"}, "record_grid": "1 ms"},
        "signals": {"w": {"type": "square", "amplitude": 1.0, "period": "2 s"}},
        "nodes": {"n": {"tasks": [{"name": "t", "program": "idle", "period": "100 ms", "priority": 1}]}},
        "record": ["y", "w"],
    }


def _y(result) -> tuple[np.ndarray, np.ndarray]:
    s = result.signals[["time_s", "y"]].dropna()
    return s["time_s"].to_numpy(), s["y"].to_numpy()


def test_ss_plant_from_yaml_equals_the_python_control_system_given_from_python() -> None:
    A = [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, -2.0, -3.0]]
    B, C = [0.0, 0.0, 1.0], [[2.0, 1.0, 0.0]]
    yaml_plant = {"type": "ss", "A": A, "B": B, "C": C, "inputs": ["u"], "outputs": ["y"]}
    sys = control.ss(A, np.reshape(B, (3, 1)), C, 0, inputs=["u"], outputs=["y"])
    a = netsim.run(_open_loop(yaml_plant))
    b = netsim.run(_open_loop({"system": sys}))
    ta, ya = _y(a)
    tb, yb = _y(b)
    assert ta.size == 4001 and np.array_equal(ta, tb)
    assert np.array_equal(ya, yb)  # the same matrices: the same bits
    plant = build(load_scenario(_open_loop(yaml_plant))).plant
    assert type(plant).__name__ == "LTIPlant"
    np.testing.assert_array_equal(plant.A, np.asarray(sys.A))
    np.testing.assert_array_equal(plant.B, np.asarray(sys.B))
    assert np.abs(ya).max() > 0.1  # the square wave moved the output


def test_tf_plant_equals_an_independent_zoh_simulation_of_its_realisation() -> None:
    result = netsim.run(_open_loop({"type": "tf", "num": NUM, "den": DEN, "inputs": ["u"], "outputs": ["y"]}))
    t, y = _y(result)
    # independent: scipy's lsim of the same transfer function, input held between samples (interp=False is a
    # zero-order hold, exact for the square wave whose jumps at multiples of 1 s lie on the 1 ms grid)
    w = result.signals[["time_s", "w"]].dropna()
    # the square wave, recorded at 0 and at every jump, held
    u = np.array([w["w"].to_numpy()[np.searchsorted(w["time_s"].to_numpy(), ti, side="right") - 1] for ti in t])
    _, y_ref, _ = scipy.signal.lsim((NUM, DEN), u, t, interp=False)
    assert np.abs(y).max() > 0.3  # the square wave moved the output (slow poles: it reaches 0.49)
    np.testing.assert_allclose(y, y_ref, rtol=0, atol=1e-9)


def test_mimo_tf_and_discrete_ss() -> None:
    spec = plant_spec_from_system(control.tf([[[1.0], [2.0]]], [[[1.0, 1.0], [1.0, 2.0]]]))
    assert spec["type"] == "tf" and np.shape(spec["num"]) == (1, 2, 1)
    sc = load_scenario({**_open_loop({"type": "ss", "A": [[0.5]], "B": [[1.0]], "C": [[1.0]], "dt": "10 ms",
                                      "inputs": ["u"], "outputs": ["y"]})})
    plant = build(sc).plant
    assert type(plant).__name__ == "DiscretePlant" and plant.dt_ns == 10_000_000


@pytest.mark.parametrize(("plant", "path", "words"), [
    ({"type": "ss", "A": [[0, 1]], "B": [0, 1], "C": [1, 0]}, "plant.A", "square"),
    ({"type": "ss", "A": [[0, 1], [0, 0]], "B": [[0, 1]], "C": [1, 0]}, "plant.B", "n = 2 rows"),
    ({"type": "ss", "A": [[0, 1], [0, 0]], "B": [0, 1], "C": [1, 0, 0]}, "plant.C", "n = 2 columns"),
    ({"type": "ss", "A": [[0, 1], [0, 0]], "B": [0, 1], "C": [1, 0], "D": [[1, 2]]}, "plant.D", "1x1"),
    ({"type": "tf", "num": [1, 0, 0], "den": [1, 1]}, "plant.den", "not proper"),
    ({"type": "tf", "num": [1], "den": [0, 0]}, "plant.den", "nonzero denominator"),
])
def test_wrong_plant_dimensions_are_located_problems(plant: dict, path: str, words: str) -> None:
    with pytest.raises(ScenarioError) as err:
        load_scenario(_open_loop(plant))
    problems = [(p.path, p.message) for p in err.value.problems]
    assert any(p == path and words in m for p, m in problems), problems


def test_a_nonlinear_io_system_from_python_runs_its_updfcn() -> None:
    def updfcn(t, x, u, params):
        return [x[1], -params["k"] * x[0] + u[0]]

    def outfcn(t, x, u, params):
        return [x[0]]

    sys = control.nlsys(updfcn, outfcn, states=2, inputs=["u"], outputs=["y"], params={"k": 1.0}, name="osc")
    raw = {"name": "nl", "duration": "2 s", "record": ["y"],
           "plant": {"system": sys, "x0": [1.0, 0.0], "record_grid": "10 ms", "params": {"params": {"k": 4.0}}},
           "nodes": {"c": {"tasks": [{"name": "t", "program": "idle", "period": "100 ms", "priority": 1}]}}}
    result = netsim.run(raw)
    t, y = _y(result)
    # analytic: x'' = -4 x, x(0) = 1 -> y = cos(2 t) (k = 4 from the scenario overrides the system's k = 1)
    assert t.size == 201
    np.testing.assert_allclose(y, np.cos(2.0 * t), atol=1e-7)
    assert type(build(raw).plant).__name__ == "NonlinearPlant"
