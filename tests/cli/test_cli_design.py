"""``netsim design FILE``: the state_feedback designs printed without running (issue 26 s4).

The expected gains are computed in the test: python-control's ``dlqr`` on the plant discretised by scipy's matrix
exponential of the augmented matrix.
"""

from __future__ import annotations

import json
from pathlib import Path

import control
import numpy as np
import scipy.linalg as sla
import yaml
from cli_files import write

from netsim.cli import main

H = 0.01
A_C = np.array([[0.0, 1.0], [0.0, -1.0]])  # the DC servo 1000 / (s (s + 1))
B_C = np.array([[0.0], [1000.0]])


def _scenario(law: dict) -> str:
    raw = {
        "name": "servo_design",
        "duration": "50 ms",
        "plant": {"type": "ss", "A": A_C.tolist(), "B": B_C.ravel().tolist(), "C": [[1.0, 0.0]], "inputs": ["u"],
                  "outputs": ["y"]},
        "io": {"ym": {"type": "adc", "output": "y"}, "u": {"type": "dac", "input": "u"}},
        "nodes": {"ctrl": {"policy": "dm", "tasks": [{
            "name": "control", "program": "state_feedback", "period": "10 ms",
            "params": {"measurements": [{"channel": "ym"}], "estimator": {"type": "kalman", "Q": [0, 0.01], "R": 1e-6},
                       "law": law, "output_channel": "u"}}]}},
    }
    return yaml.safe_dump(raw, sort_keys=False)


def _lqr_gain(R: float) -> np.ndarray:
    M = np.zeros((3, 3))
    M[:2, :2], M[:2, 2:] = A_C * H, B_C * H
    E = sla.expm(M)
    K, _, _ = control.dlqr(E[:2, :2], E[:2, 2:], np.diag([1.0, 0.0]), R)
    return np.asarray(K).ravel()


def test_design_prints_each_task_with_its_gain_and_eigenvalues(tmp_path: Path, capsys) -> None:
    path = write(tmp_path, "servo.yaml", _scenario({"type": "lqr", "Q": [1, 0], "R": 0.1}))
    assert main(["design", str(path)]) == 0
    out = capsys.readouterr().out
    K = _lqr_gain(0.1)
    assert out.startswith("servo_design: 1 state_feedback task\n")
    assert "ctrl.control  (nodes.ctrl.tasks[0])" in out
    assert f"K = [[{K[0]:.6g}, {K[1]:.6g}]]" in out
    for title in ("state feedback", "observer", "nominal loop", "delay margin"):
        assert title in out
    assert "UNSTABLE" not in out


def test_design_applies_set_overrides(tmp_path: Path, capsys) -> None:
    path = write(tmp_path, "servo.yaml", _scenario({"type": "lqr", "Q": [1, 0], "R": 0.1}))
    assert main(["design", str(path), "--set", "nodes.ctrl.tasks[0].params.law.R=0.001"]) == 0
    K = _lqr_gain(0.001)
    assert f"K = [[{K[0]:.6g}, {K[1]:.6g}]]" in capsys.readouterr().out


def test_design_json_is_what_a_run_writes_to_design_json(tmp_path: Path, capsys) -> None:
    path = write(tmp_path, "servo.yaml", _scenario({"type": "lqr", "Q": [1, 0], "R": 0.1}))
    assert main(["design", str(path), "--json"]) == 0
    printed = capsys.readouterr().out
    data = json.loads(printed)
    np.testing.assert_allclose(data["tasks"]["ctrl.control"]["law"]["K"], [_lqr_gain(0.1)], rtol=1e-8)
    assert main(["run", str(path), "--out", str(tmp_path / "run"), "-q"]) == 0
    assert (tmp_path / "run" / "design.json").read_text(encoding="utf-8") == printed


def test_design_marks_an_unstable_nominal_loop(tmp_path: Path, capsys) -> None:
    path = write(tmp_path, "servo.yaml", _scenario({"type": "state_feedback", "K": [[-5.0, 0.0]]}))
    assert main(["design", str(path)]) == 0
    captured = capsys.readouterr()
    assert "UNSTABLE" in captured.out
    assert "nominal closed loop" in captured.err and "ctrl.control" in captured.err  # validation's warning


def test_design_of_an_invalid_scenario_exits_2_and_names_the_problem(tmp_path: Path, capsys) -> None:
    path = write(tmp_path, "servo.yaml", _scenario({"type": "lqr", "Q": [1, 0], "R": -1}))
    assert main(["design", str(path)]) == 2
    err = capsys.readouterr().err
    assert "nodes.ctrl.tasks[0].params.law" in err and "nothing was designed" in err
