"""The state_feedback program (issue 16): loops composed in YAML against independent numpy computations."""

from __future__ import annotations

import copy

import numpy as np
import pytest
import scipy.linalg as sla

import netsim
from netsim.scenario import load_scenario
from netsim.scenario.problems import ScenarioError

H = 0.01  # the controller period, s
A_C = np.array([[0.0, 1.0], [0.0, -1.0]])  # the DC servo 1000 / (s (s + 1)), states [theta, omega]
B_C = np.array([[0.0], [1000.0]])
C = np.array([[1.0, 0.0]])
Q_LQR, R_LQR = np.diag([1.0, 0.0]), 0.1
Q_KF, R_KF = np.diag([0.0, 0.01]), 1e-6


def _servo(controller_params: dict, *, network: dict, sensor_exec: str | None = None, noise: bool = False,
           offset: str = "1 ms", duration: str = "0.5 s", actuator_node: bool = True) -> dict:
    """Sensor -> controller (state_feedback) -> actuator over ``network`` (``actuator_node=False``: the controller
    writes the DAC itself); the reference r is 0.5 rad (with ``noise``: a +-1 rad square wave)."""
    sensor = {"name": "sample", "program": "sensor", "period": "10 ms",
              "params": {"channels": ["ym"], "network": "net", "to": "controller", "tag": "y"}}
    if sensor_exec:
        sensor["execution"] = sensor_exec
    plant = {"type": "ss", "A": A_C.tolist(), "B": B_C.ravel().tolist(), "C": C.tolist(), "inputs": ["u"],
             "outputs": ["theta"], "x0": [1.0, 0.0], "record_grid": "1 ms"}
    if noise:
        plant["process_noise"] = [0.0, 1.0]
    output = {"network": "net", "to": "actuator"} if actuator_node else {"output_channel": "u"}
    raw = {
        "name": "servo_sf",
        "seed": 3,
        "duration": duration,
        "plant": plant,
        "io": {"ym": {"type": "adc", "output": "theta", "noise_std": 0.001 if noise else 0.0},
               "u": {"type": "dac", "input": "u"}},
        "signals": {"r": {"type": "constant", "value": 0.5} if not noise else
                    {"type": "square", "amplitude": 1.0, "period": "0.4 s"}},
        "nodes": {
            "sensor": {"policy": "dm", "tasks": [sensor]},
            "controller": {"policy": "dm", "tasks": [{
                "name": "control", "program": "state_feedback", "period": "10 ms", "offset": offset,
                "params": {"measurements": [{"network": "net", "sender": "sensor", "tag": "y"}],
                           "reference": "r", **output, "record_as": "u_cmd",
                           "record_estimate": "x_hat", **controller_params}}]},
            "actuator": {"policy": "dm", "tasks": [{"name": "actuate", "program": "actuator",
                                                    "params": {"network": "net", "channel": "u"},
                                                    "release": "on_message:net"}]},
        },
        "networks": {"net": {"type": network.pop("type"), "nodes": ["sensor", "controller", "actuator"], **network}},
        "record": ["r", "theta", "u_cmd", "x_hat"],
    }
    if not actuator_node:
        del raw["nodes"]["actuator"]
        raw["networks"]["net"]["nodes"] = ["sensor", "controller"]
    return raw


def _zoh(h: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact transition over ``h`` s with the input held: scipy's expm of the augmented matrix."""
    M = np.zeros((3, 3))
    M[:2, :2], M[:2, 2:] = A_C * h, B_C * h
    E = sla.expm(M)
    return E[:2, :2], E[:2, 2:]


def test_lqr_kalman_loop_over_an_ideal_network_equals_a_numpy_closed_loop() -> None:
    params = {"estimator": {"type": "kalman", "Q": [0.0, 0.01], "R": R_KF},
              "law": {"type": "lqr", "Q": [1.0, 0.0], "R": R_LQR}}
    result = netsim.run(_servo(params, network={"type": "ideal"}))
    sig = result.signals
    jobs = np.round((0.001 + H * np.arange(50)) * 1e6)  # the controller's job instants, in us
    u_run = sig["u_cmd"].to_numpy()[np.isin(np.round(sig["time_s"].to_numpy() * 1e6), jobs)]

    # the same discrete design computed independently: ZOH by scipy's expm, the LQR gain from scipy's DARE,
    # the Kalman filter's recursion written out; the loop: y_k sampled at t_k = 10 k ms, u_k applied 1 ms later
    # (the controller's offset; the ideal network and zero execution times add nothing)
    Ad, Bd = _zoh(H)
    A1, B1 = _zoh(0.001)
    A9, B9 = _zoh(0.009)
    P = sla.solve_discrete_are(Ad, Bd, Q_LQR, np.array([[R_LQR]]))
    K = np.linalg.solve(R_LQR + Bd.T @ P @ Bd, Bd.T @ P @ Ad)
    NxNu = np.linalg.solve(np.block([[Ad - np.eye(2), Bd], [C, np.zeros((1, 1))]]), np.array([0.0, 0.0, 1.0]))
    Fr = NxNu[2] + K @ NxNu[:2]
    x = np.array([1.0, 0.0])
    xh, Pk = np.zeros(2), np.eye(2)
    u_prev = 0.0
    u_ref = []
    for _ in range(len(u_run)):
        y = C @ x
        S = C @ Pk @ C.T + R_KF
        L = Pk @ C.T / S
        xh = xh + (L * (y - C @ xh)).ravel()
        IKC = np.eye(2) - L @ C
        Pk = IKC @ Pk @ IKC.T + R_KF * (L @ L.T)
        u = float(Fr[0] * 0.5 - (K @ xh)[0])
        u_ref.append(u)
        xh = Ad @ xh + Bd.ravel() * u
        Pk = Ad @ Pk @ Ad.T + Q_KF
        x = A1 @ x + B1.ravel() * u_prev  # 1 ms with the previous input, then 9 ms with the new one
        x = A9 @ x + B9.ravel() * u
        u_prev = u
    assert len(u_run) == 50
    assert abs(u_ref[-1] - 0.0) < 1e-3 and abs(u_ref[0]) > 0.1  # a transient that settles (r = 0.5, x0 = [1, 0])
    np.testing.assert_allclose(u_run, u_ref, rtol=1e-7, atol=1e-10)


def _estimation_rms(fuse_at: str) -> float:
    params = {"estimator": {"type": "kalman", "Q": [0.0, 0.01], "R": R_KF, "history": 10},
              "law": {"type": "lqr", "Q": [1.0, 0.0], "R": R_LQR}, "fuse_at": fuse_at}
    # a constant 25 ms network delay: each measurement arrives 2.5 periods after it was taken; the controller
    # writes the DAC itself (only the measurements are late), with a slow design (R = 30) that tolerates them
    params["law"]["R"] = 30.0
    raw = _servo(params, network={"type": "link", "delay": "25 ms"}, noise=True, offset="2 ms", duration="2 s",
                 actuator_node=False)
    result = netsim.run(raw)
    s = result.signals
    t_us = np.round(s["time_s"].to_numpy() * 1e6)
    at = np.isin(t_us, np.round((0.002 + H * np.arange(200)) * 1e6))  # the controller's sample instants
    assert at.sum() == 200
    # the estimate the law used at each sample against the plant's angle at that instant (the 1 ms plant grid)
    err = s["x_hat[0]"].to_numpy()[at] - s["theta"].to_numpy()[at]
    return float(np.sqrt(np.mean(err[10:] ** 2)))  # after 100 ms: the estimate starts at 0, the plant at 1 rad


def test_a_delayed_measurement_fused_at_its_sample_time_beats_fusing_it_at_arrival() -> None:
    at_sample = _estimation_rms("sample_time")
    at_arrival = _estimation_rms("arrival")
    # measured on this scenario: 0.022 rad against 0.54 rad RMS (fused at arrival, a 25 ms old angle is taken
    # for the current one while the servo moves, and the loop oscillates on the wrong estimate)
    assert at_sample < 0.5 * at_arrival, (at_sample, at_arrival)


BASE = _servo({"estimator": {"type": "kalman", "Q": [0.0, 0.01], "R": R_KF},
               "law": {"type": "lqr", "Q": [1.0, 0.0], "R": R_LQR}}, network={"type": "ideal"})
P0 = "nodes.controller.tasks[0].params"


def _with(path: str, value) -> dict:
    raw = copy.deepcopy(BASE)
    node = raw
    parts = path.split(".")
    for part in parts[:-1]:
        node = node[int(part)] if part.isdigit() else node[part]  # 'tasks.0': the list index
    node[parts[-1]] = value
    return raw


@pytest.mark.parametrize(("raw", "where", "words"), [
    (_with("plant.B", [[0.0, 1000.0]]), "plant.B", "n = 2 rows"),
    (_with("nodes.controller.tasks.0.params.law", {"type": "lqr", "Q": [[1, 2], [2, 1]], "R": 0.1}),
     f"{P0}.law.Q", "positive semidefinite"),
    (_with("nodes.controller.tasks.0.params.estimator", {"type": "kalman", "Q": [0, 0.01], "R": -1}),
     f"{P0}.estimator.R", "positive definite"),
    (_with("plant.B", [0.0, 0.0]), f"{P0}.law", "not stabilisable: the mode(s) at eigenvalue 1"),
    (_with("plant.C", [[0.0, 1.0]]), f"{P0}.estimator", "not detectable: the mode(s) at eigenvalue 1"),
    (_with("nodes.controller.tasks.0.params.estimator", {"type": "kalman", "Q": "big", "R": 1e-6}),
     f"{P0}.estimator.Q", "a number (times the identity), a list (the diagonal) or a square matrix"),
    (_with("nodes.controller.tasks.0.params.estimator", {"type": "luenberger", "poles": [0.5, 1.2]}),
     f"{P0}.estimator.poles", "inside the unit circle"),
    (_with("nodes.controller.tasks.0.params.law", {"type": "mpc", "horizon": 10, "Q": [1, 0], "R": 1,
                                                     "x_max": [0.5, None]}),
     f"{P0}.law", "x0: state 0 = 1 is above x_max[0] = 0.5"),
    (_with("nodes.controller.tasks.0.params.measurements", [{"network": "net", "outputs": [3]}]),
     f"{P0}.measurements[0].outputs", "no output 3"),
])
def test_bad_input_is_a_located_problem_never_a_traceback(raw: dict, where: str, words: str) -> None:
    with pytest.raises(ScenarioError) as err:
        load_scenario(raw)
    problems = [(p.path, p.message) for p in err.value.problems]
    assert any(p == where and words in m for p, m in problems), problems


def test_mpc_scenario_keeps_its_active_input_limit_and_charges_the_solve_time() -> None:
    result = netsim.run("scenarios/double_integrator_mpc.yaml")
    u = result.signals["u"].dropna().to_numpy()
    assert np.abs(u).max() == pytest.approx(1.0, abs=1e-12)  # the limit is reached (active) ...
    assert np.all(np.abs(u) <= 1.0 + 1e-12)  # ... and never passed
    assert (np.abs(u) > 1.0 - 1e-9).sum() >= 10  # active for a while in the transient
    jobs = result.jobs[result.jobs["task"] == "control"]
    m = result.metrics
    iterations = m["control.mpc.control.mpc_solver_iterations"]
    assert iterations > 0 and m["control.mpc.control.mpc_fallbacks"] == 0
    # every job runs execution (0.1 ms) + the model: 0.3 ms + 0.2 ms per solver iteration (the scenario's
    # numbers), alone on its CPU: the CPU time adds up to exactly that
    # (the job released at the end of the run, 5 s, has not run: it is left out; it took the unconstrained
    # shortcut, no solver iteration, like every step after the transient)
    done = jobs[jobs["finish_s"].notna()]
    assert len(done) == 100 and m["control.mpc.control.steps"] == 101
    expected = len(done) * (0.1e-3 + 0.3e-3) + 0.2e-3 * iterations
    assert done["cpu_time_s"].sum() == pytest.approx(expected, rel=1e-9)
    assert m["task.mpc.control.deadline_misses"] >= 1  # a long solve passes the 2 ms deadline


def test_two_sensors_feed_one_estimator_selected_by_sender_and_tag() -> None:
    from netsim.scenario import build

    sensor = {"program": "sensor", "period": "10 ms", "priority": 1}
    raw = {
        "name": "two_sensors",
        "duration": "0.5 s",
        "plant": {"type": "ss", "A": A_C.tolist(), "B": B_C.ravel().tolist(), "C": [[1, 0], [0, 1]],
                  "inputs": ["u"], "outputs": ["theta", "omega"], "x0": [1.0, 0.0], "record_grid": "1 ms"},
        "io": {"th": {"type": "adc", "output": "theta"}, "om": {"type": "adc", "output": "omega"},
               "u": {"type": "dac", "input": "u"}},
        "nodes": {
            "s1": {"tasks": [{**sensor, "name": "a", "params": {"channels": ["th"], "network": "net",
                                                                 "to": "controller", "tag": "y"}}]},
            "s2": {"tasks": [{**sensor, "name": "b", "params": {"channels": ["om"], "network": "net",
                                                                 "to": "controller", "tag": "y"}}]},
            # a third node sends frames tagged 'y' to the controller every 1 ms: the sender filter leaves them
            "noise": {"tasks": [{"name": "n", "program": "interference", "period": "1 ms", "priority": 1,
                                 "params": {"network": "net", "to": "controller", "tag": "y"}}]},
            "controller": {"tasks": [{
                "name": "control", "program": "state_feedback", "period": "10 ms", "offset": "1 ms", "priority": 1,
                "params": {"measurements": [{"network": "net", "sender": "s1", "tag": "y", "outputs": ["theta"]},
                                            {"network": "net", "sender": "s2", "tag": "y", "outputs": ["omega"]}],
                           "estimator": {"type": "none"}, "law": {"type": "lqr", "Q": [1, 0], "R": 0.1},
                           "output_channel": "u", "record_estimate": "x_hat"}}]},
        },
        "networks": {"net": {"type": "ideal", "nodes": ["s1", "s2", "noise", "controller"]}},
        "record": ["theta", "omega", "x_hat"],
    }
    sim = build(raw)
    sim.run()
    program = sim.programs["controller.control"]
    assert program.metrics()["fused"] == program.metrics()["steps"] == 50
    assert program.metrics()["partial"] == 0
    left = sim.kernels["controller"].inbox("net")
    assert len(left) > 400 and {m.sender for m in left} == {"noise", "s1", "s2"}  # the other frames stay ...
    assert {m.sent_ns for m in left if m.sender != "noise"} == {500_000_000}  # ... and the sensors' last sample
    result = netsim.run(raw)
    s = result.signals
    at = np.isin(np.round(s["time_s"].to_numpy() * 1e6), np.round((0.001 + H * np.arange(50)) * 1e6))
    # the sensors sample at 10 k ms, the controller uses x_hat = y at 10 k + 1 ms: the input written at
    # 10 (k - 1) + 1 ms moves the plant in between, so compare with the plant 1 ms earlier (the sample instants)
    before = np.flatnonzero(at) - 1
    np.testing.assert_array_equal(s["x_hat[0]"].to_numpy()[at], s["theta"].to_numpy()[before])
    np.testing.assert_array_equal(s["x_hat[1]"].to_numpy()[at], s["omega"].to_numpy()[before])
    assert np.abs(s["omega"].to_numpy()).max() > 1.0  # the loop moved the servo


def test_a_lost_measurement_makes_a_prediction_only_step() -> None:
    params = {"estimator": {"type": "kalman", "Q": [0.0, 0.01], "R": R_KF},
              "law": {"type": "lqr", "Q": [1.0, 0.0], "R": R_LQR}}
    raw = _servo(params, network={"type": "link", "loss_probability": 0.3}, duration="1 s", actuator_node=False)
    result = netsim.run(raw)
    m = result.metrics
    msgs = result.messages
    # the controller's 100 jobs (1 ms after each sample from 0 to 0.99 s) see the samples sent before 1 s
    seen = msgs[msgs["sent_s"] < 0.995]
    lost = int(seen["dropped"].sum())
    assert len(seen) == 100 and 15 < lost < 45  # about 30 % lost (a binomial draw)
    assert m["control.controller.control.prediction_only"] == lost
    assert m["control.controller.control.fused"] == 100 - lost


def _two_rate_sensors(estimator: dict) -> dict:
    """theta sent every 10 ms by s1, omega every 20 ms by s2, into one estimator at 10 ms."""
    def sensor(name: str, channel: str, period: str) -> dict:
        return {"tasks": [{"name": name, "program": "sensor", "period": period, "priority": 1,
                           "params": {"channels": [channel], "network": "net", "to": "controller", "tag": "y"}}]}

    return {
        "name": "two_rates",
        "duration": "0.5 s",
        "seed": 5,
        "plant": {"type": "ss", "A": A_C.tolist(), "B": B_C.ravel().tolist(), "C": [[1, 0], [0, 1]],
                  "inputs": ["u"], "outputs": ["theta", "omega"], "x0": [1.0, 0.0], "process_noise": [0.0, 1.0],
                  "record_grid": "1 ms"},
        "io": {"th": {"type": "adc", "output": "theta", "noise_std": 0.001},
               "om": {"type": "adc", "output": "omega", "noise_std": 0.01},
               "u": {"type": "dac", "input": "u"}},
        "nodes": {
            "s1": sensor("a", "th", "10 ms"),
            "s2": sensor("b", "om", "20 ms"),
            "controller": {"tasks": [{
                "name": "control", "program": "state_feedback", "period": "10 ms", "offset": "1 ms", "priority": 1,
                "params": {"measurements": [{"network": "net", "sender": "s1", "tag": "y", "outputs": ["theta"]},
                                            {"network": "net", "sender": "s2", "tag": "y", "outputs": ["omega"]}],
                           "estimator": estimator, "law": {"type": "lqr", "Q": [1, 0], "R": 0.1},
                           "output_channel": "u", "record_estimate": "x_hat"}}]},
        },
        "networks": {"net": {"type": "ideal", "nodes": ["s1", "s2", "controller"]}},
        "record": ["theta", "omega", "x_hat"],
    }


def test_sensors_with_their_own_rates_each_correct_the_kalman_filter():
    # R diagonal (independent sensors): every part is fused at its sample; 50 theta + 25 omega parts in 0.5 s
    kalman = {"type": "kalman", "Q": [0.0, 0.01], "R": [1e-6, 1e-4]}
    m = netsim.run(_two_rate_sensors(kalman)).metrics
    assert m["control.controller.control.fused"] == 75
    assert m["control.controller.control.partial"] == 0
    assert m["control.controller.control.prediction_only"] == 0
    # an estimator that needs the whole y (Luenberger) fuses only the 25 complete (even) samples and drops the
    # odd ones at the next job: 24 of them, the last one (sample 49) is still waiting when the run ends
    luenberger = {"type": "luenberger", "poles": [0.5, 0.6]}
    m = netsim.run(_two_rate_sensors(luenberger)).metrics
    assert m["control.controller.control.fused"] == 25
    assert m["control.controller.control.partial"] == 24


def test_correlated_sensor_noise_waits_for_the_whole_measurement():
    # a cross-covariance between the two sensors: fusing them apart would be wrong, so samples wait for both
    # (history 0: an incomplete sample is dropped at the next job; 24 dropped, sample 49 still waiting at the end)
    kalman = {"type": "kalman", "Q": [0.0, 0.01], "R": [[1e-6, 1e-6], [1e-6, 1e-4]], "history": 0}
    m = netsim.run(_two_rate_sensors(kalman)).metrics
    assert m["control.controller.control.fused"] == 25
    assert m["control.controller.control.partial"] == 24
