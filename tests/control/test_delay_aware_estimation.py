"""Estimation that knows the actuation delay (issue 26 section 5): ``input_delay``, ``applied_input`` and
``x0_hat: first_measurement`` of the state_feedback program, against independent numpy computations."""

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
Q_KF, R_KF = np.diag([0.0, 0.01]), 1e-6
P0 = "nodes.controller.tasks[0].params"


def _loop(params: dict, act_delay: object, *, report: bool = False, x0: tuple = (1.0, 0.0),
          duration: str = "0.6 s") -> dict:
    """Controller (ADC, no noise; state_feedback, period 10 ms, no offset, no execution) -> 'act' link with
    ``act_delay`` -> actuator (optionally reporting back over the 'rep' link, no delay). Plant noise excites it."""
    actuator = {"network": "act", "channel": "u", "record_as": "u_applied"}
    if report:
        actuator["report"] = {"network": "rep", "to": "controller"}
    raw = {
        "name": "servo_delay", "seed": 5, "duration": duration,
        "plant": {"type": "ss", "A": A_C.tolist(), "B": B_C.ravel().tolist(), "C": C.tolist(), "inputs": ["u"],
                  "outputs": ["theta"], "x0": list(x0), "record_grid": "1 ms", "process_noise": [0.0, 1.0]},
        "io": {"ym": {"type": "adc", "output": "theta", "noise_std": 0.0}, "u": {"type": "dac", "input": "u"}},
        "nodes": {
            "controller": {"policy": "dm", "tasks": [{
                "name": "control", "program": "state_feedback", "period": "10 ms",
                "params": {"measurements": [{"channel": "ym"}], "network": "act", "to": "actuator",
                           "record_as": "u_cmd", "record_estimate": "x_hat",
                           "estimator": {"type": "kalman", "Q": [0.0, 0.01], "R": R_KF, "history": 10},
                           "law": {"type": "lqr", "Q": [1.0, 0.0], "R": 30.0}, **params}}]},
            "actuator": {"policy": "dm", "tasks": [{"name": "actuate", "program": "actuator", "params": actuator,
                                                    "release": "on_message:act"}]},
        },
        "networks": {"act": {"type": "link", "nodes": ["controller", "actuator"], "delay": act_delay}},
        "record": ["theta", "u_cmd", "u_applied", "x_hat"],
    }
    if report:
        raw["networks"]["rep"] = {"type": "link", "nodes": ["actuator", "controller"], "delay": "0 ms"}
    return raw


def _phi_gamma(t: float) -> tuple[np.ndarray, np.ndarray]:
    """``(e^(A t), int_0^t e^(A s) ds B)``: scipy's expm of the augmented matrix."""
    M = np.zeros((3, 3))
    M[:2, :2], M[:2, 2:] = A_C * t, B_C * t
    E = sla.expm(M)
    return E[:2, :2], E[:2, 2:]


def _at(sig, name: str, times_s: np.ndarray) -> np.ndarray:
    """Values of signal ``name`` at the given instants (first sample at each instant)."""
    t = np.round(sig["time_s"].to_numpy() * 1e6)
    col = sig[name].to_numpy()
    out = []
    for ti in np.round(times_s * 1e6):
        idx = np.flatnonzero((t == ti) & ~np.isnan(col))
        out.append(col[idx[0]])
    return np.array(out)


def _kalman(F: np.ndarray, G: np.ndarray, Cm: np.ndarray, Q: np.ndarray, P: np.ndarray, ys: np.ndarray,
            inputs: list[np.ndarray]) -> np.ndarray:
    """Time-varying Kalman filter written out (current form): posterior at each sample, z0 = 0."""
    z = np.zeros(F.shape[0])
    post = []
    for y, v in zip(ys, inputs):
        S = Cm @ P @ Cm.T + R_KF
        K = P @ Cm.T / S
        z = z + (K * (y - Cm @ z)).ravel()
        IKC = np.eye(F.shape[0]) - K @ Cm
        P = IKC @ P @ IKC.T + R_KF * (K @ K.T)
        post.append(z.copy())
        z = F @ z + G @ v
        P = F @ P @ F.T + Q
    return np.array(post)


def test_input_delay_estimate_equals_a_hand_built_augmented_kalman_filter() -> None:
    res = netsim.run(_loop({"input_delay": "23 ms"}, "23 ms"))
    sig = res.signals
    tk = H * np.arange(60)
    ys = _at(sig, "theta", tk)  # the ADC has no noise: y[k] is the plant's theta at t_k
    u = _at(sig, "u_cmd", tk)
    xh = np.column_stack([_at(sig, "x_hat[0]", tk), _at(sig, "x_hat[1]", tk)])
    # Astrom & Wittenmark's model of a delay tau = 2 h + 3 ms: z = [x; u[k-3]; u[k-2]; u[k-1]],
    # x[k+1] = Phi x + Gamma1 u[k-3] + Gamma0 u[k-2]; Gamma0 = int_0^(7 ms), Gamma1 = e^(A 7 ms) int_0^(3 ms)
    Phi, _ = _phi_gamma(H)
    F7, G7 = _phi_gamma(0.007)
    _, G3 = _phi_gamma(0.003)
    G0, G1 = G7, F7 @ G3
    F = np.zeros((5, 5))
    F[:2, :2], F[:2, 2:3], F[:2, 3:4] = Phi, G1, G0
    F[2, 3] = F[3, 4] = 1.0
    G = np.zeros((5, 1))
    G[4, 0] = 1.0
    Ca = np.hstack([C, np.zeros((1, 3))])
    Q = sla.block_diag(Q_KF, np.zeros((3, 3)))  # the delayed inputs are known: no noise, no initial doubt
    P = sla.block_diag(np.eye(2), np.zeros((3, 3)))
    ref = _kalman(F, G, Ca, Q, P, ys, [np.array([v]) for v in u])
    assert np.max(np.abs(xh[:, 0])) > 0.1  # a real transient (x0 = [1, 0], estimate from 0)
    np.testing.assert_allclose(xh, ref[:, :2], rtol=1e-7, atol=1e-9)


def test_applied_input_reports_give_the_exact_zoh_split_of_each_period_under_a_varying_delay() -> None:
    raw = _loop({"applied_input": {"network": "rep", "sender": "actuator"}},
                {"dist": "uniform", "low": "4 ms", "high": "27 ms"}, report=True)
    res = netsim.run(raw)
    sig = res.signals
    tk = H * np.arange(60)
    ys = _at(sig, "theta", tk)
    xh = np.column_stack([_at(sig, "x_hat[0]", tk), _at(sig, "x_hat[1]", tk)])
    # the input on the plant, from the actuator's own record: (instant in ns, value)
    ua = sig[["time_s", "u_applied"]].dropna()
    t_app = np.round(ua["time_s"].to_numpy() * 1e9).astype(np.int64)
    v_app = ua["u_applied"].to_numpy()
    assert len(np.unique(np.diff(t_app) % 10_000_000)) > 5  # the delay really varies

    def held(t_ns: int) -> float:
        i = np.searchsorted(t_app, t_ns, side="right")
        return 0.0 if i == 0 else float(v_app[i - 1])

    # the effect of the held input over period k, integrated piece by piece with scipy's expm
    effects = []
    for k in range(60):
        a, b = 10_000_000 * k, 10_000_000 * (k + 1)
        cuts = [a] + [int(t) for t in t_app if a < t < b] + [b]
        w = np.zeros(2)
        for s0, s1 in zip(cuts[:-1], cuts[1:]):
            after, _ = _phi_gamma((b - s1) * 1e-9)
            _, gam = _phi_gamma((s1 - s0) * 1e-9)
            w += (after @ gam).ravel() * held(s0)
        effects.append(w)
    Phi, _ = _phi_gamma(H)
    ref = _kalman(Phi, np.eye(2), C, Q_KF, np.eye(2), ys, effects)
    np.testing.assert_allclose(xh, ref, rtol=1e-7, atol=1e-9)
    msgs = res.messages
    reports = int((msgs["tag"] == "applied").sum())
    assert reports > 40 and res.metrics["control.controller.control.inputs_reported"] == reports


def test_the_delay_unaware_estimate_is_what_the_delay_options_change() -> None:
    # the same loop without input_delay: the filter predicts with u at the sample instant, its estimate leaves
    # the reference above (this is what the options fix; without it the first test could pass by accident)
    tk = H * np.arange(60)
    old = netsim.run(_loop({}, "23 ms")).signals
    new = netsim.run(_loop({"input_delay": "23 ms"}, "23 ms")).signals
    err = []
    for sig in (old, new):
        x_true = np.column_stack([_at(sig, "theta", tk)])
        err.append(np.max(np.abs(_at(sig, "x_hat[0]", tk) - x_true[:, 0])))
    assert err[1] < 0.5 * err[0]


def test_first_measurement_start_takes_the_measured_state_and_leaves_the_unseen_one_at_x0() -> None:
    raw = _loop({"x0_hat": "first_measurement"}, "0 ms", x0=(0.7, 0.0), duration="0.05 s")
    raw["nodes"]["controller"]["tasks"][0]["params"]["estimator"]["x0"] = [0.0, 0.3]
    sig = netsim.run(raw).signals
    x0_hat = np.array([_at(sig, "x_hat[0]", np.array([0.0]))[0], _at(sig, "x_hat[1]", np.array([0.0]))[0]])
    # C = [1 0]: theta takes its measured value 0.7, omega (unseen by C) keeps the estimator's x0 = 0.3; the
    # Kalman correction that follows has a zero innovation
    np.testing.assert_allclose(x0_hat, [0.7, 0.3], atol=1e-12)


def test_first_measurement_estimate_is_the_minimum_norm_least_squares_change() -> None:
    from netsim.control.interface import first_measurement_estimate

    rng = np.random.default_rng(4)
    Cm = rng.normal(size=(2, 4))
    y = rng.normal(size=2)
    x0 = rng.normal(size=4)
    dx, *_ = np.linalg.lstsq(Cm, y - Cm @ x0, rcond=None)  # numpy's minimum-norm solution
    np.testing.assert_allclose(first_measurement_estimate(Cm, y, x0), x0 + dx, atol=1e-12)


def test_luenberger_with_input_delay_equals_the_augmented_observer_with_deadbeat_input_states() -> None:
    from netsim.control.interface import InputDelayLine, zoh_split
    from netsim.control.luenberger import LuenbergerObserver, observer_gain

    Phi, G0, G1 = zoh_split(A_C, B_C, H, 0.004)
    obs = LuenbergerObserver(Phi, np.hstack([G0, G1]), C, [0.5, 0.6], form="current")
    line = InputDelayLine(1, 1)
    # the augmented model z = [x; u[k-2]; u[k-1]] (tau = h + 4 ms), observer gain [L; 0]: the error of the known
    # input states is zero, its eigenvalues are those of A - L C A and 0, 0
    F = np.zeros((4, 4))
    F[:2, :2], F[:2, 2:3], F[:2, 3:4] = Phi, G1, G0
    F[2, 3] = 1.0
    G = np.array([0.0, 0.0, 0.0, 1.0])
    Ca = np.hstack([C, np.zeros((1, 2))])
    L = observer_gain(Phi, C, [0.5, 0.6], "current")
    La = np.vstack([L, np.zeros((2, 1))])
    rng = np.random.default_rng(1)
    z = np.zeros(4)
    for _ in range(40):
        y, u = rng.normal(size=1), rng.normal(size=1)
        obs.correct(y)
        z = z + (La @ (y - Ca @ z)).ravel()
        np.testing.assert_allclose(obs.x_hat, z[:2], atol=1e-12)
        obs.predict(line.push(u))
        z = F @ z + G * u[0]


def test_zoh_split_sums_to_the_plain_zoh_and_matches_two_held_pieces() -> None:
    from netsim.control.interface import zoh_split

    Phi, G0, G1 = zoh_split(A_C, B_C, H, 0.0037)
    Ph, Gh = _phi_gamma(H)
    np.testing.assert_allclose(G0 + G1, Gh, rtol=1e-12)
    F1, B1 = _phi_gamma(0.0037)  # u_old over 3.7 ms, then u_new over 6.3 ms
    F2, B2 = _phi_gamma(0.0063)
    x0, uo, un = np.array([0.3, -1.0]), 0.2, -0.5
    np.testing.assert_allclose(Phi @ x0 + (G1 * uo + G0 * un).ravel(),
                               F2 @ (F1 @ x0 + B1.ravel() * uo) + B2.ravel() * un, rtol=1e-12)


def _with(path: str, value: object, raw: dict) -> dict:
    raw = copy.deepcopy(raw)
    node = raw
    parts = path.split(".")
    for part in parts[:-1]:
        node = node[int(part)] if part.isdigit() else node[part]
    node[parts[-1]] = value
    return raw


_BASE = _loop({}, "23 ms")
_SF = "nodes.controller.tasks.0.params"


@pytest.mark.parametrize(("raw", "where", "words"), [
    (_with(f"{_SF}.input_delay", "-1 ms", _BASE), f"{P0}.input_delay", "must not be negative"),
    (_with(f"{_SF}.model", {"A": [[1, 0.01], [0, 0.99]], "B": [[0.05], [9.95]], "C": [[1, 0]]},
           _with(f"{_SF}.measurements", [{"channel": "ym", "outputs": [0]}],
                 _with(f"{_SF}.input_delay", "23 ms", _BASE))), f"{P0}.input_delay", "a whole number of periods"),
    (_with(f"{_SF}.applied_input", {"network": "act"},
           _with(f"{_SF}.estimator", {"type": "luenberger", "poles": [0.5, 0.6]}, _BASE)),
     f"{P0}.applied_input", "cannot take inputs learned late"),
    (_with(f"{_SF}.applied_input", {"network": "act"}, _with(f"{_SF}.input_delay", "20 ms", _BASE)),
     f"{P0}.applied_input", "not both"),
    (_with(f"{_SF}.x0_hat", "first", _BASE), f"{P0}.x0_hat", "first_measurement"),
])
def test_bad_delay_options_are_located_problems(raw: dict, where: str, words: str) -> None:
    with pytest.raises(ScenarioError) as err:
        load_scenario(raw)
    problems = [(p.path, p.message) for p in err.value.problems]
    assert any(p == where and words in m for p, m in problems), problems


def test_every_state_feedback_and_actuator_parameter_has_a_description() -> None:
    from netsim.programs.basic import Actuator, ActuatorReport
    from netsim.programs.state_feedback import AppliedInputSource, MeasurementSource, ModelSpec, SolveTime, _Params

    missing = [f"{model.__name__}.{name}" for model in (_Params, MeasurementSource, AppliedInputSource, ModelSpec,
                                                       SolveTime, Actuator.Params, ActuatorReport)
               for name, field in model.model_fields.items() if not (field.description or "").strip()]
    assert not missing, missing
