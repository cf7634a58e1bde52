"""Scenarios given from Python take numpy values and python-control systems wherever YAML takes numbers,
vectors, matrices or a plant/model (issue 26 section 2).

Each test gives one kind of field from Python and checks that the scenario loads and hashes exactly as the same
scenario written with plain lists does (the expected side is written by hand or with ``tolist()``, never with
netsim's converter).
"""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import control
import numpy as np
import pytest

import netsim
from netsim.scenario import check_scenario, load_scenario, scenario_hash
from netsim.scenario.safe_yaml import load_file
from netsim.sweep.spec import load_sweep

ROOT = Path(__file__).resolve().parents[2]

# the DC servo 1000 / (s (s + 1)) of scenarios/dc_servo_lqr_kalman.yaml (states theta, omega; y = theta)
A_C = [[0.0, 1.0], [0.0, -1.0]]
B_C = [[0.0], [1000.0]]
C_C = [[1.0, 0.0]]
PERIOD_S = 0.01  # the controller task's period in that file


def _base() -> dict[str, Any]:
    raw, _ = load_file(ROOT / "scenarios" / "dc_servo_lqr_kalman.yaml")
    raw["duration"] = "50 ms"
    return raw


def _ctl(raw: dict[str, Any]) -> dict[str, Any]:
    return raw["nodes"]["controller"]["tasks"][0]["params"]


def _pair(edit_numpy: Any, edit_plain: Any) -> tuple[dict[str, Any], dict[str, Any]]:
    """The base scenario with one edit given as numpy values and the same edit given as plain lists."""
    given, plain = _base(), _base()
    edit_numpy(given)
    edit_plain(plain)
    return given, plain


def _hashes(given: dict[str, Any], plain: dict[str, Any]) -> tuple[str, str]:
    """The scenario hash of the numpy-given scenario and of the same scenario written as lists."""
    return scenario_hash(given), scenario_hash(plain)


def _discrete() -> Any:
    return control.c2d(control.ss(A_C, B_C, C_C, 0), PERIOD_S)


# ------------------------------------------------------------------------------------------ numbers, arrays
def test_a_gain_from_dlqr_runs_as_state_feedback_K() -> None:
    sysd = _discrete()
    K, _, _ = control.dlqr(sysd.A, sysd.B, np.diag([1.0, 0.0]), 0.1)
    assert isinstance(K, np.ndarray)
    given, plain = _pair(lambda r: _ctl(r).update(law={"type": "state_feedback", "K": K}),
                         lambda r: _ctl(r).update(law={"type": "state_feedback", "K": K.tolist()}))
    result = netsim.run(given)  # issue 26: a raw PydanticSerializationError from the hash, after validation
    assert result.meta["status"] == "ok"
    numpy_hash, plain_hash = _hashes(given, plain)
    assert numpy_hash == plain_hash


def test_np_diag_weights_and_a_0d_array_weight_are_accepted() -> None:
    given, plain = _pair(lambda r: _ctl(r)["law"].update(Q=np.diag([1.0, 0.0]), R=np.array(0.1)),
                         lambda r: _ctl(r)["law"].update(Q=[[1.0, 0.0], [0.0, 0.0]], R=0.1))
    numpy_hash, plain_hash = _hashes(given, plain)
    assert numpy_hash == plain_hash


@pytest.mark.parametrize("value, plain", [(np.float32(0.25), float(np.float32(0.25))), (np.int64(2), 2),
                                          (np.float64(0.1), 0.1)])
def test_numpy_scalars_are_numbers(value: Any, plain: Any) -> None:
    given, expected = _pair(lambda r: _ctl(r)["law"].update(R=value), lambda r: _ctl(r)["law"].update(R=plain))
    numpy_hash, plain_hash = _hashes(given, expected)
    assert numpy_hash == plain_hash


def test_a_numpy_integer_where_an_integer_is_wanted() -> None:
    given, plain = _pair(lambda r: _ctl(r).update(bits=np.int64(64)), lambda r: _ctl(r).update(bits=64))
    numpy_hash, plain_hash = _hashes(given, plain)
    assert numpy_hash == plain_hash


def test_a_numpy_bool_where_a_bool_is_wanted() -> None:
    given, plain = _pair(lambda r: _ctl(r)["law"].update(feedforward=np.bool_(False)),
                         lambda r: _ctl(r)["law"].update(feedforward=False))
    numpy_hash, plain_hash = _hashes(given, plain)
    assert numpy_hash == plain_hash
    assert load_scenario(given).nodes["controller"].tasks[0].params["law"]["feedforward"] is False


def test_vectors_in_nested_program_params() -> None:
    """The estimator's diagonal covariance and initial estimate inside the state_feedback program's params."""
    given, plain = _pair(lambda r: _ctl(r)["estimator"].update(Q=np.array([0.0, 0.01]), x0=np.zeros(2)),
                         lambda r: _ctl(r)["estimator"].update(Q=[0.0, 0.01], x0=[0.0, 0.0]))
    numpy_hash, plain_hash = _hashes(given, plain)
    assert numpy_hash == plain_hash


def test_plant_matrices_and_process_noise_as_arrays() -> None:
    given, plain = _pair(lambda r: r["plant"].update(A=np.array(A_C), process_noise=np.array([0.0, 1.0])),
                         lambda r: r["plant"].update(A=A_C, process_noise=[0.0, 1.0]))
    numpy_hash, plain_hash = _hashes(given, plain)
    assert numpy_hash == plain_hash


def test_signal_parameters_as_numpy_scalars() -> None:
    given, plain = _pair(lambda r: r["signals"]["r"].update(amplitude=np.float32(0.5)),
                         lambda r: r["signals"]["r"].update(amplitude=0.5))
    numpy_hash, plain_hash = _hashes(given, plain)
    assert numpy_hash == plain_hash


def test_a_time_given_as_a_numpy_zero_is_zero() -> None:
    """Times take no bare number except 0 (timebase.parse_time); a numpy 0 is that 0, and any other numpy number
    gets the message the plain number gets."""
    given, plain = _pair(lambda r: r["nodes"]["controller"]["tasks"][0].update(offset=np.int64(0)),
                         lambda r: r["nodes"]["controller"]["tasks"][0].update(offset=0))
    numpy_hash, plain_hash = _hashes(given, plain)
    assert numpy_hash == plain_hash
    numpy_msgs = [p.message for p in check_scenario({"name": "t", "duration": np.int64(2)})]
    plain_msgs = [p.message for p in check_scenario({"name": "t", "duration": 2})]
    assert numpy_msgs == plain_msgs and "has no unit" in plain_msgs[0]


def test_override_values_from_python_may_be_numpy() -> None:
    path = "nodes.controller.tasks[0].params.law.Q"
    assert (scenario_hash(load_scenario(_base(), {path: np.diag([2.0, 0.0])}))
            == scenario_hash(load_scenario(_base(), {path: [[2.0, 0.0], [0.0, 0.0]]})))


@pytest.mark.parametrize("K_numpy, K_plain", [
    (np.array([[np.nan, 1.0]]), [[float("nan"), 1.0]]),
    (np.array([[1.0, np.inf]]), [[1.0, float("inf")]]),
    (np.array([[1.0, "a"]], dtype=object), [[1.0, "a"]]),
])
def test_non_finite_values_and_object_arrays_get_the_plain_messages(K_numpy: Any, K_plain: Any) -> None:
    given, plain = _pair(lambda r: _ctl(r).update(law={"type": "state_feedback", "K": K_numpy}),
                         lambda r: _ctl(r).update(law={"type": "state_feedback", "K": K_plain}))
    got = [(p.path, p.message) for p in check_scenario(given)]
    assert got and got == [(p.path, p.message) for p in check_scenario(plain)]
    assert all(p.path.startswith("nodes.controller.tasks[0].params.law.K") for p in check_scenario(given))


# ------------------------------------------------------------------------------------------ python-control
# the documented form of this plant written by hand: plant: {type: ss, A, B, C, D, inputs, outputs, states}
PLANT_LISTS = {"type": "ss", "A": A_C, "B": B_C, "C": C_C, "D": [[0.0]], "inputs": ["u"], "outputs": ["y"],
               "states": ["theta", "omega"]}


def _named_ss() -> Any:
    return control.ss(A_C, B_C, C_C, 0, inputs=["u"], outputs=["y"], states=["theta", "omega"])


def _keep(raw: dict[str, Any]) -> dict[str, Any]:
    return {k: raw["plant"][k] for k in ("process_noise", "record_grid")}


@pytest.mark.parametrize("form", ["itself", "system", "model"])
def test_a_statespace_plant_loads_as_its_ss_form(form: str) -> None:
    def given_edit(raw: dict[str, Any]) -> None:
        sys = _named_ss()
        raw["plant"] = sys if form == "itself" else {form: sys, **_keep(raw)}

    def plain_edit(raw: dict[str, Any]) -> None:
        raw["plant"] = dict(PLANT_LISTS) if form == "itself" else {**PLANT_LISTS, **_keep(raw)}

    given, plain = _pair(given_edit, plain_edit)
    assert load_scenario(given).plant.model == "ss"  # load_scenario itself, not only netsim.run
    numpy_hash, plain_hash = _hashes(given, plain)
    assert numpy_hash == plain_hash


def test_a_transfer_function_plant_loads_as_its_tf_form() -> None:
    def weights(raw: dict[str, Any]) -> None:  # python-control's realisation orders the states its own way
        _ctl(raw)["law"]["Q"] = [1.0, 1.0]

    given, plain = _pair(
        lambda r: (weights(r), r.update(plant=control.tf([1000], [1, 1, 0], inputs="u", outputs="y"))),
        lambda r: (weights(r), r.update(plant={"type": "tf", "num": [1000.0], "den": [1.0, 1.0, 0.0],
                                                "inputs": ["u"], "outputs": ["y"]})))
    assert load_scenario(given).plant.model == "tf"
    numpy_hash, plain_hash = _hashes(given, plain)
    assert numpy_hash == plain_hash


def test_a_discrete_statespace_model_becomes_A_B_C() -> None:
    sysd = _discrete()
    given, plain = _pair(lambda r: _ctl(r).update(model=sysd),
                         lambda r: _ctl(r).update(model={"A": sysd.A.tolist(), "B": sysd.B.tolist(),
                                                         "C": sysd.C.tolist()}))
    numpy_hash, plain_hash = _hashes(given, plain)
    assert numpy_hash == plain_hash


def test_a_discrete_transfer_function_model_is_realised_by_python_control() -> None:
    tfd = control.c2d(control.tf([1000], [1, 1, 0]), PERIOD_S)
    ssd = control.ss(tfd)  # python-control's realisation, the one a tf plant gets
    given, plain = _pair(lambda r: _ctl(r).update(model=tfd),
                         lambda r: _ctl(r).update(model={"A": ssd.A.tolist(), "B": ssd.B.tolist(),
                                                         "C": ssd.C.tolist()}))
    numpy_hash, plain_hash = _hashes(given, plain)
    assert numpy_hash == plain_hash


@pytest.mark.parametrize("system, words", [
    (lambda: control.ss(A_C, B_C, C_C, 0), "continuous"),
    (lambda: control.c2d(control.ss(A_C, B_C, C_C, 0), 0.02), "not the task period (10 ms)"),
    (lambda: control.tf([1, 0.5], [1, -0.5], PERIOD_S), "feed-through"),
])
def test_a_model_that_is_not_the_discrete_model_at_the_period_is_refused(system: Any, words: str) -> None:
    raw = _base()
    _ctl(raw)["model"] = system()
    problems = check_scenario(raw)
    assert [p.path for p in problems] == ["nodes.controller.tasks[0].params.model"]
    assert words in problems[0].message


def test_a_model_given_as_an_override_is_checked_against_the_task_period() -> None:
    path = "nodes.controller.tasks[0].params.model"
    problems = check_scenario(_base(), {path: control.c2d(control.ss(A_C, B_C, C_C, 0), 0.02)})
    assert [p.path for p in problems] == [path] and "not the task period (10 ms)" in problems[0].message
    sysd = _discrete()
    assert (scenario_hash(load_scenario(_base(), {path: sysd}))
            == scenario_hash(load_scenario(_base(), {path: {"A": sysd.A.tolist(), "B": sysd.B.tolist(),
                                                            "C": sysd.C.tolist()}})))


def test_a_system_where_numbers_are_wanted_says_where_systems_go() -> None:
    raw = _base()
    _ctl(raw)["law"] = {"type": "state_feedback", "K": _discrete()}
    problems = check_scenario(raw)
    assert [p.path for p in problems] == ["nodes.controller.tasks[0].params.law.K"]
    assert "accepted as the plant" in problems[0].message and "give numbers" in problems[0].message


# ------------------------------------------------------------------------------------------ sweeps
def test_a_sweep_from_python_takes_numpy_factor_values() -> None:
    def sweep(values: Any) -> list[str]:
        spec = {"sweep": "np", "base": "unused.yaml", "factors": {"x0": {"paths": ["plant.x0"], "values": values}}}
        loaded = load_sweep(spec, base=_base())
        return [scenario_hash(loaded.point_raw(p)) for p in loaded.points]

    assert sweep(np.array([[1.0, 0.0], [0.5, 0.0]])) == sweep([[1.0, 0.0], [0.5, 0.0]])
    assert sweep([np.array([1.0, 0.0]), np.array([0.5, 0.0])]) == sweep([[1.0, 0.0], [0.5, 0.0]])


def test_a_mapping_given_from_python_is_not_modified() -> None:
    raw = _base()
    K = np.array([[1.0, 0.1]])
    _ctl(raw)["law"] = {"type": "state_feedback", "K": K}
    before = copy.deepcopy(raw)
    load_scenario(raw)
    assert _ctl(raw)["law"]["K"] is K and np.array_equal(K, [[1.0, 0.1]])
    assert raw.keys() == before.keys()
