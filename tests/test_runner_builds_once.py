"""A run builds its scenario once (issue 28): ``netsim run`` no longer makes loading's dry run and then the real
build; the real build is checked as the dry run checks it, before the run folder is made.

Before: ``load_scenario`` built every scenario on a dry-run environment while loading, then the runner built it
again to run it: ``netsim run dc_servo_can`` called ``build()`` twice, ``netsim run hdd_case4`` (with a baseline)
four times. A scenario that does not build is still refused as loading refused it: the same ``file:line: path:
message``, exit code 2, and no run folder.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import pytest

from netsim.build import builder
from netsim.build.simulation import DryRunEnv
from netsim.cli import main
from netsim.runner import clear_baseline_cache, run
from netsim.scenario import ScenarioError

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture
def builds(monkeypatch: pytest.MonkeyPatch) -> list[tuple[str, bool]]:
    """``(scenario name, dry run?)`` of every ``build()`` call (the loader, the dry run and the runner all call
    ``netsim.build.builder.build`` through the module, so wrapping it counts them all)."""
    calls: list[tuple[str, bool]] = []
    real = builder.build

    def counted(scenario: Any, *, dry_run: bool = False) -> Any:
        calls.append((scenario.name, dry_run))
        sim = real(scenario, dry_run=dry_run)
        assert isinstance(sim.env, DryRunEnv) == dry_run
        return sim

    monkeypatch.setattr(builder, "build", counted)
    clear_baseline_cache()  # a baseline cached by another test would not be built here
    yield calls
    clear_baseline_cache()


def test_netsim_run_builds_a_scenario_once(tmp_path: Path, builds: list[tuple[str, bool]]) -> None:
    # before: [("dc_servo_can", True), ("dc_servo_can", False)] (loading's dry run, then the run's build)
    assert main(["run", "dc_servo_can", "--out", str(tmp_path / "run"), "--set", "duration=100 ms", "-q"]) == 0
    assert builds == [("dc_servo_can", False)]
    assert (tmp_path / "run" / "meta.json").is_file()


def test_netsim_run_builds_a_scenario_and_its_baseline_once_each(tmp_path: Path, builds: list[tuple[str, bool]]
                                                                 ) -> None:
    # hdd_case4 has a baseline (the same scenario with baseline.overrides); before: 4 builds, two of them dry
    assert main(["run", "hdd_case4", "--out", str(tmp_path / "run"), "--set", "duration=20 ms", "-q"]) == 0
    assert builds == [("hdd_case4", False), ("hdd_case4", False)]  # the scenario, then its baseline


def test_the_python_run_of_a_file_builds_it_once(tmp_path: Path, builds: list[tuple[str, bool]]) -> None:
    run(ROOT / "scenarios" / "dc_servo_can.yaml", out=tmp_path / "run", overrides={"duration": "100 ms"})
    assert builds == [("dc_servo_can", False)]


#: A state_feedback loop whose program refuses two DACs for its one input: only building the program finds it
#: (the same scenario as tests/build/test_dry_run.py).
TWO_DACS = """\
name: two_dacs
duration: 50 ms
plant:
  type: ss
  A: [[0, 1], [0, -1]]
  B: [0, 1000]
  C: [1, 0]
  inputs: [u]
  outputs: [y]
io:
  y: {type: adc, output: y}
  u: {type: dac, input: u}
  u2: {type: dac, input: u}
nodes:
  c:
    tasks:
      - name: control
        program: state_feedback
        period: 10 ms
        deadline: 20 ms
        priority: 1
        params:
          measurements: [{channel: y}]
          estimator: {type: kalman, Q: [0, 0.01], R: 1.0e-6}
          law: {type: lqr, Q: [1, 0], R: 0.1}
          output_channels: [u, u2]
"""
WHERE = "nodes.c.tasks[0].params.output_channels"
WHAT = "output_channels must name 1 DAC channels (one per input), got 2"


def _line_of(text: str, marker: str) -> int:
    """1-based line of ``marker`` in ``text`` (found here, not by netsim)."""
    return next(i for i, line in enumerate(text.splitlines(), start=1) if marker in line)


def test_a_run_that_does_not_build_is_refused_as_loading_refused_it(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                                    capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "two_dacs.yaml"
    path.write_text(TWO_DACS)
    monkeypatch.chdir(tmp_path)  # a default run folder would go to ./reports
    assert main(["run", str(path), "--out", str(tmp_path / "run")]) == 2
    assert main(["run", str(path)]) == 2
    err = capsys.readouterr().err.splitlines()
    # the warning (deadline > period) comes with the error, sorted by line, as loading printed them
    one = [f"{path}:{_line_of(TWO_DACS, 'deadline:')}: warning: nodes.c.tasks[0].deadline: deadline 20 ms is longer "
           "than the period 10 ms; jobs may overlap (allowed)",
           f"{path}:{_line_of(TWO_DACS, 'output_channels:')}: {WHERE}: {WHAT}",
           f"netsim: error: {path}: 1 problem; nothing was run"]
    assert err == one + one
    assert not (tmp_path / "run").exists() and not (tmp_path / "reports").exists()


def test_a_baseline_that_does_not_build_is_refused_at_its_overrides(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                                     capsys: pytest.CaptureFixture[str]) -> None:
    text = TWO_DACS.replace("output_channels: [u, u2]", "output_channels: [u]").replace("        deadline: 20 ms\n", "")
    text += 'baseline:\n  overrides: {"nodes.c.tasks[0].params.output_channels": [u, u2]}\n'
    path = tmp_path / "base.yaml"
    path.write_text(text)
    monkeypatch.chdir(tmp_path)
    assert main(["run", str(path), "--out", str(tmp_path / "run")]) == 2
    assert capsys.readouterr().err.splitlines() == [
        f"{path}:{_line_of(text, 'overrides:')}: baseline.overrides: override gives {WHERE}: {WHAT}",
        f"netsim: error: {path}: 1 problem; nothing was run"]
    assert not (tmp_path / "run").exists()
    assert main(["validate", str(path)]) == 1  # validate refuses it at the same place
    assert f"{path}:{_line_of(text, 'overrides:')}: baseline.overrides: override gives {WHERE}: {WHAT}" in \
        capsys.readouterr().out.splitlines()


def test_a_sweep_point_that_does_not_build_raises_the_loaders_error(tmp_path: Path) -> None:
    import yaml

    raw = yaml.safe_load(TWO_DACS)
    with pytest.raises(ScenarioError) as refused:  # what netsim.runner.run_point raises for a sweep point
        run(raw, out=tmp_path / "point", seed=1)
    assert [(p.path, p.message, p.is_error) for p in refused.value.problems] == [
        ("nodes.c.tasks[0].deadline", "deadline 20 ms is longer than the period 10 ms; jobs may overlap (allowed)",
         False), (WHERE, WHAT, True)]
    assert not (tmp_path / "point").exists()


def test_the_builds_warnings_are_logged_once_in_loadings_order(tmp_path: Path, caplog: pytest.LogCaptureFixture,
                                                               builds: list[tuple[str, bool]]) -> None:
    # pendulum_hold_still's law K = 0 leaves the upright pendulum unstable: the build warns at params.law (a
    # nominal loop with |z| = 1.05417 >= 1, computed by the design); two deadlines longer than their periods warn
    # while validating, one before and one after it in the file; the baseline's deadline warns too (its own
    # value), its unstable loop is the scenario's (said once)
    text = (ROOT / "scenarios" / "pendulum_hold_still.yaml").read_text()
    text = text.replace("duration: 10 s", "duration: 20 ms")
    text = text.replace("        deadline: 5 ms\n        priority: 1", "        deadline: 6 ms\n        priority: 1")
    text = text.replace("          record_estimate: x_hat\n", "          record_estimate: x_hat\n"
                        "      - {name: idle, program: sampler, period: 10 ms, deadline: 12 ms, priority: 2,\n"
                        "         execution: 0.1 ms, params: {channel: theta_m}}\n")
    text += 'baseline:\n  overrides: {"nodes.rip.tasks[1].deadline": 15 ms}\n'
    path = tmp_path / "warn.yaml"
    path.write_text(text)
    with caplog.at_level(logging.WARNING, logger="netsim"):
        run(path, out=tmp_path / "run")
    said = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    overlap = "is longer than the period {} ms; jobs may overlap (allowed)"
    assert said[:4] == [
        f"{path}:{_line_of(text, 'deadline: 6 ms')}: nodes.rip.tasks[0].deadline: deadline 6 ms "
        + overlap.format(5),
        f"{path}:{_line_of(text, 'law:')}: nodes.rip.tasks[0].params.law: task rip.control: the nominal closed loop "
        "(estimator and law on the discrete model, no network) is unstable: eigenvalue 1.05417+0j has magnitude "
        "1.05417 >= 1 (state feedback |z| = 1.05417); check the law's gain or weights and the estimator",
        f"{path}:{_line_of(text, 'deadline: 12 ms')}: nodes.rip.tasks[1].deadline: deadline 12 ms "
        + overlap.format(10),
        "nodes.rip.tasks[1].deadline: deadline 15 ms " + overlap.format(10)]
    assert not any("nominal closed loop" in s for s in said[4:])
    assert builds == [("pendulum_hold_still", False), ("pendulum_hold_still", False)]


def test_netsim_analyze_builds_a_scenario_once(tmp_path: Path, builds: list[tuple[str, bool]]) -> None:
    # before: [("dc_servo_can", True), ("dc_servo_can", False), ("dc_servo_can", False)]: analyze loaded with the
    # dry run, ran (one build), then built an unrun copy for the analysis tables (netsim.cli.analyze.analyze_run);
    # now the loading's dry run is gone: the run's build, then the analysis' copy
    assert main(["analyze", "dc_servo_can", "--out", str(tmp_path / "run"), "--set", "duration=100 ms"]) == 0
    assert builds == [("dc_servo_can", False), ("dc_servo_can", False)]
    assert (tmp_path / "run" / "analysis.csv").is_file()

