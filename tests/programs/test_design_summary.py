"""design.json (issue 26 s4): every state_feedback task's design, checked against independent computations.

Every expected number here is computed in the test from the scenario's own model: the discrete model by scipy's
matrix exponential of the augmented matrix, the LQR gains by python-control's ``dlqr``, the Kalman gain from
scipy's DARE, eigenvalues by numpy, and the delay margin of a sampled integrator from its characteristic
polynomial (Jury's test).
"""

from __future__ import annotations

import json
import logging
from pathlib import Path

import control
import numpy as np
import pytest
import scipy.linalg as sla

import netsim
from netsim.scenario import check_scenario

H = 0.01  # controller period, s
A_C = np.array([[0.0, 1.0], [0.0, -1.0]])  # the DC servo 1000 / (s (s + 1)), states [theta, omega]
B_C = np.array([[0.0], [1000.0]])
C = np.array([[1.0, 0.0]])


def _loop(estimator: dict, law: dict, *, A=A_C, B=B_C, Cm=C, period: str = "10 ms", reference: bool = True,
          extra: dict | None = None) -> dict:
    """One node that samples y (ADC), runs state_feedback and writes u (DAC); no network."""
    n = np.asarray(A).shape[0]
    params = {"measurements": [{"channel": "ym"}], "estimator": estimator, "law": law, "output_channel": "u",
              **(extra or {})}
    if reference:
        params["reference"] = "r"
    return {
        "name": "design_loop",
        "seed": 1,
        "duration": "50 ms",
        "plant": {"type": "ss", "A": np.asarray(A).tolist(), "B": np.asarray(B).ravel().tolist(),
                  "C": np.asarray(Cm).tolist(), "inputs": ["u"], "outputs": ["y"], "x0": [0.1] + [0.0] * (n - 1)},
        "io": {"ym": {"type": "adc", "output": "y"}, "u": {"type": "dac", "input": "u"}},
        "signals": {"r": {"type": "constant", "value": 0.0}},
        "nodes": {"ctrl": {"policy": "dm", "tasks": [{"name": "control", "program": "state_feedback",
                                                       "period": period, "params": params}]}},
    }


def _zoh(A: np.ndarray, B: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    n, m = B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n], M[:n, n:] = A * h, B * h
    E = sla.expm(M)
    return E[:n, :n], E[:n, n:]


def _design(raw: dict, tmp_path: Path) -> dict:
    result = netsim.run(raw, out=tmp_path / "run")
    assert result.ok, result.meta
    data = json.loads((Path(result.out_dir) / "design.json").read_text(encoding="utf-8"))
    assert data["format"] == "netsim-design/1"
    return data["tasks"]["ctrl.control"]


def _complex(pairs: list) -> np.ndarray:
    return np.array([complex(re_, im_) for re_, im_ in pairs])


def _same_spectrum(got_pairs: list, want: np.ndarray, tol: float = 1e-8) -> None:
    got = np.sort_complex(_complex(got_pairs))
    want = np.sort_complex(np.asarray(want, dtype=complex))
    assert got.shape == want.shape
    np.testing.assert_allclose(got, want, atol=tol)


def _kalman_gain(A: np.ndarray, Cm: np.ndarray, Q: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    M = sla.solve_discrete_are(A.T, Cm.T, Q, R)
    return M @ Cm.T @ np.linalg.inv(Cm @ M @ Cm.T + R), M


def test_design_json_holds_the_lqr_and_kalman_gains_and_eigenvalues_of_an_independent_design(tmp_path: Path) -> None:
    Qkf, Rkf = np.diag([0.0, 0.01]), np.array([[1e-6]])
    d = _design(_loop({"type": "kalman", "Q": [0.0, 0.01], "R": 1e-6}, {"type": "lqr", "Q": [1.0, 0.0], "R": 0.1}),
                tmp_path)
    Ad, Bd = _zoh(A_C, B_C, H)
    np.testing.assert_allclose(d["model"]["A"], Ad, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(d["model"]["B"], Bd, rtol=1e-12, atol=1e-15)
    assert d["model"]["C"] == C.tolist() and d["model"]["period_s"] == H and d["model"]["source"] == "zoh"
    K, _, _ = control.dlqr(Ad, Bd, np.diag([1.0, 0.0]), 0.1)
    np.testing.assert_allclose(d["law"]["K"], K, rtol=1e-8)
    assert d["law"]["Ki"] is None
    _same_spectrum(d["law"]["eigenvalues"], np.linalg.eigvals(Ad - Bd @ K))
    # the time-varying filter is summarised by the gain its covariance settles to (the filter DARE)
    L, M = _kalman_gain(Ad, C, Qkf, Rkf)
    np.testing.assert_allclose(d["estimator"]["gain"], L, rtol=1e-7)
    np.testing.assert_allclose(d["estimator"]["dare_prior_covariance"], M, rtol=1e-7, atol=1e-14)
    np.testing.assert_allclose(d["estimator"]["dare_posterior_covariance"], M - L @ C @ M, rtol=1e-6, atol=1e-14)
    assert d["estimator"]["form"] == "current"
    observer = np.linalg.eigvals((np.eye(2) - L @ C) @ Ad)
    _same_spectrum(d["estimator"]["eigenvalues"], observer)
    np.testing.assert_allclose(sorted(d["estimator"]["magnitudes"]), sorted(np.abs(observer)), rtol=1e-8)
    # separation: the nominal loop has the state-feedback and the observer eigenvalues
    _same_spectrum(d["nominal"]["eigenvalues"], np.r_[np.linalg.eigvals(Ad - Bd @ K), observer])
    assert d["nominal"]["stable"] is True


def test_design_json_of_an_integral_lqr_matches_dlqr_on_the_augmented_model(tmp_path: Path) -> None:
    d = _design(_loop({"type": "steady_state_kalman", "Q": [0.0, 0.01], "R": 1e-6},
                      {"type": "lqr", "Q": [1.0, 0.0], "R": 0.01, "integral": True, "Qi": 0.5}), tmp_path)
    Ad, Bd = _zoh(A_C, B_C, H)
    Aa = np.block([[Ad, np.zeros((2, 1))], [-C, np.eye(1)]])  # z[k+1] = z[k] + r - C x
    Ba = np.vstack([Bd, np.zeros((1, 1))])
    Ka, _, _ = control.dlqr(Aa, Ba, np.diag([1.0, 0.0, 0.5]), 0.01)
    np.testing.assert_allclose(d["law"]["K"], Ka[:, :2], rtol=1e-7)
    np.testing.assert_allclose(d["law"]["Ki"], Ka[:, 2:], rtol=1e-7)
    assert d["law"]["with_integrator"] is True
    _same_spectrum(d["law"]["eigenvalues"], np.linalg.eigvals(Aa - Ba @ Ka))
    L, _ = _kalman_gain(Ad, C, np.diag([0.0, 0.01]), np.array([[1e-6]]))
    np.testing.assert_allclose(d["estimator"]["gain"], L, rtol=1e-7)
    _same_spectrum(d["nominal"]["eigenvalues"],
                   np.r_[np.linalg.eigvals(Aa - Ba @ Ka), np.linalg.eigvals((np.eye(2) - L @ C) @ Ad)], tol=1e-7)


@pytest.mark.parametrize("form", ["predictor", "current"])
def test_design_json_observer_eigenvalues_are_the_requested_luenberger_poles(tmp_path: Path, form: str) -> None:
    poles = ["0.5+0.2j", "0.5-0.2j"]
    d = _design(_loop({"type": "luenberger", "poles": poles, "form": form},
                      {"type": "state_feedback", "K": [[2.0, 0.05]]}), tmp_path)
    want = [complex(p) for p in poles]
    _same_spectrum(d["estimator"]["eigenvalues"], want, tol=1e-9)
    # the gain in the file gives those eigenvalues in the form's own error matrix
    Ad, Bd = _zoh(A_C, B_C, H)
    L = np.array(d["estimator"]["gain"])
    E = Ad - L @ C if form == "predictor" else (np.eye(2) - L @ C) @ Ad
    _same_spectrum([[z.real, z.imag] for z in np.linalg.eigvals(E)], want, tol=1e-9)
    assert d["estimator"]["form"] == form
    _same_spectrum(d["law"]["eigenvalues"], np.linalg.eigvals(Ad - Bd @ np.array([[2.0, 0.05]])))


def test_design_json_mpc_gain_is_the_lqr_gain_of_its_weights(tmp_path: Path) -> None:
    # with the default terminal weight (the LQR Riccati solution) the unconstrained MPC's first move is the LQR law
    d = _design(_loop({"type": "kalman", "Q": [0.0, 0.01], "R": 1e-6},
                      {"type": "mpc", "horizon": 5, "Q": [1.0, 0.0], "R": 0.1}), tmp_path)
    Ad, Bd = _zoh(A_C, B_C, H)
    K, _, _ = control.dlqr(Ad, Bd, np.diag([1.0, 0.0]), 0.1)
    np.testing.assert_allclose(d["law"]["K"], K, rtol=1e-6)


def test_delay_margin_of_a_sampled_integrator_is_one_over_the_gain(tmp_path: Path) -> None:
    # x' = u, u = -k x(t_k) applied tau after the sample (0 <= tau <= h): x[k+1] = (1 - (h - tau) k) x[k] + tau u[k-1],
    # characteristic polynomial z^2 - (1 - (h - tau) k) z + tau k. For 1 < k h < 2, Jury's test fails first at
    # tau k = 1 (a root on the unit circle): the margin is 1 / k.
    k = 1.5 / H
    d = _design(_loop({"type": "none"}, {"type": "state_feedback", "K": [[k]]}, A=[[0.0]], B=[[1.0]],
                      Cm=[[1.0]], reference=False), tmp_path)
    margin = d["delay_margin"]
    assert margin["seconds"] == pytest.approx(1.0 / k, abs=H / 8 / 2 ** 11)
    assert margin["stable_up_to_s"] < 1.0 / k <= margin["seconds"]
    # the same loop without delay: eigenvalues 1 - k h (state feedback) and 0 (the measured state, L = C^-1)
    _same_spectrum(d["law"]["eigenvalues"], [1 - k * H])
    _same_spectrum(d["estimator"]["eigenvalues"], [0.0])


def test_delay_margin_is_null_with_the_reason_when_the_analysis_cannot_give_it(tmp_path: Path) -> None:
    Ad, Bd = _zoh(A_C, B_C, H)
    model = {"A": Ad.tolist(), "B": Bd.tolist(), "C": C.tolist()}
    d = _design(_loop({"type": "kalman", "Q": [0.0, 0.01], "R": 1e-6}, {"type": "lqr", "Q": [1.0, 0.0], "R": 0.1},
                      extra={"model": model, "measurements": [{"channel": "ym", "outputs": [0]}]}), tmp_path / "given")
    assert d["delay_margin"]["seconds"] is None and "continuous LTI model" in d["delay_margin"]["reason"]
    # a slow design is still stable with a whole period of delay: at least the period, said so
    d = _design(_loop({"type": "kalman", "Q": [0.0, 0.01], "R": 1e-6}, {"type": "lqr", "Q": [1.0, 0.0], "R": 0.1}),
                tmp_path / "slow")
    assert d["delay_margin"]["seconds"] is None and d["delay_margin"]["stable_up_to_s"] == H
    assert "up to one period" in d["delay_margin"]["reason"]


def test_no_design_json_without_tables(tmp_path: Path) -> None:
    raw = _loop({"type": "kalman", "Q": [0.0, 0.01], "R": 1e-6}, {"type": "lqr", "Q": [1.0, 0.0], "R": 0.1})
    from netsim.runner import run

    run(raw, out=tmp_path / "full")
    assert (tmp_path / "full" / "design.json").exists()
    run(raw, out=tmp_path / "full", tables=False)  # a sweep's runs: metrics rewriting the folder
    assert not (tmp_path / "full" / "design.json").exists()


# --------------------------------------------------------------------------------------------- the warning
BAD_K = [[-5.0, 0.0]]  # positive feedback on the angle: the servo runs away


def _bad_radius() -> float:
    Ad, Bd = _zoh(A_C, B_C, H)
    return float(np.max(np.abs(np.linalg.eigvals(Ad - Bd @ np.array(BAD_K)))))


def test_validate_warns_of_an_unstable_nominal_loop_naming_task_and_magnitude() -> None:
    raw = _loop({"type": "kalman", "Q": [0.0, 0.01], "R": 1e-6}, {"type": "state_feedback", "K": BAD_K})
    problems = check_scenario(raw)
    warned = [p for p in problems if "nominal closed loop" in p.message]
    assert len(warned) == 1 and not warned[0].is_error
    assert warned[0].path == "nodes.ctrl.tasks[0].params.law"
    assert "ctrl.control" in warned[0].message and f"{_bad_radius():.6g}" in warned[0].message
    good = _loop({"type": "kalman", "Q": [0.0, 0.01], "R": 1e-6}, {"type": "state_feedback", "K": [[2.0, 0.05]]})
    assert not [p for p in check_scenario(good) if "nominal closed loop" in p.message]


def test_run_records_the_unstable_nominal_loop_in_meta_json_and_logs_it(tmp_path: Path, caplog) -> None:
    raw = _loop({"type": "kalman", "Q": [0.0, 0.01], "R": 1e-6}, {"type": "state_feedback", "K": BAD_K})
    with caplog.at_level(logging.WARNING, logger="netsim"):
        result = netsim.run(raw, out=tmp_path / "bad")
    meta = json.loads((tmp_path / "bad" / "meta.json").read_text(encoding="utf-8"))
    texts = [w for w in meta["warnings"] if "nominal closed loop" in w]
    assert len(texts) == 1 and "ctrl.control" in texts[0] and f"{_bad_radius():.6g}" in texts[0]
    assert any("nominal closed loop" in r.getMessage() and "ctrl.control" in r.getMessage() for r in caplog.records)
    d = json.loads((Path(result.out_dir) / "design.json").read_text(encoding="utf-8"))["tasks"]["ctrl.control"]
    assert d["nominal"]["stable"] is False
    assert d["nominal"]["spectral_radius"] == pytest.approx(_bad_radius(), rel=1e-9)


def test_pid_law_nominal_loop_is_the_plant_with_the_discrete_pid(tmp_path: Path) -> None:
    # expected: netsim.analysis.lqg.pid_controller (the PID's state-space form, written for the Jitterbug-style
    # analysis) closed around the discretised plant y = theta
    from netsim.analysis.lqg import pid_controller

    pid = {"type": "pid", "K": 0.1, "Ti": 0.5, "Td": 0.02, "N": 10.0}
    d = _design(_loop({"type": "kalman", "Q": [0.0, 0.01], "R": 1e-6}, pid), tmp_path)
    Ad, Bd = _zoh(A_C, B_C, H)
    Ac, Bc, Cc, Dc = pid_controller(0.1, 0.5, 0.02, 10.0, H)
    loop = np.block([[Ad + Bd @ Dc @ C, Bd @ Cc], [Bc @ C, Ac]])
    _same_spectrum(d["nominal"]["eigenvalues"], np.linalg.eigvals(loop))
    assert d["law"]["K"] is None and d["law"]["pid"]["Ti"] == 0.5


def test_design_json_with_input_delay_keeps_the_gains_and_says_the_loop_is_without_it(tmp_path: Path) -> None:
    # the delay-aware prediction changes only the estimator's input matrix: the gains are the design's
    d = _design(_loop({"type": "kalman", "Q": [0.0, 0.01], "R": 1e-6}, {"type": "lqr", "Q": [1.0, 0.0], "R": 0.1},
                      extra={"input_delay": "20 ms"}), tmp_path)
    Ad, Bd = _zoh(A_C, B_C, H)
    L, _ = _kalman_gain(Ad, C, np.diag([0.0, 0.01]), np.array([[1e-6]]))
    np.testing.assert_allclose(d["estimator"]["gain"], L, rtol=1e-7)
    K, _, _ = control.dlqr(Ad, Bd, np.diag([1.0, 0.0]), 0.1)
    np.testing.assert_allclose(d["law"]["K"], K, rtol=1e-8)
    assert d["input_delay_s"] == pytest.approx(0.02) and "input_delay" in d["nominal"]["note"]
