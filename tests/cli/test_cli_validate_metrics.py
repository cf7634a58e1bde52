"""Metric parameters of the shipped scenarios are checked by ``netsim validate`` (and before ``netsim run``),
not after the run: misspelt et_control keys, signals left out of ``record:``, unknown latency chain tasks."""

from __future__ import annotations

from pathlib import Path

import pytest

from netsim.cli import main

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"


@pytest.mark.parametrize(
    ("scenario", "override", "expected"),
    [
        ("hdd_case2.yaml", "metrics[0].params.perio=2e-5",
         "metrics[0].params.perio: unknown key 'perio'; did you mean 'period'?"),
        ("dc_servo_ideal.yaml", "record=[r, u]",
         "metrics[0].params.output: metric 'control_error' reads signal 'y', which 'record:' leaves out "
         "(record: [r, u]); add 'y' to 'record:'"),
        ("dc_servo_can.yaml", "metrics[1].params.chain=[sensor.nope, controller.control]",
         "metrics[1].params.chain[0]: node 'sensor' has no task or handler 'nope' (known tasks and handlers: sample)"),
    ],
)
def test_metric_problems_are_found_before_running(scenario, override, expected, tmp_path, capsys):
    path = SCENARIOS / scenario
    assert main(["validate", str(path), "--set", override]) == 1
    out = capsys.readouterr().out
    assert out.count("\n") == 1 and out.rstrip("\n").endswith(expected)
    assert main(["run", str(path), "--set", override, "--out", str(tmp_path / "run")]) == 2
    assert expected in capsys.readouterr().err
    assert not (tmp_path / "run").exists()  # nothing ran
